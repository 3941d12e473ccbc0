// tsm::simplify (tsm/simplify.hpp): the guaranteed bound checked by the
// independent sampled distance (tsm::measure_distance), and the topology,
// seams, attributes and components it promises to keep.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <set>

#include "mesh_gen.hpp"
#include "surface_gen.hpp"
#include "triangle_bvh.hpp"
#include "tsm/distance.hpp"
#include "tsm/simplify.hpp"

namespace {

using tsm::Mesh;

struct EdgeStats {
  size_t boundary = 0, non_manifold = 0, edges = 0, loops = 0;
};

EdgeStats edge_stats(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> count;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      const uint32_t a = m.face(f)[k], b = m.face(f)[(k + 1) % m.face_size(f)];
      ++count[std::minmax(a, b)];
    }
  EdgeStats s;
  std::vector<uint32_t> parent(m.vertex_count());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::set<uint32_t> on_boundary;
  for (const auto& [e, c] : count) {
    ++s.edges;
    if (c == 1) {
      ++s.boundary;
      parent[find(e.first)] = find(e.second);
      on_boundary.insert(e.first);
      on_boundary.insert(e.second);
    }
    if (c > 2) ++s.non_manifold;
  }
  std::set<uint32_t> roots;
  for (uint32_t v : on_boundary) roots.insert(find(v));
  s.loops = roots.size();
  return s;
}

size_t components(const Mesh& m) {
  std::vector<uint32_t> parent(m.vertex_count());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::set<uint32_t> used;
  for (size_t f = 0; f < m.face_count(); ++f)
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      parent[find(m.face(f)[k])] = find(m.face(f)[0]);
      used.insert(m.face(f)[k]);
    }
  std::set<uint32_t> roots;
  for (uint32_t v : used) roots.insert(find(v));
  return roots.size();
}

long euler(const Mesh& m) {
  std::set<uint32_t> used;
  for (uint32_t i : m.indices) used.insert(i);
  return static_cast<long>(used.size()) - static_cast<long>(edge_stats(m).edges) + static_cast<long>(m.face_count());
}

bool has_degenerate(const Mesh& m) {
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    auto p = [&](int k) {
      return std::array<double, 3>{m.positions[3 * c[k]], m.positions[3 * c[k] + 1], m.positions[3 * c[k] + 2]};
    };
    const auto a = p(0), b = p(1), d = p(2);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || n[0] * n[0] + n[1] * n[1] + n[2] * n[2] == 0) return true;
  }
  return false;
}

// Simplifies within `fraction` of the diagonal; checks the result against
// the input with the sampled distance (a sampled distance above the limit
// would be a proof that the bound failed).
Mesh simplify_checked(const Mesh& in, double fraction, double max_kept = 1.0) {
  const double e = fraction * tsm::bounding_box(in).diagonal();
  tsm::SimplifyOptions o;
  o.max_error = e;
  Mesh out;
  tsm::SimplifyReport r;
  EXPECT_TRUE(tsm::simplify(in, o, out, &r).ok());
  EXPECT_TRUE(out.valid());
  EXPECT_LT(static_cast<double>(out.face_count()), max_kept * static_cast<double>(in.face_count()));
  EXPECT_EQ(r.faces_out, out.face_count());
  EXPECT_FALSE(has_degenerate(out));
  tsm::DistanceOptions d;
  d.target_samples = 150000;
  tsm::DistanceReport dr;
  EXPECT_TRUE(tsm::measure_distance(in, out, d, dr).ok());
  EXPECT_LE(dr.hausdorff, e * (1 + 1e-9)) << "faces " << out.face_count();
  EXPECT_GT(dr.hausdorff, 0.0);
  return out;
}

TEST(Simplify, SphereStaysClosedAndWithinTheBound) {
  const Mesh in = tsm_test::icosphere(4);
  const Mesh out = simplify_checked(in, 0.01, 0.5);
  const EdgeStats s = edge_stats(out);
  EXPECT_EQ(s.boundary, 0u);
  EXPECT_EQ(s.non_manifold, 0u);
  EXPECT_EQ(euler(out), 2);
}

TEST(Simplify, TorusKeepsItsGenus) {
  const Mesh in = tsm_test::torus(64, 32);
  const Mesh out = simplify_checked(in, 0.005, 0.5);
  EXPECT_EQ(euler(out), 0);
  EXPECT_EQ(edge_stats(out).boundary, 0u);
}

// A flat grid with holes: the boundary loops stay (none closes), the flat
// parts reduce a lot.
TEST(Simplify, GridWithHolesKeepsItsHoles) {
  const Mesh in = tsm_test::grid_with_holes(24, 4);
  const Mesh out = simplify_checked(in, 0.002, 0.6);
  EXPECT_EQ(edge_stats(out).loops, edge_stats(in).loops);
  EXPECT_EQ(euler(out), euler(in));
}

// Fins and stitches (edges of three or more triangles): those edges stay.
TEST(Simplify, NonManifoldEdgesAreKept) {
  const Mesh in = tsm_test::irregular_grid(30, 5);
  ASSERT_GT(edge_stats(in).non_manifold, 0u);
  const Mesh out = simplify_checked(in, 0.01, 0.9);
  EXPECT_EQ(edge_stats(out).non_manifold, edge_stats(in).non_manifold);
  const Mesh bow = tsm_test::bowtie();
  tsm::SimplifyOptions o;
  o.max_error = 10;
  Mesh b;
  ASSERT_TRUE(tsm::simplify(bow, o, b).ok());
  EXPECT_EQ(components(b), 1u);
  EXPECT_GE(b.face_count(), 2u);
}

// A UV seam: the vertices with two texture coordinates keep them (they
// never move or go), the bound holds, the attribute stays per corner.
TEST(Simplify, UvSeamIsRespected) {
  const Mesh in = tsm_test::uv_sphere_with_seam(48, 24);
  auto seam_positions = [](const Mesh& m) {
    std::map<uint32_t, std::set<std::pair<float, float>>> uv;
    const tsm::Attribute& a = m.attributes[0];
    for (size_t c = 0; c < m.indices.size(); ++c)
      uv[m.indices[c]].insert({a.values[2 * a.indices[c]], a.values[2 * a.indices[c] + 1]});
    std::set<std::array<float, 3>> out;
    for (const auto& [v, s] : uv)
      if (s.size() > 1) out.insert({m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]});
    return out;
  };
  const Mesh out = simplify_checked(in, 0.01, 0.5);
  ASSERT_EQ(out.attributes.size(), 1u);
  EXPECT_EQ(out.attributes[0].domain, tsm::AttributeDomain::corner);
  EXPECT_EQ(out.attributes[0].indices.size(), out.indices.size());
  const auto before = seam_positions(in), after = seam_positions(out);
  EXPECT_EQ(before, after);
  // Texture coordinates stay in the unit square (interpolated, not invented).
  for (float v : out.attributes[0].values) EXPECT_TRUE(v >= 0 && v <= 1);
}

// Vertex attributes are interpolated: normals stay unit length, one per vertex.
TEST(Simplify, VertexNormalsAreInterpolated) {
  Mesh in = tsm_test::icosphere(4);
  tsm::Attribute n;
  n.name = "normal";
  n.kind = tsm::AttributeKind::normal;
  n.components = 3;
  n.values = in.positions;
  in.attributes.push_back(n);
  const Mesh out = simplify_checked(in, 0.01, 0.5);
  ASSERT_EQ(out.attributes.size(), 1u);
  ASSERT_EQ(out.attributes[0].values.size(), out.positions.size());
  for (size_t v = 0; v < out.vertex_count(); ++v) {
    const float* p = &out.attributes[0].values[3 * v];
    EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 1e-5);
  }
}

// Components never vanish, even with a bound larger than the mesh.
TEST(Simplify, ComponentsAreNeverDropped) {
  const Mesh in = tsm_test::copies(tsm_test::icosphere(2), 3);
  tsm::SimplifyOptions o;
  o.max_error = 100;
  Mesh out;
  ASSERT_TRUE(tsm::simplify(in, o, out).ok());
  EXPECT_EQ(components(out), 3u);
  EXPECT_EQ(edge_stats(out).boundary, 0u);
  EXPECT_FALSE(has_degenerate(out));
}

TEST(Simplify, FaceTargetWithoutBound) {
  const Mesh in = tsm_test::torus(40, 20);
  tsm::SimplifyOptions o;
  o.target_faces = 400;
  Mesh out;
  ASSERT_TRUE(tsm::simplify(in, o, out).ok());
  EXPECT_LE(out.face_count(), 400u);
  EXPECT_GE(out.face_count(), 398u);
  EXPECT_EQ(euler(out), 0);
}

// Polygons are split as fans; their face attributes follow each triangle.
TEST(Simplify, PolygonsAndFaceAttributes) {
  Mesh in = tsm_test::cube_quads();
  tsm::Attribute c;
  c.name = "color";
  c.kind = tsm::AttributeKind::color;
  c.domain = tsm::AttributeDomain::face;
  c.components = 3;
  for (size_t f = 0; f < in.face_count(); ++f) c.values.insert(c.values.end(), {float(f), 0, 1});
  in.attributes.push_back(c);
  tsm::SimplifyOptions o;
  o.max_error = 1e-6;
  Mesh out;
  ASSERT_TRUE(tsm::simplify(in, o, out).ok());
  EXPECT_EQ(out.face_count(), 12u);
  ASSERT_EQ(out.attributes[0].values.size(), 36u);
}

// The largest distance from points sampled on triangle t of m (a
// barycentric grid, n steps a side) to the input, through a BVH over it.
double sampled_face_distance(const Mesh& m, size_t t, const tsm::geom::TriangleBvh& input, int n) {
  const uint32_t* c = m.face(t);
  auto p = [&](int k) {
    return tsm::geom::Vec3{m.positions[3 * c[k]], m.positions[3 * c[k] + 1], m.positions[3 * c[k] + 2]};
  };
  const tsm::geom::Vec3 a = p(0), b = p(1), d = p(2);
  double worst2 = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const tsm::geom::Vec3 x = a + (b - a) * (double(i) / n) + (d - a) * (double(j) / n);
      double d2;
      input.nearest(x, d2);
      worst2 = std::max(worst2, d2);
    }
  return std::sqrt(worst2);
}

// Every result triangle carries a bound of its distance to the input
// (SimplifyReport::face_error), proven through the triangles it replaced
// (their distance plus their own bound) or through the input itself; after
// hundreds of collapses on top of each other, each triangle's bound must
// still be at least the distance sampled on that triangle (its corners
// included: a vertex written elsewhere than where its bound was proven
// fails here) and within the limit.
TEST(Simplify, ChainedBoundsDominateTheSampledDistance) {
  for (const Mesh& in : {tsm_test::jittered(tsm_test::icosphere(3), 0.002f, 3), tsm_test::torus(32, 16),
                         tsm_test::irregular_grid(30, 7), tsm_test::jittered(tsm_test::icosphere(3), 0.02f, 5)}) {
    const tsm::geom::TriangleSet input = tsm::geom::triangles_of(in);
    const tsm::geom::TriangleBvh bvh(input);
    for (double fraction : {0.003, 0.02}) {
      const double e = fraction * tsm::bounding_box(in).diagonal();
      tsm::SimplifyOptions o;
      o.max_error = e;
      Mesh out;
      tsm::SimplifyReport r;
      ASSERT_TRUE(tsm::simplify(in, o, out, &r).ok());
      EXPECT_GT(r.collapses, 150u);
      ASSERT_EQ(r.face_error.size(), out.face_count());
      size_t broken = 0, chained = 0;
      double largest = 0;
      for (size_t t = 0; t < out.face_count(); ++t) {
        const double sampled = sampled_face_distance(out, t, bvh, 6);
        if (sampled > r.face_error[t] * (1 + 1e-9) + 1e-12) ++broken;
        chained += r.face_error[t] > 0;
        largest = std::max(largest, r.face_error[t]);
      }
      EXPECT_EQ(broken, 0u) << fraction << " faces " << out.face_count();
      EXPECT_GT(chained, out.face_count() / 2);
      EXPECT_EQ(largest, r.result_error);
      EXPECT_LE(r.result_error, e);
      tsm::DistanceOptions d;
      d.target_samples = 30000;
      tsm::DistanceReport dr;
      ASSERT_TRUE(tsm::measure_distance(in, out, d, dr).ok());
      EXPECT_LE(dr.a_to_b.max, e * (1 + 1e-9));
    }
  }
}

TEST(Simplify, RefusesBadOptions) {
  Mesh out;
  EXPECT_FALSE(tsm::simplify(tsm_test::icosphere(1), {}, out).ok());
  tsm::SimplifyOptions o;
  o.max_error = -1;
  EXPECT_FALSE(tsm::simplify(tsm_test::icosphere(1), o, out).ok());
}

}  // namespace
