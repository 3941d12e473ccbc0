// Internal: the encoder's side of progressive files (FORMAT.md §4.8): the
// collapses that turn the input into the base mesh, in batches.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm {

struct ProgressiveOptions {
  size_t max_batches = 32;        // at most this many refinement batches
  size_t min_base_vertices = 16;  // stop coarsening below this many vertices
  size_t min_batch_splits = 8;    // a batch of fewer collapses is the last one
};

// Vertex u merged into its neighbour v; y and x are the neighbours of v
// next to u in v's ring (..., y, u, x, ...), bounding u's faces.
struct CollapseRecord {
  uint32_t u = 0, v = 0, y = 0, x = 0;
};

constexpr uint32_t kNotInBase = 0xFFFFFFFFu;

struct CollapsePlan {
  std::vector<std::vector<CollapseRecord>> batches;  // in collapse order (the finest level's first)
  // errors[b]: the level after batches 0..b are collapsed: the largest
  // distance (grid steps) of a removed vertex from the level's vertex it was
  // merged into (following later merges); errors.back() is the base's.
  std::vector<double> errors;
  Mesh base;                      // the coarsest level: input positions, remaining faces
  std::vector<uint32_t> base_id;  // input vertex -> base vertex (kNotInBase when collapsed or loose)
  // Vertices no face uses, left out of the base when there are batches (the
  // loose section codes them after the last; FORMAT.md §4.8).
  std::vector<uint32_t> loose;
  // Triangles left out of the levels (input ids): a repeat of another's
  // corners, or a third face at an edge (or a second in one direction);
  // the loose section codes them after the last batch (FORMAT.md §4.8), so
  // the faces the collapses see form fans where the input's sheets touch.
  std::vector<std::array<uint32_t, 3>> left_out;
};

// q: the input's grid indices, 3 per vertex.
void plan_collapses(const Mesh& mesh, const std::vector<uint32_t>& q, const ProgressiveOptions& options,
                    CollapsePlan& plan);

}  // namespace tsm
