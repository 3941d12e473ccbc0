// Smooth generated surfaces for the distance and simplification tests: a
// torus, a flat grid, a sphere with a UV seam, and plain transforms.
#pragma once
#include <cmath>
#include <cstdint>

#include "tsm/mesh.hpp"

namespace tsm_test {

// Torus of radii R (ring) and r (tube), n x m quads split in two.
inline tsm::Mesh torus(int n, int m, double R = 1.0, double r = 0.35) {
  tsm::Mesh out;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / m;
      out.add_vertex(static_cast<float>((R + r * std::cos(v)) * std::cos(u)),
                     static_cast<float>((R + r * std::cos(v)) * std::sin(u)), static_cast<float>(r * std::sin(v)));
    }
  auto id = [&](int i, int j) { return static_cast<uint32_t>(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      out.add_triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      out.add_triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return out;
}

// n x n vertices on [0, 1]^2 at height z, triangulated.
inline tsm::Mesh flat_grid(int n, float z = 0) {
  tsm::Mesh out;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      out.add_vertex(static_cast<float>(x) / static_cast<float>(n - 1),
                     static_cast<float>(y) / static_cast<float>(n - 1), z);
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      const uint32_t a = static_cast<uint32_t>(y * n + x), b = a + 1, c = a + static_cast<uint32_t>(n), d = c + 1;
      out.add_triangle(a, b, d);
      out.add_triangle(a, d, c);
    }
  return out;
}

// A latitude-longitude sphere (radius 1) with a per-corner texcoord
// attribute whose u jumps from 1 to 0 along the meridian at longitude 0:
// the seam. Shared vertices there, two texcoord values each.
inline tsm::Mesh uv_sphere_with_seam(int slices, int stacks) {
  tsm::Mesh out;
  tsm::Attribute uv;
  uv.name = "texcoord";
  uv.kind = tsm::AttributeKind::texcoord;
  uv.domain = tsm::AttributeDomain::corner;
  uv.components = 2;
  // Vertex (i, j): i = 0..stacks (poles at 0 and stacks, one vertex each), j = 0..slices-1.
  auto vid = [&](int i, int j) -> uint32_t {
    if (i == 0) return 0;
    if (i == stacks) return static_cast<uint32_t>(1 + (stacks - 1) * slices);
    return static_cast<uint32_t>(1 + (i - 1) * slices + (j % slices));
  };
  for (int i = 0; i <= stacks; ++i) {
    const int count = (i == 0 || i == stacks) ? 1 : slices;
    for (int j = 0; j < count; ++j) {
      const double th = M_PI * i / stacks, ph = 2 * M_PI * j / slices;
      out.add_vertex(static_cast<float>(std::sin(th) * std::cos(ph)), static_cast<float>(std::sin(th) * std::sin(ph)),
                     static_cast<float>(std::cos(th)));
    }
  }
  auto corner = [&](int i, int j) {
    uv.values.push_back(static_cast<float>(j) / static_cast<float>(slices));  // j == slices: u = 1 on the seam
    uv.values.push_back(static_cast<float>(i) / static_cast<float>(stacks));
    uv.indices.push_back(static_cast<uint32_t>(uv.values.size() / 2 - 1));
  };
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      if (i > 0) {
        out.add_triangle(vid(i, j), vid(i + 1, j), vid(i, j + 1));
        corner(i, j), corner(i + 1, j), corner(i, j + 1);
      }
      if (i + 1 < stacks) {
        out.add_triangle(vid(i, j + 1), vid(i + 1, j), vid(i + 1, j + 1));
        corner(i, j + 1), corner(i + 1, j), corner(i + 1, j + 1);
      }
    }
  out.attributes.push_back(uv);
  return out;
}

inline tsm::Mesh scaled(tsm::Mesh m, float s) {
  for (float& v : m.positions) v *= s;
  return m;
}

inline tsm::Mesh shifted(tsm::Mesh m, float dx, float dy, float dz) {
  for (size_t i = 0; i < m.vertex_count(); ++i) {
    m.positions[3 * i] += dx;
    m.positions[3 * i + 1] += dy;
    m.positions[3 * i + 2] += dz;
  }
  return m;
}

}  // namespace tsm_test
