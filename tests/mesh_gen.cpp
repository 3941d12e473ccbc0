#include "mesh_gen.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>

namespace tsm_test {

using tsm::Mesh;

Mesh icosphere(int level) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<std::array<float, 3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto m = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back({(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2});
      return mid[key] = static_cast<uint32_t>(v.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> nf;
    for (auto [a, b, c] : f) {
      uint32_t ab = m(a, b), bc = m(b, c), ca = m(c, a);
      nf.push_back({a, ab, ca});
      nf.push_back({b, bc, ab});
      nf.push_back({c, ca, bc});
      nf.push_back({ab, bc, ca});
    }
    f = nf;
  }
  Mesh out;
  for (auto& p : v) {
    float n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    out.add_vertex(p[0] / n, p[1] / n, p[2] / n);
  }
  for (auto [a, b, c] : f) out.add_triangle(a, b, c);
  return out;
}

Mesh genus_surface(int g, int res) {
  // Voxel slab: (2g+1) x 3 cells in x,y, 1 cell thick; cells (2i+1, 1) removed.
  const int nx = (2 * g + 1) * res, ny = 3 * res, nz = res;
  auto solid = [&](int x, int y, int z) {
    if (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz) return false;
    int cx = x / res, cy = y / res;
    return !(cy == 1 && cx % 2 == 1);
  };
  Mesh m;
  std::map<std::tuple<int, int, int>, uint32_t> ids;
  auto vid = [&](int x, int y, int z) {
    auto key = std::make_tuple(x, y, z);
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    const float s = 1.0f / static_cast<float>(res);
    m.add_vertex(static_cast<float>(x) * s, static_cast<float>(y) * s, static_cast<float>(z) * s);
    return ids[key] = static_cast<uint32_t>(m.vertex_count() - 1);
  };
  // For each solid voxel face with an empty neighbour, emit a quad facing out
  // (counter-clockwise seen from outside), as two triangles.
  for (int x = 0; x < nx; ++x)
    for (int y = 0; y < ny; ++y)
      for (int z = 0; z < nz; ++z) {
        if (!solid(x, y, z)) continue;
        for (int axis = 0; axis < 3; ++axis)
          for (int dir = -1; dir <= 1; dir += 2) {
            int d[3] = {0, 0, 0};
            d[axis] = dir;
            if (solid(x + d[0], y + d[1], z + d[2])) continue;
            // The face plane and the two in-plane axes (u, w) with u x w = outward normal.
            int u = (axis + 1) % 3, w = (axis + 2) % 3;
            int base[3] = {x, y, z};
            if (dir > 0) base[axis] += 1;
            auto corner = [&](int du, int dw) {
              int p[3] = {base[0], base[1], base[2]};
              p[u] += du;
              p[w] += dw;
              return vid(p[0], p[1], p[2]);
            };
            uint32_t a = corner(0, 0), b = corner(1, 0), c = corner(1, 1), e = corner(0, 1);
            if (dir > 0) {
              m.add_triangle(a, b, c);
              m.add_triangle(a, c, e);
            } else {
              m.add_triangle(a, c, b);
              m.add_triangle(a, e, c);
            }
          }
      }
  return m;
}

Mesh grid_with_holes(int n, int holes) {
  Mesh m;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      m.add_vertex(static_cast<float>(x), static_cast<float>(y), 0.01f * static_cast<float>((x * 7 + y * 3) % 5));
  // Hole centres on a coarse lattice, each removing the faces of one cell block.
  std::set<std::pair<int, int>> removed;
  int per_row = 1;
  while (per_row * per_row < holes) ++per_row;
  int spacing = (n - 1) / (per_row + 1);
  for (int h = 0; h < holes; ++h) {
    int cx = spacing * (1 + h % per_row), cy = spacing * (1 + h / per_row);
    removed.insert({cx, cy});
  }
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      if (removed.count({x, y})) continue;
      uint32_t a = static_cast<uint32_t>(y * n + x), b = a + 1, c = a + static_cast<uint32_t>(n), d = c + 1;
      m.add_triangle(a, b, d);
      m.add_triangle(a, d, c);
    }
  return m;
}

Mesh fan(int n, bool closed) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  int rim = closed ? n : n + 1;
  for (int i = 0; i < rim; ++i) {
    double a = 2 * M_PI * i / (closed ? n : n + 1);
    m.add_vertex(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0);
  }
  for (int i = 0; i < n; ++i)
    m.add_triangle(0, static_cast<uint32_t>(1 + i), static_cast<uint32_t>(1 + (i + 1) % rim));
  return m;
}

Mesh strip(int n) {
  Mesh m;
  for (int i = 0; i < n + 2; ++i) m.add_vertex(static_cast<float>(i / 2), static_cast<float>(i % 2), 0);
  for (int i = 0; i < n; ++i) {
    uint32_t a = static_cast<uint32_t>(i);
    if (i % 2 == 0) m.add_triangle(a, a + 1, a + 2);
    else m.add_triangle(a, a + 2, a + 1);
  }
  return m;
}

Mesh moebius(int n) {
  Mesh m;
  for (int i = 0; i < n; ++i) {
    double a = 2 * M_PI * i / n, tw = a / 2;
    for (int s = -1; s <= 1; s += 2) {
      double r = 1 + 0.3 * s * std::cos(tw);
      m.add_vertex(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                   static_cast<float>(0.3 * s * std::sin(tw)));
    }
  }
  for (int i = 0; i < n; ++i) {
    uint32_t a = static_cast<uint32_t>(2 * i), b = a + 1;
    uint32_t c, d;
    if (i + 1 < n) {
      c = a + 2;
      d = a + 3;
    } else {  // the half twist: the last quad joins the first with sides swapped
      c = 1;
      d = 0;
    }
    m.add_triangle(a, c, d);
    m.add_triangle(a, d, b);
  }
  return m;
}

Mesh book(int k) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(0, 0, 1);
  for (int i = 0; i < k; ++i) {
    double a = 2 * M_PI * i / k;
    m.add_vertex(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0.5f);
    m.add_triangle(0, 1, static_cast<uint32_t>(2 + i));
  }
  return m;
}

Mesh bowtie() {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(1, 1, 0);
  m.add_vertex(1, -1, 0);
  m.add_vertex(-1, 1, 0);
  m.add_vertex(-1, -1, 0);
  m.add_vertex(2, 0, 0);
  m.add_triangle(0, 2, 1);
  m.add_triangle(2, 5, 1);
  m.add_triangle(0, 3, 4);
  return m;
}

Mesh flipped_face_sphere(int level) {
  Mesh m = icosphere(level);
  std::swap(m.indices[1], m.indices[2]);
  return m;
}

Mesh random_soup(int vertices, int faces, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-1, 1);
  Mesh m;
  for (int i = 0; i < vertices; ++i) m.add_vertex(pos(rng), pos(rng), pos(rng));
  if (vertices == 0) return m;
  std::uniform_int_distribution<uint32_t> pick(0, static_cast<uint32_t>(vertices - 1));
  for (int i = 0; i < faces; ++i) {
    uint32_t a = pick(rng), b = pick(rng), c = pick(rng);
    m.add_triangle(a, b, c);
    if (i % 17 == 5) m.add_triangle(a, b, c);  // a duplicate
  }
  return m;
}

Mesh cube_quads() {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.add_vertex(static_cast<float>(i & 1), static_cast<float>((i >> 1) & 1), static_cast<float>((i >> 2) & 1));
  const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto& f : q) m.add_face(f, 4);
  return m;
}

Mesh ngon(int n) {
  Mesh m;
  std::vector<uint32_t> f;
  for (int i = 0; i < n; ++i) {
    double a = 2 * M_PI * i / n;
    m.add_vertex(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)), 0);
    f.push_back(static_cast<uint32_t>(i));
  }
  m.add_face(f.data(), f.size());
  return m;
}

// A grid of n x n vertices, each quad split along a random diagonal, every
// 7th quad left out (holes), and a fin of three faces on the lower edge of
// every 11th quad (edges of three faces: stitches): irregular valences and
// runs that do not repeat, as on a scan.
Mesh irregular_grid(int n, uint32_t seed) {
  Mesh m;
  std::mt19937 rng(seed);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      m.add_vertex(static_cast<float>(x), static_cast<float>(y), static_cast<float>(rng() % 100) * 0.001f);
  int quad = 0;
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x, ++quad) {
      const uint32_t a = static_cast<uint32_t>(y * n + x), b = a + 1, c = a + static_cast<uint32_t>(n), d = c + 1;
      if (quad % 7 == 3) continue;
      if (rng() & 1) {
        m.add_triangle(a, b, d);
        m.add_triangle(a, d, c);
      } else {
        m.add_triangle(a, b, c);
        m.add_triangle(b, d, c);
      }
      if (quad % 11 == 5) {
        const uint32_t tip = static_cast<uint32_t>(m.vertex_count());
        m.add_vertex(static_cast<float>(x) + 0.5f, static_cast<float>(y), 1.0f);
        m.add_triangle(a, b, tip);
      }
    }
  return m;
}

Mesh jittered(Mesh m, float amplitude, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> offset(-amplitude, amplitude);
  for (float& x : m.positions) x += offset(rng);
  return m;
}

Mesh double_sided(Mesh m) {
  for (size_t f = 0, n = m.face_count(); f < n; ++f) m.add_triangle(m.face(f)[0], m.face(f)[2], m.face(f)[1]);
  return m;
}

Mesh copies(const Mesh& src, int count) {
  Mesh m;
  for (int c = 0; c < count; ++c) {
    uint32_t base = static_cast<uint32_t>(m.vertex_count());
    for (size_t v = 0; v < src.vertex_count(); ++v)
      m.add_vertex(src.positions[3 * v] + 3.0f * static_cast<float>(c), src.positions[3 * v + 1], src.positions[3 * v + 2]);
    for (size_t f = 0; f < src.face_count(); ++f) {
      std::vector<uint32_t> corners(src.face(f), src.face(f) + src.face_size(f));
      for (auto& x : corners) x += base;
      m.add_face(corners.data(), corners.size());
    }
  }
  return m;
}

tsm::Mesh flat_shaded(const tsm::Mesh& in) {
  tsm::Mesh m;
  tsm::Attribute n;
  n.name = "normal";
  n.kind = tsm::AttributeKind::normal;
  n.components = 3;
  for (uint32_t f = 0; f < in.face_count(); ++f) {
    const uint32_t* c = in.face(f);
    const float* a = &in.positions[3 * size_t{c[0]}];
    const float* b = &in.positions[3 * size_t{c[1]}];
    const float* d = &in.positions[3 * size_t{c[2]}];
    const float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const float nn[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const float len = std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    std::vector<uint32_t> corners;
    for (uint32_t k = 0; k < in.face_size(f); ++k) {
      const float* p = &in.positions[3 * size_t{c[k]}];
      corners.push_back(static_cast<uint32_t>(m.vertex_count()));
      m.add_vertex(p[0], p[1], p[2]);
      for (float x : nn) n.values.push_back(len > 0 ? x / len : 0.0f);
    }
    m.add_face(corners.data(), corners.size());
  }
  m.attributes = {n};
  return m;
}

tsm::Mesh flat_shaded_textured_sphere(int level) {
  tsm::Mesh m = flat_shaded(icosphere(level));
  tsm::Attribute t;
  t.name = "texcoord";
  t.kind = tsm::AttributeKind::texcoord;
  t.components = 2;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float* p = &m.positions[3 * v];
    t.values.push_back(0.5f + std::atan2(p[1], p[0]) / 6.2831853f);
    t.values.push_back(0.5f + std::asin(std::max(-1.0f, std::min(1.0f, p[2]))) / 3.1415927f);
  }
  m.attributes.push_back(t);
  return m;
}

// An open cylinder with a vt list: one texture coordinate per (ring,
// column), the seam's column twice (u = 0 and u = 1), corners naming them.
Mesh indexed_uv_cylinder(int around, int rings) {
  Mesh m;
  const uint32_t n = static_cast<uint32_t>(around);
  for (int r = 0; r <= rings; ++r)
    for (uint32_t i = 0; i < n; ++i) {
      const float t = 6.2831853f * static_cast<float>(i) / static_cast<float>(n);
      m.add_vertex(std::cos(t), std::sin(t), static_cast<float>(r) / static_cast<float>(rings));
    }
  tsm::Attribute uv;
  uv.name = "texcoord";
  uv.kind = tsm::AttributeKind::texcoord;
  uv.domain = tsm::AttributeDomain::corner;
  uv.components = 2;
  for (int r = 0; r <= rings; ++r)
    for (uint32_t i = 0; i <= n; ++i) {
      uv.values.push_back(static_cast<float>(i) / static_cast<float>(n));
      uv.values.push_back(static_cast<float>(r) / static_cast<float>(rings));
    }
  auto vid = [&](int r, uint32_t i) { return static_cast<uint32_t>(r) * n + i % n; };
  auto tid = [&](int r, uint32_t i) { return static_cast<uint32_t>(r) * (n + 1) + i; };
  for (int r = 0; r < rings; ++r)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t v[4] = {vid(r, i), vid(r, i + 1), vid(r + 1, i + 1), vid(r + 1, i)};
      const uint32_t t[4] = {tid(r, i), tid(r, i + 1), tid(r + 1, i + 1), tid(r + 1, i)};
      static const int kTriangles[2][3] = {{0, 1, 2}, {0, 2, 3}};
      for (const int* tri : kTriangles) {
        const uint32_t f[3] = {v[tri[0]], v[tri[1]], v[tri[2]]};
        m.add_face(f, 3);
        for (int k = 0; k < 3; ++k) uv.indices.push_back(t[tri[k]]);
      }
    }
  m.attributes = {uv};
  return m;
}

// A flat-shaded sphere as an OBJ exporter writes it: one vertex per
// position, one normal per face in a vn list, each corner naming its face's.
Mesh indexed_flat_sphere(int level) {
  Mesh m = icosphere(level);
  tsm::Attribute n;
  n.name = "normal";
  n.kind = tsm::AttributeKind::normal;
  n.domain = tsm::AttributeDomain::corner;
  n.components = 3;
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    const float* p0 = &m.positions[3 * size_t{c[0]}];
    const float* p1 = &m.positions[3 * size_t{c[1]}];
    const float* p2 = &m.positions[3 * size_t{c[2]}];
    const float a[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const float b[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    float x[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const float len = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (float& v : x) n.values.push_back(v / len);
    for (int k = 0; k < 3; ++k) n.indices.push_back(f);
  }
  m.attributes = {n};
  return m;
}

}  // namespace tsm_test
