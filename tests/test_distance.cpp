// tsm::measure_distance (tsm/distance.hpp) on meshes whose distances are
// known in closed form, and its guaranteed bound against dense sampling.
#include <gtest/gtest.h>

#include <cmath>

#include "mesh_gen.hpp"
#include "surface_gen.hpp"
#include "tsm/distance.hpp"

namespace {

using tsm::DistanceOptions;
using tsm::DistanceReport;
using tsm::Mesh;

DistanceReport measure(const Mesh& a, const Mesh& b, uint64_t samples = 200000) {
  DistanceOptions o;
  o.target_samples = samples;
  DistanceReport r;
  EXPECT_TRUE(tsm::measure_distance(a, b, o, r).ok());
  return r;
}

TEST(Distance, IdenticalMeshesAreAtZero) {
  const Mesh m = tsm_test::torus(24, 12);
  const DistanceReport r = measure(m, m);
  EXPECT_LT(r.hausdorff_bound, 1e-12);
  EXPECT_LT(r.a_to_b.mean, 1e-12);
  EXPECT_DOUBLE_EQ(r.area_a, r.area_b);
  EXPECT_LT(r.normal_max_deg, 1e-3);
  EXPECT_GT(r.a_to_b.samples, 100000u);
}

// The grid moved along its normal by h: every point is exactly h away.
TEST(Distance, GridShiftedAlongItsNormal) {
  const Mesh a = tsm_test::flat_grid(20);
  const Mesh b = tsm_test::shifted(a, 0, 0, 0.125f);
  const DistanceReport r = measure(a, b);
  EXPECT_NEAR(r.hausdorff, 0.125, 1e-7);
  EXPECT_NEAR(r.hausdorff_bound, 0.125, 1e-7);
  EXPECT_NEAR(r.a_to_b.mean, 0.125, 1e-7);
  EXPECT_NEAR(r.b_to_a.rms, 0.125, 1e-7);
  EXPECT_NEAR(r.area_b / r.area_a, 1.0, 1e-6);
  EXPECT_LT(r.normal_max_deg, 1e-3);
  EXPECT_NEAR(r.diagonal, std::sqrt(2.0), 1e-6);
}

// The grid moved in its plane by d along x: the strip x in [0, d) of A is d
// from B at its far edge, the rest is on B. Mean = d^2 / 2 per unit length.
TEST(Distance, GridShiftedInItsPlane) {
  const Mesh a = tsm_test::flat_grid(33);
  const Mesh b = tsm_test::shifted(a, 0.0625f, 0, 0);
  const DistanceReport r = measure(a, b, 400000);
  EXPECT_NEAR(r.hausdorff, 0.0625, 1e-6);
  EXPECT_GE(r.hausdorff_bound, r.hausdorff);
  EXPECT_LT(r.hausdorff_bound, 0.0625 + 1e-6);
  EXPECT_NEAR(r.a_to_b.mean, 0.0625 * 0.0625 / 2, 2e-4);
}

// A sphere and the same sphere scaled by s > 1 around its centre: the
// inner one lies in the unit ball, so a vertex s v of the outer one is
// exactly s - 1 from it, and no point of either is farther.
TEST(Distance, SphereAgainstScaledSphere) {
  const Mesh a = tsm_test::icosphere(3);
  const float s = 1.25f;
  const Mesh b = tsm_test::scaled(a, s);
  const DistanceReport r = measure(a, b);
  EXPECT_NEAR(r.hausdorff, s - 1.0, 1e-6);
  EXPECT_NEAR(r.b_to_a.max, s - 1.0, 1e-6);
  EXPECT_LE(r.a_to_b.max, s - 1.0 + 1e-6);
  EXPECT_GE(r.hausdorff_bound, s - 1.0 - 1e-6);
  EXPECT_LT(r.hausdorff_bound, s - 1.0 + 1e-6);
  EXPECT_NEAR(r.area_b / r.area_a, s * s, 1e-5);
  EXPECT_NEAR(r.volume_b / r.volume_a, s * s * s, 1e-5);
  EXPECT_GT(r.volume_a, 0);
}

// The bound from a coarse sampling holds against a much denser one, and
// the sampled maximum approaches it from below.
TEST(Distance, BoundHoldsAgainstDenseSampling) {
  const Mesh a = tsm_test::torus(16, 8);
  const Mesh b = tsm_test::jittered(tsm_test::torus(40, 20), 0.02f, 7);
  const DistanceReport coarse = measure(a, b, 5000), dense = measure(a, b, 600000);
  EXPECT_GE(coarse.hausdorff_bound, dense.hausdorff);
  EXPECT_GE(dense.hausdorff_bound, dense.hausdorff);
  EXPECT_LE(coarse.hausdorff, dense.hausdorff + 1e-12);
  EXPECT_LT(dense.hausdorff_bound - dense.hausdorff, 0.05 * dense.hausdorff);
}

TEST(Distance, RefusesMeshesWithoutTriangles) {
  Mesh empty;
  DistanceReport r;
  EXPECT_FALSE(tsm::measure_distance(empty, tsm_test::icosphere(1), {}, r).ok());
  Mesh nan = tsm_test::icosphere(1);
  nan.positions[4] = std::nanf("");
  EXPECT_FALSE(tsm::measure_distance(nan, tsm_test::icosphere(1), {}, r).ok());
}

}  // namespace
