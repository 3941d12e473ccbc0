// Welding, the split layout (FORMAT.md §8.13): a mesh with
// attributes usually repeats a position wherever a normal, texture
// coordinate or colour changes (a flat-shaded model three times per
// triangle, a CAD part once per face normal). The encoder codes one point
// per grid position (connectivity and positions on the welded surface) and
// here, per corner of the welded faces in the decoder's order, which of its
// point's vertices the corner was: the first corner of a point makes its
// first vertex; each later corner is either a new vertex or one of the
// point's vertices so far, ranked with those the neighbouring faces across
// the corner's two edges use at the point first (across an edge that is not
// a seam the corner is the neighbour's vertex: rank 0 at a small cost), then
// those an earlier edge joins to the face's vertices so far, then by how
// close their normals are to the face's.
// The vertices are then numbered point by point in point order, each
// point's in the order its corners made them: a decoded mesh welds back to
// the same points in the same order, and codes the same layout again.
#include "split_layout.hpp"

#include <algorithm>
#include <memory>
#include <unordered_map>

#include "range_coder.hpp"

namespace tsm {

namespace {

constexpr uint32_t kNoVertex = 0xFFFFFFFFu;

// Normals as small integers (9 bits a component, FORMAT.md §8.13): exact,
// so that every decoder ranks and buckets alike.
struct Normal {
  int64_t x[3] = {0, 0, 0};
  bool zero() const { return x[0] == 0 && x[1] == 0 && x[2] == 0; }
};

Normal reduced(const int64_t v[3]) {
  int64_t m = 0;
  for (int a = 0; a < 3; ++a) m = std::max(m, v[a] < 0 ? -v[a] : v[a]);
  // The shift that brings the largest component below 2^9.
  const int s = m < 512 ? 0 : 64 - __builtin_clzll(static_cast<unsigned long long>(m)) - 9;
  Normal n;
  for (int a = 0; a < 3; ++a) n.x[a] = v[a] >> s;  // floor
  return n;
}

// A face's normal from its first three corners' grid positions.
Normal face_normal(const std::vector<uint32_t>& q, const uint32_t* c) {
  int64_t d1[3], d2[3];
  for (int a = 0; a < 3; ++a) {
    d1[a] = int64_t{q[3 * size_t{c[1]} + a]} - int64_t{q[3 * size_t{c[0]} + a]};
    d2[a] = int64_t{q[3 * size_t{c[2]} + a]} - int64_t{q[3 * size_t{c[0]} + a]};
  }
  const int64_t n[3] = {d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2], d1[0] * d2[1] - d1[1] * d2[0]};
  return reduced(n);
}

// How close a vertex's normal (the sum of its faces' so far) is to a
// face's: 0 within 1.8 degrees (cos^2 >= 1023/1024), 1 within 8 (1004/1024),
// 2 within 26 (829/1024), 3 within 60 (256/1024), 4 farther, 5 either is 0.
int closeness(const Normal& f, const int64_t sum[3]) {
  const Normal v = reduced(sum);
  if (f.zero() || v.zero()) return 5;
  const int64_t dot = f.x[0] * v.x[0] + f.x[1] * v.x[1] + f.x[2] * v.x[2];
  if (dot <= 0) return 4;
  const int64_t ff = f.x[0] * f.x[0] + f.x[1] * f.x[1] + f.x[2] * f.x[2];
  const int64_t vv = v.x[0] * v.x[0] + v.x[1] * v.x[1] + v.x[2] * v.x[2];
  const int64_t d2 = dot * dot * 1024, n2 = ff * vv;
  if (d2 >= 1023 * n2) return 0;
  if (d2 >= 1004 * n2) return 1;
  if (d2 >= 829 * n2) return 2;
  if (d2 >= 256 * n2) return 3;
  return 4;
}

// The neighbours' say (SplitWalk::gather): 0 none known, 1 one, 2 both the
// same vertex, 3 two different vertices.
struct SplitModels {
  // [neighbours (0-3)][the face's previous corner: 0 none, 1 a new vertex,
  // 2 an old one][the first candidate's closeness (0-5)][the second's class
  // (none, 0-3, 4-5)][4 or more candidates: a point of many vertices, as a
  // CAD part's slivers make][the first candidate linked to the face's
  // vertices so far]
  Prob fresh[4][3][6][3][2][2];
  // [the first candidate's closeness][the second's (0-5)][4 or more][the
  // first linked]: two candidates as close to the face say little which it
  // is, a near one beside a far one much
  UIntModel rank[6][6][2][2];
  // A new vertex with an earlier vertex's values (CopyChoice, CopyContext):
  // the values of the original across the corner's edge to the next corner,
  // [the other end of that edge: not known, kept its values, changed][the
  // vertex across the edge from the previous corner: none, the same
  // original, another][the original's closeness]; of the one across the
  // edge from the previous corner, [its other end][an edge to the next
  // corner][closeness]; of another of the point's, [an edge][more than
  // one][the first one's closeness]; which.
  Prob copy_next[3][3][6];
  Prob copy_prev[3][2][6];
  Prob copy_other[2][2][6];
  UIntModel copy_rank;
};

// Whether the corner's vertex has the values of the vertex across one of
// its edges (its original's): 0 no vertex across (or not known yet), 1 the
// same, 2 others. Across an edge inside a texture chart both ends keep
// their values, across a seam both change: one end tells the other.
struct FaceEnds {
  std::vector<uint8_t> next, prev;  // per corner, across its edge to the next corner, from the previous
  void start(uint32_t n) {
    next.assign(n, 0);
    prev.assign(n, 0);
  }
  // The other end of corner i's edge to the next corner, and of its edge
  // from the previous one (corners after i are not known yet: 0).
  int next_partner(uint32_t i) const { return (i + 1) % next.size() < i ? prev[(i + 1) % next.size()] : 0; }
  int prev_partner(uint32_t i) const {
    const uint32_t j = (i + static_cast<uint32_t>(next.size()) - 1) % static_cast<uint32_t>(next.size());
    return j < i ? next[j] : 0;
  }
};

// The copy choice of a new vertex (FORMAT.md §8.13): the originals it may
// take the values of, the one across the corner's edge to the next corner
// first, then the one across the edge from the previous corner, then the
// point's others in candidate order, each once.
struct CopyChoice {
  uint32_t next = kNoVertex, prev = kNoVertex;
  std::vector<uint32_t> others;
};

// The walk both sides make: per corner, the candidates, then (after the
// choice) the vertex it is; per face, its edges and its normal remembered.
// Directed edge (two points) -> the vertices at its ends, as the last face
// through it left them: open addressing with linear probing (the walk
// inserts three edges per triangle; std::unordered_map spent most of the
// decoder's time allocating and freeing their nodes).
class EdgeMap {
 public:
  using Ends = std::pair<uint32_t, uint32_t>;
  const Ends* find(uint64_t key) const {
    if (slots_.empty()) return nullptr;
    for (size_t i = slot_of(key);; i = (i + 1) & mask_) {
      if (slots_[i].key == kEmpty) return nullptr;
      if (slots_[i].key == key) return &slots_[i].ends;
    }
  }
  // Room for `n` keys without growing.
  void reserve(size_t n) {
    size_t size = 1024;
    while (size < 2 * n) size *= 2;
    if (size > slots_.size()) rehash(size);
  }
  void set(uint64_t key, Ends ends) {
    if (2 * (used_ + 1) > slots_.size()) rehash(slots_.empty() ? 1024 : 2 * slots_.size());
    size_t i = slot_of(key);
    while (slots_[i].key != kEmpty && slots_[i].key != key) i = (i + 1) & mask_;
    if (slots_[i].key == kEmpty) ++used_;
    slots_[i] = {key, ends};
  }

 private:
  // Points are below 2^32 - 1 (a uint32 count), so no key is all ones.
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  struct Slot {
    uint64_t key = kEmpty;
    Ends ends;
  };
  size_t slot_of(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_; }
  void rehash(size_t size) {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(size, Slot());
    mask_ = slots_.size() - 1;
    used_ = 0;
    for (const Slot& s : old)
      if (s.key != kEmpty) set(s.key, s.ends);
  }
  std::vector<Slot> slots_;
  size_t mask_ = 0, used_ = 0;
};

class SplitWalk {
 public:
  // `corners`: how many the faces have (the edge maps are sized for them).
  SplitWalk(uint32_t points, const std::vector<uint32_t>& q, size_t corners)
      : first_(points, kNoVertex), last_(points, kNoVertex), count_(points, 0), q_(q) {
    edge_.reserve(corners);
    linked_.reserve(corners);
    sum_.reserve(corners);
    original_.reserve(corners);
    later_.reserve(corners);
    earlier_.reserve(corners);
  }
  void start_face(const uint32_t* c, uint32_t n) {
    normal_ = n >= 3 ? face_normal(q_, c) : Normal();
    ref_ = normal_;
  }
  // What candidates are ranked by at the face's corner i, given the
  // vertices its corners 0 .. i-1 took (`v`): those vertices (a candidate
  // an edge already links to one of them is of the same surface piece,
  // where parts overlap or touch at a point), and the face's normal, or
  // where that is zero (a sliver flat on the grid) their summed normals.
  void refer(const uint32_t* v, uint32_t i) {
    taken_ = v;
    taken_count_ = i;
    if (!normal_.zero()) return;
    int64_t t[3] = {0, 0, 0};
    for (uint32_t j = 0; j < i; ++j)
      for (int a = 0; a < 3; ++a) t[a] += sum_[v[j]].x[a];
    ref_ = reduced(t);
  }
  // The candidates for a corner at p whose face continues to `next` and
  // comes from `prev`, in cand(): the vertices of the neighbours across the
  // corner's two edges, then the point's other vertices (the latest made
  // first), then stably those linked to the face's vertices so far first,
  // each group by closeness to the face's normal. Returns the neighbours'
  // say (0-3); best() is the first candidate's closeness, linked() whether
  // it is linked.
  int gather(uint32_t p, uint32_t next, uint32_t prev) {
    cand_.clear();
    const EdgeMap::Ends* a = edge_.find(key(next, p));  // the neighbour across p -> next runs next -> p
    if (a) offer(a->second);
    const EdgeMap::Ends* b = edge_.find(key(p, prev));  // across prev -> p: p -> prev
    if (b) offer(b->first);
    across_next_ = a ? a->second : kNoVertex;
    across_prev_ = b ? b->first : kNoVertex;
    const bool both = a && b;
    const int nb = cand_.empty() ? 0 : !both ? 1 : cand_.size() == 1 ? 2 : 3;
    for (uint32_t w = last_[p]; w != kNoVertex; w = earlier_[w]) offer(w);
    const size_t k = cand_.size();
    for (Candidate& c : cand_) {
      c.close = closeness(ref_, sum_[c.v].x);
      bool linked = false;
      for (uint32_t j = 0; j < taken_count_ && !linked; ++j) linked = linked_.find(pair_key(taken_[j], c.v)) != nullptr;
      c.key = (linked ? 0 : 8) + c.close;
    }
    // Stable insertion sort: a point has a handful of vertices.
    for (size_t i = 1; i < k; ++i) {
      const Candidate x = cand_[i];
      size_t j = i;
      for (; j > 0 && x.key < cand_[j - 1].key; --j) cand_[j] = cand_[j - 1];
      cand_[j] = x;
    }
    sorted_.clear();
    for (const Candidate& c : cand_) sorted_.push_back(c.v);
    best_ = cand_[0].close;
    second_ = k > 1 ? cand_[1].close : 6;
    linked_first_ = cand_[0].key < 8 ? 1 : 0;
    return nb;
  }
  const std::vector<uint32_t>& cand() const { return sorted_; }
  // The vertices across the corner's edges (gather), kNoVertex where none.
  uint32_t across_next() const { return across_next_; }
  uint32_t across_prev() const { return across_prev_; }
  uint32_t original(uint32_t w) const { return original_[w]; }
  // How close vertex w's normal is to the face's (0-5, as in gather).
  int closeness_of(uint32_t w) const { return closeness(ref_, sum_[w].x); }
  // The corner's ends (FaceEnds) once it is vertex w.
  void ends(FaceEnds& e, uint32_t i, uint32_t w) const {
    auto state = [&](uint32_t x) -> uint8_t { return x == kNoVertex ? 0 : original_[x] == original_[w] ? 1 : 2; };
    e.next[i] = state(across_next_);
    e.prev[i] = state(across_prev_);
  }
  // The originals a new vertex may copy, in the order they are offered.
  void copy_choice(CopyChoice& c) const {
    c.next = across_next_ == kNoVertex ? kNoVertex : original_[across_next_];
    c.prev = across_prev_ == kNoVertex || original_[across_prev_] == c.next ? kNoVertex : original_[across_prev_];
    c.others.clear();
    for (uint32_t w : sorted_) {
      const uint32_t o = original_[w];
      if (o != c.next && o != c.prev && std::find(c.others.begin(), c.others.end(), o) == c.others.end())
        c.others.push_back(o);
    }
  }
  int best() const { return best_; }
  int linked() const { return linked_first_; }
  // The second candidate's closeness, 6 if there is none; in three classes
  // (none, 0-3, 4-5) for the new-vertex bit.
  int second() const { return second_; }
  int second_class() const { return second_ == 6 ? 0 : second_ <= 3 ? 1 : 2; }
  size_t vertices_at(uint32_t p) const { return count_[p]; }
  // A new vertex at p; `original`: the vertex whose attribute values it
  // has (kNoVertex: its own).
  uint32_t make(uint32_t p, uint32_t original = kNoVertex) {
    earlier_.push_back(last_[p]);
    later_.push_back(kNoVertex);
    if (last_[p] == kNoVertex)
      first_[p] = next_;
    else
      later_[last_[p]] = next_;
    last_[p] = next_;
    ++count_[p];
    sum_.emplace_back();
    original_.push_back(original == kNoVertex ? next_ : original_[original]);
    return next_++;
  }
  const std::vector<uint32_t>& originals() const { return original_; }
  // After a face: its edges (corner points c, their vertices v) and its
  // normal added to its vertices' (once per corner).
  void remember(const uint32_t* c, const uint32_t* v, uint32_t n) {
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t j = (i + 1) % n;
      edge_.set(key(c[i], c[j]), {v[i], v[j]});
      linked_.set(pair_key(v[i], v[j]), {v[i], v[j]});
      for (int a = 0; a < 3; ++a) sum_[v[i]].x[a] += normal_.x[a];
    }
  }
  // Final numbering: the output ids go point by point, each point's
  // vertices in the order made, a point on no corner getting one. The walk
  // vertices are those made, in order, then one per point on no corner, in
  // point order; per walk vertex its output id and its point.
  void number(std::vector<uint32_t>& walk_out, std::vector<uint32_t>& walk_point) const {
    walk_out.assign(next_, kNoVertex);
    walk_point.assign(next_, kNoVertex);
    uint32_t id = 0;
    for (uint32_t p = 0; p < first_.size(); ++p) {
      if (first_[p] == kNoVertex) {
        walk_out.push_back(id++);
        walk_point.push_back(p);
      }
      for (uint32_t w = first_[p]; w != kNoVertex; w = later_[w]) {
        walk_out[w] = id++;
        walk_point[w] = p;
      }
    }
  }
  uint32_t made() const { return next_; }

 private:
  static uint64_t key(uint32_t a, uint32_t b) { return uint64_t{a} << 32 | b; }
  static uint64_t pair_key(uint32_t a, uint32_t b) { return a < b ? key(a, b) : key(b, a); }
  // A candidate not offered yet goes to the end of cand_.
  void offer(uint32_t v) {
    if (v == kNoVertex) return;
    for (const Candidate& c : cand_)
      if (c.v == v) return;
    cand_.push_back({v, 0, 0});
  }
  // A candidate: its vertex, closeness to the face's normal, and sort key
  // (0-7 linked to the face's vertices so far, 8-15 not; plus closeness).
  struct Candidate {
    uint32_t v;
    int close, key;
  };
  // The vertices made at each point, as a list in the order made: per point
  // its first and last, per walk vertex the next and previous at its point.
  std::vector<uint32_t> first_, last_, count_;
  std::vector<uint32_t> later_, earlier_;
  const std::vector<uint32_t>& q_;
  std::vector<Normal> sum_;         // per walk vertex: its faces' normals summed
  std::vector<uint32_t> original_;  // per walk vertex: the one whose values it has
  Normal normal_;                   // the current face's
  Normal ref_;                      // what candidates are ranked by (refer)
  EdgeMap edge_;
  EdgeMap linked_;                   // vertex pairs an edge of a face so far joins (either way)
  const uint32_t* taken_ = nullptr;  // the current face's vertices so far (refer)
  uint32_t taken_count_ = 0;
  std::vector<Candidate> cand_;   // in gather's order, then sorted
  std::vector<uint32_t> sorted_;  // their vertices
  int second_ = 6;
  int linked_first_ = 0;
  int best_ = 5;
  uint32_t across_next_ = kNoVertex, across_prev_ = kNoVertex;
  uint32_t next_ = 0;
};

// The contexts of a new vertex's copy choice: the other ends of the
// corner's two edges (FaceEnds), whether the vertex across the edge from the
// previous corner has the same original as the one across the next (0 none
// across the previous edge, 1 the same, 2 another), and the closeness of the
// vertex across each edge and of the first other original (5 if none).
struct CopyContext {
  int next_partner, prev_partner, prev_kind;
  int next_close, prev_close, other_close;
};
CopyContext copy_context(const SplitWalk& walk, const FaceEnds& ends, uint32_t i, const CopyChoice& c) {
  const uint32_t a = walk.across_next(), b = walk.across_prev();
  const int kind = b == kNoVertex ? 0 : a != kNoVertex && walk.original(a) == walk.original(b) ? 1 : 2;
  return {ends.next_partner(i),
          ends.prev_partner(i),
          kind,
          a == kNoVertex ? 5 : walk.closeness_of(a),
          b == kNoVertex ? 5 : walk.closeness_of(b),
          c.others.empty() ? 5 : walk.closeness_of(c.others[0])};
}

// A new vertex's copy choice (CopyChoice), `match` telling whether it has
// an original's values: returns that original, kNoVertex if none.
template <class Match>
uint32_t encode_copy(RangeEncoder& e, SplitModels& m, const CopyChoice& c, const CopyContext& x, Match match) {
  if (c.next != kNoVertex) {
    const bool same = match(c.next);
    e.bit(m.copy_next[x.next_partner][x.prev_kind][x.next_close], same);
    if (same) return c.next;
  }
  if (c.prev != kNoVertex) {
    const bool same = match(c.prev);
    e.bit(m.copy_prev[x.prev_partner][c.next != kNoVertex ? 1 : 0][x.prev_close], same);
    if (same) return c.prev;
  }
  if (c.others.empty()) return kNoVertex;
  uint32_t r = 0;
  while (r < c.others.size() && !match(c.others[r])) ++r;
  const bool any_edge = c.next != kNoVertex || c.prev != kNoVertex;
  e.bit(m.copy_other[any_edge ? 1 : 0][c.others.size() > 1 ? 1 : 0][x.other_close], r < c.others.size());
  if (r == c.others.size()) return kNoVertex;
  if (c.others.size() > 1) m.copy_rank.encode(e, r);
  return c.others[r];
}

// The decoder's side: false on a rank out of range.
bool decode_copy(RangeDecoder& d, SplitModels& m, const CopyChoice& c, const CopyContext& x, uint32_t& original) {
  original = kNoVertex;
  if (c.next != kNoVertex && d.bit(m.copy_next[x.next_partner][x.prev_kind][x.next_close])) {
    original = c.next;
    return true;
  }
  if (c.prev != kNoVertex && d.bit(m.copy_prev[x.prev_partner][c.next != kNoVertex ? 1 : 0][x.prev_close])) {
    original = c.prev;
    return true;
  }
  if (c.others.empty()) return true;
  const bool any_edge = c.next != kNoVertex || c.prev != kNoVertex;
  if (!d.bit(m.copy_other[any_edge ? 1 : 0][c.others.size() > 1 ? 1 : 0][x.other_close])) return true;
  const uint32_t r = c.others.size() > 1 ? m.copy_rank.decode(d) : 0;
  if (r >= c.others.size()) return false;
  original = c.others[r];
  return true;
}

// Whether some input vertex is the vertex of two corners. Without (a
// flat-shaded model: every corner a vertex of its own), every corner at a
// point with vertices is a new vertex and no new-vertex bit is coded; the
// decoder knows it from the counts: the vertices then number the corners
// plus the points on no corner.
bool corners_share_vertices(const std::vector<uint32_t>& corner_vertex) {
  std::vector<uint32_t> sorted = corner_vertex;
  std::sort(sorted.begin(), sorted.end());
  return std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
}
bool counts_say_joins(const Mesh& faces, uint32_t points, uint64_t vertex_count) {
  std::vector<uint8_t> used(points, 0);
  for (uint32_t p : faces.indices) used[p] = 1;
  const uint64_t unused = static_cast<uint64_t>(std::count(used.begin(), used.end(), uint8_t{0}));
  return vertex_count < faces.indices.size() + unused;
}

}  // namespace

std::string encode_split_layout(const Mesh& faces, uint32_t points, const std::vector<uint32_t>& q,
                                const std::vector<uint32_t>& corner_vertex, const std::vector<uint32_t>& point_vertex,
                                const std::vector<uint32_t>& value_class, std::vector<uint32_t>& walk_input,
                                std::vector<uint32_t>& walk_out, std::vector<uint32_t>& walk_point,
                                std::vector<uint32_t>& walk_orig, std::vector<uint32_t>& indices) {
  RangeEncoder e;
  const std::unique_ptr<SplitModels> models = std::make_unique<SplitModels>();  // large: on the heap
  SplitModels& m = *models;
  SplitWalk walk(points, q, faces.indices.size());
  std::unordered_map<uint32_t, uint32_t> walk_of;  // input vertex -> walk vertex
  std::vector<uint32_t> input_of;                  // walk vertex -> input vertex
  std::vector<uint32_t> corner_walk(faces.indices.size());
  std::vector<uint32_t> v;
  FaceEnds ends;
  CopyChoice choice;
  const bool joins = corners_share_vertices(corner_vertex);
  for (uint32_t f = 0; f < faces.face_count(); ++f) {
    const uint32_t* c = faces.face(f);
    const uint32_t n = faces.face_size(f), base = faces.face_offsets[f];
    v.assign(n, kNoVertex);
    walk.start_face(c, n);
    ends.start(n);
    int before = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = c[i], x = corner_vertex[base + i];
      const auto it = walk_of.find(x);
      const bool fresh = it == walk_of.end();
      if (walk.vertices_at(p) == 0) {
        v[i] = walk.make(p);
      } else {
        walk.refer(v.data(), i);
        const int nb = walk.gather(p, c[(i + 1) % n], c[(i + n - 1) % n]);
        if (joins)
          e.bit(m.fresh[nb][before][walk.best()][walk.second_class()][walk.cand().size() >= 4 ? 1 : 0][walk.linked()],
                fresh);
        if (fresh) {
          // A copy: the values of an original of the point (the first such
          // in the choice's order).
          walk.copy_choice(choice);
          const uint32_t o = encode_copy(e, m, choice, copy_context(walk, ends, i, choice),
                                         [&](uint32_t w) { return value_class[input_of[w]] == value_class[x]; });
          v[i] = walk.make(p, o);
        } else {
          const auto& cand = walk.cand();
          const uint32_t r = static_cast<uint32_t>(std::find(cand.begin(), cand.end(), it->second) - cand.begin());
          if (cand.size() > 1) m.rank[walk.best()][walk.second()][cand.size() >= 4 ? 1 : 0][walk.linked()].encode(e, r);
          v[i] = it->second;
        }
        walk.ends(ends, i, v[i]);
      }
      before = fresh ? 1 : 2;
      if (it == walk_of.end()) {
        walk_of.emplace(x, v[i]);
        input_of.push_back(x);
      }
      corner_walk[base + i] = v[i];
    }
    walk.remember(c, v.data(), n);
  }
  walk.number(walk_out, walk_point);
  walk_orig = walk.originals();
  for (size_t w = walk_orig.size(); w < walk_point.size(); ++w) walk_orig.push_back(static_cast<uint32_t>(w));
  walk_input = input_of;
  for (size_t w = input_of.size(); w < walk_point.size(); ++w) walk_input.push_back(point_vertex[walk_point[w]]);
  indices = std::move(corner_walk);
  return e.finish();
}

Status decode_split_layout(std::string_view stream, uint64_t vertex_count, uint32_t points,
                           const std::vector<uint32_t>& q, Mesh& faces, std::vector<uint32_t>& walk_out,
                           std::vector<uint32_t>& walk_point, std::vector<uint32_t>& walk_orig) {
  auto corrupt = [](const char* why) { return Status(ErrorCode::corrupt_data, std::string("split layout: ") + why); };
  RangeDecoder d(stream);
  // Default-initialized (not make_unique's value-initialization, which would
  // zero every UIntModel's mantissa rows first: they are set up on first use).
  const std::unique_ptr<SplitModels> models(new SplitModels);  // large: on the heap
  SplitModels& m = *models;
  SplitWalk walk(points, q, faces.indices.size());
  std::vector<uint32_t> v;
  FaceEnds ends;
  CopyChoice choice;
  for (uint32_t p : faces.indices)
    if (p >= points) return corrupt("a corner outside the points");
  const bool joins = counts_say_joins(faces, points, vertex_count);
  for (uint32_t f = 0; f < faces.face_count(); ++f) {
    uint32_t* c = faces.indices.data() + faces.face_offsets[f];
    const uint32_t n = faces.face_size(f);
    v.assign(n, kNoVertex);
    walk.start_face(c, n);
    ends.start(n);
    int before = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = c[i];
      if (walk.vertices_at(p) == 0) {
        v[i] = walk.make(p);
        before = 1;
      } else {
        walk.refer(v.data(), i);
        const int nb = walk.gather(p, c[(i + 1) % n], c[(i + n - 1) % n]);
        before = !joins || d.bit(m.fresh[nb][before][walk.best()][walk.second_class()][walk.cand().size() >= 4 ? 1 : 0]
                                        [walk.linked()])
                     ? 1
                     : 2;
        if (before == 1) {
          walk.copy_choice(choice);
          uint32_t original = kNoVertex;
          if (!decode_copy(d, m, choice, copy_context(walk, ends, i, choice), original))
            return corrupt("a copy's rank out of range");
          v[i] = walk.make(p, original);
        } else {
          const auto& cand = walk.cand();
          const uint32_t r = cand.size() > 1
                                 ? m.rank[walk.best()][walk.second()][cand.size() >= 4 ? 1 : 0][walk.linked()].decode(d)
                                 : 0;
          if (r >= cand.size()) return corrupt("a vertex rank out of range");
          v[i] = cand[r];
        }
        walk.ends(ends, i, v[i]);
      }
      if (walk.made() > vertex_count || d.overrun() > RangeDecoder::kMaxOverrun)
        return corrupt("more vertices than the header says, or the stream is truncated");
    }
    walk.remember(c, v.data(), n);
    std::copy(v.begin(), v.end(), c);  // walk vertices for now
  }
  walk.number(walk_out, walk_point);
  if (walk_point.size() != vertex_count) return corrupt("the vertex count differs from the header's");
  walk_orig = walk.originals();
  for (size_t w = walk_orig.size(); w < walk_point.size(); ++w) walk_orig.push_back(static_cast<uint32_t>(w));
  return Status::Ok();
}

uint64_t per_vertex_corner_attributes(const Mesh& mesh) {
  const size_t V = mesh.vertex_count();
  uint64_t mask = 0;
  for (size_t i = 0; i < mesh.attributes.size() && i < 64; ++i) {
    const Attribute& a = mesh.attributes[i];
    if (a.domain != AttributeDomain::corner || a.value_count() != V) continue;
    std::vector<uint32_t> value(V, kNoVertex);
    std::vector<uint8_t> taken(V, 0);
    bool ok = a.indices.size() == mesh.indices.size();
    for (size_t k = 0; k < mesh.indices.size() && ok; ++k) {
      const uint32_t v = mesh.indices[k], x = a.indices[k];
      if (value[v] == kNoVertex) {
        ok = !taken[x];
        value[v] = x;
        taken[x] = 1;
      } else {
        ok = value[v] == x;
      }
    }
    if (ok) mask |= uint64_t{1} << i;
  }
  return mask;
}

Mesh corner_attributes_on_vertices(const Mesh& mesh, uint64_t mask) {
  Mesh m = mesh;
  for (size_t i = 0; i < m.attributes.size() && i < 64; ++i) {
    if (!(mask >> i & 1)) continue;
    Attribute& a = m.attributes[i];
    const Attribute& from = mesh.attributes[i];
    const size_t n = from.components, V = mesh.vertex_count();
    std::vector<uint32_t> value(V, kNoVertex);
    std::vector<uint8_t> taken(V, 0);
    for (size_t k = 0; k < mesh.indices.size(); ++k) {
      value[mesh.indices[k]] = from.indices[k];
      taken[from.indices[k]] = 1;
    }
    uint32_t unused = 0;  // vertices on no face take the values no corner uses, in order
    for (size_t v = 0; v < V; ++v) {
      if (value[v] == kNoVertex) {
        while (taken[unused]) ++unused;
        value[v] = unused++;
      }
      std::copy_n(&from.values[n * value[v]], n, &a.values[n * v]);
    }
    a.domain = AttributeDomain::vertex;
    a.indices.clear();
  }
  return m;
}

RankNeighbours rank_neighbours(const Mesh& faces, size_t n) {
  RankNeighbours nb;
  nb.start.assign(n + 1, 0);
  for (uint32_t f = 0; f < faces.face_count(); ++f) {
    const uint32_t* c = faces.face(f);
    for (uint32_t i = 0, k = faces.face_size(f); i < k; ++i) {
      ++nb.start[c[i] + 1];
      ++nb.start[c[(i + 1) % k] + 1];
    }
  }
  for (size_t o = 0; o < n; ++o) nb.start[o + 1] += nb.start[o];
  nb.list.resize(nb.start[n]);
  std::vector<uint32_t> at(nb.start.begin(), nb.start.end() - 1);
  for (uint32_t f = 0; f < faces.face_count(); ++f) {
    const uint32_t* c = faces.face(f);
    for (uint32_t i = 0, k = faces.face_size(f); i < k; ++i) {
      const uint32_t a = c[i], b = c[(i + 1) % k];
      nb.list[at[a]++] = b;
      nb.list[at[b]++] = a;
    }
  }
  return nb;
}

int neighbours_say(const RankNeighbours& nb, uint32_t o, const std::vector<uint32_t>& coded) {
  int say = 0;
  for (uint32_t j = nb.start[o]; j < nb.start[o + 1]; ++j) {
    const uint32_t r = coded[nb.list[j]];
    if (r != kNoVertex) say = std::max(say, r > 0 ? 2 : 1);
  }
  return say;
}

}  // namespace tsm
