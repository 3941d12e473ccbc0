// The test oracle itself (tsm::compare_meshes, tsm::Grid): it must accept
// exactly what the codec may change (vertex order, face order, corner
// rotation, quantization) and reject everything else.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "mesh_gen.hpp"
#include "test_util.hpp"
#include "tsm/tsm.hpp"

namespace {

using tsm::compare_meshes;
using tsm::Grid;
using tsm::Mesh;

using tsm_test::permute_vertices;
using tsm_test::random_permutation;

// Rebuilds the mesh with faces in the order `order` (old face ids), each face's
// corners rotated left by `rotate(f)`, and reversed when f == flip.
template <typename Rot>
Mesh rebuild_faces(const Mesh& m, const std::vector<size_t>& order, Rot rotate, size_t flip = SIZE_MAX) {
  Mesh out;
  out.positions = m.positions;
  std::vector<uint32_t> c;
  for (size_t f : order) {
    uint32_t n = m.face_size(f);
    c.assign(m.face(f), m.face(f) + n);
    if (f == flip) std::reverse(c.begin(), c.end());
    std::rotate(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(rotate(f) % n), c.end());
    out.add_face(c.data(), c.size());
  }
  return out;
}

std::vector<size_t> identity_order(const Mesh& m) {
  std::vector<size_t> o(m.face_count());
  std::iota(o.begin(), o.end(), size_t{0});
  return o;
}

// A small mesh whose vertices sit exactly on the 8-bit grid (coordinates are
// multiples of 1/255 of the extent), plus an unreferenced vertex.
Mesh grid_aligned_mesh() {
  Mesh m;
  // Extent 255 along x: step 1 at bits = 8.
  m.add_vertex(0, 0, 0);
  m.add_vertex(255, 0, 0);
  m.add_vertex(0, 100, 0);
  m.add_vertex(100, 50, 20);  // interior: moving it keeps the bounding box
  m.add_vertex(40, 60, 80);
  m.add_vertex(10, 10, 10);   // unreferenced
  m.add_triangle(0, 1, 3);
  m.add_triangle(1, 2, 3);
  m.add_triangle(2, 0, 3);
  m.add_triangle(0, 2, 4);
  return m;
}

TEST(Compare, IdenticalMeshesAreEqual) {
  Mesh m = tsm_test::icosphere(2);
  for (int bits : {0, 1, 8, 14, 30}) {
    auto r = compare_meshes(m, m, bits);
    EXPECT_TRUE(r.equal) << "bits " << bits << ": " << r.difference;
    EXPECT_EQ(r.max_position_error, 0.0);
  }
}

TEST(Compare, EqualUnderVertexPermutation) {
  Mesh m = tsm_test::icosphere(2);
  Mesh p = permute_vertices(m, random_permutation(m.vertex_count(), 7));
  ASSERT_NE(p.indices, m.indices);
  for (int bits : {0, 14}) {
    auto r = compare_meshes(m, p, bits);
    EXPECT_TRUE(r.equal) << r.difference;
  }
  // Also with several families, including polygons and unreferenced vertices.
  for (const Mesh& g : {tsm_test::random_soup(60, 90, 3), tsm_test::cube_quads(), tsm_test::bowtie(),
                        tsm_test::book(4)}) {
    Mesh q = permute_vertices(g, random_permutation(g.vertex_count(), 11));
    auto r = compare_meshes(g, q, 0);
    EXPECT_TRUE(r.equal) << r.difference;
  }
}

TEST(Compare, EqualUnderFacePermutationAndCornerRotation) {
  Mesh m = tsm_test::copies(tsm_test::cube_quads(), 2);
  std::vector<size_t> order = identity_order(m);
  std::mt19937 rng(5);
  std::shuffle(order.begin(), order.end(), rng);
  Mesh shuffled = rebuild_faces(m, order, [](size_t) { return 0u; });
  ASSERT_NE(shuffled.indices, m.indices);
  EXPECT_TRUE(compare_meshes(m, shuffled, 0).equal) << compare_meshes(m, shuffled, 0).difference;

  Mesh rotated = rebuild_faces(m, identity_order(m), [](size_t f) { return static_cast<uint32_t>(f + 1); });
  ASSERT_NE(rotated.indices, m.indices);
  EXPECT_TRUE(compare_meshes(m, rotated, 0).equal) << compare_meshes(m, rotated, 0).difference;

  // All three at once, on a triangle mesh.
  Mesh s = tsm_test::icosphere(1);
  std::vector<size_t> o2 = identity_order(s);
  std::shuffle(o2.begin(), o2.end(), rng);
  Mesh all = permute_vertices(rebuild_faces(s, o2, [](size_t f) { return static_cast<uint32_t>(f * 7); }),
                              random_permutation(s.vertex_count(), 99));
  auto r = compare_meshes(s, all, 12);
  EXPECT_TRUE(r.equal) << r.difference;
}

TEST(Compare, FlippedFaceIsNotEqual) {
  Mesh m = tsm_test::icosphere(1);
  Mesh flipped = rebuild_faces(m, identity_order(m), [](size_t) { return 0u; }, 17);
  for (int bits : {0, 8}) {
    auto r = compare_meshes(m, flipped, bits);
    EXPECT_FALSE(r.equal) << "bits " << bits;
    EXPECT_FALSE(r.difference.empty());
  }
  // A quad reversed (a rotation of it would still be equal).
  Mesh c = tsm_test::cube_quads();
  EXPECT_FALSE(compare_meshes(c, rebuild_faces(c, identity_order(c), [](size_t) { return 1u; }, 2), 0).equal);
  EXPECT_TRUE(compare_meshes(c, rebuild_faces(c, identity_order(c), [](size_t) { return 1u; }), 0).equal);
}

TEST(Compare, PositionChangeBeyondHalfStepIsNotEqual) {
  Mesh m = grid_aligned_mesh();
  Grid g = Grid::for_mesh(m, 8);
  ASSERT_DOUBLE_EQ(g.step, 1.0);
  // Within half a step of its grid point: equal, and the error is reported.
  Mesh near = m;
  near.positions[3 * 3 + 0] += 0.25f;
  auto r = compare_meshes(m, near, 8);
  EXPECT_TRUE(r.equal) << r.difference;
  EXPECT_NEAR(r.max_position_error, 0.25, 1e-9);
  // Beyond half a step: a different grid point.
  Mesh far = m;
  far.positions[3 * 3 + 1] += 0.75f;
  r = compare_meshes(m, far, 8);
  EXPECT_FALSE(r.equal);
  EXPECT_NE(r.difference.find("position"), std::string::npos) << r.difference;
  // The unreferenced vertex is compared too.
  Mesh lone = m;
  lone.positions[3 * 5 + 2] -= 1.0f;
  EXPECT_FALSE(compare_meshes(m, lone, 8).equal);
  // bits = 0: any change at all.
  Mesh ulp = m;
  ulp.positions[3 * 4 + 0] = std::nextafter(ulp.positions[3 * 4 + 0], 1e9f);
  EXPECT_FALSE(compare_meshes(m, ulp, 0).equal);
  EXPECT_TRUE(compare_meshes(m, ulp, 8).equal);
}

TEST(Compare, SwappedPositionsOfTwoVerticesIsNotEqual) {
  // Same position multiset, same face index lists: the faces now connect
  // different points.
  Mesh m = grid_aligned_mesh();
  Mesh s = m;
  for (size_t a = 0; a < 3; ++a) std::swap(s.positions[3 * 3 + a], s.positions[3 * 4 + a]);
  EXPECT_FALSE(compare_meshes(m, s, 8).equal);
  EXPECT_FALSE(compare_meshes(m, s, 0).equal);
}

TEST(Compare, MissingExtraOrDuplicatedFaceIsNotEqual) {
  Mesh m = grid_aligned_mesh();
  std::vector<size_t> order = identity_order(m);

  std::vector<size_t> missing(order.begin(), order.end() - 1);
  auto r = compare_meshes(m, rebuild_faces(m, missing, [](size_t) { return 0u; }), 8);
  EXPECT_FALSE(r.equal);
  EXPECT_NE(r.difference.find("face count"), std::string::npos) << r.difference;

  std::vector<size_t> extra = order;
  extra.push_back(1);
  EXPECT_FALSE(compare_meshes(m, rebuild_faces(m, extra, [](size_t) { return 0u; }), 8).equal);

  // Same counts: the last face replaced by a second copy of face 0.
  std::vector<size_t> dup = order;
  dup.back() = 0;
  Mesh d = rebuild_faces(m, dup, [](size_t) { return 0u; });
  ASSERT_EQ(d.face_count(), m.face_count());
  ASSERT_EQ(d.corner_count(), m.corner_count());
  EXPECT_FALSE(compare_meshes(m, d, 8).equal);
  EXPECT_FALSE(compare_meshes(m, d, 0).equal);
  EXPECT_FALSE(compare_meshes(d, m, 0).equal);

  // Multiplicity matters: {A, A, B} vs {A, B, B}.
  Mesh x = m;
  x.face_offsets = {0};
  x.indices.clear();
  x.add_triangle(0, 1, 3);
  x.add_triangle(0, 1, 3);
  x.add_triangle(1, 2, 3);
  Mesh y = x;
  y.face_offsets = {0};
  y.indices.clear();
  y.add_triangle(0, 1, 3);
  y.add_triangle(1, 2, 3);
  y.add_triangle(2, 3, 1);
  EXPECT_FALSE(compare_meshes(x, y, 8).equal);
}

TEST(Compare, MissingUnreferencedVertexIsNotEqual) {
  Mesh m = grid_aligned_mesh();
  Mesh less = m;
  less.positions.resize(less.positions.size() - 3);  // vertex 5 is unreferenced
  ASSERT_TRUE(less.valid());
  auto r = compare_meshes(m, less, 8);
  EXPECT_FALSE(r.equal);
  EXPECT_NE(r.difference.find("vertex count"), std::string::npos) << r.difference;
  EXPECT_FALSE(compare_meshes(less, m, 8).equal);
}

TEST(Compare, CoincidentVerticesWithDifferentNeighbourhoods) {
  // Two triangles sharing vertex 0 at the origin; vertex 5, also at the
  // origin, unreferenced.
  Mesh shared;
  shared.add_vertex(0, 0, 0);
  shared.add_vertex(1, 0, 0);
  shared.add_vertex(0, 1, 0);
  shared.add_vertex(-1, 0, 0);
  shared.add_vertex(0, -1, 0);
  shared.add_vertex(0, 0, 0);
  shared.add_triangle(0, 1, 2);
  shared.add_triangle(0, 3, 4);
  // The same triangles with that vertex split in two coincident vertices.
  Mesh split = shared;
  split.indices = {0, 1, 2, 5, 3, 4};
  ASSERT_EQ(split.vertex_count(), shared.vertex_count());
  ASSERT_EQ(split.face_count(), shared.face_count());
  for (int bits : {0, 8, 14}) {
    auto r = compare_meshes(shared, split, bits);
    EXPECT_FALSE(r.equal) << "bits " << bits;
    EXPECT_FALSE(compare_meshes(split, shared, bits).equal) << "bits " << bits;
  }
  // Swapping which coincident copy is used is a vertex permutation: equal.
  Mesh split2 = shared;
  split2.indices = {5, 1, 2, 0, 3, 4};
  EXPECT_TRUE(compare_meshes(split, split2, 0).equal) << compare_meshes(split, split2, 0).difference;
  Mesh shared2 = shared;
  shared2.indices = {5, 1, 2, 5, 3, 4};
  EXPECT_TRUE(compare_meshes(shared, shared2, 8).equal) << compare_meshes(shared, shared2, 8).difference;
}

TEST(Compare, CoincidentVerticesOnAWiderMesh) {
  // Two copies of a fan stacked on the same positions; the decoded mesh
  // swaps the apexes of the two copies for one face only.
  Mesh one = tsm_test::fan(6, false);
  Mesh two = one;
  const uint32_t n = static_cast<uint32_t>(one.vertex_count());
  two.positions.insert(two.positions.end(), one.positions.begin(), one.positions.end());
  for (size_t f = 0; f < one.face_count(); ++f) {
    const uint32_t* c = one.face(f);
    two.add_triangle(c[0] + n, c[1] + n, c[2] + n);
  }
  // Stacked copies with vertices permuted: equal.
  Mesh perm = permute_vertices(two, random_permutation(two.vertex_count(), 21));
  EXPECT_TRUE(compare_meshes(two, perm, 10).equal) << compare_meshes(two, perm, 10).difference;
  // Cross-wire one face: it uses the other copy's vertex for one corner.
  Mesh wired = two;
  wired.indices[0] = wired.indices[0] < n ? wired.indices[0] + n : wired.indices[0] - n;
  EXPECT_FALSE(compare_meshes(two, wired, 10).equal);
  EXPECT_FALSE(compare_meshes(two, wired, 0).equal);
}

TEST(Compare, InvalidMeshesAreNotEqual) {
  Mesh m = grid_aligned_mesh();
  Mesh bad = m;
  bad.indices[0] = 99;
  auto r = compare_meshes(m, bad, 8);
  EXPECT_FALSE(r.equal);
  EXPECT_NE(r.difference.find("invalid"), std::string::npos) << r.difference;
  EXPECT_FALSE(compare_meshes(bad, m, 8).equal);
}

TEST(Compare, EmptyAndSinglePointMeshes) {
  Mesh empty;
  EXPECT_TRUE(compare_meshes(empty, empty, 8).equal);
  Mesh point;
  point.add_vertex(1, 2, 3);
  EXPECT_FALSE(compare_meshes(empty, point, 8).equal);
  EXPECT_TRUE(compare_meshes(point, point, 8).equal);
  Grid g = Grid::for_mesh(point, 8);
  EXPECT_EQ(g.step, 0.0);
  EXPECT_EQ(g.quantize(1.0, 0), 0);
  EXPECT_EQ(g.quantize(5.0, 2), 0);
}

TEST(Compare, GridQuantizationMath) {
  Mesh m;
  m.add_vertex(-1.0f, 2.0f, 10.0f);
  m.add_vertex(2.0f, 2.5f, 10.75f);  // extents 3, 0.5, 0.75: largest 3
  Grid g2 = Grid::for_mesh(m, 2);   // 2^2 - 1 = 3 cells
  EXPECT_EQ(g2.bits, 2);
  EXPECT_EQ(g2.origin[0], -1.0);
  EXPECT_EQ(g2.origin[1], 2.0);
  EXPECT_EQ(g2.origin[2], 10.0);
  EXPECT_EQ(g2.step, 1.0);
  EXPECT_EQ(g2.quantize(-1.0, 0), 0);
  EXPECT_EQ(g2.quantize(2.0, 0), 3);
  EXPECT_EQ(g2.quantize(0.0, 0), 1);
  // Round half up, at the exact half point, on every axis.
  EXPECT_EQ(g2.quantize(0.5, 0), 2);              // (0.5 + 1) / 1 = 1.5 -> 2
  EXPECT_EQ(g2.quantize(0.49, 0), 1);
  EXPECT_EQ(g2.quantize(-0.5, 0), 1);             // 0.5 -> 1
  EXPECT_EQ(g2.quantize(-1.5, 0), 0);             // -0.5 -> floor(0) = 0, not -1
  EXPECT_EQ(g2.quantize(-1.6, 0), -1);            // below the box: negative index
  EXPECT_EQ(g2.quantize(2.5, 1), 1);              // (2.5 - 2) / 1 = 0.5 -> 1
  EXPECT_EQ(g2.quantize(10.5, 2), 1);
  EXPECT_EQ(g2.quantize(10.49, 2), 0);
  EXPECT_EQ(g2.dequantize(2, 0), 1.0);
  EXPECT_EQ(g2.dequantize(3, 2), 13.0);

  Grid g4 = Grid::for_mesh(m, 4);  // 15 cells: step 0.2
  EXPECT_DOUBLE_EQ(g4.step, 3.0 / 15.0);
  EXPECT_EQ(g4.quantize(2.0, 0), 15);
  EXPECT_EQ(g4.quantize(-1.0 + 0.29, 0), 1);
  EXPECT_EQ(g4.quantize(-1.0 + 0.31, 0), 2);
  EXPECT_EQ(g4.quantize(2.45, 1), 2);   // 0.45 / 0.2 = 2.25 -> 2
  EXPECT_EQ(g4.quantize(2.55, 1), 3);   // 2.75 -> 3
  EXPECT_DOUBLE_EQ(g4.dequantize(5, 1), 3.0);

  // A step that is a power of two: the half point is exact at any index.
  Mesh q;
  q.add_vertex(0.0f, 0.0f, 0.0f);
  q.add_vertex(3.75f, 1.0f, 1.0f);
  Grid g4b = Grid::for_mesh(q, 4);  // 3.75 / 15 = 0.25
  EXPECT_EQ(g4b.step, 0.25);
  EXPECT_EQ(g4b.quantize(1.125, 0), 5);              // 4.5 -> 5
  EXPECT_EQ(g4b.quantize(std::nextafter(1.125, 0.0), 0), 4);
  EXPECT_EQ(g4b.quantize(1.375, 1), 6);              // 5.5 -> 6
  EXPECT_EQ(g4b.dequantize(6, 1), 1.5);

  Grid g14 = Grid::for_mesh(m, 14);
  EXPECT_DOUBLE_EQ(g14.step, 3.0 / 16383.0);
  EXPECT_EQ(g14.quantize(2.0, 0), 16383);
  EXPECT_EQ(g14.quantize(-1.0, 0), 0);

  Grid g30 = Grid::for_mesh(m, 30);
  EXPECT_DOUBLE_EQ(g30.step, 3.0 / 1073741823.0);
  EXPECT_EQ(g30.quantize(2.0, 0), 1073741823);

  Grid g0 = Grid::for_mesh(m, 0);
  EXPECT_EQ(g0.bits, 0);
  EXPECT_EQ(g0.step, 0.0);

  // Non-finite input gets an index no finite value maps to.
  EXPECT_EQ(g14.quantize(std::nan(""), 0), std::numeric_limits<int64_t>::min());
}

TEST(Compare, ZeroBitsComparesRawFloatBits) {
  Mesh a;
  a.add_vertex(0.0f, 1.0f, 2.0f);
  a.add_vertex(1.0f, 0.0f, 0.0f);
  a.add_vertex(0.0f, 0.0f, 1.0f);
  a.add_triangle(0, 1, 2);
  Mesh b = a;
  b.positions[0] = -0.0f;
  ASSERT_EQ(a.positions[0], b.positions[0]);  // equal as numbers
  auto r = compare_meshes(a, b, 0);
  EXPECT_FALSE(r.equal);
  EXPECT_NE(r.difference.find("float bits"), std::string::npos) << r.difference;
  EXPECT_TRUE(compare_meshes(a, b, 8).equal);
  EXPECT_TRUE(compare_meshes(a, a, 0).equal);
}

TEST(Compare, QuantizedRoundTripErrorAtMostHalfStep) {
  Mesh m = tsm_test::random_soup(200, 300, 42);
  for (int bits : {4, 8, 12}) {
    Grid g = Grid::for_mesh(m, bits);
    ASSERT_GT(g.step, 0);
    // Snap every coordinate to its grid point (in double, kept as float):
    // what a quantizing codec does.
    Mesh snapped = m;
    for (size_t i = 0; i < snapped.positions.size(); ++i) {
      int a = static_cast<int>(i % 3);
      snapped.positions[i] = static_cast<float>(g.dequantize(g.quantize(m.positions[i], a), a));
    }
    auto r = compare_meshes(m, snapped, bits);
    EXPECT_TRUE(r.equal) << "bits " << bits << ": " << r.difference;
    // Half a step, plus the rounding of the snapped value to float (half an
    // ulp of coordinates in [-1, 1]).
    const double float_rounding = 0.5 * static_cast<double>(std::nextafter(1.0f, 2.0f) - 1.0f) / g.step;
    EXPECT_LE(r.max_position_error, 0.5 + float_rounding + 1e-12) << "bits " << bits;
    EXPECT_GT(r.max_position_error, 0.3) << "bits " << bits << ": random points should need real snapping";
  }
  // And through the codec.
  std::string bytes;
  ASSERT_TRUE(tsm::encode(m, tsm::EncodeOptions{8, 6}, bytes).ok());
  Mesh back;
  ASSERT_TRUE(tsm::decode(bytes, back).ok());
  auto r = compare_meshes(m, back, 8);
  EXPECT_TRUE(r.equal) << r.difference;
  const double step = Grid::for_mesh(m, 8).step;
  EXPECT_LE(r.max_position_error, 0.5 + 0.5 * static_cast<double>(std::nextafter(1.0f, 2.0f) - 1.0f) / step + 1e-12);
}

}  // namespace
