// Simplification with a guaranteed maximum error: edge collapses ordered by
// quadric error (Garland & Heckbert 1997), each accepted only when a
// conservative bound of the symmetric Hausdorff distance between the
// original mesh and the result stays within the limit (after Wendt's
// guaranteed-deviation reduction).
//
// The bound rests on two facts: the distance from a point to ONE triangle
// is a convex function, so a (sub-)triangle whose three corners are within
// E of a triangle t lies wholly within E of t; and the triangle inequality,
// d(p, X) <= d(p, t) + (the farthest any point of t is from X).
//  - original -> result: every original triangle is cut into pieces (at
//    first one piece, itself), each held by a result triangle with a proven
//    bound of its distance to it. A collapse hands the pieces of the
//    triangles it changes to the new triangles around the kept vertex (or
//    the unchanged ones next to them): through the triangle inequality
//    (the piece's bound plus the farthest corner of its old triangle from
//    the new one) when that is within E, else by its corners, cutting it in
//    four where no single triangle takes it.
//  - result -> original: every result triangle carries a proven bound of
//    its distance to the original (0 at first). A new triangle is checked
//    first through the triangles it replaces (the distance to one of them
//    plus its bound), then through the BVH over the original, cut in four
//    recursively until each part is within E of one triangle (convexity)
//    or its corners' bounds plus its covering radius are (the distance to
//    a mesh is 1-Lipschitz).
// A collapse that fails either, flips or degenerates a triangle, or changes
// the topology is refused. Vertices of non-manifold edges and fans may move
// but never go; vertices on attribute seams and degenerate input triangles
// neither move nor go.
#include "tsm/simplify.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "triangle_bvh.hpp"

namespace tsm {
namespace {

using geom::Vec3;

// Plane quadric: sum of w (n.x + d)^2, stored as the symmetric 4x4 upper half.
struct Quadric {
  double a[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};  // xx xy xz xw yy yz yw zz zw ww
  void add_plane(Vec3 n, double d, double w) {
    const double v[4] = {n.x, n.y, n.z, d};
    int k = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) a[k++] += w * v[i] * v[j];
  }
  void add(const Quadric& o) {
    for (int i = 0; i < 10; ++i) a[i] += o.a[i];
  }
  double eval(Vec3 p) const {
    const double x = p.x, y = p.y, z = p.z;
    return a[0] * x * x + 2 * a[1] * x * y + 2 * a[2] * x * z + 2 * a[3] * x + a[4] * y * y + 2 * a[5] * y * z +
           2 * a[6] * y + a[7] * z * z + 2 * a[8] * z + a[9];
  }
  // The minimising point, when the 3x3 system is well conditioned.
  bool optimum(Vec3& p) const {
    const double m00 = a[0], m01 = a[1], m02 = a[2], m11 = a[4], m12 = a[5], m22 = a[7];
    const double b0 = -a[3], b1 = -a[6], b2 = -a[8];
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11;
    const double det = m00 * c00 + m01 * c01 + m02 * c02;
    const double scale = std::fabs(m00) + std::fabs(m11) + std::fabs(m22);
    if (!(std::fabs(det) > 1e-9 * scale * scale * scale)) return false;
    const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12, c22 = m00 * m11 - m01 * m01;
    p = {(c00 * b0 + c01 * b1 + c02 * b2) / det, (c01 * b0 + c11 * b1 + c12 * b2) / det,
         (c02 * b0 + c12 * b1 + c22 * b2) / det};
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  }
};

double longest_edge(Vec3 a, Vec3 b, Vec3 c) {
  return std::max({geom::length(b - a), geom::length(c - b), geom::length(a - c)});
}

// A part of an original triangle (its corners), assigned to a result triangle.
struct Piece {
  Vec3 p[3];
  uint32_t depth = 0;
  uint32_t orig = 0;  // the original triangle it is part of
  double delta = 0;   // proven: no point of the piece is farther from the triangle holding it
};

constexpr uint32_t kMaxPieceDepth = 4;  // a piece is cut at most this many times (4^4 parts)
constexpr uint32_t kMaxCheckDepth = 5;  // a new triangle is cut at most this many times
// kLocked: the vertex never moves or goes; kKeep: it may move but never goes.
constexpr uint8_t kLocked = 1, kBoundary = 2, kRemoved = 4, kKeep = 8;

// An edge to try, 16 bytes (four to a cache line in the heap). `stamps`:
// the sum of its ends' change counters when queued (each only grows, so
// the sum is unchanged only when neither end changed).
struct Candidate {
  float cost;
  uint32_t u, v;
  uint32_t stamps;
};

// Cheaper first, ties by the edge: the order depends only on the entries,
// not on how the heap was built (it is rebuilt without its stale entries).
bool comes_before(const Candidate& a, const Candidate& b) {
  if (a.cost != b.cost) return a.cost < b.cost;
  return a.u != b.u ? a.u < b.u : a.v < b.v;
}

// A 4-ary min-heap: half the levels of a binary one, the children of a
// node side by side. The entries are placed so that each node's four
// children fill one 64-byte cache line (entry 1 on a line boundary): one
// miss per level of a heap far larger than the caches, not two.
class CandidateHeap {
 public:
  bool empty() const { return n_ == 0; }
  size_t size() const { return n_; }
  void push(const Candidate& c) {
    if (off_ + n_ + 1 > buf_.size()) grow();
    Candidate* a = base_;
    size_t i = n_++;
    while (i > 0) {
      const size_t parent = (i - 1) / 4;
      if (!comes_before(c, a[parent])) break;
      a[i] = a[parent];
      i = parent;
    }
    a[i] = c;
  }
  Candidate pop() {
    const Candidate top = base_[0];
    const Candidate last = base_[--n_];
    if (n_ > 0) sift_down(0, last);
    return top;
  }
  // Keeps the entries `keep` accepts, then restores the heap order.
  template <typename Keep>
  void filter(Keep keep) {
    n_ = static_cast<size_t>(std::remove_if(base_, base_ + n_, [&](const Candidate& c) { return !keep(c); }) - base_);
    for (size_t i = n_ / 4 + 1; i-- > 0;)
      if (i < n_) sift_down(i, base_[i]);
  }

 private:
  void grow() {
    std::vector<Candidate> b(std::max<size_t>(64, 2 * buf_.size()));
    size_t off = 0;  // the vector's 16-byte alignment: entry off + 1 on a line within 4 steps
    while (off < 3 && (reinterpret_cast<uintptr_t>(&b[off + 1]) & 63) != 0) ++off;
    if (n_ > 0) std::copy(base_, base_ + n_, b.data() + off);
    buf_.swap(b);
    off_ = off;
    base_ = buf_.data() + off_;
  }
  void sift_down(size_t i, const Candidate c) {
    Candidate* a = base_;
    const size_t n = n_;
    for (;;) {
      const size_t first = 4 * i + 1;
      if (first >= n) break;
      // The grandchildren's lines, fetched while this level is compared.
      for (size_t k = 4 * first + 1; k < std::min(4 * first + 17, n); k += 4) __builtin_prefetch(&a[k]);
      size_t best = first;
      for (size_t k = first + 1; k < std::min(first + 4, n); ++k)
        if (comes_before(a[k], a[best])) best = k;
      if (!comes_before(a[best], c)) break;
      a[i] = a[best];
      i = best;
    }
    a[i] = c;
  }
  std::vector<Candidate> buf_;
  Candidate* base_ = nullptr;
  size_t off_ = 0, n_ = 0;
};

class Simplifier {
 public:
  Simplifier(const Mesh& in, const SimplifyOptions& o) : in_(in), o_(o), orig_(geom::triangles_of(in)), bvh_(orig_) {}

  Status run(Mesh& out, SimplifyReport& report);

 private:
  // ---- setup
  void build();
  void find_locked();
  void find_components();
  void init_quadrics();
  void push_edges_of(uint32_t v, bool higher_only = false);
  std::vector<uint32_t> ends_;  // push_edges_of's scratch
  bool candidate_for(uint32_t u, uint32_t v, Candidate& c);

  // ---- one collapse
  struct Place {
    double cost;
    uint32_t u, v;  // u goes, v stays (at x)
    Vec3 x;
  };
  struct Places {
    Place at[4];
    int count = 0;
    const Place* begin() const { return at; }
    const Place* end() const { return at + count; }
    void push_back(const Place& p) { at[count++] = p; }
  };
  Places placements(uint32_t a, uint32_t b, const Quadric& q) const;
  bool try_collapse(uint32_t u, uint32_t v);
  bool topology_ok(uint32_t u, uint32_t v, std::vector<uint32_t>& edge_tris);
  // Scratch reused by every try (no allocation per collapse).
  std::vector<uint32_t> edge_tris_, commit_edge_tris_, topo_nu_, topo_nv_, topo_opposite_, topo_common_;
  std::vector<std::pair<uint32_t, uint32_t>> again_;
  bool attempt(uint32_t u, uint32_t v, Vec3 x, const std::vector<uint32_t>& edge_tris);
  void commit(uint32_t u, uint32_t v);

  // ---- the bound
  bool assign_pieces(const std::vector<uint32_t>& changed);
  bool assign_piece(const Piece& pc);
  // A triangle that may take pieces: its corners (new ones for a changed
  // triangle) and box.
  struct Taker {
    Vec3 p[3], lo, hi;
    uint32_t t;
  };
  double fit2(const Piece& pc, const Taker& k, double limit2) const;
  bool take(const Piece& pc, size_t from);
  void add_near_takers();
  void add_taker(uint32_t t, Vec3 a, Vec3 b, Vec3 c);
  std::vector<Taker> takers_;
  size_t last_taker_ = 0;
  bool near_added_ = false;
  // Per current triangle: tri_gen_ when changed by the attempt, tri_gen_ + 1
  // when already among its near takers.
  std::vector<uint32_t> tri_mark_;
  uint32_t tri_gen_ = 0;
  // A bound of a point's distance to the original: b >= d(p, original),
  // proven through `ref` (>= 0: that original triangle, with no error of its
  // own; < 0: ring_[-1 - ref], a current triangle within tri_err_ of it).
  struct Near {
    double b;
    int64_t ref;
    bool exact = false;  // b is the distance to the original itself (through the BVH)
  };
  bool within_original(uint32_t t, double& err);
  Near ring_bound(Vec3 p);
  Near exact_bound(Vec3 p, int64_t hint);
  struct NearEntry;
  NearEntry& near_entry(Vec3 p);
  double leaf_bound(const Vec3 p[3], const Near n[3]) const;
  bool within_original_rec(const Vec3 p[3], Near n[3], uint32_t depth, double& err);
  Vec3 new_corner(uint32_t t, int k) const;

  // ---- output
  void write(Mesh& out) const;
  uint64_t live_faces() const { return live_; }

  const Mesh& in_;
  const SimplifyOptions& o_;
  geom::TriangleSet orig_;
  geom::TriangleBvh bvh_;
  double e2_ = 0;  // max_error squared
  bool bounded_ = false;

  std::vector<Vec3> pos_;
  std::vector<std::array<uint32_t, 3>> tri_;
  std::vector<uint8_t> tri_alive_;
  std::vector<std::vector<uint32_t>> vtris_;
  std::vector<uint8_t> flags_;
  std::vector<uint8_t> had_faces_;   // the vertex is on a triangle of the input
  std::vector<uint32_t> comp_;       // per triangle: its edge-connected component
  std::vector<uint32_t> comp_live_;  // per component: live triangles
  std::vector<Quadric> quad_;
  std::vector<uint32_t> stamp_;
  // Per vertex: the other ends of its edges whose collapse was refused, tried
  // again once the vertex's neighbourhood changes (an edge still queued
  // keeps its cost: only the kept vertex's position and quadric change).
  std::vector<std::vector<uint32_t>> refused_;
  std::vector<double> param_;  // per vertex: scratch
  uint64_t live_ = 0;
  // The candidates, a binary heap (std::push_heap order). Entries of edges
  // whose ends changed since are stale: skipped when they come up, and
  // dropped all at once when they outnumber the live edges.
  CandidateHeap heap_;
  void push(const Candidate& c) { heap_.push(c); }
  bool stale(const Candidate& c) const {
    return ((flags_[c.u] | flags_[c.v]) & kRemoved) || stamp_[c.u] + stamp_[c.v] != c.stamps;
  }
  void drop_stale();

  // Attributes: vertex ones interpolated per vertex, corner ones through a
  // value index per triangle corner (values appended as they are made).
  std::vector<size_t> vertex_attrs_, corner_attrs_;
  std::vector<std::vector<float>> vvalues_;                   // per vertex attribute
  std::vector<std::vector<float>> cvalues_;                   // per corner attribute
  std::vector<std::vector<std::array<uint32_t, 3>>> cindex_;  // per corner attribute, per triangle

  // The bound's state: pieces and which triangle holds each. A triangle's
  // list holds each piece's original triangle and bound beside it (the loops
  // over a changed triangle's pieces read only the list). A bound is kept
  // relative to its holder's offset, and the holder keeps the largest: a
  // triangle that moves by h with every piece still within E adds h to both,
  // touching no piece.
  struct PieceRef {
    uint32_t piece, orig;
    double delta;  // + tri_offset_[holder]: the piece's bound
  };
  std::vector<Piece> pieces_;
  std::vector<std::vector<PieceRef>> tri_pieces_;
  std::vector<double> tri_offset_, tri_max_delta_;
  std::vector<uint32_t> free_pieces_;
  void hold(uint32_t t, uint32_t piece, uint32_t orig, double delta);

  // Scratch of one attempt: the collapse u -> v at x.
  uint32_t cu_ = 0, cv_ = 0;
  Vec3 cx_;
  std::vector<uint32_t> changed_;   // triangles whose corners move or that go
  std::vector<uint32_t> new_tris_;  // changed triangles that stay (with u or v replaced by the moved v)
  // An attempt's assignments: pieces that stay whole (triangle, piece, its
  // new bound), parts of cut ones (triangle, part), the cut ones.
  struct Placed {
    uint32_t t, piece, orig;
    double delta;
  };
  // Changed triangles whose pieces all stay, within E after the move by h.
  struct Shift {
    uint32_t t;
    double h;
  };
  std::vector<Shift> shifted_;
  std::vector<Placed> placed_;
  std::vector<std::pair<uint32_t, Piece>> placed_new_;
  std::vector<uint32_t> cut_;
  std::vector<double> new_err_;  // per new_tris_ entry: the bound its check proved
  // Per current triangle: a proven bound of the distance from any of its
  // points to the original (0 for an original triangle). By the triangle
  // inequality a point p is within d(p, T) + tri_err_[T] of the original.
  std::vector<double> tri_err_;
  std::vector<uint32_t> ring_;  // the triangles around the edge tried, before the collapse
  // Original triangles of the changed triangles' pieces (the first 64): their
  // corners, and their boxes grown by E (a triangle whose corners are all
  // within E of one lies inside its grown box: a test of six comparisons
  // before any distance), read when first needed (most attempts stop at
  // one of the first few).
  struct LocalOrig {
    uint32_t o;
    bool ready;
    Vec3 p[3], lo, hi;
  };
  std::vector<LocalOrig> local_orig_;
  void fill_local_orig(LocalOrig& l) const;
  std::vector<uint8_t> local_tried_;  // per new_tris_ entry: small enough to be within E of one of them
  double longest_orig_edge_ = 0;
  std::vector<uint32_t> orig_mark_;  // per original triangle: orig_mark_gen_ when in local_orig_
  uint32_t orig_mark_gen_ = 0;
  bool near_local_original(uint32_t t, double& err);
  // Bounds of the points met in one try_collapse (corners and cut points
  // are shared between neighbouring triangles and between placements),
  // each computed when first asked: through the ring, through the BVH.
  // Open addressing, emptied by a new generation.
  struct NearEntry {
    Vec3 p;
    Near ring, exact;
    uint32_t gen = 0;
    bool has_ring = false, has_exact = false;
  };
  std::vector<NearEntry> near_cache_ = std::vector<NearEntry>(1u << 12);
  uint32_t near_gen_ = 1, near_used_ = 0;
  void clear_near_cache() { ++near_gen_, near_used_ = 0; }

  uint64_t collapses_ = 0, rejected_ = 0, locked_count_ = 0;
};

Vec3 Simplifier::new_corner(uint32_t t, int k) const {
  const uint32_t w = tri_[t][k];
  return (w == cu_ || w == cv_) ? cx_ : pos_[w];
}

void Simplifier::build() {
  const size_t nv = in_.vertex_count();
  pos_ = orig_.points;
  vtris_.assign(nv, {});
  flags_.assign(nv, 0);
  stamp_.assign(nv, 0);
  refused_.assign(nv, {});
  for (size_t i = 0; i < in_.attributes.size(); ++i) {
    const Attribute& a = in_.attributes[i];
    if (a.domain == AttributeDomain::vertex) {
      vertex_attrs_.push_back(i);
      vvalues_.push_back(a.values);
    } else if (a.domain == AttributeDomain::corner) {
      corner_attrs_.push_back(i);
      cvalues_.push_back(a.values);
      cindex_.push_back({});
    }
  }
  for (size_t f = 0; f < in_.face_count(); ++f) {
    const uint32_t n = in_.face_size(f);
    const uint32_t* c = in_.face(f);
    const uint32_t base = in_.face_offsets[f];
    for (uint32_t k = 2; k < n; ++k) {
      tri_.push_back({c[0], c[k - 1], c[k]});
      for (size_t a = 0; a < corner_attrs_.size(); ++a) {
        const std::vector<uint32_t>& idx = in_.attributes[corner_attrs_[a]].indices;
        cindex_[a].push_back({idx[base], idx[base + k - 1], idx[base + k]});
      }
    }
  }
  tri_alive_.assign(tri_.size(), 1);
  for (uint32_t t = 0; t < tri_.size(); ++t) {
    const auto& c = tri_[t];
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
      // A degenerate input triangle stays as it is: its vertices never move.
      for (uint32_t w : c) flags_[w] |= kLocked;
    }
    for (int k = 0; k < 3; ++k)
      if (k == 0 || (c[k] != c[0] && (k == 1 || c[k] != c[1]))) vtris_[c[k]].push_back(t);
  }
  find_components();
  had_faces_.assign(nv, 0);
  for (uint32_t v = 0; v < nv; ++v) had_faces_[v] = !vtris_[v].empty();
  live_ = tri_.size();
  pieces_.resize(tri_.size());
  tri_err_.assign(tri_.size(), 0.0);
  orig_mark_.assign(tri_.size(), 0);
  tri_pieces_.assign(tri_.size(), {});
  tri_mark_.assign(tri_.size(), 0);
  for (size_t t = 0; t < orig_.size(); ++t)
    longest_orig_edge_ =
        std::max(longest_orig_edge_, longest_edge(orig_.corner(t, 0), orig_.corner(t, 1), orig_.corner(t, 2)));
  tri_offset_.assign(tri_.size(), 0.0);
  tri_max_delta_.assign(tri_.size(), 0.0);
  for (uint32_t t = 0; t < tri_.size(); ++t) {
    for (int k = 0; k < 3; ++k) pieces_[t].p[k] = pos_[tri_[t][k]];
    pieces_[t].orig = t;
    tri_pieces_[t].push_back({t, t, 0.0});
  }
}

// Edge-connected components of the triangles (union-find over shared edges).
void Simplifier::find_components() {
  std::vector<uint32_t> parent(tri_.size());
  for (uint32_t t = 0; t < tri_.size(); ++t) parent[t] = t;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<std::array<uint32_t, 3>> edges;  // lo, hi, triangle
  for (uint32_t t = 0; t < tri_.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri_[t][k], b = tri_[t][(k + 1) % 3];
      if (a != b) edges.push_back({std::min(a, b), std::max(a, b), t});
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 1; i < edges.size(); ++i)
    if (edges[i][0] == edges[i - 1][0] && edges[i][1] == edges[i - 1][1])
      parent[find(edges[i][2])] = find(edges[i - 1][2]);
  comp_.resize(tri_.size());
  comp_live_.assign(tri_.size(), 0);
  for (uint32_t t = 0; t < tri_.size(); ++t) {
    comp_[t] = find(t);
    ++comp_live_[comp_[t]];
  }
}

// Vertices that never move or go: on an edge of more than two triangles or
// of two that disagree on its direction, with more than one fan of
// triangles, or where a corner attribute has different values (a seam).
void Simplifier::find_locked() {
  std::vector<uint32_t> ring;
  for (uint32_t v = 0; v < vtris_.size(); ++v) {
    if (vtris_[v].empty()) continue;
    // Edges (v, w): how many triangles, and in which direction.
    ring.clear();
    for (uint32_t t : vtris_[v])
      for (int k = 0; k < 3; ++k)
        if (tri_[t][k] == v) ring.push_back(tri_[t][(k + 1) % 3]), ring.push_back(tri_[t][(k + 2) % 3]);
    std::vector<uint32_t> sorted = ring;
    std::sort(sorted.begin(), sorted.end());
    uint32_t boundary = 0;
    bool bad = false;
    for (size_t i = 0; i < sorted.size();) {
      size_t j = i;
      while (j < sorted.size() && sorted[j] == sorted[i]) ++j;
      const size_t count = j - i;
      if (count == 1) ++boundary;
      if (count > 2) bad = true;
      i = j;
    }
    // Direction: w after v in one triangle and before v in the other.
    for (uint32_t t : vtris_[v])
      for (int k = 0; k < 3; ++k)
        if (tri_[t][k] == v) {
          const uint32_t next = tri_[t][(k + 1) % 3];
          for (uint32_t s : vtris_[v])
            if (s != t)
              for (int q = 0; q < 3; ++q)
                if (tri_[s][q] == v && tri_[s][(q + 1) % 3] == next) bad = true;
        }
    // One fan: the triangles around v connected through their edges at v.
    const size_t n = vtris_[v].size();
    std::vector<uint32_t> comp(n);
    for (size_t i = 0; i < n; ++i) comp[i] = static_cast<uint32_t>(i);
    auto find = [&](uint32_t i) {
      while (comp[i] != i) i = comp[i] = comp[comp[i]];
      return i;
    };
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) {
        int shared = 0;
        for (uint32_t a : tri_[vtris_[v][i]])
          for (uint32_t b : tri_[vtris_[v][j]])
            if (a == b && a != v) ++shared;
        if (shared > 0) comp[find(static_cast<uint32_t>(i))] = find(static_cast<uint32_t>(j));
      }
    size_t fans = 0;
    for (size_t i = 0; i < n; ++i) fans += find(static_cast<uint32_t>(i)) == i;
    if (fans != 1 || (boundary != 0 && boundary != 2)) bad = true;
    if (boundary) flags_[v] |= kBoundary;
    // Seams: all corners of v agree on every corner attribute.
    bool seam = false;
    for (size_t a = 0; a < corner_attrs_.size() && !seam; ++a) {
      const uint32_t comps = in_.attributes[corner_attrs_[a]].components;
      const float* first = nullptr;
      for (uint32_t t : vtris_[v])
        for (int k = 0; k < 3; ++k)
          if (tri_[t][k] == v) {
            const float* val = &cvalues_[a][static_cast<size_t>(cindex_[a][t][k]) * comps];
            if (!first)
              first = val;
            else if (std::memcmp(first, val, comps * sizeof(float)) != 0)
              seam = true;
          }
    }
    // A non-manifold vertex may move (only geometry changes) but not go; a
    // seam vertex neither (its values on each side would need their own
    // interpolation).
    if (bad) flags_[v] |= kKeep;
    if (seam) flags_[v] |= kLocked;
  }
  for (uint8_t f : flags_) locked_count_ += (f & (kLocked | kKeep)) != 0;
}

void Simplifier::init_quadrics() {
  quad_.assign(pos_.size(), {});
  for (uint32_t t = 0; t < tri_.size(); ++t) {
    const auto& c = tri_[t];
    const Vec3 a = pos_[c[0]], b = pos_[c[1]], d = pos_[c[2]];
    Vec3 n = geom::cross(b - a, d - a);
    const double len = geom::length(n);
    if (!(len > 0)) continue;
    n = n * (1 / len);
    Quadric q;
    q.add_plane(n, -geom::dot(n, a), len / 2);
    for (uint32_t w : c) quad_[w].add(q);
    // Boundary edges: a plane through the edge, perpendicular to the triangle.
    // (Both ends of a boundary edge are kBoundary, found by find_locked: the
    // triangles around the others are not searched.)
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = c[k], r = c[(k + 1) % 3];
      if (!(flags_[p] & flags_[r] & kBoundary)) continue;
      int count = 0;
      for (uint32_t s : vtris_[p])
        for (int j = 0; j < 3; ++j)
          if ((tri_[s][j] == p && tri_[s][(j + 1) % 3] == r) || (tri_[s][j] == r && tri_[s][(j + 1) % 3] == p)) ++count;
      if (count != 1) continue;
      const Vec3 e = pos_[r] - pos_[p];
      Vec3 m = geom::cross(e, n);
      const double ml = geom::length(m);
      if (!(ml > 0)) continue;
      m = m * (1 / ml);
      Quadric qb;
      qb.add_plane(m, -geom::dot(m, pos_[p]), 4 * geom::dot(e, e));
      quad_[p].add(qb);
      quad_[r].add(qb);
    }
  }
}

// The cheapest placement's cost; false when the edge cannot collapse at all.
bool Simplifier::candidate_for(uint32_t u, uint32_t v, Candidate& c) {
  Quadric q = quad_[u];
  q.add(quad_[v]);
  double best = std::numeric_limits<double>::infinity();
  bool any = false;
  for (const Place& p : placements(u, v, q)) best = std::min(best, p.cost), any = true;
  c = {static_cast<float>(std::max(best, 0.0)), u, v, stamp_[u] + stamp_[v]};
  return any;
}

// The edges of v, each once (with `higher_only`, those to a higher index:
// the first pass over all vertices queues every edge once).
void Simplifier::push_edges_of(uint32_t v, bool higher_only) {
  ends_.clear();
  for (uint32_t t : vtris_[v])
    for (uint32_t w : tri_[t])
      if (w != v && (!higher_only || w > v)) ends_.push_back(w);
  std::sort(ends_.begin(), ends_.end());
  ends_.erase(std::unique(ends_.begin(), ends_.end()), ends_.end());
  for (uint32_t w : ends_) {
    Candidate c;
    if (candidate_for(std::min(v, w), std::max(v, w), c)) push(c);
  }
}

// Link condition, boundary and component rules; `edge_tris` gets the
// triangles on the edge.
bool Simplifier::topology_ok(uint32_t u, uint32_t v, std::vector<uint32_t>& edge_tris) {
  edge_tris.clear();
  for (uint32_t t : vtris_[u])
    if (tri_[t][0] == v || tri_[t][1] == v || tri_[t][2] == v) edge_tris.push_back(t);
  if (edge_tris.empty() || edge_tris.size() > 2) return false;
  if ((flags_[u] & kBoundary) && (flags_[v] & kBoundary) && edge_tris.size() == 2) return false;
  // A corner attribute must have one value at each end on both sides of the
  // edge (else the edge ends a seam, which the collapse would move).
  if (edge_tris.size() == 2)
    for (size_t a = 0; a < corner_attrs_.size(); ++a) {
      const uint32_t n = in_.attributes[corner_attrs_[a]].components;
      for (uint32_t w : {u, v}) {
        const float* val[2];
        for (int i = 0; i < 2; ++i)
          for (int k = 0; k < 3; ++k)
            if (tri_[edge_tris[i]][k] == w) val[i] = &cvalues_[a][static_cast<size_t>(cindex_[a][edge_tris[i]][k]) * n];
        if (std::memcmp(val[0], val[1], n * sizeof(float)) != 0) return false;
      }
    }
  std::vector<uint32_t>&nu = topo_nu_, &nv = topo_nv_, &opposite = topo_opposite_, &common = topo_common_;
  nu.clear(), nv.clear(), opposite.clear(), common.clear();
  for (uint32_t t : vtris_[u])
    for (uint32_t w : tri_[t])
      if (w != u) nu.push_back(w);
  for (uint32_t t : vtris_[v])
    for (uint32_t w : tri_[t])
      if (w != v) nv.push_back(w);
  for (uint32_t t : edge_tris)
    for (uint32_t w : tri_[t])
      if (w != u && w != v) opposite.push_back(w);
  for (auto* s : {&nu, &nv, &opposite}) {
    std::sort(s->begin(), s->end());
    s->erase(std::unique(s->begin(), s->end()), s->end());
  }
  std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
  common.erase(std::remove_if(common.begin(), common.end(), [&](uint32_t w) { return w == u || w == v; }),
               common.end());
  if (common != opposite) return false;
  // No triangle may come to repeat another (a tetrahedron's last collapse),
  // and v keeps at least one triangle (no component vanishes).
  size_t remaining = 0;
  for (uint32_t t : vtris_[u]) {
    if (std::find(edge_tris.begin(), edge_tris.end(), t) != edge_tris.end()) continue;
    ++remaining;
    uint32_t a = 0, b = 0;
    int k = 0;
    for (uint32_t w : tri_[t])
      if (w != u) (k++ == 0 ? a : b) = w;
    for (uint32_t s : vtris_[v]) {
      const auto& c = tri_[s];
      const bool has_a = c[0] == a || c[1] == a || c[2] == a, has_b = c[0] == b || c[1] == b || c[2] == b;
      if (has_a && has_b) return false;
    }
  }
  for (uint32_t t : vtris_[v])
    if (std::find(edge_tris.begin(), edge_tris.end(), t) == edge_tris.end()) ++remaining;
  if (remaining == 0) return false;
  // Every edge-connected piece of surface keeps a triangle (the fans of a
  // non-manifold vertex are pieces of their own).
  for (uint32_t t : edge_tris) {
    uint32_t gone = 0;
    for (uint32_t s : edge_tris) gone += comp_[s] == comp_[t];
    if (comp_live_[comp_[t]] <= gone) return false;
  }
  return true;
}

// Pieces of the changed triangles onto the new triangles (or the unchanged
// ones around); the assignments go to placed_ (whole pieces) and
// placed_new_ (the parts of cut ones). A piece of T within delta of T is
// within delta + h of T's new shape, h = the largest distance of T's
// corners to it (the distance to a triangle is convex, so no point of T is
// farther; only the moved corner counts): most pieces stay by that sum
// alone; the others are checked corner by corner.
bool Simplifier::assign_pieces(const std::vector<uint32_t>& changed) {
  placed_.clear();
  placed_new_.clear();
  cut_.clear();
  shifted_.clear();
  takers_.clear();
  tri_gen_ += 2;
  for (uint32_t t : changed) tri_mark_[t] = tri_gen_;
  for (uint32_t t : new_tris_) add_taker(t, new_corner(t, 0), new_corner(t, 1), new_corner(t, 2));
  near_added_ = false;
  last_taker_ = 0;
  const double e = std::sqrt(e2_);
  for (uint32_t t : changed) {
    // h: the farthest corner of t from its own new shape (none when t goes).
    size_t self = takers_.size();
    for (size_t k = 0; k < new_tris_.size(); ++k)
      if (new_tris_[k] == t) self = k;
    double h = std::numeric_limits<double>::infinity();
    if (self < takers_.size()) {
      const Piece whole{{pos_[tri_[t][0]], pos_[tri_[t][1]], pos_[tri_[t][2]]}, 0, 0, 0};
      h = std::sqrt(fit2(whole, takers_[self], e2_));
    }
    if (tri_max_delta_[t] + h <= e) {
      shifted_.push_back({t, h});
      continue;
    }
    for (const PieceRef& r : tri_pieces_[t]) {
      const uint32_t pi = r.piece;
      const double delta = r.delta + tri_offset_[t];
      if (delta + h <= e) {
        placed_.push_back({t, pi, r.orig, delta + h});
        continue;
      }
      const size_t before = placed_new_.size();
      if (!assign_piece(pieces_[pi])) return false;
      if (placed_new_.size() == before + 1 && placed_new_.back().second.depth == pieces_[pi].depth) {
        // Taken whole: the piece stays (with its new bound).
        placed_.push_back({placed_new_.back().first, pi, r.orig, placed_new_.back().second.delta});
        placed_new_.pop_back();
      } else {
        cut_.push_back(pi);
      }
    }
  }
  return true;
}

void Simplifier::add_taker(uint32_t t, Vec3 a, Vec3 b, Vec3 c) {
  takers_.push_back({{a, b, c},
                     {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})},
                     {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})},
                     t});
}

// The unchanged triangles around the new ring, as takers after the new
// triangles: added when a piece first fits no new triangle.
void Simplifier::add_near_takers() {
  near_added_ = true;
  for (uint32_t t : new_tris_)
    for (uint32_t w : tri_[t])
      if (w != cu_ && w != cv_)
        for (uint32_t s : vtris_[w])
          if (tri_mark_[s] != tri_gen_ && tri_mark_[s] != tri_gen_ + 1) {
            tri_mark_[s] = tri_gen_ + 1;
            add_taker(s, pos_[tri_[s][0]], pos_[tri_[s][1]], pos_[tri_[s][2]]);
          }
}

// The largest squared distance of the piece's corners to the taker, or
// more than `limit2` as soon as one is (a box test first: most takers are
// far from most pieces).
double Simplifier::fit2(const Piece& pc, const Taker& k, double limit2) const {
  for (const Vec3& p : pc.p) {
    const double dx = std::max({k.lo.x - p.x, p.x - k.hi.x, 0.0}), dy = std::max({k.lo.y - p.y, p.y - k.hi.y, 0.0}),
                 dz = std::max({k.lo.z - p.z, p.z - k.hi.z, 0.0});
    if (dx * dx + dy * dy + dz * dz > limit2) return std::numeric_limits<double>::infinity();
  }
  double worst = 0;
  for (const Vec3& p : pc.p) {
    worst = std::max(worst, geom::point_triangle_dist2(p, k.p[0], k.p[1], k.p[2]));
    if (worst > limit2) return std::numeric_limits<double>::infinity();
  }
  return worst;
}

// The piece to the first taker from `from` on within E of its corners,
// trying the last one that took a piece first (the pieces of one triangle
// come in order, neighbours mostly go together).
bool Simplifier::take(const Piece& pc, size_t from) {
  for (size_t j = from; j <= takers_.size(); ++j) {
    const size_t i = j == from ? last_taker_ : j - 1;
    if (i < from || i >= takers_.size() || (j > from && i == last_taker_)) continue;
    const double d2 = fit2(pc, takers_[i], e2_);
    if (d2 <= e2_) {
      Piece taken = pc;
      taken.delta = std::sqrt(d2);
      placed_new_.push_back({takers_[i].t, taken});
      last_taker_ = i;
      return true;
    }
  }
  return false;
}

// The piece to a new triangle, else to an unchanged one around, else cut
// in four.
bool Simplifier::assign_piece(const Piece& pc) {
  if (take(pc, 0)) return true;
  if (!near_added_) {
    const size_t first_near = takers_.size();
    add_near_takers();
    if (take(pc, first_near)) return true;
  }
  if (pc.depth >= kMaxPieceDepth) return false;
  const Vec3 m01 = (pc.p[0] + pc.p[1]) * 0.5, m12 = (pc.p[1] + pc.p[2]) * 0.5, m20 = (pc.p[2] + pc.p[0]) * 0.5;
  const Vec3 parts[4][3] = {{pc.p[0], m01, m20}, {m01, pc.p[1], m12}, {m20, m12, pc.p[2]}, {m01, m12, m20}};
  for (const auto& q : parts) {
    Piece child;
    child.p[0] = q[0], child.p[1] = q[1], child.p[2] = q[2];
    child.depth = pc.depth + 1;
    child.orig = pc.orig;
    if (!assign_piece(child)) return false;
  }
  return true;
}

// The cache entry of p in this try_collapse (its bounds computed when first
// asked).
Simplifier::NearEntry& Simplifier::near_entry(Vec3 p) {
  if (2 * (near_used_ + 1) > near_cache_.size()) {
    // Full: start again twice as large (the entries are only a cache).
    near_cache_.assign(2 * near_cache_.size(), {});
    near_gen_ = 1, near_used_ = 0;
  }
  uint64_t bits[3];
  std::memcpy(&bits[0], &p.x, 8), std::memcpy(&bits[1], &p.y, 8), std::memcpy(&bits[2], &p.z, 8);
  uint64_t h =
      (bits[0] * 0x9E3779B97F4A7C15ull) ^ (bits[1] * 0xC2B2AE3D27D4EB4Full) ^ (bits[2] * 0x165667B19E3779F9ull);
  const size_t mask = near_cache_.size() - 1;
  size_t i = static_cast<size_t>(h ^ (h >> 29)) & mask;
  for (; near_cache_[i].gen == near_gen_; i = (i + 1) & mask) {
    NearEntry& c = near_cache_[i];
    if (c.p.x == p.x && c.p.y == p.y && c.p.z == p.z) return c;
  }
  NearEntry& c = near_cache_[i];
  c.p = p, c.gen = near_gen_, c.has_ring = false, c.has_exact = false;
  ++near_used_;
  return c;
}

// Through the ring: min over its triangles T of d(p, T) + tri_err_[T].
Simplifier::Near Simplifier::ring_bound(Vec3 p) {
  NearEntry& c = near_entry(p);
  if (c.has_ring) return c.ring;
  c.has_ring = true;
  c.ring = {std::numeric_limits<double>::infinity(), -1};
  for (size_t k = 0; k < ring_.size(); ++k) {
    const uint32_t t = ring_[k];
    const double e = tri_err_[t];
    if (e >= c.ring.b) continue;
    const double d2 = geom::point_triangle_dist2(p, pos_[tri_[t][0]], pos_[tri_[t][1]], pos_[tri_[t][2]]);
    const double r = c.ring.b - e;
    if (d2 >= r * r) continue;
    c.ring = {std::sqrt(d2) + e, -1 - static_cast<int64_t>(k)};
  }
  return c.ring;
}

// The distance to the original itself (its nearest triangle, through the
// BVH).
Simplifier::Near Simplifier::exact_bound(Vec3 p, int64_t hint) {
  NearEntry& c = near_entry(p);
  if (!c.has_exact) {
    double d2;
    const int64_t t = bvh_.nearest(p, d2, hint);
    c.exact = {std::sqrt(d2), t, true};
    c.has_exact = true;
  }
  return c.exact;
}

// The smallest bound of d(x, original) over the points x of the triangle p
// that one test proves (+inf when none): convexity of the distance to one
// triangle (a corner's reference triangle, plus its own error), or the
// corners' bounds plus the covering radius (the distance is 1-Lipschitz).
double Simplifier::leaf_bound(const Vec3 p[3], const Near n[3]) const {
  double best = std::max({n[0].b, n[1].b, n[2].b}) + longest_edge(p[0], p[1], p[2]) / std::sqrt(3.0);
  const double e = std::sqrt(e2_);
  for (int k = 0; k < 3; ++k) {
    const int64_t ref = n[k].ref;
    if ((k > 0 && ref == n[0].ref) || (k > 1 && ref == n[1].ref)) continue;
    Vec3 a, b, c;
    double own = 0;
    if (ref >= 0) {
      a = orig_.corner(static_cast<size_t>(ref), 0), b = orig_.corner(static_cast<size_t>(ref), 1),
      c = orig_.corner(static_cast<size_t>(ref), 2);
    } else {
      const uint32_t t = ring_[static_cast<size_t>(-1 - ref)];
      a = pos_[tri_[t][0]], b = pos_[tri_[t][1]], c = pos_[tri_[t][2]], own = tri_err_[t];
    }
    const double limit = std::min(best, e) - own;  // only a better bound within E is of use
    if (!(limit >= 0)) continue;
    double worst2 = 0;
    for (int j = 0; j < 3 && worst2 <= limit * limit; ++j)
      worst2 = std::max(worst2, geom::point_triangle_dist2(p[j], a, b, c));
    if (worst2 <= limit * limit) best = std::min(best, std::sqrt(worst2) + own);
  }
  return best;
}

// The new triangle t within E of one original triangle of local_orig_;
// err gets its largest corner distance.
bool Simplifier::near_local_original(uint32_t t, double& err) {
  const Vec3 a = new_corner(t, 0), b = new_corner(t, 1), c = new_corner(t, 2);
  const Vec3 lo{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
  const Vec3 hi{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
  for (LocalOrig& o : local_orig_) {
    if (!o.ready) fill_local_orig(o);
    if (lo.x < o.lo.x || lo.y < o.lo.y || lo.z < o.lo.z || hi.x > o.hi.x || hi.y > o.hi.y || hi.z > o.hi.z) continue;
    double worst = geom::point_triangle_dist2(a, o.p[0], o.p[1], o.p[2]);
    if (worst > e2_) continue;
    worst = std::max(worst, geom::point_triangle_dist2(b, o.p[0], o.p[1], o.p[2]));
    if (worst > e2_) continue;
    worst = std::max(worst, geom::point_triangle_dist2(c, o.p[0], o.p[1], o.p[2]));
    if (worst > e2_) continue;
    err = std::sqrt(worst);
    return true;
  }
  return false;
}

void Simplifier::fill_local_orig(LocalOrig& l) const {
  const Vec3 a = orig_.corner(l.o, 0), b = orig_.corner(l.o, 1), c = orig_.corner(l.o, 2);
  // Grown a little more than E: the box test only skips what the distances
  // would refuse.
  const double g = std::sqrt(e2_) * (1 + 1e-9);
  l.p[0] = a, l.p[1] = b, l.p[2] = c;
  l.lo = {std::min({a.x, b.x, c.x}) - g, std::min({a.y, b.y, c.y}) - g, std::min({a.z, b.z, c.z}) - g};
  l.hi = {std::max({a.x, b.x, c.x}) + g, std::max({a.y, b.y, c.y}) + g, std::max({a.z, b.z, c.z}) + g};
  l.ready = true;
}

// The new triangle t within E of the original; err gets the bound proved.
bool Simplifier::within_original(uint32_t tri, double& err) {
  Vec3 p[3];
  Near n[3];
  for (int k = 0; k < 3; ++k) {
    p[k] = new_corner(tri, k);
    n[k] = ring_bound(p[k]);
  }
  err = 0;
  return within_original_rec(p, n, 0, err);
}

// p: corners, n: their bounds (the new triangle's corners through the
// ring, cut points through a corner of the part cut: its bound plus the
// distance to it, the distance being 1-Lipschitz). A part those bounds do
// not prove is tried with the distances to the original at its corners
// (through the BVH), then cut in four; err gets the largest bound of the
// parts proved.
bool Simplifier::within_original_rec(const Vec3 p[3], Near n[3], uint32_t depth, double& err) {
  const double e = std::sqrt(e2_);
  double b = leaf_bound(p, n);
  if (b <= e) {
    err = std::max(err, b);
    return true;
  }
  if (!n[0].exact || !n[1].exact || !n[2].exact) {
    int64_t hint = -1;
    for (int k = 0; k < 3; ++k)
      if (n[k].ref >= 0) hint = n[k].ref;
    // A corner farther than E from the original is a point no bound can
    // prove: refused at once.
    for (int k = 0; k < 3; ++k) {
      if (!n[k].exact) n[k] = exact_bound(p[k], hint);
      if (!(n[k].b <= e)) return false;
      hint = n[k].ref;
    }
    b = leaf_bound(p, n);
    if (b <= e) {
      err = std::max(err, b);
      return true;
    }
  }
  if (depth >= kMaxCheckDepth) return false;
  const Vec3 m[3] = {(p[0] + p[1]) * 0.5, (p[1] + p[2]) * 0.5, (p[2] + p[0]) * 0.5};
  Near nm[3];
  for (int k = 0; k < 3; ++k) {
    const Near& a = n[k];
    const Near& c = n[(k + 1) % 3];
    const Near& near = a.b <= c.b ? a : c;
    nm[k] = {near.b + geom::length(p[(k + 1) % 3] - p[k]) * 0.5, near.ref, false};
  }
  const Vec3 c0[3] = {p[0], m[0], m[2]}, c1[3] = {m[0], p[1], m[1]}, c2[3] = {m[2], m[1], p[2]},
             c3[3] = {m[0], m[1], m[2]};
  Near n0[3] = {n[0], nm[0], nm[2]}, n1[3] = {nm[0], n[1], nm[1]}, n2[3] = {nm[2], nm[1], n[2]},
       n3[3] = {nm[0], nm[1], nm[2]};
  return within_original_rec(c3, n3, depth + 1, err) && within_original_rec(c0, n0, depth + 1, err) &&
         within_original_rec(c1, n1, depth + 1, err) && within_original_rec(c2, n2, depth + 1, err);
}

// Collapse u into v placed at x: flips, degeneracy and the bound.
bool Simplifier::attempt(uint32_t u, uint32_t v, Vec3 x, const std::vector<uint32_t>& edge_tris) {
  cu_ = u, cv_ = v, cx_ = geom::to_float(x);
  const bool moved = !(cx_.x == pos_[v].x && cx_.y == pos_[v].y && cx_.z == pos_[v].z);
  changed_.clear();
  new_tris_.clear();
  for (uint32_t t : vtris_[u]) changed_.push_back(t);
  if (moved)
    for (uint32_t t : vtris_[v])
      if (std::find(edge_tris.begin(), edge_tris.end(), t) == edge_tris.end()) changed_.push_back(t);
  for (uint32_t t : changed_) {
    if (std::find(edge_tris.begin(), edge_tris.end(), t) != edge_tris.end()) continue;
    new_tris_.push_back(t);
    const Vec3 a = pos_[tri_[t][0]], b = pos_[tri_[t][1]], c = pos_[tri_[t][2]];
    const Vec3 na = new_corner(t, 0), nb = new_corner(t, 1), nc = new_corner(t, 2);
    const Vec3 n_old = geom::cross(b - a, c - a), n_new = geom::cross(nb - na, nc - na);
    const double l = longest_edge(na, nb, nc);
    if (!(geom::length(n_new) > 1e-6 * l * l)) return false;  // degenerate
    if (!(geom::dot(n_old, n_new) > 0)) return false;         // flipped (90 degrees or more)
  }
  if (!bounded_) return true;
  // First the original triangles whose pieces the changed triangles hold:
  // a new triangle within E of one of them needs no search. One longer than
  // 2 E + the longest original edge cannot be (corners within E of one
  // triangle are at most that far apart): not tried that way.
  const double e = std::sqrt(e2_), reach = (2 * e + longest_orig_edge_) * (1 + 1e-9);
  new_err_.resize(new_tris_.size());
  local_tried_.assign(new_tris_.size(), 0);
  bool any_local = false;
  for (size_t i = 0; i < new_tris_.size(); ++i) {
    const uint32_t t = new_tris_[i];
    local_tried_[i] = longest_edge(new_corner(t, 0), new_corner(t, 1), new_corner(t, 2)) <= reach;
    any_local = any_local || local_tried_[i];
  }
  local_orig_.clear();
  ++orig_mark_gen_;
  for (size_t i = 0; any_local && i < changed_.size() && local_orig_.size() < 64; ++i)
    for (const PieceRef& r : tri_pieces_[changed_[i]]) {
      const uint32_t o = r.orig;
      if (orig_mark_[o] == orig_mark_gen_) continue;
      if (local_orig_.size() >= 64) break;
      orig_mark_[o] = orig_mark_gen_;
      local_orig_.push_back({o, false, {}, {}, {}});
    }
  for (size_t i = 0; i < new_tris_.size(); ++i)
    if (!(local_tried_[i] && near_local_original(new_tris_[i], new_err_[i])) &&
        !within_original(new_tris_[i], new_err_[i]))
      return false;
  return assign_pieces(changed_);
}

// The piece to triangle t's list with the bound delta (relative to t's
// offset; t's largest bound raised to what the list will read back).
void Simplifier::hold(uint32_t t, uint32_t piece, uint32_t orig, double delta) {
  const double rel = delta - tri_offset_[t];
  tri_pieces_[t].push_back({piece, orig, rel});
  tri_max_delta_[t] = std::max({tri_max_delta_[t], rel + tri_offset_[t], delta});
}

void Simplifier::commit(uint32_t u, uint32_t v) {
  // Interpolation parameter of the new position along u -> v (0 at u, 1 at v).
  const Vec3 e = pos_[v] - pos_[u];
  const double ee = geom::dot(e, e);
  const double s = ee > 0 ? std::clamp(geom::dot(cx_ - pos_[u], e) / ee, 0.0, 1.0) : 1.0;
  for (size_t a = 0; a < vertex_attrs_.size(); ++a) {
    const Attribute& at = in_.attributes[vertex_attrs_[a]];
    const uint32_t n = at.components;
    float* pv = &vvalues_[a][static_cast<size_t>(v) * n];
    const float* pu = &vvalues_[a][static_cast<size_t>(u) * n];
    for (uint32_t k = 0; k < n; ++k) pv[k] = static_cast<float>(pu[k] + (pv[k] - pu[k]) * s);
    if (at.kind == AttributeKind::normal && n == 3) {
      const double l = std::sqrt(double(pv[0]) * pv[0] + double(pv[1]) * pv[1] + double(pv[2]) * pv[2]);
      if (l > 0)
        for (uint32_t k = 0; k < 3; ++k) pv[k] = static_cast<float>(pv[k] / l);
    }
  }
  // Corner attributes: u is not on a seam (it is not locked), so its corners
  // share one value. The corners that come to v take v's value on the edge
  // (v's value there is the same on both sides); when v moves (then v is not
  // on a seam either) every corner of v takes the interpolated value.
  std::vector<uint32_t>& edge_tris = commit_edge_tris_;
  edge_tris.clear();
  for (uint32_t t : vtris_[u])
    if (tri_[t][0] == v || tri_[t][1] == v || tri_[t][2] == v) edge_tris.push_back(t);
  const bool moved = !(cx_.x == pos_[v].x && cx_.y == pos_[v].y && cx_.z == pos_[v].z);
  for (size_t a = 0; a < corner_attrs_.size(); ++a) {
    const uint32_t n = in_.attributes[corner_attrs_[a]].components;
    uint32_t val_u = 0, val_v = 0;
    for (int k = 0; k < 3; ++k) {
      if (tri_[edge_tris[0]][k] == u) val_u = cindex_[a][edge_tris[0]][k];
      if (tri_[edge_tris[0]][k] == v) val_v = cindex_[a][edge_tris[0]][k];
    }
    uint32_t target = val_v;
    if (moved) {
      target = static_cast<uint32_t>(cvalues_[a].size() / n);
      for (uint32_t k = 0; k < n; ++k) {
        const float fu = cvalues_[a][static_cast<size_t>(val_u) * n + k],
                    fv = cvalues_[a][static_cast<size_t>(val_v) * n + k];
        cvalues_[a].push_back(static_cast<float>(fu + (fv - fu) * s));
      }
      for (uint32_t t : vtris_[v])
        for (int k = 0; k < 3; ++k)
          if (tri_[t][k] == v) cindex_[a][t][k] = target;
    }
    for (uint32_t t : vtris_[u])
      for (int k = 0; k < 3; ++k)
        if (tri_[t][k] == u) cindex_[a][t][k] = target;
  }
  // Topology: the edge's triangles go, u's others take v.
  for (uint32_t t : edge_tris) {
    tri_alive_[t] = 0;
    --live_;
    --comp_live_[comp_[t]];
    for (uint32_t w : tri_[t]) {
      auto& l = vtris_[w];
      l.erase(std::remove(l.begin(), l.end(), t), l.end());
    }
  }
  for (uint32_t t : vtris_[u]) {
    for (uint32_t& w : tri_[t])
      if (w == u) w = v;
    vtris_[v].push_back(t);
  }
  vtris_[u].clear();
  pos_[v] = cx_;
  flags_[v] = static_cast<uint8_t>(flags_[v] | (flags_[u] & kBoundary));
  flags_[u] |= kRemoved;
  quad_[v].add(quad_[u]);
  // The pieces: the changed triangles' lists are rebuilt from placed_.
  if (bounded_) {
    for (size_t i = 0; i < new_tris_.size(); ++i) tri_err_[new_tris_[i]] = new_err_[i];
    // Shifted triangles keep their lists (offset and largest bound + h); the
    // other changed ones are refilled from placed_.
    for (const Shift& sh : shifted_) {
      tri_offset_[sh.t] += sh.h;
      tri_max_delta_[sh.t] += sh.h;
    }
    for (uint32_t t : changed_)
      if (std::none_of(shifted_.begin(), shifted_.end(), [&](const Shift& sh) { return sh.t == t; })) {
        tri_pieces_[t].clear();
        tri_offset_[t] = 0;
        tri_max_delta_[t] = 0;
      }
    for (const Placed& pl : placed_) hold(pl.t, pl.piece, pl.orig, pl.delta);
    for (uint32_t pi : cut_) free_pieces_.push_back(pi);
    for (const auto& [t, pc] : placed_new_) {
      uint32_t pi;
      if (!free_pieces_.empty()) {
        pi = free_pieces_.back();
        free_pieces_.pop_back();
        pieces_[pi] = pc;
      } else {
        pi = static_cast<uint32_t>(pieces_.size());
        pieces_.push_back(pc);
      }
      hold(t, pi, pc.orig, pc.delta);
    }
  }
  ++collapses_;
  // New candidates: v's edges, and the refused edges of v's ring (each once).
  ++stamp_[v];
  refused_[u].clear();
  refused_[v].clear();
  push_edges_of(v);
  std::vector<std::pair<uint32_t, uint32_t>>& again = again_;
  again.clear();
  for (uint32_t t : vtris_[v])
    for (uint32_t w : tri_[t])
      if (w != v) {
        for (uint32_t x : refused_[w])
          if (x != v && !(flags_[x] & kRemoved)) again.push_back({std::min(w, x), std::max(w, x)});
        refused_[w].clear();
      }
  std::sort(again.begin(), again.end());
  again.erase(std::unique(again.begin(), again.end()), again.end());
  for (const auto& [a, b] : again) {
    Candidate c;
    if (candidate_for(a, b, c)) push(c);
  }
}

// Where the edge (a, b) may collapse to, cheapest first: the quadric
// optimum, the midpoint, the endpoints; only into a vertex that stays (not
// kLocked / kKeep going), only at a vertex that cannot move.
Simplifier::Places Simplifier::placements(uint32_t a, uint32_t b, const Quadric& q) const {
  Places places;
  auto can_go = [&](uint32_t w) { return !(flags_[w] & (kLocked | kKeep)); };
  auto can_move = [&](uint32_t w) { return !(flags_[w] & kLocked); };
  uint32_t u = a, v = b;  // u goes
  if (!can_go(u)) std::swap(u, v);
  if (!can_go(u)) return places;
  if (can_move(v)) {
    Vec3 x;
    if (q.optimum(x)) {
      // Only near the edge: a far optimum is a badly conditioned one.
      const Vec3 mid = (pos_[a] + pos_[b]) * 0.5;
      if (geom::length(x - mid) <= 2 * geom::length(pos_[b] - pos_[a])) places.push_back({q.eval(x), u, v, x});
    }
    places.push_back({q.eval((pos_[a] + pos_[b]) * 0.5), u, v, (pos_[a] + pos_[b]) * 0.5});
    if (can_go(v) && can_move(u)) places.push_back({q.eval(pos_[u]), v, u, pos_[u]});
  }
  places.push_back({q.eval(pos_[v]), u, v, pos_[v]});
  for (int i = 1; i < places.count; ++i)  // cheapest first, ties in the order above
    for (int j = i; j > 0 && places.at[j].cost < places.at[j - 1].cost; --j) std::swap(places.at[j], places.at[j - 1]);
  return places;
}

bool Simplifier::try_collapse(uint32_t a, uint32_t b) {
  std::vector<uint32_t>& edge_tris = edge_tris_;
  if (!topology_ok(a, b, edge_tris)) return false;
  clear_near_cache();
  ring_ = vtris_[a];
  for (uint32_t t : vtris_[b])
    if (std::find(edge_tris.begin(), edge_tris.end(), t) == edge_tris.end()) ring_.push_back(t);
  Quadric q = quad_[a];
  q.add(quad_[b]);
  for (const Place& p : placements(a, b, q))
    if (attempt(p.u, p.v, p.x, edge_tris)) {
      commit(p.u, p.v);
      return true;
    }
  return false;
}

void Simplifier::write(Mesh& out) const {
  out.clear();
  // Vertices: those not removed and still on a triangle (or on none in the
  // input), in order. (A collapse can take the last triangle of a vertex
  // next to it: an ear on a boundary.)
  std::vector<uint8_t> used(pos_.size(), 0);
  for (uint32_t t = 0; t < tri_.size(); ++t)
    if (tri_alive_[t])
      for (uint32_t w : tri_[t]) used[w] = 1;
  std::vector<uint32_t> remap(pos_.size(), UINT32_MAX);
  uint32_t nv = 0;
  for (uint32_t v = 0; v < pos_.size(); ++v)
    if (!(flags_[v] & kRemoved) && (used[v] || !had_faces_[v])) remap[v] = nv++;
  out.positions.reserve(3 * nv);
  for (uint32_t v = 0; v < pos_.size(); ++v)
    if (remap[v] != UINT32_MAX)
      out.add_vertex(static_cast<float>(pos_[v].x), static_cast<float>(pos_[v].y), static_cast<float>(pos_[v].z));
  std::vector<uint32_t> live;
  for (uint32_t t = 0; t < tri_.size(); ++t)
    if (tri_alive_[t]) live.push_back(t);
  for (uint32_t t : live) out.add_triangle(remap[tri_[t][0]], remap[tri_[t][1]], remap[tri_[t][2]]);
  // The triangles' source faces, for face attributes.
  std::vector<uint32_t> face_of = orig_.face_of;
  size_t vi = 0, ci = 0;
  for (size_t i = 0; i < in_.attributes.size(); ++i) {
    const Attribute& a = in_.attributes[i];
    Attribute r;
    r.name = a.name, r.kind = a.kind, r.domain = a.domain, r.type = a.type, r.components = a.components;
    const uint32_t n = a.components;
    if (a.domain == AttributeDomain::vertex) {
      const std::vector<float>& vals = vvalues_[vi++];
      for (uint32_t v = 0; v < pos_.size(); ++v)
        if (remap[v] != UINT32_MAX) r.values.insert(r.values.end(), vals.begin() + v * n, vals.begin() + (v + 1) * n);
    } else if (a.domain == AttributeDomain::face) {
      for (uint32_t t : live)
        r.values.insert(r.values.end(), a.values.begin() + face_of[t] * n, a.values.begin() + (face_of[t] + 1) * n);
    } else {
      // Corner values: only those still used, in order of first use.
      const std::vector<float>& vals = cvalues_[ci];
      const auto& idx = cindex_[ci++];
      std::vector<uint32_t> vmap(vals.size() / n, UINT32_MAX);
      for (uint32_t t : live)
        for (int k = 0; k < 3; ++k) {
          uint32_t& m = vmap[idx[t][k]];
          if (m == UINT32_MAX) {
            m = static_cast<uint32_t>(r.values.size() / n);
            r.values.insert(r.values.end(), vals.begin() + idx[t][k] * n, vals.begin() + (idx[t][k] + 1) * n);
          }
          r.indices.push_back(m);
        }
    }
    out.attributes.push_back(std::move(r));
  }
  out.metadata = in_.metadata;
}

// The heap without its stale entries (a smaller heap: fewer cache misses on
// every pop; the pop order, cost then edge, is the same).
void Simplifier::drop_stale() {
  heap_.filter([&](const Candidate& c) { return !stale(c); });
}

Status Simplifier::run(Mesh& out, SimplifyReport& report) {
  bounded_ = o_.max_error > 0;
  e2_ = bounded_ ? o_.max_error * o_.max_error : std::numeric_limits<double>::infinity();
  build();
  find_locked();
  init_quadrics();
  report.faces_in = tri_.size();
  report.vertices_in = pos_.size();
  for (uint32_t v = 0; v < pos_.size(); ++v) push_edges_of(v, true);
  uint64_t since = 0, pops_since_drop = 0;
  while (!heap_.empty() && live_faces() > o_.target_faces) {
    // A live triangle has three edges, most shared by two: most of a heap of
    // more than 4 entries per live triangle are stale. (At most once per
    // size/4 pops: linear time overall even when they are not.)
    if (heap_.size() > 4 * live_ + 4096 && 4 * ++pops_since_drop > heap_.size()) {
      drop_stale();
      pops_since_drop = 0;
    }
    const Candidate c = heap_.pop();
    if (stale(c)) continue;
    if (!try_collapse(c.u, c.v)) {
      ++rejected_;
      refused_[c.u].push_back(c.v);
      refused_[c.v].push_back(c.u);
    }
    if (o_.progress && ++since >= 256) {
      since = 0;
      o_.progress(live_faces(), report.faces_in, o_.progress_user);
    }
  }
  write(out);
  report.faces_out = out.face_count();
  report.vertices_out = out.vertex_count();
  report.collapses = collapses_;
  report.rejected = rejected_;
  report.locked_vertices = locked_count_;
  report.face_error.clear();
  if (bounded_)
    for (uint32_t t = 0; t < tri_.size(); ++t)
      if (tri_alive_[t]) {
        report.face_error.push_back(tri_err_[t]);
        report.result_error = std::max(report.result_error, tri_err_[t]);
      }
  return Status::Ok();
}

}  // namespace

Status simplify(const Mesh& in, const SimplifyOptions& options, Mesh& out, SimplifyReport* report) {
  std::string why;
  if (!in.valid(&why)) return Status(ErrorCode::invalid_argument, "simplify: the mesh is not consistent: " + why);
  if (!(options.max_error >= 0) || !std::isfinite(options.max_error))
    return Status(ErrorCode::invalid_argument, "simplify: the maximum error must be a finite number >= 0");
  if (options.max_error == 0 && options.target_faces == 0)
    return Status(ErrorCode::invalid_argument,
                  "simplify: give a maximum error, a target face count, or both (with neither nothing would change)");
  for (float v : in.positions)
    if (!std::isfinite(v)) return Status(ErrorCode::invalid_argument, "simplify: a position is NaN or infinite");
  SimplifyReport local;
  Simplifier s(in, options);
  return s.run(out, report ? *report : local);
}

}  // namespace tsm
