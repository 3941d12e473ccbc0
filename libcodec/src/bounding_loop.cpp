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

bool decoder_loop(const std::vector<uint32_t>& parent, const std::vector<JumpEndpoint>& jumps,
                  std::vector<uint32_t>& loop, std::vector<uint32_t>& loop_twin) {
  const uint32_t n = static_cast<uint32_t>(parent.size());
  loop.clear();
  loop_twin.clear();
  if (n < 2) return true;
  // Tree slots per vertex in clockwise order: parent first, then children in
  // pre-order (= clockwise) order. slot_start[v] .. slot_start[v+1].
  std::vector<uint32_t> degree(n, 0);
  for (uint32_t v = 1; v < n; ++v) {
    if (parent[v] >= v) return false;
    degree[v]++;
    degree[parent[v]]++;
  }
  // Corner after tree slot s of vertex v, numbered by tour position.
  const uint32_t tour = 2 * (n - 1);
  std::vector<uint32_t> tree_start(n + 1, 0);
  for (uint32_t v = 0; v < n; ++v) tree_start[v + 1] = tree_start[v] + degree[v];
  std::vector<uint32_t> tree_to(tree_start[n]);  // neighbour of each tree slot
  std::vector<uint32_t> fill(tree_start.begin(), tree_start.end() - 1);
  for (uint32_t v = 1; v < n; ++v) tree_to[fill[v]++] = parent[v];  // parent slot first
  for (uint32_t v = 1; v < n; ++v) tree_to[fill[parent[v]]++] = v;
  // The tree slot at w pointing back to its neighbour v: the parent slot (0)
  // if v is w's parent, else v's child slot (children sorted by position).
  auto slot_back = [&](uint32_t v, uint32_t w) -> uint32_t {
    if (w != 0 && parent[w] == v) return 0;
    uint32_t lo = tree_start[w] + (w != 0 ? 1 : 0), hi = tree_start[w + 1];
    auto it = std::lower_bound(tree_to.begin() + lo, tree_to.begin() + hi, v);
    if (it == tree_to.begin() + hi || *it != v) return kNone;
    return static_cast<uint32_t>(it - tree_to.begin()) - tree_start[w];
  };
  // Tree tour: position q arrives at vertex corner_v[q] after slot corner_s[q].
  std::vector<uint32_t> corner_v(tour), corner_s(tour);
  {
    uint32_t v = 0, s = 0;  // leaving the root by slot 0 (first child)
    for (uint32_t step = 0; step < tour; ++step) {
      uint32_t w = tree_to[tree_start[v] + s];
      uint32_t back = slot_back(v, w);
      if (back == kNone) return false;
      uint32_t q = (step + 1) % tour;
      corner_v[q] = w;
      corner_s[q] = back;
      v = w;
      s = (back + 1) % degree[w];
    }
  }
  // Full slot arrays: each tree slot followed by the jump ends of its corner.
  const uint32_t nj = static_cast<uint32_t>(jumps.size());
  std::vector<uint32_t> extra(n, 0);
  for (uint32_t i = 0; i < nj; ++i) {
    const JumpEndpoint& j = jumps[i];
    if (j.corner >= tour || j.partner >= nj || j.partner == i || jumps[j.partner].partner != i) return false;
    if (i > 0 && (jumps[i - 1].corner > j.corner)) return false;
    extra[corner_v[j.corner]]++;
  }
  std::vector<uint32_t> start(n + 1, 0);
  for (uint32_t v = 0; v < n; ++v) start[v + 1] = start[v] + degree[v] + extra[v];
  std::vector<uint32_t> to(start[n]), back(start[n], kNone);
  std::vector<uint32_t> tree_slot_pos(tree_start[n]), jump_slot_pos(nj);
  {
    // Jump ends grouped per (vertex, tree slot), in list order.
    std::vector<uint32_t> count(tree_start[n] + 1, 0);
    for (uint32_t i = 0; i < nj; ++i) count[tree_start[corner_v[jumps[i].corner]] + corner_s[jumps[i].corner] + 1]++;
    for (uint32_t v = 0; v < n; ++v) {
      uint32_t at = start[v];
      for (uint32_t s = 0; s < degree[v]; ++s) {
        tree_slot_pos[tree_start[v] + s] = at;
        to[at] = tree_to[tree_start[v] + s];
        at += 1 + count[tree_start[v] + s + 1];
      }
    }
    std::vector<uint32_t> used(tree_start[n], 0);
    for (uint32_t i = 0; i < nj; ++i) {
      uint32_t v = corner_v[jumps[i].corner], ts = tree_start[v] + corner_s[jumps[i].corner];
      jump_slot_pos[i] = tree_slot_pos[ts] + 1 + used[ts]++;
    }
    for (uint32_t i = 0; i < nj; ++i) {
      to[jump_slot_pos[i]] = corner_v[jumps[jumps[i].partner].corner];
      back[jump_slot_pos[i]] = jump_slot_pos[jumps[i].partner];
    }
    for (uint32_t v = 0; v < n; ++v)
      for (uint32_t s = 0; s < degree[v]; ++s) {
        uint32_t w = tree_to[tree_start[v] + s];
        uint32_t ws = slot_back(v, w);
        if (ws == kNone) return false;
        back[tree_slot_pos[tree_start[v] + s]] = tree_slot_pos[tree_start[w] + ws];
      }
  }
  // Walk: arrive by a slot's reverse, leave by the next slot clockwise.
  const uint32_t total = start[n];
  std::vector<uint32_t> owner(total);
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t s = start[v]; s < start[v + 1]; ++s) owner[s] = v;
  // Loop position p leaves by slot s; the same edge walked the other way is
  // the position that leaves by back[s] (its twin on the cut surface).
  loop.reserve(total);
  std::vector<uint32_t> left_at(total, kNone), slot_of;
  slot_of.reserve(total);
  uint32_t s = start[0];
  do {
    if (loop.size() >= total || left_at[s] != kNone) return false;
    left_at[s] = static_cast<uint32_t>(loop.size());
    slot_of.push_back(s);
    loop.push_back(owner[s]);
    uint32_t r = back[s];
    uint32_t w = owner[r];
    s = r + 1 == start[w + 1] ? start[w] : r + 1;
  } while (s != start[0]);
  if (loop.size() != total) return false;
  loop_twin.resize(total);
  for (uint32_t p = 0; p < total; ++p) {
    loop_twin[p] = left_at[back[slot_of[p]]];
    if (loop_twin[p] == kNone) return false;
  }
  return true;
}

}  // namespace tsm
