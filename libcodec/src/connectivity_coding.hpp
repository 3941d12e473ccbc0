// Internal: what the connectivity coder (connectivity_encode.cpp) and
// decoder (connectivity_decode.cpp) share so that both adapt alike: the
// streams' context models (FORMAT.md §8.3), the run values' table contexts
// (§8.3.1) and the stitch candidates (§8.3.2).
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <vector>

#include "connectivity.hpp"
#include "range_coder.hpp"

namespace tsm::conn {

// Context models, shared by encoder and decoder so both adapt alike.
struct VertexTreeModels {
  UIntModel length[2];  // by previous run's end (0 branch, 1 leaf)
  Prob leaf[2];
  // By the run's index among its branching node's children: 1, or 2 and
  // more. The first child (index 0) is never the last (a branching node has
  // at least two), so its bit is not coded.
  Prob last[2];
};

struct TriangleTreeModels {
  UIntModel root;
  UIntModel march[2][2];     // [previous run's end type][this run's end type]
  Prob end[2][2];            // [previous run's end][the end of the run before it]
  Prob bit[kMarchContexts];  // see MarchBitDecoder
  Prob diagonal[2];          // by previous flag
};

struct TopologyModels {
  UIntModel count, corner, partner, position, distance, face_size, index;
  // A stitch target's candidate rank + 1 (0: its distance follows), by
  // StitchCandidates::context.
  UIntModel rank[2];
  Prob has_polygons;
  // Side faces on edges (FORMAT.md §8.3.3): whether the list is coded;
  // per edge, whether faces lie on it (by the previous edge's bit and
  // whether an end already had some), more than one, how many more, and
  // per face its repeated end (by the previous face's on the edge).
  Prob on_edges;
  Prob edge_any[2][2];
  Prob edge_more;
  UIntModel edge_count;
  Prob edge_end[2];
};

// FORMAT.md §8.3.3: the edges a degenerate triangle (a, a, b) may be coded
// on: the cut surface's half-edges h in decode order, each pair once (h
// before its twin), as output ids (u, v) from h's start to its end; left
// out when an end is virtual or both ends are one vertex. `id` maps a
// pre-order position (decoder) or an output id (encoder) to an output id,
// kNone for a virtual position. f(u, v) returns false to stop.
template <class Id, class F>
void each_side_edge(const std::vector<uint32_t>& corner, const std::vector<uint32_t>& twin, Id id, F f) {
  const uint32_t nh = static_cast<uint32_t>(corner.size());
  for (uint32_t h = 0; h < nh; ++h) {
    if (twin[h] < h) continue;
    const uint32_t u = id(corner[h]), v = id(corner[h % 3 == 2 ? h - 2 : h + 1]);
    if (u == kNone || v == kNone || u == v) continue;
    if (!f(u, v)) return;
  }
}

// FORMAT.md §8.3.2: the candidates for a stitch's target. A
// stitched position d is a copy of a vertex T; each of d's neighbours in
// the cut surface whose vertex is known (a position not stitched, or one
// stitched before d: its target) is a neighbour of T in the mesh, so T is
// usually a neighbour, in the cut surface, of those vertices: the
// candidates (positions before d; the neighbours' vertices themselves
// excluded), ranked by how many of them propose each (votes), ties by
// position, the later first. Encoder and decoder run it on the same cut
// surface (triangle corners as pre-order positions and twins, in decode
// order); at most kRing neighbours per position keep hostile files linear.
class StitchCandidates {
 public:
  static constexpr uint32_t kRing = 16;
  StitchCandidates(const std::vector<uint32_t>& corner, const std::vector<uint32_t>& twin,
                   const std::vector<uint8_t>& is_virtual, const std::vector<uint8_t>& stitched,
                   const std::vector<uint32_t>& target)
      : corner_(corner), twin_(twin), virtual_(is_virtual), stitched_(stitched), target_(target) {
    const size_t P = is_virtual.size();
    first_he_.assign(P, kNone);
    for (size_t h = 0; h < corner.size(); ++h)
      if (corner[h] < P) first_he_[corner[h]] = static_cast<uint32_t>(h);  // the last one in decode order
    stamp_.assign(P, kNone);
    near_.assign(P, kNone);
    votes_.assign(P, 0);
  }
  // Gathers the candidates for the stitch at position d, each as a key
  // (votes << 32 | position: distinct, the larger the better).
  void gather(uint32_t d) {
    keys_.clear();
    ring(d, [&](uint32_t n) {
      const uint32_t r = vertex(n, d);
      if (r != kNone) near_[r] = d;
    });
    ring(d, [&](uint32_t n) {
      const uint32_t r = vertex(n, d);
      if (r == kNone) return;
      ring(r, [&](uint32_t x) {
        const uint32_t c = vertex(x, d);
        if (c == kNone || c >= d || near_[c] == d) return;
        if (stamp_[c] != d) {
          stamp_[c] = d;
          votes_[c] = 0;
          keys_.push_back(c);
        }
        ++votes_[c];
      });
    });
    for (uint64_t& k : keys_) k |= uint64_t{votes_[k]} << 32;
  }
  // The rank's model: 1 when the best candidate has 3 votes or more.
  int context() const {
    uint64_t best = 0;
    for (uint64_t k : keys_) best = std::max(best, k);
    return (best >> 32) >= 3 ? 1 : 0;
  }
  // Encoder: the rank + 1 of position c among the candidates, 0 if not one.
  uint32_t rank_of(uint32_t c) const {
    const auto it = std::find_if(keys_.begin(), keys_.end(), [c](uint64_t k) { return static_cast<uint32_t>(k) == c; });
    if (it == keys_.end()) return 0;
    const uint64_t key = *it;
    return 1 + static_cast<uint32_t>(std::count_if(keys_.begin(), keys_.end(), [key](uint64_t k) { return k > key; }));
  }
  // Decoder: the candidate of rank + 1 `r`, kNone if there is none.
  uint32_t at_rank(uint32_t r) {
    if (r == 0 || r > keys_.size()) return kNone;
    std::nth_element(keys_.begin(), keys_.begin() + (r - 1), keys_.end(), std::greater<uint64_t>());
    return static_cast<uint32_t>(keys_[r - 1]);
  }

 private:
  // The vertex position n stands for as seen from stitch d: itself, or the
  // target of a stitch before d; kNone when not known or virtual.
  uint32_t vertex(uint32_t n, uint32_t d) const {
    if (n >= virtual_.size() || virtual_[n]) return kNone;
    if (!stitched_[n]) return n;
    return n < d ? target_[n] : kNone;
  }
  // Calls f with the heads of the half-edges leaving p, turning from the
  // last one in decode order (next edge out: the twin of the previous
  // half-edge of its triangle), at most kRing, until back at the first.
  template <class F>
  void ring(uint32_t p, F f) const {
    const uint32_t h0 = p < first_he_.size() ? first_he_[p] : kNone;
    uint32_t h = h0;
    for (uint32_t i = 0; i < kRing && h < corner_.size(); ++i) {
      const uint32_t t = h - h % 3;
      f(corner_[t + (h % 3 + 1) % 3]);
      h = twin_[t + (h % 3 + 2) % 3];
      if (h == h0) break;
    }
  }
  const std::vector<uint32_t>& corner_;
  const std::vector<uint32_t>& twin_;
  const std::vector<uint8_t>& virtual_;
  const std::vector<uint8_t>& stitched_;
  const std::vector<uint32_t>& target_;
  std::vector<uint32_t> first_he_, stamp_, near_, votes_;
  std::vector<uint64_t> keys_;
};

// Run-value contexts of the tables (FORMAT.md §8.3.1).
constexpr int kRunLengthCtx = 0;    // + previous run's end (vertex-run length)
constexpr int kRunMarchCtx = 2;     // + 2 * previous run's end + this run's end (march count)
constexpr int kRunPositionCtx = 6;  // virtual and stitched vertices' position gaps
constexpr int kRunDistanceCtx = 7;  // stitch distances

}  // namespace tsm::conn
