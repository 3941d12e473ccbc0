// tsm::measure_distance against an independent implementation: CGAL's
// bounded-error symmetric Hausdorff distance, on generated meshes.
#include <gtest/gtest.h>

#include <cmath>

#include "cgal_oracle.hpp"
#include "mesh_gen.hpp"
#include "surface_gen.hpp"
#include "tsm/distance.hpp"

namespace {

using tsm::Mesh;

void expect_agrees_with_cgal(const Mesh& a, const Mesh& b) {
  tsm::DistanceOptions o;
  o.target_samples = 300000;
  tsm::DistanceReport r;
  ASSERT_TRUE(tsm::measure_distance(a, b, o, r).ok());
  const double tol = 1e-5 * r.diagonal;
  const double cgal = tsm_oracle::symmetric_hausdorff(a, b, tol);
  // CGAL's value is within tol of the truth; ours brackets the truth.
  EXPECT_LE(r.hausdorff, cgal + tol);
  EXPECT_GE(r.hausdorff_bound, cgal - tol);
  EXPECT_NEAR(r.hausdorff, cgal, 0.02 * cgal + tol);
}

TEST(CgalDistance, TorusAgainstCoarserJitteredTorus) {
  expect_agrees_with_cgal(tsm_test::torus(48, 24), tsm_test::jittered(tsm_test::torus(20, 10), 0.01f, 3));
}

TEST(CgalDistance, SphereAgainstShiftedSphere) {
  expect_agrees_with_cgal(tsm_test::icosphere(3), tsm_test::shifted(tsm_test::icosphere(2), 0.05f, -0.02f, 0.01f));
}

TEST(CgalDistance, GridWithHolesAgainstShiftedGrid) {
  const Mesh a = tsm_test::grid_with_holes(30, 4);
  expect_agrees_with_cgal(a, tsm_test::shifted(tsm_test::flat_grid(10), 0.1f, 0.1f, 0.2f));
}

}  // namespace
