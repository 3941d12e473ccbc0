// tsm: mesh simplification with a guaranteed maximum error.
//
//   tsm::SimplifyOptions o;
//   o.max_error = 0.005 * diagonal;   // model units
//   tsm::Mesh small;
//   tsm::simplify(mesh, o, small);
//
// Edge collapses in quadric-error order, each accepted only when a
// conservative bound of the symmetric Hausdorff distance between the
// ORIGINAL mesh and the result stays within max_error (the result is
// guaranteed within it, up to float rounding of the input).
#pragma once
#include <cstdint>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm {

struct SimplifyOptions {
  // The largest symmetric Hausdorff distance allowed between the input and
  // the result, in model units; 0 = no bound (then target_faces decides).
  double max_error = 0;
  // Stop once the result has at most this many triangles (0 = reduce as
  // far as max_error allows).
  uint64_t target_faces = 0;
  // Called now and then with the triangle count so far (may be null).
  void (*progress)(uint64_t faces_now, uint64_t faces_in, void* user) = nullptr;
  void* progress_user = nullptr;
};

struct SimplifyReport {
  uint64_t faces_in = 0, faces_out = 0;  // triangles (polygons count as their fans)
  uint64_t vertices_in = 0, vertices_out = 0;
  uint64_t collapses = 0;        // accepted
  uint64_t rejected = 0;         // candidate collapses refused (topology, flips, the bound)
  uint64_t locked_vertices = 0;  // never removed: non-manifold, on an attribute seam, on a degenerate face
  // With max_error: the bound proven of the distance from any point of the
  // result to the input (<= max_error; 0 when nothing moved). The other
  // direction is proven within max_error.
  double result_error = 0;
  // With max_error: per triangle of the result (in its face order), the
  // bound proven of the distance from any of its points to the input (their
  // largest is result_error).
  std::vector<double> face_error;
};

// Simplifies `in` into `out` (triangles; polygons are split as fans first).
// Kept: boundaries (as boundaries, within the bound), non-manifold edges
// and vertices (their vertices may move, within the bound, but never go),
// attribute seams (their vertices never move or go), components (none vanishes), face attributes
// (per triangle), vertex and corner attributes (interpolated along the
// collapsed edge). No triangle is flipped (normal turned by 90 degrees or
// more) or made degenerate. Vertices no face uses are kept; metadata is
// copied.
Status simplify(const Mesh& in, const SimplifyOptions& options, Mesh& out, SimplifyReport* report = nullptr);

}  // namespace tsm
