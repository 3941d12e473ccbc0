// Topological surgery on the input itself: turn any mesh into closed,
// oriented, manifold triangle components that the method of seed 004 §3-4
// can code, and remember how to undo it (design notes §5, "Every mesh"):
//   - polygons are fan-triangulated, their diagonals flagged (restored by
//     one bit per marching edge, as MPEG-4's polygon-edge flags);
//   - degenerate faces (fewer than 3 or repeated corners) go to a side list;
//   - the uses of an edge are paired one each way: two faces in opposite
//     directions are the usual manifold edge; more are sheets meeting at
//     the edge, paired by their third corners' positions (a face not with
//     its own reverse where another pairing avoids it); uses left over
//     (boundaries, faces that disagree in orientation) are cut;
//   - a vertex whose faces form several fans is split into one vertex per
//     fan (duplicates, stitched back by the decoder);
//   - each hole is closed by a virtual vertex and a fan of virtual triangles.
#include <algorithm>
#include <memory>
#include <numeric>
#include <queue>

#include "connectivity.hpp"

namespace tsm {

namespace {

// All half-edges grouped by their edge, for pairing and counting: a bucket
// per smaller endpoint (start[v] .. start[v + 1]), in it each half-edge as
// (larger endpoint << 32 | half-edge), sorted, so the uses of one edge are
// neighbours in half-edge order. Linear: a counting sort by the smaller
// endpoint, then each vertex's few entries sorted; 8 bytes per half-edge
// (the full dragon's 2.6 million half-edges are 21 MB to move, not 42;
// every entry is written by the scatter, none zeroed first).
struct EdgeGroups {
  std::vector<uint32_t> start;
  std::unique_ptr<uint64_t[]> e;
  // Calls f(first, last) for each edge's entries [first, last).
  template <class F>
  void each_edge(F f) const {
    for (size_t v = 0; v + 1 < start.size(); ++v)
      for (size_t i = start[v], j; i < start[v + 1]; i = j) {
        for (j = i + 1; j < start[v + 1] && (e[j] >> 32) == (e[i] >> 32);) ++j;
        f(i, j);
      }
  }
  uint32_t half_edge(size_t k) const { return static_cast<uint32_t>(e[k]); }
};

EdgeGroups sorted_edges(const std::vector<uint32_t>& tri) {
  const uint32_t nh = static_cast<uint32_t>(tri.size());
  uint32_t nv = 0;
  for (uint32_t v : tri) nv = std::max(nv, v + 1);
  EdgeGroups g;
  g.start.assign(size_t{nv} + 1, 0);
  for (uint32_t h = 0; h < nh; ++h) ++g.start[std::min(tri[h], tri[he_next(h)]) + size_t{1}];
  for (uint32_t v = 0; v < nv; ++v) g.start[v + 1] += g.start[v];
  g.e.reset(new uint64_t[nh]);
  std::vector<uint32_t> fill(g.start.begin(), g.start.end() - 1);
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t a = tri[h], b = tri[he_next(h)];
    g.e[fill[std::min(a, b)]++] = (uint64_t{std::max(a, b)} << 32) | h;
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (g.start[v + 1] - g.start[v] > 1) std::sort(g.e.get() + g.start[v], g.e.get() + g.start[v + 1]);
  return g;
}

// CutHints::root_rule > 0: each component with triangles starts at its real
// vertex of extreme position instead of its smallest id (the components keep
// their order, by smallest id). A tie on position sets m.root_tie.
void root_by_position(CutMesh& m, const std::vector<uint8_t>& on_triangle, const std::vector<uint32_t>& qpos,
                      int rule) {
  std::vector<PositionExtreme> root(m.component_count(), PositionExtreme{&qpos, (rule - 1) / 2, rule % 2 ? 1 : -1});
  for (uint32_t v = 0; v < m.vertex_count; ++v)
    if (m.kind[v] == VertexKind::real && on_triangle[v]) root[m.vertex_component[v]].offer(v, m.source[v]);
  for (uint32_t c = 0; c < m.component_count(); ++c) {
    if (root[c].best == kNone) continue;  // a component on no triangle: its only vertex
    m.component_root[c] = root[c].best;
    if (root[c].tie) m.root_tie = true;
  }
}

// Orders the components with triangles (the first `count`, numbered by
// smallest vertex id, each rooted there) as the decoder numbers their
// vertices: next the component holding the smallest input vertex that no
// component before it has, rooted there; then those whose every vertex an
// earlier one has, by smallest id as before. A vertex split across
// components keeps its id in the first of them (its copy of smallest id
// there; the ids are swapped when another copy had it). The decoder gives
// a vertex's id to its first copy in tree order, and a decoded mesh's cut to
// its first copy in face order, so in a decoded mesh both are the copy in
// the first component: it orders and roots its components alike, and its
// roots' reference edges (to the neighbour of smallest id) are the same,
// so re-encoding it codes the same streams after one round (design notes
// §5). Components sharing no vertex keep their order, roots and ids.
void order_components(CutMesh& m, uint32_t count, uint32_t input_vertex_count) {
  if (count < 2) return;
  std::vector<uint32_t> start(size_t{count} + 1, 0), member;
  for (uint32_t v = 0; v < m.vertex_count; ++v)
    if (m.kind[v] != VertexKind::virtual_ && m.vertex_component[v] < count) ++start[m.vertex_component[v] + 1];
  for (uint32_t c = 0; c < count; ++c) start[c + 1] += start[c];
  member.resize(start[count]);
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t v = 0; v < m.vertex_count; ++v)
      if (m.kind[v] != VertexKind::virtual_ && m.vertex_component[v] < count) member[fill[m.vertex_component[v]]++] = v;
  }
  // Per component: the smallest input vertex not yet taken (kNone when
  // every vertex is taken) and its copy of smallest id there. Its members
  // by (input vertex, id) and a cursor past the taken ones: vertices are
  // only ever taken, so all keys together cost one pass over the members.
  // That order in linear time: one stable counting sort of all members by
  // input vertex (`member` lists each component's by id), each then put
  // back in its component's range.
  std::vector<uint8_t> taken(input_vertex_count, 0);
  std::vector<uint32_t> by_source(member.size());
  {
    std::vector<uint32_t> at(size_t{input_vertex_count} + 1, 0), sorted(member.size());
    for (uint32_t v : member) ++at[m.source[v] + 1];
    for (size_t s = 0; s < input_vertex_count; ++s) at[s + 1] += at[s];
    for (uint32_t v : member) sorted[at[m.source[v]]++] = v;
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t v : sorted) by_source[fill[m.vertex_component[v]]++] = v;
  }
  std::vector<uint32_t> cursor(start.begin(), start.end() - 1);
  auto key = [&](uint32_t c) {
    uint32_t& i = cursor[c];
    while (i < start[c + 1] && taken[m.source[by_source[i]]]) ++i;
    if (i == start[c + 1]) return std::pair<uint32_t, uint32_t>{kNone, kNone};
    return std::pair<uint32_t, uint32_t>{m.source[by_source[i]], by_source[i]};
  };
  using Entry = std::pair<std::pair<uint32_t, uint32_t>, uint32_t>;  // key, component
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> next;
  for (uint32_t c = 0; c < count; ++c) next.push({key(c), c});
  std::vector<uint32_t> order, rest;                 // rest: components with every vertex taken
  std::vector<std::pair<uint32_t, uint32_t>> swaps;  // (vertex id, its copy that takes the id)
  order.reserve(count);
  while (!next.empty()) {
    const auto [k, c] = next.top();
    next.pop();
    const std::pair<uint32_t, uint32_t> now = key(c);
    if (now != k) {  // a component taken since has some of its vertices
      next.push({now, c});
      continue;
    }
    if (k.first == kNone) {
      rest.push_back(c);
      continue;
    }
    order.push_back(c);
    for (uint32_t i = start[c]; i < start[c + 1]; ++i) {  // (members by id: the first copy is the smallest)
      const uint32_t v = member[i], s = m.source[v];
      if (taken[s]) continue;
      taken[s] = 1;
      if (v != s) swaps.emplace_back(s, v);
    }
  }
  std::sort(rest.begin(), rest.end());
  order.insert(order.end(), rest.begin(), rest.end());
  std::vector<uint32_t> id(m.vertex_count);
  std::iota(id.begin(), id.end(), 0u);
  for (auto [s, v] : swaps) {
    id[s] = v;
    id[v] = s;
    std::swap(m.kind[s], m.kind[v]);
    std::swap(m.vertex_component[s], m.vertex_component[v]);
  }
  if (!swaps.empty())
    for (uint32_t& x : m.tri) x = id[x];
  std::vector<uint32_t> new_of(count);
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t c = order[i];
    new_of[c] = i;
    uint32_t root = kNone;  // its smallest id now
    for (uint32_t j = start[c]; j < start[c + 1]; ++j) root = std::min(root, id[member[j]]);
    m.component_root[i] = root;
  }
  for (uint32_t& c : m.vertex_component)
    if (c < count) c = new_of[c];
}

bool triangles_only(const Mesh& mesh) {
  for (size_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face_offsets[f + 1] - mesh.face_offsets[f] != 3) return false;
  return true;
}

}  // namespace

PreparedInput prepare_input(const Mesh& mesh) {
  PreparedInput out;
  // Pass 1: classify faces; fan-triangulate polygons with distinct corners.
  std::vector<uint32_t> poly_of_tri;  // per triangle: face index if from a polygon, else kNone
  auto emit = [&](const std::vector<uint32_t>& corners, uint32_t face, bool polygon) {
    size_t n = corners.size();
    for (size_t i = 1; i + 1 < n; ++i) {
      for (size_t k : {size_t{0}, i, i + 1}) out.tri.push_back(corners[k]);
      out.tri_diagonal.push_back(i > 1);
      out.tri_diagonal.push_back(0);
      out.tri_diagonal.push_back(i + 2 < n);
      poly_of_tri.push_back(polygon ? face : kNone);
    }
  };
  const size_t corners_in = mesh.corner_count(), faces_in = mesh.face_count();
  if (corners_in > 2 * faces_in) {  // exact unless some faces are degenerate
    const size_t tris = corners_in - 2 * faces_in;
    // With room for the fans by which the cut closes a few holes (a
    // triangle per boundary edge), so it need not move the arrays.
    out.tri.reserve(3 * (tris + tris / 64 + 16));
    out.tri_diagonal.reserve(3 * (tris + tris / 64 + 16));
    poly_of_tri.reserve(tris);
  }
  if (triangles_only(mesh)) {
    // The loop below for triangles alone, writing in place (no polygons:
    // pass 2 has nothing to check).
    out.tri.resize(corners_in);
    out.tri_diagonal.resize(corners_in);
    size_t k = 0;
    for (uint32_t f = 0; f < faces_in; ++f) {
      const uint32_t* c = mesh.face(f);
      if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
        out.side_faces.push_back(f);
        continue;
      }
      out.tri[k] = c[0];
      out.tri[k + 1] = c[1];
      out.tri[k + 2] = c[2];
      k += 3;
    }
    out.tri.resize(k);
    out.tri_diagonal.resize(k);
    return out;
  }
  std::vector<uint32_t> corners, sorted;
  for (uint32_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* c = mesh.face(f);
    uint32_t n = mesh.face_size(f);
    if (n == 3) {  // a triangle: emit's one fan triangle, without the copies
      if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
        out.side_faces.push_back(f);
        continue;
      }
      out.tri.insert(out.tri.end(), c, c + 3);
      out.tri_diagonal.insert(out.tri_diagonal.end(), 3, 0);
      poly_of_tri.push_back(kNone);
      continue;
    }
    corners.assign(c, c + n);
    sorted.assign(c, c + n);
    std::sort(sorted.begin(), sorted.end());
    if (n < 3 || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      out.side_faces.push_back(f);
      continue;
    }
    emit(corners, f, true);
  }
  // Pass 2: a polygon whose diagonal is not used by exactly its two fan
  // triangles cannot be glued back from the triangle tree: keep it verbatim.
  bool any_polygon = std::any_of(poly_of_tri.begin(), poly_of_tri.end(), [](uint32_t p) { return p != kNone; });
  if (!any_polygon) return out;
  const EdgeGroups edges = sorted_edges(out.tri);
  std::vector<uint8_t> bad_face(mesh.face_count(), 0);
  edges.each_edge([&](size_t i, size_t j) {
    if (j - i != 2)
      for (size_t k = i; k < j; ++k) {
        const uint32_t h = edges.half_edge(k);
        if (out.tri_diagonal[h]) bad_face[poly_of_tri[h / 3]] = 1;
      }
  });
  PreparedInput kept;
  kept.side_faces = out.side_faces;
  for (uint32_t t = 0; t < poly_of_tri.size(); ++t) {
    uint32_t f = poly_of_tri[t];
    if (f != kNone && bad_face[f]) continue;
    kept.tri.insert(kept.tri.end(), out.tri.begin() + 3 * t, out.tri.begin() + 3 * t + 3);
    kept.tri_diagonal.insert(kept.tri_diagonal.end(), out.tri_diagonal.begin() + 3 * t,
                             out.tri_diagonal.begin() + 3 * t + 3);
  }
  for (uint32_t f = 0; f < bad_face.size(); ++f)
    if (bad_face[f]) kept.side_faces.push_back(f);
  std::sort(kept.side_faces.begin(), kept.side_faces.end());
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face_size(f) > 3 && !bad_face[f] &&
        !std::binary_search(kept.side_faces.begin(), kept.side_faces.end(), f))
      ++kept.polygon_count;
  return kept;
}

CutMesh cut_mesh(PreparedInput& in, uint32_t input_vertex_count, const CutHints& hints) {
  const std::vector<uint32_t>* isolated_key = hints.anchor;
  CutMesh m;
  const uint32_t nh = static_cast<uint32_t>(in.tri.size());
  m.twin.reserve(in.tri.capacity());  // the room prepare_input left for holes' fans
  m.twin.assign(nh, kNone);

  // 1. Pair half-edges: the uses of an edge in one direction with those in
  // the other, in order (two opposite uses: a manifold edge; more: sheets
  // meeting at an edge, kept as pairs so only unmatched uses are cut).
  const EdgeGroups edges = sorted_edges(in.tri);
  std::vector<uint32_t> forward, backward, open_he;  // open_he: the uses left unpaired
  edges.each_edge([&](size_t i, size_t j) {
    if (j - i == 2) {  // the usual edge: two uses, paired when they are opposite
      const uint32_t x = edges.half_edge(i), y = edges.half_edge(i + 1);
      if ((in.tri[x] < in.tri[he_next(x)]) != (in.tri[y] < in.tri[he_next(y)])) {
        m.twin[x] = y;
        m.twin[y] = x;
      } else {
        ++m.cut_edges;
        open_he.insert(open_he.end(), {x, y});
      }
      return;
    }
    forward.clear();
    backward.clear();
    for (size_t k = i; k < j; ++k) {
      const uint32_t h = edges.half_edge(k);
      (in.tri[h] < in.tri[he_next(h)] ? forward : backward).push_back(h);
    }
    auto third = [&](uint32_t h) { return &(*hints.qpos)[3 * static_cast<size_t>(in.tri[he_prev(h)])]; };
    if (hints.qpos && j - i > 2) {
      // By the third corner's quantized position (then half-edge order).
      auto less = [&](uint32_t x, uint32_t y) {
        const uint32_t *a = third(x), *b = third(y);
        return std::lexicographical_compare(a, a + 3, b, b + 3);
      };
      std::stable_sort(forward.begin(), forward.end(), less);
      std::stable_sort(backward.begin(), backward.end(), less);
    }
    const size_t pairs = std::min(forward.size(), backward.size());
    if (hints.qpos && forward.size() == 2 && backward.size() == 2) {
      // A double-sided sheet (its faces given both ways round on the same
      // vertices): each edge has two uses each way, and pairing a face
      // with its own reverse (their third corners coincide, so the sorted
      // order lines them up) would close every face on itself, the sheet
      // falling apart into two-triangle pieces stitched together. So the
      // pairs cross when that makes fewer such pairs. The choice follows
      // positions alone (in particular not ids or the face order, which a
      // decoded mesh does not keep): both sides' third corners are apart.
      auto same_third = [&](uint32_t x, uint32_t y) { return std::equal(third(x), third(x) + 3, third(y)); };
      const int straight = same_third(forward[0], backward[0]) + same_third(forward[1], backward[1]);
      const int crossed = same_third(forward[0], backward[1]) + same_third(forward[1], backward[0]);
      if (crossed < straight && !same_third(forward[0], forward[1]) && !same_third(backward[0], backward[1]))
        std::swap(backward[0], backward[1]);
    }
    for (size_t k = 0; k < pairs; ++k) {
      m.twin[forward[k]] = backward[k];
      m.twin[backward[k]] = forward[k];
    }
    for (const auto* side : {&forward, &backward}) open_he.insert(open_he.end(), side->begin() + pairs, side->end());
    if (j - i != 2 * pairs || j - i > 2) ++m.cut_edges;
  });

  // Each half-edge left unpaired borders a hole, whose closing fan (step 3)
  // adds a triangle for it: room for those before the arrays are filled.
  // Step 2 renames vertices in place: it reads a corner before its fan is
  // renamed, and a fan's corners all held the same vertex before.
  std::sort(open_he.begin(), open_he.end());
  const size_t open = open_he.size();
  m.tri.swap(in.tri);
  m.diagonal.swap(in.tri_diagonal);
  if (open) {
    m.tri.reserve(nh + 3 * open);
    m.diagonal.reserve(nh + 3 * open);
    m.twin.reserve(nh + 3 * open);
  }
  m.tri_source.reserve(nh / 3 + open);

  // 2. Split vertices into one per fan: corners (= outgoing half-edges) that
  // are rotations of each other around their vertex form one fan.
  // Each fan is walked once, from its first corner in half-edge order
  // (which so decides which fan keeps the vertex id), both ways round.
  m.source.resize(input_vertex_count);
  std::iota(m.source.begin(), m.source.end(), 0u);
  m.kind.assign(input_vertex_count, VertexKind::real);
  std::vector<uint8_t> claimed(input_vertex_count, 0), in_fan(nh, 0);
  for (uint32_t h = 0; h < nh; ++h) {
    if (in_fan[h]) continue;
    const uint32_t v = m.tri[h];  // not yet renamed (not in a fan)
    uint32_t id = v;
    if (!claimed[v]) {
      claimed[v] = 1;
    } else {
      id = static_cast<uint32_t>(m.source.size());
      m.source.push_back(v);
      m.kind.push_back(VertexKind::duplicate);
      ++m.duplicates;
    }
    uint32_t g = h;
    do {  // clockwise: g -> next(twin(g))
      in_fan[g] = 1;
      m.tri[g] = id;
    } while (m.twin[g] != kNone && !in_fan[g = he_next(m.twin[g])]);
    for (g = h; m.twin[he_prev(g)] != kNone && !in_fan[m.twin[he_prev(g)]];) {  // and back
      g = m.twin[he_prev(g)];
      in_fan[g] = 1;
      m.tri[g] = id;
    }
  }

  // 3. Close every hole with a virtual vertex. The boundary half-edge after
  // h = a->b is found by rotating clockwise around b to the open side.
  m.tri_source.resize(nh / 3);
  std::iota(m.tri_source.begin(), m.tri_source.end(), 0u);
  // Holes in the order of their first half-edge; done: per open half-edge.
  std::vector<uint8_t> done_open(open, 0);
  uint8_t not_open = 1;
  auto done = [&](uint32_t h) -> uint8_t& {
    const auto it = std::lower_bound(open_he.begin(), open_he.end(), h);
    if (it == open_he.end() || *it != h) return not_open = 1;  // (a walk meets only open half-edges)
    return done_open[static_cast<size_t>(it - open_he.begin())];
  };
  std::vector<uint32_t> hole;
  for (uint32_t h0 : open_he) {
    if (done(h0)) continue;
    hole.clear();
    for (uint32_t h = h0; !done(h);) {
      done(h) = 1;
      hole.push_back(h);
      uint32_t g = he_next(h);
      while (m.twin[g] != kNone) g = he_next(m.twin[g]);
      h = g;
    }
    const uint32_t w = static_cast<uint32_t>(m.source.size());
    m.source.push_back(kNone);
    m.kind.push_back(VertexKind::virtual_);
    ++m.holes;
    const uint32_t first = static_cast<uint32_t>(m.tri.size() / 3);
    const uint32_t k = static_cast<uint32_t>(hole.size());
    for (uint32_t i = 0; i < k; ++i) {
      uint32_t h = hole[i];
      uint32_t t = first + i;
      m.tri.insert(m.tri.end(), {m.tri[he_next(h)], m.tri[h], w});
      m.twin.insert(m.twin.end(), {h, kNone, kNone});
      m.diagonal.insert(m.diagonal.end(), {0, 0, 0});
      m.twin[h] = 3 * t;
      m.tri_source.push_back(kNone);
    }
    for (uint32_t i = 0; i < k; ++i) {  // a->w of triangle i pairs with w->a of the previous one
      uint32_t t = first + i, tp = first + (i + k - 1) % k;
      m.twin[3 * t + 1] = 3 * tp + 2;
      m.twin[3 * tp + 2] = 3 * t + 1;
    }
  }
  m.vertex_count = static_cast<uint32_t>(m.source.size());

  // 4. Components: those with triangles first, in the order the decoder
  // numbers their vertices (order_components; by smallest vertex id, never
  // virtual, which is the root, when they share no vertex); then the
  // vertices on no triangle, by `isolated_key` when given (else by id).
  UnionFind comp(m.vertex_count);
  std::vector<uint8_t> on_triangle(m.vertex_count, 0);
  for (uint32_t h = 0; h < m.tri.size(); h += 3) {  // two edges of a triangle join its three corners
    comp.unite(m.tri[h], m.tri[h + 1]);
    comp.unite(m.tri[h + 1], m.tri[h + 2]);
    on_triangle[m.tri[h]] = on_triangle[m.tri[h + 1]] = on_triangle[m.tri[h + 2]] = 1;
  }
  m.vertex_component.assign(m.vertex_count, kNone);
  std::vector<uint32_t> isolated;
  for (uint32_t v = 0; v < m.vertex_count; ++v) {
    uint32_t r = comp.find(v);  // the smallest id of the set (unite keeps the minimum)
    if (r == v) {
      if (!on_triangle[v]) {
        isolated.push_back(v);
        continue;
      }
      m.vertex_component[v] = static_cast<uint32_t>(m.component_root.size());
      m.component_root.push_back(v);
    }
    m.vertex_component[v] = m.vertex_component[r];
  }
  order_components(m, m.component_count(), input_vertex_count);
  if (hints.root_rule > 0 && hints.qpos) root_by_position(m, on_triangle, *hints.qpos, hints.root_rule);
  // Those of one anchor by position (then id): the order then follows ids
  // only among vertices of one grid cell, so a decoded mesh (other ids)
  // orders them alike under every vertex tree the encoder tries.
  if (isolated_key)
    std::stable_sort(isolated.begin(), isolated.end(), [&](uint32_t a, uint32_t b) {
      const uint32_t ka = (*isolated_key)[a], kb = (*isolated_key)[b];
      if (ka != kb || !hints.qpos) return ka < kb;
      const uint32_t *pa = &(*hints.qpos)[3 * size_t{m.source[a]}], *pb = &(*hints.qpos)[3 * size_t{m.source[b]}];
      return std::lexicographical_compare(pa, pa + 3, pb, pb + 3);
    });
  for (uint32_t v : isolated) {
    m.vertex_component[v] = static_cast<uint32_t>(m.component_root.size());
    m.component_root.push_back(v);
  }
  return m;
}

}  // namespace tsm
