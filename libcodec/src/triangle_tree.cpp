// The triangle tree and marching pattern (seed 004 §4; design notes §4). The
// cut surface is a triangulated polygon bounded by the loop. From a root
// triangle (an ear at loop position r) the polygon is consumed through a
// gate (a, b): the triangle on the gate either marches right (new loop edge
// after b, bit 0), marches left (before a, bit 1), is a leaf (closes the
// polygon) or branches at a Y-vertex x into Q1 = b..x and Q2 = x..a (Q1 first).
// Runs (march count + end type) are stored in pre-order; the decoder places
// each Y-vertex from the size of Q1's subtree, computed in one backward pass,
// and walks with an explicit stack (no recursion; linear time).
#include <algorithm>

#include "connectivity.hpp"

namespace tsm {

Status encode_triangle_tree(const CutMesh& m, const ComponentLoop& cl, std::vector<uint32_t>& corner_pos,
                            TriangleRuns& out) {
  const uint32_t L = static_cast<uint32_t>(cl.loop.size());
  out = TriangleRuns();
  if (L < 4) return Status(ErrorCode::internal, "triangle tree: loop of length " + std::to_string(L));
  auto fwd = [L](uint32_t p, uint32_t d) { return (p + d) % L; };
  auto bwd = [L](uint32_t p, uint32_t d) { return (p + L - d) % L; };

  // Loop position of every corner: sweep clockwise around loop[p] from the
  // arriving loop edge to the leaving one.
  for (uint32_t p = 0; p < L; ++p) {
    uint32_t h = he_next(cl.loop_he[bwd(p, 1)]);
    for (uint32_t guard = 0;; ++guard) {
      corner_pos[h] = p;
      if (h == cl.loop_he[p]) break;
      if (guard > m.tri.size()) return Status(ErrorCode::internal, "triangle tree: corner sweep does not end");
      h = he_next(m.twin[h]);
    }
  }
  // Root: the first ear, a triangle holding loop edges r-1 and r.
  uint32_t r = kNone;
  for (uint32_t p = 0; p < L && r == kNone; ++p)
    if (cl.loop_he[bwd(p, 1)] / 3 == cl.loop_he[p] / 3) r = p;
  if (r == kNone) return Status(ErrorCode::internal, "triangle tree: no ear on the loop");
  out.root = r;
  out.triangle_order.push_back(cl.loop_he[r] / 3);
  out.parent_slot.push_back(0);

  struct Gate {
    uint32_t a, b, g;
  };
  std::vector<Gate> stack;
  uint32_t march = 0;
  Gate cur{bwd(r, 1), fwd(r, 1), m.twin[he_next(cl.loop_he[r])]};
  for (;;) {
    const uint32_t g = cur.g;
    out.triangle_order.push_back(g / 3);
    out.parent_slot.push_back(static_cast<uint8_t>(g % 3));
    if (corner_pos[g] != cur.a || corner_pos[he_next(g)] != cur.b)
      return Status(ErrorCode::internal, "triangle tree: gate corners are not on the loop where expected");
    const uint32_t x = corner_pos[he_prev(g)];
    const bool right = x == fwd(cur.b, 1), left = x == bwd(cur.a, 1);
    if (right && left) {
      out.march.push_back(march);
      out.branch.push_back(0);
      march = 0;
      if (stack.empty()) break;
      cur = stack.back();
      stack.pop_back();
    } else if (right) {
      out.bits.push_back(0);
      ++march;
      cur = {cur.a, x, m.twin[he_prev(g)]};
    } else if (left) {
      out.bits.push_back(1);
      ++march;
      cur = {x, cur.b, m.twin[he_next(g)]};
    } else {
      out.march.push_back(march);
      out.branch.push_back(1);
      march = 0;
      stack.push_back({cur.a, x, m.twin[he_prev(g)]});
      cur = {x, cur.b, m.twin[he_next(g)]};
    }
    if (out.triangle_order.size() > L) return Status(ErrorCode::internal, "triangle tree: more triangles than the loop allows");
  }
  if (out.triangle_order.size() != L - 2)
    return Status(ErrorCode::internal, "triangle tree: " + std::to_string(out.triangle_order.size()) +
                                           " triangles for a loop of " + std::to_string(L));
  return Status::Ok();
}

template <class Bits>
Status decode_triangle_tree(uint32_t L, const TriangleRuns& runs, const std::vector<uint32_t>& loop, uint32_t n,
                            Bits& bits, const TriangleTreeOut& out, uint64_t& bit_count) {
  auto corrupt = [](const std::string& what) { return Status(ErrorCode::corrupt_data, "triangle tree: " + what); };
  const size_t nr = runs.march.size();
  if (L < 4 || runs.root >= L) return corrupt("bad loop length or root position");
  if (nr == 0 || runs.branch.size() != nr) return corrupt("no runs");
  // Q1 subtree sizes (triangles) of every branching run: backward pass.
  std::vector<uint32_t> q1(nr, 0), sizes;
  sizes.reserve(64);
  for (size_t i = nr; i-- > 0;) {
    uint64_t s = static_cast<uint64_t>(runs.march[i]) + 1;
    if (runs.branch[i]) {
      if (sizes.size() < 2) return corrupt("a branching run lacks its two subtrees");
      uint64_t s1 = sizes.back();
      sizes.pop_back();
      uint64_t s2 = sizes.back();
      sizes.pop_back();
      q1[i] = static_cast<uint32_t>(s1);
      s += s1 + s2;
    }
    if (s > L) return corrupt("a subtree has more triangles than the loop allows");
    sizes.push_back(static_cast<uint32_t>(s));
  }
  if (sizes.size() != 1 || sizes[0] != L - 3) return corrupt("runs do not add up to one tree of loop length - 2 triangles");

  const uint32_t T = L - 2;
  // Loop positions move by less than L: a compare instead of a division.
  auto fwd = [L](uint32_t p, uint32_t d) { return p + d >= L ? p + d - L : p + d; };
  auto bwd = [L](uint32_t p, uint32_t d) { return p >= d ? p - d : p + L - d; };
  auto span_of = [L](uint32_t a, uint32_t b) { return a >= b ? a - b : a + L - b; };  // (a - b) mod L
  if (loop.size() != L) return corrupt("loop length mismatch");
  std::vector<uint32_t> valence(n, 0);  // triangles emitted so far around each vertex
  std::vector<uint8_t> visits(n, 0);    // loop positions of each vertex (its tree degree), capped at 3
  for (uint32_t p = 0; p < L; ++p) {
    if (loop[p] >= n) return corrupt("loop vertex out of range");
    if (visits[loop[p]] < 3) ++visits[loop[p]];
  }
  // Raw pointers: the walk's stores could otherwise make the compiler
  // reload each vector's data (and the run's march count) every step.
  const uint32_t* const lp = loop.data();
  uint32_t* const val = valence.data();
  const uint8_t* const vis = visits.data();
  uint32_t* const corner = out.corner;
  uint32_t* const twin = out.twin;
  uint32_t* const loop_he = out.loop_he;
  const uint32_t vb = out.vertex_base, hb = out.he_base;
  uint32_t k = 0;
  // Triangle (a, b, x) entered through the parent's edge `slot` (inlined at
  // its four uses: the walk's inner loop).
  auto emit = [&](uint32_t a, uint32_t b, uint32_t x, uint32_t par, uint8_t slot) __attribute__((always_inline)) {
    const uint32_t va = lp[a], vbb = lp[b], vx = lp[x];
    ++val[va];
    ++val[vbb];
    ++val[vx];
    uint32_t* c = corner + 3 * size_t{k};
    c[0] = vb + va;
    c[1] = vb + vbb;
    c[2] = vb + vx;
    if (par != kNone) {
      const uint32_t ph = hb + 3 * par + slot;
      twin[hb + 3 * size_t{k}] = ph;
      twin[ph] = hb + 3 * k;
    }
    if (out.parent) {
      out.parent[k] = par;
      out.slot[k] = slot;
    }
    return k++;
  };
  bool twice = false;  // a loop edge claimed by two triangles (a forged file)
  auto on_loop = [&](uint32_t p, uint32_t t, uint32_t e) {
    twice |= loop_he[p] != kNone;
    loop_he[p] = hb + 3 * t + e;
  };
  const uint32_t r = runs.root;
  emit(bwd(r, 1), r, fwd(r, 1), kNone, 0);
  on_loop(bwd(r, 1), 0, 0);
  on_loop(r, 0, 1);
  struct Gate {
    uint32_t a, b, par;
    uint8_t slot;
  };
  std::vector<Gate> stack;
  Gate cur{bwd(r, 1), fwd(r, 1), 0, 2};
  bit_count = 0;
  for (size_t ri = 0; ri < nr; ++ri) {
    // Edges in this polygon besides the gate: (a - b) mod L.
    int prev = 2;
    const uint32_t march = runs.march[ri];
    for (uint32_t i = 0; i < march; ++i) {
      if (span_of(cur.a, cur.b) < 3) return corrupt("a march step leaves no room for the rest of the run");
      const uint32_t right = fwd(cur.b, 1), left = bwd(cur.a, 1);
      const int ctx = ((static_cast<int>(std::min<uint32_t>(val[lp[cur.a]], 7)) * 8 +
                        static_cast<int>(std::min<uint32_t>(val[lp[cur.b]], 7))) * 3 + prev) * 9 +
                      (vis[lp[right]] - 1) * 3 + (vis[lp[left]] - 1);
      prev = bits.bit(ctx);
      ++bit_count;
      if (prev == 0) {
        uint32_t t = emit(cur.a, cur.b, right, cur.par, cur.slot);
        on_loop(cur.b, t, 1);
        cur = {cur.a, right, t, 2};
      } else {
        uint32_t t = emit(cur.a, cur.b, left, cur.par, cur.slot);
        on_loop(left, t, 2);
        cur = {left, cur.b, t, 1};
      }
    }
    const uint32_t span = span_of(cur.a, cur.b);
    if (!runs.branch[ri]) {
      if (span != 2) return corrupt("a leaf triangle does not close its polygon");
      uint32_t t = emit(cur.a, cur.b, fwd(cur.b, 1), cur.par, cur.slot);
      on_loop(cur.b, t, 1);
      on_loop(fwd(cur.b, 1), t, 2);
      if (stack.empty()) {
        if (ri + 1 != nr) return corrupt("runs left after the last polygon closed");
        break;
      }
      cur = stack.back();
      stack.pop_back();
    } else {
      uint32_t off = q1[ri] + 1;
      if (off + 2 > span) return corrupt("a Y-vertex falls outside its polygon");
      uint32_t x = fwd(cur.b, off);
      uint32_t t = emit(cur.a, cur.b, x, cur.par, cur.slot);
      stack.push_back({cur.a, x, t, 2});
      cur = {x, cur.b, t, 1};
    }
  }
  if (k != T) return corrupt("triangle count does not match the loop");
  if (twice) return corrupt("a loop edge belongs to two triangles");
  return Status::Ok();
}

template Status decode_triangle_tree<MarchBitDecoder>(uint32_t, const TriangleRuns&, const std::vector<uint32_t>&,
                                                      uint32_t, MarchBitDecoder&, const TriangleTreeOut&, uint64_t&);
template Status decode_triangle_tree<MarchBitEncoder>(uint32_t, const TriangleRuns&, const std::vector<uint32_t>&,
                                                      uint32_t, MarchBitEncoder&, const TriangleTreeOut&, uint64_t&);

}  // namespace tsm
