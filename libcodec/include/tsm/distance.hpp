// tsm: geometric distance between two meshes (Metro-style): how far a
// simplified or decoded mesh is from the original, as a surface.
//
//   tsm::DistanceReport r;
//   tsm::measure_distance(original, simplified, tsm::DistanceOptions{}, r);
//   r.hausdorff, r.hausdorff_bound, r.diagonal ...
//
// (tsm/compare.hpp is another thing: the exact round-trip check of the codec.)
#pragma once
#include <cstdint>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

struct DistanceOptions {
  // Sampling: every triangle is cut into a regular grid of sub-triangles
  // whose edges are at most `spacing` long, and the grid's points are the
  // samples (a triangle's corners and edges always among them). 0 = chosen
  // so that each side gets about `target_samples` samples.
  double spacing = 0;
  uint64_t target_samples = 1000000;
};

// The distance from every point of one surface (X) to the other (Y).
struct OneSidedDistance {
  double max = 0;    // the largest sample distance: a lower bound of the Hausdorff distance from X to Y
  double bound = 0;  // an upper bound of it (see below)
  double mean = 0;   // area-weighted mean over the samples
  double rms = 0;    // area-weighted root mean square
  uint64_t samples = 0;
};

struct DistanceReport {
  OneSidedDistance a_to_b, b_to_a;
  // Symmetric Hausdorff distance: between `hausdorff` (the sampled maximum)
  // and `hausdorff_bound` (a guaranteed upper bound: for every sub-triangle
  // S of the sampling grid, the smaller of (a) the largest distance of its
  // corners to one triangle of the other mesh (the distance to a triangle is
  // convex, so it is largest at a corner of S) and (b) the largest corner
  // distance plus S's covering radius (distance is 1-Lipschitz), maximised
  // over all S).
  double hausdorff = 0;
  double hausdorff_bound = 0;
  double spacing = 0;   // the sampling grid's edge length (the larger of the two sides')
  double diagonal = 0;  // bounding-box diagonal of mesh A (the reference for percentages)
  double area_a = 0, area_b = 0;
  // Signed volumes (divergence theorem); meaningful for closed, consistently
  // oriented meshes.
  double volume_a = 0, volume_b = 0;
  // Angle between the normal of A at each sample and the normal of B's
  // nearest triangle, in degrees (area-weighted mean, and maximum).
  double normal_mean_deg = 0, normal_max_deg = 0;
  uint64_t triangles_a = 0, triangles_b = 0;
};

// Measures A against B. Polygons are split as fans; faces with fewer than
// three corners and vertices no face uses are left out. An error when a
// side has no triangle or a position is not finite.
Status measure_distance(const Mesh& a, const Mesh& b, const DistanceOptions& options, DistanceReport& report);

}  // namespace tsm
