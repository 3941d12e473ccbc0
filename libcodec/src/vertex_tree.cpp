// The vertex spanning tree (seed 004 §3.1; design notes §3): the layered
// construction. Breadth-first rings around a root; Kruskal (union-find) over
// the edges with the root's reference edge first, then the same-ring edges,
// inner rings before outer, each vertex taking at most two of them (so a
// ring becomes paths, not branching trees), then the ring-to-ring edges,
// those that join path ends first, then the same-ring edges the path rule
// left out, then edges to virtual vertices (which so become leaves), polygon
// diagonals last (so they are never cut). Rings are paths joined by single
// edges: a spiral with few, long runs. After the rings the cut mesh is
// renumbered in ring order (the later stages then read memory in order);
// the edges are listed by walking it, already by class and ring but for
// the path-end preference, sorted within each ring (linear time). The tree
// is linearized in pre-order with the children of a node in clockwise order
// starting from the edge to its parent.
#include <algorithm>

#include "connectivity.hpp"

namespace tsm {

namespace {

// What the breadth-first rings leave for the renumbering: the vertices in
// rank order with what the walk knew of each when it reached it (so that
// nothing is gathered back from a per-vertex array in id order), each
// vertex's rank, and the triangles in the order the walk first met them.
struct Rings {
  std::vector<uint32_t> old_id;     // rank -> id
  std::vector<uint32_t> dist;       // per rank: its ring
  std::vector<uint32_t> from_he;    // per rank: the half-edge to its BFS parent, kNone at a root
  std::vector<uint32_t> reached_by; // per rank: the parent's half-edge to it (from_he's twin), numbered as
                                    // after the renumbering (3 x triangle rank + corner), kNone at a root
  std::vector<uint32_t> component;  // per rank
  std::vector<uint32_t> rank;       // id -> rank; kFar not reached, kNone a virtual vertex
  std::vector<uint32_t> tri_rank;   // triangle -> place in the walk, kNone where it did not meet it
  std::vector<uint32_t> tri_by_rank;
};
constexpr uint32_t kFar = 0xFFFFFFFEu;

// Renumbers the cut mesh for the stages after the rings: vertices by ring
// rank (those no ring reaches after them, in id order), triangles in the
// order the ring walk first met them (those it did not meet after them).
// The later stages walk the mesh ring by ring, so they then read memory
// nearly in order instead of all over a large mesh (the full dragon's
// connectivity encodes about 1.2x faster by this alone, 1.6x with the edge
// listing it allows). No choice changes: every later one depends on ranks,
// the walk and the root's reference edge, and a half-edge id only breaks
// ties between parallel edges. Leaves dist and from_he per new id, and
// ref_he (the roots' reference half-edges, given by old id) in the new
// numbering.
void renumber_by_rings(CutMesh& m, Rings& r, std::vector<uint32_t>& dist, std::vector<uint32_t>& ref_he,
                       std::vector<uint32_t>& from_he) {
  const uint32_t nv = m.vertex_count, nt = m.triangle_count();
  std::vector<uint32_t>& old_id = r.old_id;
  std::vector<uint32_t>& nid = r.rank;
  const uint32_t reached = static_cast<uint32_t>(old_id.size());
  dist.swap(r.dist);
  std::vector<uint32_t> component;
  component.swap(r.component);
  for (uint32_t v = 0; v < nv; ++v)
    if (nid[v] >= kFar) {
      nid[v] = static_cast<uint32_t>(old_id.size());
      old_id.push_back(v);
      dist.push_back(m.kind[v] == VertexKind::virtual_ ? kNone : kFar);
      component.push_back(m.vertex_component[v]);
    }
  m.vertex_component.swap(component);
  std::vector<VertexKind> kind(nv);
  std::vector<uint32_t> source(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    kind[v] = m.kind[old_id[v]];
    source[v] = m.source[old_id[v]];
  }
  m.kind.swap(kind);
  m.source.swap(source);
  // The reference half-edges are at the roots only.
  std::vector<uint32_t> ref(nv, kNone);
  for (uint32_t& root : m.component_root) {
    ref[nid[root]] = ref_he[root];
    root = nid[root];
  }
  ref_he.swap(ref);
  // Triangles, each gathered from its old place.
  std::vector<uint32_t>& nt_of = r.tri_rank;
  std::vector<uint32_t>& old_of = r.tri_by_rank;
  for (uint32_t t = 0; t < nt; ++t)
    if (nt_of[t] == kNone) {
      nt_of[t] = static_cast<uint32_t>(old_of.size());
      old_of.push_back(t);
    }
  auto nh = [&](uint32_t h) { return 3 * nt_of[h / 3] + h % 3; };
  std::vector<uint32_t> tri(m.tri.size()), twin(m.twin.size());
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t o = old_of[t];
    for (uint32_t k = 0; k < 3; ++k) {
      tri[3 * t + k] = nid[m.tri[3 * o + k]];
      twin[3 * t + k] = nh(m.twin[3 * o + k]);
    }
  }
  m.tri.swap(tri);
  m.twin.swap(twin);
  std::vector<uint32_t> tri_source(nt);
  for (uint32_t t = 0; t < nt; ++t) tri_source[t] = m.tri_source[old_of[t]];
  m.tri_source.swap(tri_source);
  // No polygon diagonals: nothing to move.
  if (std::any_of(m.diagonal.begin(), m.diagonal.end(), [](uint8_t d) { return d != 0; })) {
    std::vector<uint8_t> diagonal(m.diagonal.size());
    for (uint32_t t = 0; t < nt; ++t)
      for (uint32_t k = 0; k < 3; ++k) diagonal[3 * t + k] = m.diagonal[3 * old_of[t] + k];
    m.diagonal.swap(diagonal);
  }
  for (uint32_t& h : ref_he)
    if (h != kNone) h = nh(h);
  // A reached vertex's parent edge through the new twins (near in the new
  // order; no lookup in the old one).
  from_he.assign(nv, kNone);
  for (uint32_t v = 0; v < reached; ++v)
    if (r.reached_by[v] != kNone) from_he[v] = m.twin[r.reached_by[v]];
}

}  // namespace

VertexForest build_vertex_tree(CutMesh& m, const std::vector<uint32_t>* qpos, bool midpoint,
                               bool geometric_ref, bool* tie) {
  const uint32_t nv = m.vertex_count;
  const uint32_t nh = static_cast<uint32_t>(m.tri.size());
  VertexForest f;
  f.parent_he.assign(nv, kNone);
  f.root_ref_he.assign(nv, kNone);
  f.tree_he.assign(nh, 0);

  // One outgoing half-edge per vertex; at a root, the one to its real
  // neighbour of smallest id (not across a polygon diagonal). That edge is forced into the tree, so in the
  // decoded mesh (ids in pre-order) the same neighbour is again the smallest:
  // every later choice depends only on the root and this edge, never on the
  // input's numbering, and re-encoding a decoded mesh gives the same bytes.
  // With geometric_ref the neighbour of smallest position, which a decoded
  // mesh has too (a tie on position sets *tie).
  std::vector<uint32_t> out_he(nv, kNone);
  for (uint32_t h = 0; h < nh; ++h)
    if (out_he[m.tri[h]] == kNone) out_he[m.tri[h]] = h;
  auto is_virtual = [&](uint32_t v) { return m.kind[v] == VertexKind::virtual_; };
  for (uint32_t root : m.component_root) {
    uint32_t start = out_he[root];
    if (start == kNone) continue;
    uint32_t best = kNone, h = start;
    PositionExtreme nearest{qpos};
    do {
      uint32_t w = m.tri[he_next(h)];
      if (!is_virtual(w) && !m.diagonal[h]) {
        if (geometric_ref)
          nearest.offer(h, m.source[w]);
        else if (best == kNone || w < m.tri[he_next(best)])
          best = h;
      }
      h = he_next(m.twin[h]);
    } while (h != start);
    if (geometric_ref) {
      best = nearest.best;
      if (nearest.tie && tie) *tie = true;
    }
    out_he[root] = best;
  }

  // Breadth-first rings and order from each root over real vertices; the
  // neighbours of a vertex are taken clockwise from the edge to its BFS parent.
  // A virtual vertex is never reached (its rank is kNone, not kFar).
  Rings walk;
  walk.rank.resize(nv);
  for (uint32_t v = 0; v < nv; ++v) walk.rank[v] = is_virtual(v) ? kNone : kFar;
  walk.tri_rank.assign(nh / 3, kNone);
  for (auto* a : {&walk.old_id, &walk.dist, &walk.from_he, &walk.reached_by, &walk.component}) a->reserve(nv);
  walk.tri_by_rank.reserve(nh / 3);
  std::vector<uint32_t>& queue = walk.old_id;  // all components in one list: the vertices by rank
  auto reach = [&](uint32_t v, uint32_t d, uint32_t h, uint32_t c) {  // from h's start, or a root (h = kNone)
    walk.rank[v] = static_cast<uint32_t>(queue.size());
    queue.push_back(v);
    walk.dist.push_back(d);
    walk.from_he.push_back(h == kNone ? kNone : m.twin[h]);
    walk.reached_by.push_back(h == kNone ? kNone : 3 * walk.tri_rank[h / 3] + h % 3);
    walk.component.push_back(c);
  };
  for (uint32_t c = 0; c < m.component_count(); ++c) {
    uint32_t root = m.component_root[c];
    f.root_ref_he[root] = out_he[root];
    reach(root, 0, kNone, c);
    for (size_t qi = queue.size() - 1; qi < queue.size(); ++qi) {
      const uint32_t start = walk.from_he[qi] != kNone ? walk.from_he[qi] : out_he[queue[qi]];
      if (start == kNone) continue;  // isolated vertex
      const uint32_t d = walk.dist[qi] + 1;
      uint32_t h = start;
      do {
        if (walk.tri_rank[h / 3] == kNone) {  // triangles in the order the walk first meets them
          walk.tri_rank[h / 3] = static_cast<uint32_t>(walk.tri_by_rank.size());
          walk.tri_by_rank.push_back(h / 3);
        }
        const uint32_t w = m.tri[he_next(h)];
        if (walk.rank[w] == kFar) reach(w, d, h, c);
        h = he_next(m.twin[h]);
      } while (h != start);
    }
  }

  // After the renumbering a vertex's rank is its id (kNone where no ring
  // reached it), and its walk starts where its ring walk started.
  const uint32_t reached = static_cast<uint32_t>(queue.size());
  std::vector<uint32_t> dist, bfs_from;
  renumber_by_rings(m, walk, dist, f.root_ref_he, bfs_from);
  auto rank = [reached](uint32_t v) { return v < reached ? v : kNone; };
  auto walk_start = [&](uint32_t v) { return bfs_from[v] != kNone ? bfs_from[v] : f.root_ref_he[v]; };
  // Between parallel edges (same two vertices, as where the faces of an
  // edge with more than two faces are paired): the one met last walking
  // around the lower-ranked vertex from where its ring walk started, which
  // a decoded mesh has too (the half-edge id follows the input's face
  // order; either walk order is canonical, this one measured a few bytes
  // smaller on the stitched dragons). Each half-edge's place in that walk,
  // listed per vertex at its first tie.
  std::vector<uint32_t> turn_at;
  std::vector<uint8_t> walked;
  auto turn = [&](uint32_t h) {
    if (rank(m.tri[m.twin[h]]) < rank(m.tri[h])) h = m.twin[h];
    const uint32_t v = m.tri[h];
    if (walked.empty()) {
      turn_at.assign(nh, 0);
      walked.assign(nv, 0);
    }
    if (!walked[v]) {
      walked[v] = 1;
      const uint32_t start = walk_start(v);
      if (start != kNone) {
        uint32_t g = start, k = 0;
        do turn_at[g] = k++;
        while ((g = he_next(m.twin[g])) != start && k < nh);
      }
    }
    return turn_at[h];
  };
  auto parallel_less = [&](uint32_t x, uint32_t y) {
    const uint32_t tx = turn(x), ty = turn(y);
    return tx != ty ? tx > ty : x < y;
  };

  // Edges (each once), keyed by class and ring, Kruskal.
  struct Edge {
    uint64_t key;   // class (4 bits) | path-end preference (2) | ring (26 bits) | rank of the first endpoint (32)
    uint32_t rb;    // rank of the second endpoint
    uint32_t h;     // the edge (between parallel edges: parallel_less)
  };
  // Midpoint variant: the squared distance of each edge's midpoint from the
  // root, by the edge's smaller half-edge.
  std::vector<double> mid_dist(midpoint ? nh : 0, 0.0);
  // The edge of half-edge h and its twin, keyed.
  auto make_edge = [&](uint32_t h) __attribute__((always_inline))->Edge {  // (inline: once per edge)
    const uint32_t g = m.twin[h];
    const uint32_t a = m.tri[h], b = m.tri[g];
    uint64_t cls, ring;
    uint32_t ra = std::min(rank(a), rank(b)), rb = std::max(rank(a), rank(b));
    if (f.root_ref_he[a] == h || f.root_ref_he[b] == g) {
      cls = 0;  // the root's reference edge comes first of all
      ring = 0;
      ra = rb = 0;
    } else if (m.diagonal[h]) {
      cls = 4;
      ring = 0;
    } else if (is_virtual(a) || is_virtual(b)) {
      cls = 3;
      ring = 0;
      ra = rank(is_virtual(a) ? b : a);
      rb = 0;
    } else if (dist[a] == dist[b]) {
      cls = 1;
      ring = dist[a];
    } else {
      cls = 2;
      ring = std::min(dist[a], dist[b]);
    }
    if (midpoint && (cls == 1 || cls == 2)) {
      cls = 1;
      ring = 0;
      const uint32_t root = m.component_root[m.vertex_component[a]];
      const uint32_t* pa = &(*qpos)[3 * static_cast<size_t>(m.source[a])];
      const uint32_t* pb = &(*qpos)[3 * static_cast<size_t>(m.source[b])];
      const uint32_t* pr = &(*qpos)[3 * static_cast<size_t>(m.source[root])];
      for (int k = 0; k < 3; ++k) {
        double e = static_cast<double>(pa[k]) + pb[k] - 2.0 * pr[k];
        mid_dist[std::min(h, g)] += e * e;
      }
    }
    return {(cls << 60) | (std::min<uint64_t>(ring, (1u << 26) - 1) << 32) | ra, rb, std::min(h, g)};
  };
  auto by_key = [&](const Edge& x, const Edge& y) {
    if ((x.key >> 60) != (y.key >> 60)) return x.key < y.key;
    if (midpoint && mid_dist[x.h] != mid_dist[y.h]) return mid_dist[x.h] < mid_dist[y.h];
    return x.key != y.key ? x.key < y.key : x.rb != y.rb ? x.rb < y.rb : parallel_less(x.h, y.h);
  };
  // The layered tree lists its edges in linear time in an order the
  // Kruskal phases below take as by_key's (dist is 0 there): walking the
  // vertices by rank (their ids now), each edge at its lower-ranked end,
  // each vertex's few edges sorted by (second rank, place in the walk); the
  // reference edges (rank 0) first, then the same-ring edges, then the rest
  // by class (phase 2 orders the ring-to-ring ones by preference within
  // each ring). Within a component the rings
  // follow the ranks, so this is by_key's order there; across components
  // it is not, but no union joins two components. Ranks are below nv
  // except at vertices no ring reaches, which a closed cut mesh does not
  // have (then by_key over the edges in half-edge order).
  auto ring_of = [](const Edge& e) { return static_cast<uint32_t>((e.key >> 32) & ((1u << 26) - 1)); };
  auto ra_of = [](const Edge& e) { return static_cast<uint32_t>(e.key); };
  auto by_rb = [&](const Edge& x, const Edge& y) { return x.rb != y.rb ? x.rb < y.rb : parallel_less(x.h, y.h); };
  auto sort_from = [&](std::vector<Edge>& v, size_t from) {
    if (v.size() - from > 1) std::sort(v.begin() + static_cast<std::ptrdiff_t>(from), v.end(), by_rb);
  };
  // Phase 1's: the reference edges, then the same-ring edges; by class, the
  // rest: ring-to-ring edges, edges to virtual vertices, polygon diagonals.
  std::vector<Edge> refs, same_ring, edges, to_virtual, diagonals;
  auto part_of = [&](uint64_t cls) -> std::vector<Edge>& {
    return cls == 2 ? edges : cls == 3 ? to_virtual : diagonals;
  };
  bool linear = !midpoint;
  if (linear) {
    edges.reserve(nh / 2);
    same_ring.reserve(nh / 4);
    for (uint32_t v = 0; v < reached; ++v) {
      const uint32_t start = walk_start(v);
      if (start == kNone) continue;
      const size_t s0 = same_ring.size(), e0 = edges.size(), v0 = to_virtual.size(), d0 = diagonals.size();
      uint32_t g = start, guard = 0;
      do {
        const uint32_t w = m.tri[he_next(g)];
        if (rank(w) > v) {  // kNone (a virtual vertex) too
          const Edge e = make_edge(g < m.twin[g] ? g : m.twin[g]);
          const uint64_t cls = e.key >> 60;
          (cls == 0 ? refs : cls == 1 ? same_ring : part_of(cls)).push_back(e);
        }
        g = he_next(m.twin[g]);
      } while (g != start && ++guard < nh);
      sort_from(same_ring, s0);
      sort_from(edges, e0);
      sort_from(to_virtual, v0);
      sort_from(diagonals, d0);
    }
    sort_from(refs, 0);
    linear = refs.size() + same_ring.size() + edges.size() + to_virtual.size() + diagonals.size() == nh / 2;
    for (const auto* part : {&refs, &same_ring, &edges, &to_virtual, &diagonals})
      for (const Edge& e : *part)
        if (ra_of(e) >= nv || e.rb >= nv) linear = false;
  }
  if (!linear) {
    std::vector<Edge> all;
    for (uint32_t h = 0; h < nh; ++h)
      if (h < m.twin[h]) all.push_back(make_edge(h));
    std::sort(all.begin(), all.end(), by_key);
    for (auto* part : {&refs, &same_ring, &edges, &to_virtual, &diagonals}) part->clear();
    for (const Edge& e : all) ((e.key >> 60) <= 1 ? refs : part_of(e.key >> 60)).push_back(e);
  }
  UnionFind uf(nv);
  // Phase 1: the reference edges and same-ring edges, each ring a set of
  // paths (a vertex takes at most two same-ring tree edges).
  std::vector<uint8_t> ring_deg(nv, 0);
  std::vector<uint32_t> skipped;  // same-ring edges left out for the path rule
  for (const auto* part : {&refs, &same_ring})
    for (const Edge& e : *part) {
      uint32_t a = m.tri[e.h], b = m.tri[m.twin[e.h]];
      const bool path_rule = (e.key >> 60) == 1 && !midpoint;
      if (path_rule && (ring_deg[a] >= 2 || ring_deg[b] >= 2)) {
        skipped.push_back(e.h);
        continue;
      }
      if (uf.unite(a, b)) {
        f.tree_he[e.h] = f.tree_he[m.twin[e.h]] = 1;
        if (path_rule) {
          ++ring_deg[a];
          ++ring_deg[b];
        }
      }
    }
  // Phase 2: the rest; ring-to-ring edges that join path ends first (a
  // path attached at its end continues a run instead of branching).
  for (Edge& e : edges) {
    uint32_t a = m.tri[e.h], b = m.tri[m.twin[e.h]];
    uint32_t inner = dist[a] < dist[b] ? a : b, outer = inner == a ? b : a;
    uint64_t ends = (ring_deg[outer] >= 2 ? 2u : 0u) + (ring_deg[inner] >= 2 ? 1u : 0u);
    e.key = (e.key & ~(uint64_t{3} << 58)) | (ends << 58);
  }
  // Ring, then path-end preference, then ranks. Listed by the walk, the
  // edges of each component are in that order but for the preference (an
  // edge's ring is that of its lower-ranked end), so a stable partition by
  // preference within each ring's run is the sort (where two components'
  // runs meet, their edges interleave differently: no union joins two
  // components).
  auto ends_of = [](const Edge& e) { return static_cast<uint32_t>((e.key >> 58) & 3); };
  if (linear) {
    std::vector<Edge> run;
    for (size_t i = 0, j; i < edges.size(); i = j) {
      for (j = i + 1; j < edges.size() && ring_of(edges[j]) == ring_of(edges[i]);) ++j;
      run.assign(edges.begin() + static_cast<std::ptrdiff_t>(i), edges.begin() + static_cast<std::ptrdiff_t>(j));
      size_t k = i;
      for (uint32_t p = 0; p < 4; ++p)
        for (const Edge& e : run)
          if (ends_of(e) == p) edges[k++] = e;
    }
  } else {
    std::sort(edges.begin(), edges.end(), [&](const Edge& x, const Edge& y) {
      if (ring_of(x) != ring_of(y)) return ring_of(x) < ring_of(y);
      if (ends_of(x) != ends_of(y)) return ends_of(x) < ends_of(y);
      return x.key != y.key ? x.key < y.key : x.rb != y.rb ? x.rb < y.rb : parallel_less(x.h, y.h);
    });
  }
  // Before any edge to a virtual vertex or polygon diagonal: the same-ring
  // edges the path rule left out. The real vertices of a component are
  // connected without those two kinds of edges (a polygon's corners by its
  // sides, a hole's by its border), so with them the real vertices form one
  // tree first: a virtual vertex then joins it by a single edge, as a leaf
  // (the decoder refuses a virtual vertex with children, FORMAT.md §8.7),
  // and a diagonal never joins it (it would be cut and split its polygon).
  auto take = [&](const std::vector<Edge>& part) {
    for (const Edge& e : part)
      if (uf.unite(m.tri[e.h], m.tri[m.twin[e.h]])) f.tree_he[e.h] = f.tree_he[m.twin[e.h]] = 1;
  };
  take(edges);
  for (uint32_t h : skipped)
    if (uf.unite(m.tri[h], m.tri[m.twin[h]])) f.tree_he[h] = f.tree_he[m.twin[h]] = 1;
  take(to_virtual);
  take(diagonals);

  // Pre-order, children clockwise from the parent edge (from the reference
  // half-edge at a root, which itself comes first).
  f.order.reserve(nv);
  f.parent.reserve(nv);
  f.child_count.reserve(nv);
  std::vector<uint32_t> pos(nv, kNone), stack, kids;
  for (uint32_t c = 0; c < m.component_count(); ++c) {
    f.component_start.push_back(static_cast<uint32_t>(f.order.size()));
    stack.assign(1, m.component_root[c]);
    while (!stack.empty()) {
      uint32_t v = stack.back();
      stack.pop_back();
      pos[v] = static_cast<uint32_t>(f.order.size());
      f.order.push_back(v);
      f.parent.push_back(f.parent_he[v] == kNone ? kNone : pos[m.tri[he_next(f.parent_he[v])]]);
      kids.clear();
      uint32_t start = f.parent_he[v] != kNone ? f.parent_he[v] : f.root_ref_he[v];
      if (start != kNone) {
        uint32_t h = start;
        do {
          if (f.tree_he[h] && h != f.parent_he[v]) {
            uint32_t w = m.tri[he_next(h)];
            f.parent_he[w] = m.twin[h];
            kids.push_back(w);
          }
          h = he_next(m.twin[h]);
        } while (h != start);
      }
      f.child_count.push_back(static_cast<uint32_t>(kids.size()));
      for (size_t k = kids.size(); k-- > 0;) stack.push_back(kids[k]);
    }
  }
  f.component_start.push_back(static_cast<uint32_t>(f.order.size()));
  return f;
}

}  // namespace tsm
