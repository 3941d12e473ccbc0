// Keep-order (FORMAT.md §4.9): the permutation from the decoder's vertex
// and face order back to the input's, and each face's first corner, coded
// relative to the decoded mesh so that an input whose order is coherent
// (scan lines, volume sweeps, faces next to the face before) costs little.
// Vertices come first, in input order: each is a pick from the unused
// neighbours of the vertex before it (the one that continues the step from
// the vertex before that first), or an escape: a jump in sweep order (the
// unused vertices sorted by slab along one axis, then by the other two
// coordinates), which follows the scan or volume sweep that wrote the file.
// Faces follow, in input order: a corner from the window of the last faces
// (most recent first) and a pick from the unused faces at it (those sharing
// an edge with the face before first), or an escape (a jump in face sweep
// order: by the sweep position of their first-swept corner); then the turn
// from that corner to the face's first, for a triangle in the context of
// its corners' labels (the lattice axis a marching-cubes vertex lies along,
// which coordinates are the triangle's smallest, corners of the face
// before). Vertex and window picks are coded in the context of whether
// the vertex (face) before was a pick, face picks in that of the window
// corner's place.
#include "order_coding.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "connectivity.hpp"
#include "range_coder.hpp"

namespace tsm {

namespace {

constexpr size_t kMaxCandidates = 16;
constexpr uint32_t kPickContexts = 5;

// Adjacency of the decoded mesh, shared by the encoder and the decoder.
struct OrderContext {
  const Mesh& m;
  std::vector<uint32_t> inc_start, inc;  // vertex -> faces using it (increasing)
  std::vector<uint32_t> nbr_start, nbr;  // vertex -> vertices on an edge with it (increasing)
  std::vector<uint8_t> face_used, vertex_used;

  explicit OrderContext(const Mesh& mesh) : m(mesh) {
    const size_t V = m.vertex_count(), F = m.face_count();
    inc_start.assign(V + 1, 0);
    for (uint32_t x : m.indices) ++inc_start[x + 1];
    for (size_t v = 0; v < V; ++v) inc_start[v + 1] += inc_start[v];
    inc.resize(m.indices.size());
    std::vector<uint32_t> at(inc_start.begin(), inc_start.end() - 1);
    for (uint32_t f = 0; f < F; ++f)
      for (uint32_t k = 0; k < m.face_size(f); ++k) inc[at[m.face(f)[k]]++] = f;
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    edges.reserve(2 * m.indices.size());
    for (uint32_t f = 0; f < F; ++f) {
      const uint32_t n = m.face_size(f);
      const uint32_t* c = m.face(f);
      for (uint32_t k = 0; k < n; ++k) {
        const uint32_t a = c[k], b = c[(k + 1) % n];
        if (a == b) continue;
        edges.emplace_back(a, b);
        edges.emplace_back(b, a);
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    nbr_start.assign(V + 1, 0);
    for (const auto& e : edges) ++nbr_start[e.first + 1];
    for (size_t v = 0; v < V; ++v) nbr_start[v + 1] += nbr_start[v];
    nbr.resize(edges.size());
    for (size_t i = 0; i < edges.size(); ++i) nbr[i] = edges[i].second;
    face_used.assign(F, 0);
    vertex_used.assign(V, 0);
  }

  // The unused neighbours of `prev`; after a step from `prev2` (kNone:
  // none) the one that continues it furthest first (largest dot product of
  // the two steps, in double, then by id).
  void vertex_candidates(uint32_t prev, uint32_t prev2, std::vector<uint32_t>& out) const {
    out.clear();
    if (prev == kNone) return;
    for (uint32_t i = nbr_start[prev]; i < nbr_start[prev + 1] && out.size() < kMaxCandidates; ++i)
      if (!vertex_used[nbr[i]]) out.push_back(nbr[i]);
    if (prev2 == kNone || out.size() < 2) return;
    std::vector<std::pair<double, uint32_t>> key;
    const float* p = m.positions.data();
    for (uint32_t c : out) {
      double dot = 0;
      for (int a = 0; a < 3; ++a)
        dot += (double(p[3 * size_t{c} + a]) - double(p[3 * size_t{prev} + a])) *
               (double(p[3 * size_t{prev} + a]) - double(p[3 * size_t{prev2} + a]));
      key.emplace_back(std::isfinite(dot) ? -dot : HUGE_VAL, c);
    }
    std::sort(key.begin(), key.end());
    for (size_t i = 0; i < out.size(); ++i) out[i] = key[i].second;
  }

  // The unused faces at decoded vertex x, as (face, corner) pairs: those
  // with two or more vertices of face `prev` (kNone: none) first, then the
  // others, each group by face then corner.
  void face_candidates(uint32_t x, uint32_t prev, std::vector<std::pair<uint32_t, uint32_t>>& out) const {
    out.clear();
    std::vector<std::pair<uint32_t, uint32_t>> later;
    for (uint32_t i = inc_start[x]; i < inc_start[x + 1]; ++i) {
      const uint32_t f = inc[i];
      if (face_used[f] || (i > inc_start[x] && inc[i - 1] == f)) continue;
      const uint32_t* c = m.face(f);
      const uint32_t n = m.face_size(f);
      uint32_t shared = 0;
      if (prev != kNone) {
        const uint32_t* pc = m.face(prev);
        const uint32_t pn = m.face_size(prev);
        for (uint32_t k = 0; k < n; ++k)
          if (std::find(c, c + k, c[k]) == c + k && std::find(pc, pc + pn, c[k]) != pc + pn) ++shared;
      }
      for (uint32_t k = 0; k < n; ++k)
        if (c[k] == x) (shared >= 2 ? out : later).emplace_back(f, k);
    }
    out.insert(out.end(), later.begin(), later.end());
  }
};

// The sweep: axis orders (slab axis, then the next two) and the slab width
// 2^e. Vertices sort by floor(coordinate / 2^e) on the slab axis, then by
// the other two coordinates (as ordered float bits), then by id.
constexpr std::array<std::array<int, 3>, 6> kSweepAxes = {
    {{{0, 1, 2}}, {{0, 2, 1}}, {{1, 0, 2}}, {{1, 2, 0}}, {{2, 0, 1}}, {{2, 1, 0}}}};
constexpr int kSlabExponentBias = 128;

uint32_t ordered_bits(float x) {
  uint32_t b;
  std::memcpy(&b, &x, 4);
  return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}

int64_t slab_of(float x, int e) {
  const double q = std::ldexp(static_cast<double>(x), -e);  // exact
  constexpr double kLimit = 4611686018427387904.0;          // 2^62
  if (std::isnan(q)) return int64_t{1} << 62;
  if (q >= kLimit) return (int64_t{1} << 62) - 1;
  if (q <= -kLimit) return -(int64_t{1} << 62);
  return static_cast<int64_t>(std::floor(q));
}

// The sweep order of the vertices (sweep position -> vertex).
std::vector<uint32_t> vertex_sweep(const Mesh& m, int axes, int e) {
  const size_t V = m.vertex_count();
  const auto& ax = kSweepAxes[static_cast<size_t>(axes)];
  struct Key {
    int64_t slab;
    uint32_t b, c, v;
  };
  std::vector<Key> keys(V);
  const float* p = m.positions.data();
  for (uint32_t v = 0; v < V; ++v)
    keys[v] = {slab_of(p[3 * size_t{v} + static_cast<size_t>(ax[0])], e),
               ordered_bits(p[3 * size_t{v} + static_cast<size_t>(ax[1])]),
               ordered_bits(p[3 * size_t{v} + static_cast<size_t>(ax[2])]), v};
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    if (a.slab != b.slab) return a.slab < b.slab;
    if (a.b != b.b) return a.b < b.b;
    if (a.c != b.c) return a.c < b.c;
    return a.v < b.v;
  });
  std::vector<uint32_t> order(V);
  for (uint32_t i = 0; i < V; ++i) order[i] = keys[i].v;
  return order;
}

// The sweep order of the faces: by the smallest sweep position among their
// corners, then by id.
std::vector<uint32_t> face_sweep(const Mesh& m, const std::vector<uint32_t>& vertex_at) {
  const size_t F = m.face_count();
  std::vector<std::pair<uint32_t, uint32_t>> keys(F);
  for (uint32_t f = 0; f < F; ++f) {
    uint32_t low = kNone;
    for (uint32_t k = 0; k < m.face_size(f); ++k) low = std::min(low, vertex_at[m.face(f)[k]]);
    keys[f] = {low, f};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(F);
  for (uint32_t i = 0; i < F; ++i) order[i] = keys[i].second;
  return order;
}

// The items not taken yet in a given order, as a Fenwick tree of 0/1 over
// the positions: rank of an item among the untaken ones, the untaken item
// of a given rank.
struct RankTree {
  std::vector<uint32_t> order, at;  // position -> item, item -> position
  std::vector<uint32_t> tree;
  uint32_t top = 1;

  explicit RankTree(std::vector<uint32_t> items) : order(std::move(items)) {
    const size_t n = order.size();
    at.resize(n);
    for (uint32_t i = 0; i < n; ++i) at[order[i]] = i;
    tree.assign(n + 1, 0);
    for (size_t i = 1; i <= n; ++i) {
      tree[i] += 1;
      const size_t up = i + (i & (~i + 1));
      if (up <= n) tree[up] += tree[i];
    }
    while (top * 2 <= n) top *= 2;
  }
  // Untaken items before item x.
  uint32_t rank(uint32_t x) const {
    uint32_t r = 0;
    for (size_t i = at[x]; i > 0; i &= i - 1) r += tree[i];
    return r;
  }
  void take(uint32_t x) {
    for (size_t i = at[x] + size_t{1}; i < tree.size(); i += i & (~i + 1)) --tree[i];
  }
  // The untaken item with `r` untaken items before it (r < untaken count).
  uint32_t at_rank(uint32_t r) const {
    size_t i = 0;
    for (uint32_t step = top; step; step >>= 1)
      if (i + step < tree.size() && tree[i + step] <= r) {
        i += step;
        r -= tree[i];
      }
    return order[i];
  }
};

// The slab exponent near the median edge length of the mesh.
int median_edge_exponent(const Mesh& m, const std::vector<uint32_t>& nbr_start, const std::vector<uint32_t>& nbr) {
  std::vector<double> len;
  const float* p = m.positions.data();
  for (uint32_t v = 0; v + 1 < nbr_start.size(); ++v)
    for (uint32_t i = nbr_start[v]; i < nbr_start[v + 1]; ++i) {
      const uint32_t w = nbr[i];
      if (w < v) continue;
      double s = 0;
      for (int a = 0; a < 3; ++a) {
        const double d = double(p[3 * size_t{w} + a]) - double(p[3 * size_t{v} + a]);
        s += d * d;
      }
      if (std::isfinite(s) && s > 0) len.push_back(s);
    }
  if (len.empty()) return 0;
  std::nth_element(len.begin(), len.begin() + static_cast<std::ptrdiff_t>(len.size() / 2), len.end());
  const int e = static_cast<int>(std::floor(std::log2(std::sqrt(len[len.size() / 2]))));
  return std::clamp(e, -kSlabExponentBias + 2, 127 - 2);
}

// A triangle's turn is coded in a context of its three corners' labels
// (from the one it is picked at, 6 bits each) and whether it was picked.
constexpr uint32_t kLabelBits = 6;

struct OrderModels {
  UIntModel vertex_pick[2][kPickContexts], window_pick[2][kPickContexts], face_pick[kPickContexts][kPickContexts],
      turn[2];
  SIntModel vertex_jump, face_jump;
  std::unordered_map<uint32_t, BitTreeModel<2>> turn3;  // by context, fresh on first use
};

// Per decoded vertex, the lattice axis it lies along: a volume's marching
// cubes put every vertex on a lattice edge, so two of its coordinates sit on
// lattice planes, values that many vertices share. A coordinate is on a
// plane when at least 4 times the mean number of vertices (per distinct value
// on that axis) have it. The label is the one axis whose coordinate is not
// on a plane, or 3 (none, or more than one).
std::vector<uint8_t> lattice_axes(const Mesh& m) {
  const size_t V = m.vertex_count();
  std::vector<uint8_t> on(V, 0), out(V, 3);
  std::vector<std::pair<uint32_t, uint32_t>> vals(V);
  for (int a = 0; a < 3; ++a) {
    for (uint32_t v = 0; v < V; ++v) {
      uint32_t b;
      std::memcpy(&b, &m.positions[3 * size_t{v} + static_cast<size_t>(a)], 4);
      vals[v] = {b, v};
    }
    std::sort(vals.begin(), vals.end());
    uint64_t distinct = 0;
    for (size_t i = 0; i < V; ++i) distinct += i == 0 || vals[i].first != vals[i - 1].first;
    for (size_t i = 0, j; i < V; i = j) {
      for (j = i; j < V && vals[j].first == vals[i].first;) ++j;
      if (uint64_t{j - i} * distinct >= 4 * uint64_t{V})
        for (size_t k = i; k < j; ++k) on[vals[k].second] |= uint8_t(1u << a);
    }
  }
  for (size_t v = 0; v < V; ++v)
    for (uint8_t a = 0; a < 3; ++a)
      if (on[v] == (7u & ~(1u << a))) out[v] = a;
  return out;
}

// The turn context of triangle f picked (or not) at its corner k: per
// corner from k on, its lattice axis (2 bits), with `detail` which of its
// coordinates are the triangle's smallest on their axis (3 bits, else 0: a
// marching-cubes triangle lists its corners by the cube edges they lie on),
// and whether it is a corner of face `prev` (1 bit).
uint32_t turn_context(const Mesh& m, const std::vector<uint8_t>& axis, uint32_t f, uint32_t k, uint32_t prev,
                      bool picked, bool detail) {
  const uint32_t* c = m.face(f);
  const uint32_t* pc = prev == kNone ? nullptr : m.face(prev);
  const uint32_t pn = prev == kNone ? 0 : m.face_size(prev);
  const float* p = m.positions.data();
  uint32_t ctx = picked;
  for (uint32_t s = 0; s < 3; ++s) {
    const uint32_t x = c[(k + s) % 3];
    uint32_t low = 0;
    for (size_t a = 0; a < 3 && detail; ++a) {
      const float v = p[3 * size_t{x} + a];
      low = low * 2 + (v <= p[3 * size_t{c[0]} + a] && v <= p[3 * size_t{c[1]} + a] && v <= p[3 * size_t{c[2]} + a]);
    }
    const uint32_t shared = pc && std::find(pc, pc + pn, x) != pc + pn;
    ctx = (ctx << kLabelBits) | (uint32_t{axis[x]} << 4) | (low << 1) | shared;
  }
  return ctx;
}

uint32_t pick_context(size_t candidates) {
  return static_cast<uint32_t>(std::min<size_t>(candidates, kPickContexts - 1));
}

// The face window: the corners of the last kWindowFaces input faces (most
// recent first, each face's corners in order, each decoded vertex once, at
// most kWindowCorners) whose vertex still has an unused face. `left`: per
// decoded vertex its unused faces; `stamp`: scratch, one per vertex.
constexpr size_t kWindowFaces = 16, kWindowCorners = 64;

void window_candidates(const Mesh& m, const std::vector<uint32_t>& taken_faces, const std::vector<uint32_t>& rot,
                       const std::vector<uint32_t>& left, std::vector<uint32_t>& stamp, std::vector<uint32_t>& out) {
  out.clear();
  const size_t j = taken_faces.size();
  for (size_t t = 1; t <= kWindowFaces && t <= j && out.size() < kWindowCorners; ++t) {
    const uint32_t g = taken_faces[j - t], n = m.face_size(g);
    const uint32_t* c = m.face(g);
    for (uint32_t q = 0, k = rot[j - t]; q < n && out.size() < kWindowCorners; ++q, k = k + 1 == n ? 0 : k + 1) {
      const uint32_t x = c[k];
      if (left[x] == 0 || stamp[x] == j + 1) continue;
      stamp[x] = static_cast<uint32_t>(j + 1);
      out.push_back(x);
    }
  }
}

// Marks decoded face f taken: one unused face less at each of its vertices.
void take_face(const Mesh& m, uint32_t f, std::vector<uint32_t>& left) {
  const uint32_t* c = m.face(f);
  for (uint32_t k = 0; k < m.face_size(f); ++k)
    if (std::find(c, c + k, c[k]) == c + k) --left[c[k]];
}

std::vector<uint32_t> unused_faces_per_vertex(const Mesh& m) {
  std::vector<uint32_t> left(m.vertex_count(), 0);
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    for (uint32_t k = 0; k < m.face_size(f); ++k)
      if (std::find(c, c + k, c[k]) == c + k) ++left[c[k]];
  }
  return left;
}

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, "order section: " + what); }

}  // namespace

namespace {

// The order stream with the turn contexts' detail on or off.
std::string encode_order_with(const Mesh& decoded, const std::vector<uint32_t>& vertex_from,
                              const std::vector<uint32_t>& face_from, const std::vector<uint32_t>& first_corner,
                              bool detail) {
  const size_t V = decoded.vertex_count(), F = decoded.face_count();
  std::vector<uint32_t> faces(F), rot(F), vertices(V);  // input order -> decoded
  for (uint32_t f = 0; f < F; ++f) {
    faces[face_from[f]] = f;
    const uint32_t n = decoded.face_size(f);
    rot[face_from[f]] = (n - first_corner[f] % n) % n;
  }
  for (uint32_t v = 0; v < V; ++v) vertices[vertex_from[v]] = v;
  OrderContext ctx(decoded);
  OrderModels models;
  RangeEncoder e;
  std::vector<uint32_t> cand;
  // The picks first (they do not depend on the sweep), then the sweep whose
  // jumps cost least, then the stream.
  std::vector<uint32_t> pick(V), ncand(V);
  for (size_t i = 0; i < V; ++i) {
    const uint32_t v = vertices[i];
    const uint32_t prev = i ? vertices[i - 1] : kNone, prev2 = i > 1 ? vertices[i - 2] : kNone;
    ctx.vertex_candidates(prev, prev2, cand);
    const size_t at = std::find(cand.begin(), cand.end(), v) - cand.begin();
    ncand[i] = static_cast<uint32_t>(cand.size());
    pick[i] = at < cand.size() ? uint32_t(at + 1) : 0;
    ctx.vertex_used[v] = 1;
  }
  auto jump_cost = [&](int axes, int slab) {
    RankTree sweep(vertex_sweep(decoded, axes, slab));
    double bits = 0;
    for (size_t i = 0; i < V; ++i) {
      if (!pick[i]) {
        const double d = double(sweep.rank(vertices[i])) - (i ? double(sweep.rank(vertices[i - 1])) : 0.0);
        bits += 2 * std::log2(std::fabs(d) + 1) + 1;
      }
      sweep.take(vertices[i]);
    }
    return bits;
  };
  const int e0 = median_edge_exponent(decoded, ctx.nbr_start, ctx.nbr);
  int best_axes = 0, best_slab = e0 + 1;
  double best = HUGE_VAL;
  for (int a = 0; a < 6; ++a) {
    const double c = jump_cost(a, e0 + 1);
    if (c < best) best = c, best_axes = a;
  }
  for (int slab : {e0, e0 + 2}) {
    const double c = jump_cost(best_axes, slab);
    if (c < best) best = c, best_slab = slab;
  }
  e.direct(static_cast<uint32_t>(best_axes), 3);
  e.direct(static_cast<uint32_t>(best_slab + kSlabExponentBias), 8);
  e.direct(detail, 1);
  RankTree sweep(vertex_sweep(decoded, best_axes, best_slab));
  for (size_t i = 0; i < V; ++i) {
    const uint32_t v = vertices[i];
    if (ncand[i]) models.vertex_pick[i && pick[i - 1]][pick_context(ncand[i])].encode(e, pick[i]);
    if (!pick[i])
      models.vertex_jump.encode(
          e, static_cast<int32_t>(int64_t{sweep.rank(v)} - (i ? int64_t{sweep.rank(vertices[i - 1])} : 0)));
    sweep.take(v);
  }
  // Faces: a vertex of the window and a face at it, or a jump in face sweep
  // order; then the turn from that corner to the first.
  RankTree fsweep(face_sweep(decoded, sweep.at));
  const std::vector<uint8_t> axis = lattice_axes(decoded);
  std::vector<uint32_t> left = unused_faces_per_vertex(decoded), stamp(V, 0), taken, taken_rot;
  std::vector<std::pair<uint32_t, uint32_t>> fc;
  bool last_picked = false;  // the face before was picked from the window
  for (size_t j = 0; j < F; ++j) {
    const uint32_t f = faces[j], n = decoded.face_size(f), prev = j ? faces[j - 1] : kNone;
    window_candidates(decoded, taken, taken_rot, left, stamp, cand);
    size_t at = cand.size();
    for (size_t i = 0; i < cand.size() && at == cand.size(); ++i)
      if (std::find(decoded.face(f), decoded.face(f) + n, cand[i]) != decoded.face(f) + n) at = i;
    if (!cand.empty())
      models.window_pick[last_picked][pick_context(cand.size())].encode(e, at < cand.size() ? uint32_t(at + 1) : 0);
    last_picked = at < cand.size();
    uint32_t k = 0;
    if (at < cand.size()) {
      ctx.face_candidates(cand[at], prev, fc);
      size_t q = 0;
      while (fc[q].first != f) ++q;
      if (fc.size() > 1)
        models.face_pick[pick_context(at)][pick_context(fc.size())].encode(e, static_cast<uint32_t>(q));
      k = fc[q].second;
    } else {
      models.face_jump.encode(
          e, static_cast<int32_t>(int64_t{fsweep.rank(f)} - (prev == kNone ? 0 : int64_t{fsweep.rank(prev)})));
    }
    if (n == 3)
      models.turn3[turn_context(decoded, axis, f, k, prev, at < cand.size(), detail)].encode(e, (rot[j] + n - k) % n);
    else if (n > 1)
      models.turn[at < cand.size()].encode(e, (rot[j] + n - k) % n);
    ctx.face_used[f] = 1;
    fsweep.take(f);
    take_face(decoded, f, left);
    taken.push_back(f);
    taken_rot.push_back(rot[j]);
  }
  return e.finish();
}

}  // namespace

// Both turn context sets are tried; the smaller stream is kept (the
// detailed one pays on lattice meshes, dilutes the statistics elsewhere).
std::string encode_order(const Mesh& decoded, const std::vector<uint32_t>& vertex_from,
                         const std::vector<uint32_t>& face_from, const std::vector<uint32_t>& first_corner) {
  std::string a = encode_order_with(decoded, vertex_from, face_from, first_corner, false);
  std::string b = encode_order_with(decoded, vertex_from, face_from, first_corner, true);
  return b.size() < a.size() ? b : a;
}

Status decode_order(std::string_view payload, Mesh& mesh) {
  const size_t V = mesh.vertex_count(), F = mesh.face_count();
  OrderContext ctx(mesh);
  OrderModels models;
  RangeDecoder d(payload);
  std::vector<uint32_t> cand, faces(F), rot(F), vertices(V), input_of(V);
  const uint32_t axes = d.direct(3), slab = d.direct(8);
  const bool detail = d.direct(1) != 0;
  if (axes >= kSweepAxes.size()) return corrupt("sweep axes " + std::to_string(axes) + " out of range");
  bool last_picked = false;  // the vertex (face) before was a pick
  RankTree sweep(vertex_sweep(mesh, static_cast<int>(axes), static_cast<int>(slab) - kSlabExponentBias));
  for (size_t i = 0; i < V; ++i) {
    const uint32_t prev = i ? vertices[i - 1] : kNone, prev2 = i > 1 ? vertices[i - 2] : kNone;
    ctx.vertex_candidates(prev, prev2, cand);
    uint32_t pick = 0;
    if (!cand.empty()) pick = models.vertex_pick[last_picked][pick_context(cand.size())].decode(d);
    if (pick > cand.size()) return corrupt("vertex " + std::to_string(i) + " picks a candidate it does not have");
    uint32_t v;
    if (pick) {
      v = cand[pick - 1];
    } else {
      const int64_t r = (prev == kNone ? 0 : int64_t{sweep.rank(prev)}) + models.vertex_jump.decode(d);
      if (r < 0 || r >= static_cast<int64_t>(V - i))
        return corrupt("vertex " + std::to_string(i) + " jumps past the unused vertices");
      v = sweep.at_rank(static_cast<uint32_t>(r));
    }
    sweep.take(v);
    last_picked = pick > 0;
    vertices[i] = v;
    input_of[v] = static_cast<uint32_t>(i);
    ctx.vertex_used[v] = 1;
    if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("cut off");
  }
  RankTree fsweep(face_sweep(mesh, sweep.at));
  const std::vector<uint8_t> axis = lattice_axes(mesh);
  std::vector<uint32_t> left = unused_faces_per_vertex(mesh), stamp(V, 0), taken;
  taken.reserve(F);
  Mesh input;  // the faces decoded so far, on input ids
  input.indices.reserve(mesh.indices.size());
  input.face_offsets.reserve(F + 1);
  std::vector<std::pair<uint32_t, uint32_t>> fc;
  last_picked = false;
  for (size_t j = 0; j < F; ++j) {
    const uint32_t prev = j ? faces[j - 1] : kNone;
    window_candidates(mesh, taken, rot, left, stamp, cand);
    uint32_t pick = 0;
    if (!cand.empty()) pick = models.window_pick[last_picked][pick_context(cand.size())].decode(d);
    if (pick > cand.size()) return corrupt("face " + std::to_string(j) + " picks a corner it does not have");
    uint32_t f, k = 0;
    if (pick) {
      ctx.face_candidates(cand[pick - 1], prev, fc);
      if (fc.empty()) return corrupt("face " + std::to_string(j) + ": no unused face at its corner");
      uint32_t q = 0;
      if (fc.size() > 1) q = models.face_pick[pick_context(pick - 1)][pick_context(fc.size())].decode(d);
      if (q >= fc.size()) return corrupt("face " + std::to_string(j) + " picks a face it does not have");
      f = fc[q].first;
      k = fc[q].second;
    } else {
      const int64_t r = (prev == kNone ? 0 : int64_t{fsweep.rank(prev)}) + models.face_jump.decode(d);
      if (r < 0 || r >= static_cast<int64_t>(F - j))
        return corrupt("face " + std::to_string(j) + " jumps past the unused faces");
      f = fsweep.at_rank(static_cast<uint32_t>(r));
    }
    const uint32_t n = mesh.face_size(f);
    const uint32_t t = n == 3  ? models.turn3[turn_context(mesh, axis, f, k, prev, pick > 0, detail)].decode(d)
                       : n > 1 ? models.turn[pick > 0].decode(d)
                               : 0;
    if (t >= n) return corrupt("face " + std::to_string(j) + " turns past its corners");
    faces[j] = f;
    rot[j] = (k + t) % n;
    ctx.face_used[f] = 1;
    fsweep.take(f);
    take_face(mesh, f, left);
    taken.push_back(f);
    last_picked = pick > 0;
    for (uint32_t c = 0; c < n; ++c) input.indices.push_back(input_of[mesh.face(f)[(rot[j] + c) % n]]);
    input.face_offsets.push_back(static_cast<uint32_t>(input.indices.size()));
    if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("cut off");
  }
  // Every face and vertex was taken once: both are permutations.
  Mesh out;
  out.metadata = std::move(mesh.metadata);
  out.positions.resize(3 * V);
  for (size_t i = 0; i < V; ++i)
    for (int a = 0; a < 3; ++a) out.positions[3 * i + a] = mesh.positions[3 * size_t{vertices[i]} + a];
  out.indices = std::move(input.indices);
  out.face_offsets = std::move(input.face_offsets);
  for (Attribute& a : mesh.attributes) {
    Attribute b = a;
    const size_t c = a.components;
    if (a.domain == AttributeDomain::vertex && a.values.size() == c * V) {
      for (size_t i = 0; i < V; ++i)
        std::copy_n(a.values.begin() + static_cast<std::ptrdiff_t>(c * vertices[i]), c,
                    b.values.begin() + static_cast<std::ptrdiff_t>(c * i));
    } else if (a.domain == AttributeDomain::face && a.values.size() == c * F) {
      for (size_t j = 0; j < F; ++j)
        std::copy_n(a.values.begin() + static_cast<std::ptrdiff_t>(c * faces[j]), c,
                    b.values.begin() + static_cast<std::ptrdiff_t>(c * j));
    } else if (a.domain == AttributeDomain::corner && a.indices.size() == mesh.indices.size()) {
      b.indices.clear();
      for (size_t j = 0; j < F; ++j) {
        const uint32_t f = faces[j], n = mesh.face_size(f);
        for (uint32_t k = 0; k < n; ++k) b.indices.push_back(a.indices[mesh.face_offsets[f] + (rot[j] + k) % n]);
      }
    }
    out.attributes.push_back(std::move(b));
  }
  mesh = std::move(out);
  return Status::Ok();
}

}  // namespace tsm
