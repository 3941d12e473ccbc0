// tsm::simplify's guarantee checked by an independent implementation: CGAL's
// bounded-error symmetric Hausdorff distance between input and result stays
// within the bound, on generated meshes of every kind the simplifier handles.
#include <gtest/gtest.h>

#include <cmath>

#include "cgal_oracle.hpp"
#include "mesh_gen.hpp"
#include "surface_gen.hpp"
#include "tsm/simplify.hpp"

namespace {

using tsm::Mesh;

void expect_within_bound(const Mesh& in, double fraction) {
  const double diag = tsm::bounding_box(in).diagonal(), e = fraction * diag;
  tsm::SimplifyOptions o;
  o.max_error = e;
  Mesh out;
  ASSERT_TRUE(tsm::simplify(in, o, out).ok());
  EXPECT_LT(out.face_count(), in.face_count());
  const double tol = 1e-6 * diag;
  const double h = tsm_oracle::symmetric_hausdorff(in, out, tol);
  EXPECT_LE(h, e + tol) << out.face_count() << " faces";
  EXPECT_GT(h, 0.2 * e);  // the bound was used, not just respected
}

TEST(CgalSimplify, Sphere) { expect_within_bound(tsm_test::icosphere(4), 0.005); }
TEST(CgalSimplify, Torus) { expect_within_bound(tsm_test::torus(64, 32), 0.002); }
TEST(CgalSimplify, NoisyTorus) { expect_within_bound(tsm_test::jittered(tsm_test::torus(48, 24), 0.01f, 9), 0.01); }
TEST(CgalSimplify, GridWithHoles) {
  expect_within_bound(tsm_test::jittered(tsm_test::grid_with_holes(40, 4), 0.05f, 2), 0.003);
}
TEST(CgalSimplify, NonManifoldFinsAndStitches) { expect_within_bound(tsm_test::irregular_grid(30, 5), 0.01); }
TEST(CgalSimplify, UvSeamSphere) { expect_within_bound(tsm_test::uv_sphere_with_seam(48, 24), 0.01); }

}  // namespace
