// The bounding loop (seed 004 §3.3; design notes §3 and §5 "Handles"): cut
// the surface along the vertex tree and, on surfaces with handles, along 2g
// jump edges (the uncut edges left over by a spanning tree of the triangles),
// so that the triangles form one triangulated polygon. Its boundary is found
// by one rule, used alike by encoder and decoder: arriving at a vertex along
// a cut edge, leave by the next cut edge clockwise. On the tree alone this is
// the Euler tour with clockwise children; each jump edge end sits in one tour
// corner and is coded as that corner (plus its clockwise order in it).
#include <algorithm>
#include <numeric>

#include "connectivity.hpp"

namespace tsm {

ComponentLoop encoder_loop(const CutMesh& m, const VertexForest& f, uint32_t c,
                           const std::vector<uint32_t>& triangles, std::vector<uint8_t>& cut_he,
                           std::vector<uint32_t>& local) {
  ComponentLoop out;
  const uint32_t start = f.component_start[c], size = f.component_start[c + 1] - start;
  if (size < 2) return out;

  const uint32_t root = f.order[start];
  const uint32_t first = m.twin[f.parent_he[f.order[start + 1]]];  // root -> first child

  // Jump edges: a spanning tree of the triangles over uncut edges, polygon
  // diagonals first (so they are never cut); the uncut edges it leaves are
  // jumps. Edges are taken in the order of a breadth-first walk over the
  // triangles from the one left of the root's first tree edge, each
  // triangle's edges starting from the one it was entered by, so the choice
  // does not depend on the input's numbering.
  for (uint32_t i = 0; i < triangles.size(); ++i) local[triangles[i]] = kNone;
  std::vector<uint32_t> queue, order;  // order: half-edges in canonical order
  queue.reserve(triangles.size());
  order.reserve(3 * triangles.size());
  local[first / 3] = 0;
  queue.push_back(first);
  for (size_t qi = 0; qi < queue.size(); ++qi) {
    uint32_t e = queue[qi];
    for (int i = 0; i < 3; ++i, e = he_next(e)) {
      order.push_back(e);
      uint32_t t2 = m.twin[e] / 3;
      if (cut_he[e] == 0 && local[t2] == kNone) {
        local[t2] = static_cast<uint32_t>(queue.size());
        queue.push_back(m.twin[e]);
      }
    }
  }
  UnionFind uf(triangles.size());
  for (int pass = 0; pass < 2; ++pass)
    for (uint32_t h : order) {
      uint32_t g = m.twin[h];
      if (cut_he[h] || (pass == 0) != (m.diagonal[h] != 0) || local[h / 3] > local[g / 3] ||
          (local[h / 3] == local[g / 3] && h > g))
        continue;
      if (!uf.unite(local[h / 3], local[g / 3])) cut_he[h] = cut_he[g] = 2;  // 2 = jump
    }

  auto sweep_from = [&](uint32_t e_in, bool tree_only) {
    uint32_t h = he_next(e_in);
    while (!(tree_only ? cut_he[h] == 1 : cut_he[h] != 0)) h = he_next(m.twin[h]);
    return h;
  };

  // Jump ends by tree-tour corner: walk the tree tour; at each arrival sweep
  // clockwise to the next tree edge, collecting the jump half-edges passed.
  struct End {
    uint32_t corner, order, he;
  };
  std::vector<End> ends;
  {
    uint32_t q = 0, h = first;
    const uint32_t tour = 2 * (size - 1);
    for (uint32_t step = 0; step < tour; ++step) {
      uint32_t arrive = h;
      q = (step + 1) % tour;  // the position reached
      uint32_t g = he_next(arrive), k = 0;
      while (cut_he[g] != 1) {
        if (cut_he[g] == 2) ends.push_back({q, k++, g});
        g = he_next(m.twin[g]);
      }
      h = g;
    }
  }
  std::stable_sort(ends.begin(), ends.end(), [](const End& a, const End& b) { return a.corner < b.corner; });
  {
    std::vector<std::pair<uint32_t, uint32_t>> by_he(ends.size());
    for (uint32_t i = 0; i < ends.size(); ++i) by_he[i] = {ends[i].he, i};
    std::sort(by_he.begin(), by_he.end());
    out.jumps.resize(ends.size());
    for (uint32_t i = 0; i < ends.size(); ++i) {
      uint32_t partner_he = m.twin[ends[i].he];
      auto it = std::lower_bound(by_he.begin(), by_he.end(), std::make_pair(partner_he, 0u));
      out.jumps[i] = {ends[i].corner, ends[i].order, it->second};
    }
  }

  // The loop: start at the root leaving to its first child; stop on return.
  uint32_t h = first, v = root;
  do {
    out.loop.push_back(v);
    out.loop_he.push_back(h);
    v = m.tri[he_next(h)];
    h = sweep_from(h, false);
  } while (!(h == first && v == root));
  return out;
}

// The loop of a tree without jump edges is its Euler tour: the walk below
// reduced to one pass over the path from the root. Vertices come in pre-order
// (the runs give no other), so each vertex hangs below a vertex on the path
// to the one before it: go up to its parent, then down to it. Each edge is
// walked down once and up once, and the two positions are twins. Returns
// false on a parent array that is not a pre-order.
bool tree_tour(const std::vector<uint32_t>& parent, std::vector<uint32_t>& loop, std::vector<uint32_t>& loop_twin) {
  const uint32_t n = static_cast<uint32_t>(parent.size());
  loop.resize(2 * (static_cast<size_t>(n) - 1));
  loop_twin.resize(loop.size());
  // The path as two arrays indexed by depth (no push_back of a struct: the
  // store-to-load forwarding of a pushed pair stalled this loop).
  std::vector<uint32_t> path_vertex(n), path_down(n);
  size_t depth = 0;  // index of the path's last vertex
  path_vertex[0] = 0;
  path_down[0] = kNone;
  uint32_t p = 0;
  uint32_t* const lp = loop.data();
  uint32_t* const tw = loop_twin.data();
  auto up = [&] {  // walk up the edge above the path's last vertex
    const uint32_t down = path_down[depth];
    lp[p] = path_vertex[depth];
    tw[p] = down;
    tw[down] = p;
    ++p;
    --depth;
  };
  for (uint32_t v = 1; v < n; ++v) {
    const uint32_t par = parent[v];
    if (par >= v) return false;
    while (path_vertex[depth] != par) {
      if (depth == 0) return false;
      up();
    }
    lp[p] = par;
    ++depth;
    path_vertex[depth] = v;
    path_down[depth] = p++;
  }
  while (depth > 0) up();
  return true;
}

bool decoder_loop(const std::vector<uint32_t>& parent, const std::vector<JumpEndpoint>& jumps,
                  std::vector<uint32_t>& loop, std::vector<uint32_t>& loop_twin) {
  loop.clear();
  loop_twin.clear();
  if (parent.size() < 2) return true;
  if (jumps.empty()) return tree_tour(parent, loop, loop_twin);
  std::vector<uint32_t> tour, tour_twin;
  if (!tree_tour(parent, tour, tour_twin)) return false;
  const uint32_t T = static_cast<uint32_t>(tour.size()), nj = static_cast<uint32_t>(jumps.size());
  // Slots: tour departure p (0 .. T-1) leaves tour[p] by a tree edge; slot
  // T + i is jump end i. Around a vertex, the jump ends of tour corner c
  // (arriving at tour[c] by departure c - 1) come, in list order, between
  // that arrival and departure c.
  std::vector<uint32_t> first_jump(T, kNone);
  for (uint32_t i = 0; i < nj; ++i) {
    const JumpEndpoint& j = jumps[i];
    if (j.corner >= T || j.partner >= nj || j.partner == i || jumps[j.partner].partner != i) return false;
    if (i > 0 && jumps[i - 1].corner > j.corner) return false;
    if (first_jump[j.corner] == kNone) first_jump[j.corner] = i;
  }
  // Walk: leave by a slot, arrive by its reverse, leave by the next slot
  // clockwise: after a tree edge into corner c, c's first jump end or
  // departure c; after jump end i, the next end at its corner or the
  // departure there.
  const uint32_t total = T + nj;
  std::vector<uint32_t> left_at(total, kNone), slot_of;
  slot_of.reserve(total);
  loop.reserve(total);
  uint32_t s = 0;
  do {
    if (loop.size() >= total || left_at[s] != kNone) return false;
    left_at[s] = static_cast<uint32_t>(loop.size());
    slot_of.push_back(s);
    if (s < T) {
      loop.push_back(tour[s]);
      const uint32_t c = s + 1 == T ? 0 : s + 1;
      s = first_jump[c] != kNone ? T + first_jump[c] : c;
    } else {
      const uint32_t i = s - T, k = jumps[i].partner, c = jumps[k].corner;
      loop.push_back(tour[jumps[i].corner]);
      s = k + 1 < nj && jumps[k + 1].corner == c ? T + k + 1 : c;
    }
  } while (s != 0);
  if (loop.size() != total) return false;
  loop_twin.resize(total);
  for (uint32_t p = 0; p < total; ++p) {
    const uint32_t x = slot_of[p];
    loop_twin[p] = left_at[x < T ? tour_twin[x] : T + jumps[x - T].partner];
  }
  return true;
}

}  // namespace tsm
