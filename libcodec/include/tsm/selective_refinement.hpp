// tsm: selective refinement of a progressive file (Hoppe, "View-dependent
// refinement of progressive meshes", 1997): the vertex splits of every batch
// kept as a hierarchy, so that a caller refines only where it asks (a view
// frustum, a screen-space error) and coarsens elsewhere, without decoding
// again.
//
//   tsm::ProgressiveHierarchy h;
//   if (!h.build(bytes).ok()) ...;                 // a file from `tsm encode --progressive`
//   h.adapt([&](const tsm::SplitView& s) { return in_frustum(s.position) && s.radius > pixel; });
//   const tsm::Mesh& m = h.current_mesh();
//
// Split k of the file (in file order) turned vertex `vertex` into itself and
// a new vertex `child`. A split depends on the splits that made the vertices
// around `vertex` when the file applied it (its own vertex's included): it
// may only be applied when they are, and they may only be undone after it
// (Hoppe's legality: a split needs its neighbours present). Under those
// rules every set of applied splits gives a valid mesh: refined everywhere
// it is the file's full mesh exactly, coarsened everywhere its base mesh.
#pragma once
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

// What a refinement predicate sees of one split.
struct SplitView {
  uint32_t index = 0;                     // the split's number, 0 .. split_count() - 1, in file order
  uint32_t batch = 0;                     // the refinement batch that holds it
  uint32_t vertex = 0;                    // the vertex split (an id of the full mesh)
  uint32_t child = 0;                     // the vertex it makes (an id of the full mesh)
  const float* position = nullptr;        // the vertex's position (3 floats)
  const float* child_position = nullptr;  // the new vertex's position
  float radius = 0;                       // distance between the two: the detail the split adds
  double batch_error = 0;                 // the encoder's error of the level before the batch (model units)
};

class ProgressiveHierarchy {
 public:
  // Decodes a whole progressive file and keeps its splits; the state is then
  // the full mesh (every split applied). A single-rate file is refused.
  Status build(std::string_view bytes, const DecodeOptions& options = {});

  uint32_t split_count() const { return static_cast<uint32_t>(splits_.size()); }
  uint32_t batch_count() const { return batches_; }
  SplitView split(uint32_t index) const;
  // The splits `index` needs applied first (each smaller than index).
  const std::vector<uint32_t>& dependencies(uint32_t index) const { return splits_[index].deps; }
  bool applied(uint32_t index) const { return applied_[index] != 0; }
  uint32_t applied_count() const { return applied_count_; }

  // Applies exactly the splits the predicate asks for and those they need
  // (forced, as in Hoppe's method); every other split is undone.
  void adapt(const std::function<bool(const SplitView&)>& refine);
  // One split at a time: refused (invalid_argument, naming the split that
  // stands in the way) when a split it needs is not applied, or, to undo
  // it, when an applied split needs it.
  Status refine(uint32_t index);
  Status coarsen(uint32_t index);

  // The mesh of the current state: the active vertices (the base's, the
  // children of applied splits, and the file's vertices no face uses) in
  // increasing id, the faces present in the full mesh's order, each corner
  // on the nearest active ancestor of its full-mesh vertex.
  const Mesh& current_mesh();
  // The full-mesh id of current_mesh()'s vertex i.
  const std::vector<uint32_t>& current_vertex_ids();

 private:
  struct Split {
    uint32_t vertex = 0, child = 0, batch = 0;
    std::vector<uint32_t> deps;
  };
  Status add_level(const Mesh& before, const Mesh& after, uint32_t batch, double error_before);
  uint32_t active_ancestor(uint32_t v) const;
  void rebuild();

  Mesh full_;
  std::vector<Split> splits_;
  std::vector<double> batch_error_;     // per batch: error_before
  std::vector<uint32_t> made_by_;       // per vertex: the split that made it, or none (base, loose)
  std::vector<uint32_t> face_made_by_;  // per face: the split that added it, or none (base)
  std::vector<uint8_t> applied_;
  uint32_t applied_count_ = 0, batches_ = 0;
  bool dirty_ = true;
  Mesh current_;
  std::vector<uint32_t> current_ids_;
};

}  // namespace tsm
