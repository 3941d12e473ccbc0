// Selective refinement (Hoppe 1997, seed 003): a progressive file's vertex
// splits kept as a vertex hierarchy with their dependencies, and the mesh
// of any legal set of applied splits, built without decoding again.
//
// The splits are recovered from the decoder's levels: between two levels
// the batch appended vertices u = n0 .. n1 - 1 and, per u in that order,
// the faces (v, u, x) and (v, y, u), and moved some faces of v to u in
// place (FORMAT.md §4.8). A face of the full mesh is present when the split
// that added it is applied (base faces always), and each of its corners sits
// on the nearest active ancestor of its full-mesh vertex (u's parent is v).
#include "tsm/selective_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace tsm {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint32_t kLeftOut = kNone - 1;  // a face of the loose section

Status refused(const std::string& message) { return Status(ErrorCode::invalid_argument, message); }

}  // namespace

Status ProgressiveHierarchy::build(std::string_view bytes, const DecodeOptions& options) {
  *this = ProgressiveHierarchy();
  StreamDecoder dec(options);
  dec.stop_at_levels(true);
  Mesh before;
  bool have_base = false;
  double error = -1;
  Status st = dec.feed(bytes);
  while (st.ok()) {
    if (dec.progressive() && dec.batches_done() == 0 && !have_base) {
      have_base = true;
      before = dec.mesh();
      made_by_.assign(before.vertex_count(), kNone);
      face_made_by_.assign(before.face_count(), kNone);
    } else if (dec.progressive() && dec.batches_done() == batches_ + 1) {
      TSM_RETURN_IF_ERROR(add_level(before, dec.mesh(), batches_, error));
      before = dec.mesh();
      ++batches_;
    }
    error = dec.level_error();
    if (!dec.level_pending()) break;
    st = dec.feed({});
  }
  if (st.ok()) st = dec.finish();
  if (!st.ok()) return st;
  if (!dec.progressive())
    return refused("not a progressive file: it has no refinement batches (encode it with tsm encode --progressive)");
  full_ = dec.take_mesh();
  made_by_.resize(full_.vertex_count(), kNone);  // the loose section's vertices: in every state
  // The loose section's faces: where all their corners are.
  face_made_by_.resize(full_.face_count(), kLeftOut);
  applied_.assign(splits_.size(), 1);
  applied_count_ = split_count();
  dirty_ = true;
  return Status::Ok();
}

// One batch: its splits recovered from the level before and after it, each
// with the splits that made the vertices around it then.
Status ProgressiveHierarchy::add_level(const Mesh& before, const Mesh& after, uint32_t batch, double error_before) {
  const size_t n0 = before.vertex_count(), n1 = after.vertex_count(), f0 = before.face_count();
  if (n1 <= n0 || after.face_count() < f0 + (n1 - n0))
    return Status(ErrorCode::internal, "batch " + std::to_string(batch) + ": unexpected vertex or face counts");
  std::vector<uint32_t> split_at(n0, kNone);  // vertex v of `before` -> its split in this batch
  const uint32_t first = split_count();
  // Each split appended (v, u, x) then (v, y, u), either left out when the
  // new vertex u lies on v's border (FORMAT.md §4.8).
  std::vector<size_t> faces_end(n1 - n0);
  size_t next = f0;
  auto is_split_face = [&](size_t g, uint32_t v, uint32_t u) {
    if (g >= after.face_count() || after.face_size(g) != 3) return false;
    const uint32_t* a = after.face(g);
    return a[0] == v && (a[1] == u || a[2] == u);
  };
  for (size_t j = 0; j < n1 - n0; ++j) {
    const uint32_t u = static_cast<uint32_t>(n0 + j);
    Split s;
    s.vertex = next < after.face_count() ? after.face(next)[0] : kNone;
    s.child = u;
    s.batch = batch;
    if (s.vertex >= n0 || !is_split_face(next, s.vertex, u) || split_at[s.vertex] != kNone)
      return Status(ErrorCode::internal, "batch " + std::to_string(batch) + ": unexpected split faces");
    const bool first_is_x = after.face(next)[1] == u;
    ++next;
    if (first_is_x && is_split_face(next, s.vertex, u) && after.face(next)[2] == u) ++next;
    faces_end[j] = next;
    split_at[s.vertex] = first + static_cast<uint32_t>(j);
    splits_.push_back(std::move(s));
  }
  if (next != after.face_count())
    return Status(ErrorCode::internal, "batch " + std::to_string(batch) + ": unexpected vertex or face counts");
  // The vertices around each split vertex in `before`, as the splits that made them.
  for (size_t f = 0; f < f0; ++f) {
    const uint32_t* c = before.face(f);
    const uint32_t n = before.face_size(f);
    for (uint32_t k = 0; k < n; ++k) {
      if (split_at[c[k]] == kNone) continue;
      std::vector<uint32_t>& deps = splits_[split_at[c[k]]].deps;
      for (uint32_t i = 0; i < n; ++i)
        if (made_by_[c[i]] != kNone) deps.push_back(made_by_[c[i]]);
    }
  }
  made_by_.resize(n1, kNone);
  face_made_by_.resize(after.face_count(), kNone);
  for (uint32_t s = first; s < split_count(); ++s) {
    std::vector<uint32_t>& deps = splits_[s].deps;
    std::sort(deps.begin(), deps.end());
    deps.erase(std::unique(deps.begin(), deps.end()), deps.end());
    made_by_[splits_[s].child] = s;
    const size_t j = s - first;
    for (size_t g = j == 0 ? f0 : faces_end[j - 1]; g < faces_end[j]; ++g) face_made_by_[g] = s;
  }
  batch_error_.push_back(error_before);
  return Status::Ok();
}

SplitView ProgressiveHierarchy::split(uint32_t index) const {
  const Split& s = splits_[index];
  SplitView v;
  v.index = index;
  v.batch = s.batch;
  v.vertex = s.vertex;
  v.child = s.child;
  v.position = &full_.positions[3 * size_t{s.vertex}];
  v.child_position = &full_.positions[3 * size_t{s.child}];
  double d2 = 0;
  for (int a = 0; a < 3; ++a)
    d2 += (double{v.child_position[a]} - v.position[a]) * (double{v.child_position[a]} - v.position[a]);
  v.radius = static_cast<float>(std::sqrt(d2));
  v.batch_error = batch_error_[s.batch];
  return v;
}

void ProgressiveHierarchy::adapt(const std::function<bool(const SplitView&)>& refine) {
  std::vector<uint8_t> want(splits_.size(), 0);
  for (uint32_t s = 0; s < split_count(); ++s) want[s] = refine(split(s)) ? 1 : 0;
  // Dependencies point to earlier splits: one pass from the last forces them all.
  for (uint32_t s = split_count(); s-- > 0;)
    if (want[s])
      for (uint32_t d : splits_[s].deps) want[d] = 1;
  applied_ = std::move(want);
  applied_count_ = static_cast<uint32_t>(std::count(applied_.begin(), applied_.end(), uint8_t{1}));
  dirty_ = true;
}

Status ProgressiveHierarchy::refine(uint32_t index) {
  if (index >= split_count()) return refused("split " + std::to_string(index) + " does not exist");
  if (applied_[index]) return Status::Ok();
  for (uint32_t d : splits_[index].deps)
    if (!applied_[d])
      return refused("split " + std::to_string(index) + " (vertex " + std::to_string(splits_[index].vertex) +
                     ") needs split " + std::to_string(d) + " (vertex " + std::to_string(splits_[d].vertex) +
                     ") applied first: it made a vertex next to it");
  applied_[index] = 1;
  ++applied_count_;
  dirty_ = true;
  return Status::Ok();
}

Status ProgressiveHierarchy::coarsen(uint32_t index) {
  if (index >= split_count()) return refused("split " + std::to_string(index) + " does not exist");
  if (!applied_[index]) return Status::Ok();
  // Only later splits can need it.
  for (uint32_t s = index + 1; s < split_count(); ++s)
    if (applied_[s] && std::binary_search(splits_[s].deps.begin(), splits_[s].deps.end(), index))
      return refused("split " + std::to_string(index) + " (vertex " + std::to_string(splits_[index].vertex) +
                     ") cannot be undone while split " + std::to_string(s) + " (vertex " +
                     std::to_string(splits_[s].vertex) + ") is applied: undo that one first");
  applied_[index] = 0;
  --applied_count_;
  dirty_ = true;
  return Status::Ok();
}

uint32_t ProgressiveHierarchy::active_ancestor(uint32_t v) const {
  while (made_by_[v] != kNone && !applied_[made_by_[v]]) v = splits_[made_by_[v]].vertex;
  return v;
}

void ProgressiveHierarchy::rebuild() {
  current_.clear();
  current_ids_.clear();
  std::vector<uint32_t> id(full_.vertex_count(), kNone);
  for (uint32_t v = 0; v < full_.vertex_count(); ++v) {
    if (made_by_[v] != kNone && !applied_[made_by_[v]]) continue;
    id[v] = static_cast<uint32_t>(current_ids_.size());
    current_ids_.push_back(v);
    const float* p = &full_.positions[3 * size_t{v}];
    current_.add_vertex(p[0], p[1], p[2]);
  }
  std::vector<uint32_t> corners;
  for (size_t f = 0; f < full_.face_count(); ++f) {
    const uint32_t* c = full_.face(f);
    if (face_made_by_[f] == kLeftOut) {
      bool all = true;
      for (uint32_t k = 0; k < full_.face_size(f); ++k) all = all && active_ancestor(c[k]) == c[k];
      if (!all) continue;
    } else if (face_made_by_[f] != kNone && !applied_[face_made_by_[f]]) {
      continue;
    }
    corners.assign(c, c + full_.face_size(f));
    for (uint32_t& x : corners) x = id[active_ancestor(x)];
    current_.add_face(corners.data(), corners.size());
  }
  dirty_ = false;
}

const Mesh& ProgressiveHierarchy::current_mesh() {
  if (dirty_) rebuild();
  return current_;
}

const std::vector<uint32_t>& ProgressiveHierarchy::current_vertex_ids() {
  if (dirty_) rebuild();
  return current_ids_;
}

}  // namespace tsm
