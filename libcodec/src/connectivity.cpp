// Connectivity coding (seed 004 §3-4, design notes §3-5): runs the stages
// (mesh_cut -> vertex_tree -> bounding_loop -> triangle_tree) and codes
// their output with the adaptive range coder in three streams:
//   vertex tree:   per component, the tree's runs (length, leaf bit, last bit
//                  for runs after their branching node's first)
//   triangle tree: per component, root position, runs (end type, march
//                  count), marching bits, polygon-edge flags
//   topology:      component count, jump edges, virtual vertices, stitches,
//                  side faces (degenerate faces kept verbatim)
// The topology stream starts with a mode byte (FORMAT.md §8.3.1): at the
// fast levels the run values (vertex-run lengths, march counts, stitch and
// virtual-vertex positions, stitch distances) may go through static prefix
// codes instead (table_coder), stored after it: one lookup per value.
// Stitch targets are coded by their rank among candidates (§8.3.2).
// The decoder reverses it and reassembles the exact input faces.
#include <algorithm>
#include <memory>

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "range_coder.hpp"
#include "table_coder.hpp"

namespace tsm {

namespace {

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
  UIntModel march[2][2];  // [previous run's end type][this run's end type]
  Prob end[2][2];         // [previous run's end][the end of the run before it]
  Prob bit[kMarchContexts];  // see MarchBitDecoder
  Prob diagonal[2];    // by previous flag
};

struct TopologyModels {
  UIntModel count, corner, partner, position, distance, face_size, index;
  // A stitch target's candidate rank + 1 (0: its distance follows), by
  // StitchCandidates::context.
  UIntModel rank[2];
  Prob has_polygons;
};

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

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

// Run-value contexts of the tables (FORMAT.md §8.3.1).
constexpr int kRunLengthCtx = 0;    // + previous run's end (vertex-run length)
constexpr int kRunMarchCtx = 2;     // + 2 * previous run's end + this run's end (march count)
constexpr int kRunPositionCtx = 6;  // virtual and stitched vertices' position gaps
constexpr int kRunDistanceCtx = 7;  // stitch distances

// The encoder's run values (RunCoding): through their adaptive models into
// the stream they belong to, or, with tables, listed in the order the
// decoder reads them and coded at the end; then also coded adaptively into
// a stream of their own (`adaptive`), whose length is what they would have
// cost in the streams (their models code nothing else).
struct RunEncoder {
  bool tables = false;
  std::vector<std::pair<uint8_t, uint32_t>> values;  // (context, value)
  RangeEncoder adaptive;
  void put(RangeEncoder& e, UIntModel& m, int ctx, uint32_t v) {
    if (tables) {
      values.emplace_back(static_cast<uint8_t>(ctx), v);
      m.encode(adaptive, v);
    } else {
      m.encode(e, v);
    }
  }
  // The topology stream's prefix with tables: mode byte 1, the bit
  // stream's length, the table block, the bit stream.
  std::string block() const {
    TableEncoder codes(kRunContexts);
    for (auto [c, v] : values) codes.count(c, v);
    codes.build();
    BitWriter w;
    for (auto [c, v] : values) codes.put(w, c, v);
    return std::string(1, '\x01') + write_table_block(codes.lengths(), kRunMapBytes, w.finish());
  }
};

// The topology stream from the virtual vertices on: the lists it codes.
struct TopologyTail {
  std::vector<uint32_t> virtual_pos;                     // ascending
  std::vector<std::pair<uint32_t, uint32_t>> stitches;  // (position, target), ascending positions
  uint32_t side_faces = 0;
  std::vector<uint32_t> side;  // per side face: its size, then its corners (output ids)
};

// Codes the tail: with `sc`, stitch targets by their rank among the
// candidates (§8.3.2; positions all first), as the file has them; without,
// every target as a distance, after its position (what the encoder
// measures the run tables on and orders codings by, encode_connectivity).
void code_tail(RangeEncoder& e, TopologyModels& o, RunEncoder& r, const TopologyTail& t,
               StitchCandidates* sc = nullptr, std::vector<uint32_t>* target = nullptr) {
  o.count.encode(e, static_cast<uint32_t>(t.virtual_pos.size()));
  uint32_t prev = 0;
  for (uint32_t p : t.virtual_pos) {
    r.put(e, o.position, kRunPositionCtx, p - prev);
    prev = p;
  }
  o.count.encode(e, static_cast<uint32_t>(t.stitches.size()));
  prev = 0;
  for (auto [dup, orig] : t.stitches) {
    r.put(e, o.position, kRunPositionCtx, dup - prev);
    if (!sc) r.put(e, o.distance, kRunDistanceCtx, dup - orig - 1);
    prev = dup;
  }
  if (sc)
    for (auto [dup, orig] : t.stitches) {
      sc->gather(dup);
      const uint32_t rank = sc->rank_of(orig);
      o.rank[sc->context()].encode(e, rank);
      if (rank == 0) r.put(e, o.distance, kRunDistanceCtx, dup - orig - 1);
      (*target)[dup] = orig;
    }
  o.count.encode(e, t.side_faces);
  for (size_t i = 0; i < t.side.size(); i += 1 + size_t{t.side[i]}) {
    o.face_size.encode(e, t.side[i]);
    for (uint32_t j = 1; j <= t.side[i]; ++j) o.index.encode(e, t.side[i + j]);
  }
}

// What the topology stream with stitch targets by candidates needs beyond
// the lists: the coder, models and run values where the tail starts, and
// the cut surface in decode order (corners as pre-order positions, twins).
struct CandidateTail {
  RangeEncoder coder;
  TopologyModels models;
  RunEncoder runs;
  TopologyTail tail;
  std::vector<uint32_t> corner, twin;
  uint32_t positions = 0;
};

// The topology stream (mode byte first) with the tail coded from where `c`
// left off, stitch targets by candidates.
std::string candidate_topology(CandidateTail& c) {
  std::vector<uint8_t> is_virtual(c.positions, 0), stitched(c.positions, 0);
  for (uint32_t p : c.tail.virtual_pos) is_virtual[p] = 1;
  for (auto [dup, orig] : c.tail.stitches) stitched[dup] = 1;
  std::vector<uint32_t> target(c.positions, kNone);
  StitchCandidates sc(c.corner, c.twin, is_virtual, stitched, target);
  code_tail(c.coder, c.models, c.runs, c.tail, &sc, &target);
  return (c.runs.tables ? c.runs.block() : std::string(1, '\0')) + c.coder.finish();
}

}  // namespace

Status encode_connectivity(const Mesh& mesh, ConnectivityEncoding& out, const CutHints& hints) {
  out = ConnectivityEncoding();
  if (mesh.vertex_count() >= 0x3FFFFFFFu || mesh.corner_count() >= 0x3FFFFFFFu)
    return Status(ErrorCode::limit_exceeded, "meshes above 2^30 vertices or corners are not supported");
  PreparedInput prep = prepare_input(mesh);
  CutMesh m = cut_mesh(prep, static_cast<uint32_t>(mesh.vertex_count()), hints);
  const bool by_position = hints.root_rule > 0 && hints.qpos;
  out.root_tie = m.root_tie;
  const VertexForest f =
      build_vertex_tree(m, hints.qpos, hints.midpoint_tree && hints.qpos, by_position, &out.root_tie);

  RangeEncoder ev, et, eo;
  RunEncoder runs;
  runs.tables = hints.runs == RunCoding::tables;
  VertexTreeModels vm;
  TriangleTreeModels tm;
  TopologyModels om;
  ConnectivityStats& st = out.stats;
  const uint32_t C = m.component_count();
  om.count.encode(eo, C);
  const bool polygons = prep.polygon_count > 0;
  eo.bit(om.has_polygons, polygons);

  // Triangles per component.
  std::vector<uint32_t> tri_start(C + 1, 0), tris(m.triangle_count());
  for (uint32_t t = 0; t < m.triangle_count(); ++t) tri_start[m.vertex_component[m.tri[3 * t]] + 1]++;
  for (uint32_t c = 0; c < C; ++c) tri_start[c + 1] += tri_start[c];
  {
    std::vector<uint32_t> fill(tri_start.begin(), tri_start.end() - 1);
    for (uint32_t t = 0; t < m.triangle_count(); ++t) tris[fill[m.vertex_component[m.tri[3 * t]]]++] = t;
  }
  std::vector<uint8_t> cut_he = f.tree_he;
  std::vector<uint32_t> local(m.triangle_count()), corner_pos(m.tri.size());
  std::vector<uint32_t> comp_tris, scratch_corner, scratch_twin, scratch_loop_he;
  // Per pre-order position: which triangle corners reference it, filled as we go.
  std::vector<uint32_t> pos_of(m.vertex_count);
  for (uint32_t p = 0; p < f.order.size(); ++p) pos_of[f.order[p]] = p;
  std::vector<uint32_t> last_child(f.order.size(), kNone);
  // Triangles in decode order, and how each is rotated to start at its gate.
  std::vector<uint32_t> dec_tri, dec_of(m.triangle_count(), kNone);
  std::vector<uint8_t> rot(m.triangle_count(), 0);
  dec_tri.reserve(m.triangle_count());
  for (uint32_t p = 0; p < f.order.size(); ++p)
    if (f.parent[p] != kNone) last_child[f.parent[p]] = p;
  std::vector<uint32_t> kids_seen(f.order.size(), 0);  // runs started so far at each branching node

  int prev_leaf = 1;
  for (uint32_t c = 0; c < C; ++c) {
    const uint32_t start = f.component_start[c], end = f.component_start[c + 1];
    // Vertex tree runs.
    for (uint32_t i = start; i < end;) {
      uint32_t j = i;
      while (f.child_count[j] == 1) ++j;
      const int leaf = f.child_count[j] == 0;
      runs.put(ev, vm.length[prev_leaf], kRunLengthCtx + prev_leaf, j - i);
      ev.bit(vm.leaf[prev_leaf], leaf);
      if (i != start) {
        const uint32_t idx = kids_seen[f.parent[i]]++;
        if (idx > 0) ev.bit(vm.last[idx > 1], last_child[f.parent[i]] == i);
      }
      prev_leaf = leaf;
      ++st.vertex_runs;
      i = j + 1;
    }
    if (end - start < 2) continue;
    // Jumps and loop.
    comp_tris.assign(tris.begin() + tri_start[c], tris.begin() + tri_start[c + 1]);
    ComponentLoop cl = encoder_loop(m, f, c, comp_tris, cut_he, local);
    om.count.encode(eo, static_cast<uint32_t>(cl.jumps.size()));
    uint32_t prev_corner = 0;
    for (uint32_t i = 0; i < cl.jumps.size(); ++i) {
      om.corner.encode(eo, cl.jumps[i].corner - prev_corner);
      prev_corner = cl.jumps[i].corner;
    }
    for (uint32_t i = 0; i < cl.jumps.size(); ++i)
      if (cl.jumps[i].partner > i) om.partner.encode(eo, cl.jumps[i].partner - i - 1);
    st.jump_edges += cl.jumps.size() / 2;
    // Triangle tree.
    TriangleRuns tr;
    TSM_RETURN_IF_ERROR(encode_triangle_tree(m, cl, corner_pos, tr));
    if (tr.triangle_order.size() != comp_tris.size())
      return Status(ErrorCode::internal, "component " + std::to_string(c) + ": triangle tree covers " +
                                             std::to_string(tr.triangle_order.size()) + " of " +
                                             std::to_string(comp_tris.size()) + " triangles");
    for (size_t k = 0; k < tr.triangle_order.size(); ++k) {
      const uint32_t t = tr.triangle_order[k];
      dec_of[t] = static_cast<uint32_t>(dec_tri.size());
      dec_tri.push_back(t);
      rot[t] = tr.parent_slot[k];
    }
    {  // The root triangle starts at loop position root - 1, as the decoder emits it.
      const uint32_t t = tr.triangle_order[0], L = static_cast<uint32_t>(cl.loop.size());
      const uint32_t first = cl.loop[(tr.root + L - 1) % L];
      for (uint8_t j = 0; j < 3; ++j)
        if (m.tri[3 * t + j] == first) rot[t] = j;
    }
    tm.root.encode(et, tr.root);
    int prev_end = 1, prev_end2 = 1;
    for (size_t r = 0; r < tr.march.size(); ++r) {
      et.bit(tm.end[prev_end][prev_end2], tr.branch[r]);
      runs.put(et, tm.march[prev_end][tr.branch[r]], kRunMarchCtx + 2 * prev_end + tr.branch[r], tr.march[r]);
      prev_end2 = prev_end;
      prev_end = tr.branch[r];
    }
    {  // Marching bits, coded during the same walk the decoder makes.
      MarchBitEncoder source{et, tm.bit, tr.bits};
      std::vector<uint32_t> local_loop(cl.loop.size());
      for (size_t p = 0; p < cl.loop.size(); ++p) local_loop[p] = pos_of[cl.loop[p]] - start;
      uint64_t used = 0;
      const uint32_t L = static_cast<uint32_t>(cl.loop.size());
      scratch_corner.resize(3 * size_t{L});
      scratch_twin.resize(3 * size_t{L});
      scratch_loop_he.assign(L, kNone);
      TriangleTreeOut walk;
      walk.corner = scratch_corner.data();
      walk.twin = scratch_twin.data();
      walk.loop_he = scratch_loop_he.data();
      TSM_RETURN_IF_ERROR(decode_triangle_tree(L, tr, local_loop, end - start, source, walk, used));
      if (used != tr.bits.size()) return Status(ErrorCode::internal, "marching bits: the walk used another count");
    }
    st.triangle_runs += tr.march.size();
    st.marching_bits += tr.bits.size();
    if (polygons) {
      int prev = 0;
      for (size_t k = 1; k < tr.triangle_order.size(); ++k) {
        int d = m.diagonal[3 * tr.triangle_order[k] + tr.parent_slot[k]];
        et.bit(tm.diagonal[prev], d);
        prev = d;
      }
    }
  }

  // Vertex numbering: the first occurrence of an input vertex in pre-order
  // carries it; later ones are stitched to it; virtual vertices carry nothing.
  const uint32_t P = static_cast<uint32_t>(f.order.size());
  std::vector<uint32_t> first_pos(mesh.vertex_count(), kNone), out_id(P, kNone);
  TopologyTail tail;  // the topology stream's lists from the virtual vertices on
  std::vector<uint32_t>& virtual_pos = tail.virtual_pos;
  std::vector<std::pair<uint32_t, uint32_t>>& stitches = tail.stitches;
  for (uint32_t p = 0; p < P; ++p) {
    uint32_t v = f.order[p];
    if (m.kind[v] == VertexKind::virtual_) {
      virtual_pos.push_back(p);
      continue;
    }
    uint32_t s = m.source[v];
    if (first_pos[s] == kNone) {
      first_pos[s] = p;
      out_id[p] = static_cast<uint32_t>(out.vertex_order.size());
      out.vertex_order.push_back(s);
    } else {
      stitches.push_back({p, first_pos[s]});
      out_id[p] = out_id[first_pos[s]];
    }
  }
  if (out.vertex_order.size() != mesh.vertex_count())
    return Status(ErrorCode::internal, "vertex numbering lost vertices");
  GeometryLayout& g = out.layout;
  g.vertex_count = static_cast<uint32_t>(out.vertex_order.size());
  g.parent.assign(g.vertex_count, kNone);
  for (uint32_t p = 0; p < P; ++p)
    if (m.kind[f.order[p]] != VertexKind::virtual_ && first_pos[m.source[f.order[p]]] == p)
      g.parent[out_id[p]] = f.parent[p] == kNone ? kNone : out_id[f.parent[p]];
  g.anchor.assign(g.vertex_count, kNone);
  if (hints.anchor)
    for (uint32_t v = 0; v < g.vertex_count; ++v) g.anchor[v] = (*hints.anchor)[out.vertex_order[v]];
  if (dec_tri.size() != m.triangle_count()) return Status(ErrorCode::internal, "triangle trees lost triangles");
  g.corner.resize(3 * dec_tri.size());
  g.twin.resize(3 * dec_tri.size());
  // With stitches also the corners as pre-order positions (the cut surface
  // the stitch candidates are found on, candidate_topology).
  std::vector<uint32_t> cut_corner(stitches.empty() ? 0 : g.corner.size());
  for (size_t k = 0; k < dec_tri.size(); ++k) {
    const uint32_t t = dec_tri[k];
    for (uint32_t e = 0; e < 3; ++e) {
      const uint32_t p = pos_of[m.tri[3 * t + (rot[t] + e) % 3]];
      g.corner[3 * k + e] = out_id[p];
      if (!cut_corner.empty()) cut_corner[3 * k + e] = p;
      const uint32_t h = m.twin[3 * t + (rot[t] + e) % 3], t2 = h / 3;
      g.twin[3 * k + e] = 3 * dec_of[t2] + (h % 3 + 3 - rot[t2]) % 3;
    }
  }

  // The rest of the topology stream: virtual vertices, stitches, side
  // faces (corners as output vertex ids). Coded first with every stitch
  // target as a distance (what the choice of run tables below is measured
  // on); with stitches, the coder's state where the tail starts is kept for
  // candidate_topology, which codes the tail as the file has it.
  {
    std::vector<uint32_t> input_to_out(mesh.vertex_count());
    for (uint32_t i = 0; i < out.vertex_order.size(); ++i) input_to_out[out.vertex_order[i]] = i;
    tail.side_faces = static_cast<uint32_t>(prep.side_faces.size());
    for (uint32_t face : prep.side_faces) {
      tail.side.push_back(mesh.face_size(face));
      for (uint32_t i = 0; i < mesh.face_size(face); ++i) tail.side.push_back(input_to_out[mesh.face(face)[i]]);
    }
  }
  std::unique_ptr<CandidateTail> c;
  if (!stitches.empty()) {
    c = std::make_unique<CandidateTail>();
    c->coder = eo;
    c->models = om;
    c->runs = runs;
  }
  code_tail(eo, om, runs, tail);
  st.components = C;
  st.virtual_vertices = virtual_pos.size();
  st.stitches = stitches.size();
  if (c) {
    c->corner = std::move(cut_corner);
    c->twin = g.twin;
    c->positions = P;
    c->tail = std::move(tail);
  }
  st.side_faces = prep.side_faces.size();
  st.polygons = prep.polygon_count;
  out.streams.vertex_tree = ev.finish();
  out.streams.triangle_tree = et.finish();
  out.streams.topology = eo.finish();
  // The mode byte (and the tables) first.
  const std::string block = runs.tables ? runs.block() : std::string(1, '\0');
  if (runs.tables) {
    // Tables where they cost at most 1/8 more than the adaptive models
    // (the corpus scans: 3-11% more, tables included). On regular meshes,
    // whose runs repeat, the models learn the values down to a small
    // fraction of a bit while a prefix code spends at least one bit on
    // each (40-500% more): those are coded again without tables.
    const size_t adaptive = runs.adaptive.finish().size();
    if (block.size() > adaptive + adaptive / 8) {
      CutHints again = hints;
      again.runs = RunCoding::adaptive;
      return encode_connectivity(mesh, out, again);
    }
  }
  out.streams.topology = block + out.streams.topology;
  if (c) {  // the stitch targets by candidates, as the file has them
    out.distance_topology = std::move(out.streams.topology);
    out.streams.topology = candidate_topology(*c);
  }
  st.bytes = out.streams.vertex_tree.size() + out.streams.triangle_tree.size() + out.streams.topology.size();
  return Status::Ok();
}

Status decode_connectivity(const ConnectivityStreams& in, uint64_t vertex_count, uint64_t face_count,
                           uint64_t corner_count, Mesh& out, GeometryLayout& layout,
                           ConnectivityStats* stats) {
  // §8.3.1: the mode byte, and with tables the bit stream's length, the run
  // tables and the bit stream before the range-coded rest.
  std::string_view topology = in.topology;
  bool tables = false;
  TableSet run_tables;
  BitReader run_bits;
  {
    ByteReader r(topology);
    uint8_t mode;
    if (!r.u8(mode)) return corrupt("topology stream is empty (no run coding mode)");
    if (mode > 1) return corrupt("run coding mode " + std::to_string(mode) + " (0 adaptive or 1 tables)");
    if (mode == 1) {
      std::string why;
      if (!read_table_block(r, kRunContexts, kRunMapBytes, run_tables, run_bits, why))
        return corrupt("run values: " + why);
      tables = true;
    }
    topology = topology.substr(r.offset());
  }
  RangeDecoder dv(in.vertex_tree), dt(in.triangle_tree), dop(topology);
  VertexTreeModels vm;
  TriangleTreeModels tm;
  TopologyModels om;
  ConnectivityStats st;
  auto overrun = [&] {
    return dv.overrun() > RangeDecoder::kMaxOverrun || dt.overrun() > RangeDecoder::kMaxOverrun ||
           dop.overrun() > RangeDecoder::kMaxOverrun || run_bits.overrun();
  };
  // A run value: from its model, or with tables from the bit stream
  // (0xFFFFFFFF, which every caller refuses, for a code word no table has
  // or a negative value).
  auto run_value = [&](UIntModel& m, RangeDecoder& d, int ctx) -> uint32_t {
    if (!tables) return m.decode(d);
    int32_t r;
    if (!run_tables.decode(run_bits, ctx, r) || r < 0) return 0xFFFFFFFFu;
    return static_cast<uint32_t>(r);
  };
  // Pre-order vertices: real + duplicates + virtual; the latter two are at
  // most one per corner each.
  const uint64_t max_positions = vertex_count + 2 * corner_count;
  const uint64_t max_jumps = max_decisions(topology.size()) / 6;
  const uint32_t C = om.count.decode(dop);
  const bool polygons = dop.bit(om.has_polygons);
  if (C > max_positions) return corrupt("more components than vertices");

  std::vector<uint32_t> parent;  // global pre-order parent positions
  // Decoded triangles, written in place by the triangle tree walk: per
  // half-edge the pre-order position at its origin (output vertex ids once
  // the topology stream has numbered them) and the half-edge across it.
  std::vector<uint32_t>& corner = layout.corner;
  std::vector<uint32_t>& twin = layout.twin;
  corner.clear();
  twin.clear();
  layout.corner_ref = nullptr;
  // Polygons only: per triangle its parent (global decode index), the
  // parent's edge it shares and whether it is glued to the parent there.
  std::vector<uint32_t> tri_parent;
  std::vector<uint8_t> tri_slot, tri_glued;
  std::vector<uint32_t> local_parent, loop, loop_twin, loop_he;
  std::vector<std::pair<uint32_t, uint32_t>> stack;  // branching node, runs started at it so far
  // The header's counts are within the streams' budget (check_budget): the
  // common case then grows no array while decoding (holes add a triangle
  // per hole edge, polygons up to 6 half-edges per 4 corners; reserving
  // touches no memory).
  parent.reserve(vertex_count + vertex_count / 8 + 64);  // virtual vertices and duplicates beyond the count
  const size_t half_edges = corner_count + corner_count / 2 + 96;
  corner.reserve(half_edges);
  twin.reserve(half_edges);
  int prev_leaf = 1;
  for (uint32_t c = 0; c < C; ++c) {
    const uint32_t start = static_cast<uint32_t>(parent.size());
    // Vertex tree runs.
    stack.clear();
    bool root_run = true;
    for (;;) {
      if (overrun()) return corrupt("vertex tree stream is truncated");
      uint32_t len = run_value(vm.length[prev_leaf], dv, kRunLengthCtx + prev_leaf);
      if (len == 0xFFFFFFFFu || parent.size() + len + 1 > max_positions) return corrupt("vertex tree run too long");
      int leaf = dv.bit(vm.leaf[prev_leaf]);
      prev_leaf = leaf;
      uint32_t par = kNone;
      if (!root_run) {
        if (stack.empty()) return corrupt("vertex tree run without a parent");
        par = stack.back().first;
        const uint32_t idx = stack.back().second++;
        if (idx > 0 && dv.bit(vm.last[idx > 1])) stack.pop_back();
      }
      root_run = false;
      for (uint32_t i = 0; i <= len; ++i) {
        parent.push_back(par);
        par = static_cast<uint32_t>(parent.size() - 1);
      }
      if (!leaf) stack.push_back({par, 0});
      ++st.vertex_runs;
      if (leaf && stack.empty()) break;
    }
    const uint32_t n = static_cast<uint32_t>(parent.size()) - start;
    if (n < 2) continue;
    if (n == 2) return corrupt("a component of two vertices cannot hold triangles");
    local_parent.resize(n);
    for (uint32_t i = 0; i < n; ++i) local_parent[i] = parent[start + i] == kNone ? kNone : parent[start + i] - start;
    // Jumps.
    // Jump endpoints: a dense component (duplicate faces, many handles on
    // few vertices) can have far more than its vertices, so the bound is the
    // stream's: each endpoint's corner costs at least 6 coded decisions.
    uint32_t nj = om.count.decode(dop);
    if (nj > max_jumps || nj % 2 || overrun()) return corrupt("bad jump edge count");
    std::vector<JumpEndpoint> jumps(nj);
    uint32_t jump_corner = 0;
    for (uint32_t i = 0; i < nj; ++i) {
      uint32_t d = om.corner.decode(dop);
      if (d > 2 * n) return corrupt("jump edge corner out of range");
      jump_corner += d;
      jumps[i] = {jump_corner, 0, kNone};
    }
    for (uint32_t i = 0; i < nj; ++i) {
      if (jumps[i].partner != kNone) continue;
      uint32_t d = om.partner.decode(dop);
      if (d >= nj || i + 1 + d >= nj || jumps[i + 1 + d].partner != kNone) return corrupt("bad jump edge pairing");
      jumps[i].partner = i + 1 + d;
      jumps[i + 1 + d].partner = i;
    }
    st.jump_edges += nj / 2;
    if (overrun()) return corrupt("topology stream is truncated");
    if (!decoder_loop(local_parent, jumps, loop, loop_twin)) return corrupt("jump edges do not give one bounding loop");
    const uint32_t L = static_cast<uint32_t>(loop.size());
    // Triangle tree.
    TriangleRuns tr;
    tr.root = tm.root.decode(dt);
    uint32_t total = 0;
    uint64_t leaves = 0, branches = 0;
    int prev_end = 1, prev_end2 = 1;
    for (;;) {
      if (overrun()) return corrupt("triangle tree stream is truncated");
      const int br = dt.bit(tm.end[prev_end][prev_end2]);
      uint32_t march = run_value(tm.march[prev_end][br], dt, kRunMarchCtx + 2 * prev_end + br);
      if (march == 0xFFFFFFFFu || total + static_cast<uint64_t>(march) + 1 > L) return corrupt("triangle run too long");
      tr.march.push_back(march);
      tr.branch.push_back(static_cast<uint8_t>(br));
      prev_end2 = prev_end;
      prev_end = br;
      total += march + 1;
      // Pre-order runs form a full tree when leaves = branches + 1.
      (br ? branches : leaves)++;
      if (leaves == branches + 1) break;
    }
    st.triangle_runs += tr.march.size();
    MarchBitDecoder source{dt, tm.bit};
    const uint32_t T = L - 2, base = static_cast<uint32_t>(corner.size() / 3);
    if (uint64_t{base} + T > corner_count + max_positions) return corrupt("more triangles than the header allows");
    corner.resize(3 * (size_t{base} + T));
    twin.resize(3 * (size_t{base} + T), kNone);
    loop_he.assign(L, kNone);
    TriangleTreeOut walk;
    walk.corner = corner.data() + 3 * size_t{base};
    walk.twin = twin.data();
    walk.loop_he = loop_he.data();
    walk.vertex_base = start;
    walk.he_base = 3 * base;
    if (polygons) {
      tri_parent.resize(size_t{base} + T);
      tri_slot.resize(size_t{base} + T);
      tri_glued.resize(size_t{base} + T, 0);
      walk.parent = tri_parent.data() + base;
      walk.slot = tri_slot.data() + base;
    }
    uint64_t used = 0;
    TSM_RETURN_IF_ERROR(decode_triangle_tree(L, tr, loop, n, source, walk, used));
    st.marching_bits += used;
    if (overrun()) return corrupt("triangle tree stream is truncated");
    // Each loop edge meets the loop edge that walks the same cut edge the
    // other way (parent and child were paired by the walk). With loop_twin
    // an involution without fixed points, every pair is mutual: the cut
    // surface closes (no half-edge is left without a twin: checked below).
    for (uint32_t p = 0; p < L; ++p) {
      const uint32_t o = loop_twin[p];
      if (loop_he[p] == kNone || o >= L || o == p || loop_twin[o] != p) return corrupt("the cut surface does not close");
      twin[loop_he[p]] = loop_he[o];
    }
    if (polygons)
      for (uint32_t k = 0; k < T; ++k) {
        uint32_t& par = tri_parent[base + k];
        if (par != kNone) par += base;
        if (k > 0)
          tri_glued[base + k] = static_cast<uint8_t>(dt.bit(tm.diagonal[k == 1 ? 0 : tri_glued[base + k - 1]]));
      }
  }

  // Vertex kinds and output ids.
  const uint32_t P = static_cast<uint32_t>(parent.size());
  std::vector<uint32_t> out_id(P, kNone);
  std::vector<uint8_t> is_virtual(P, 0);
  uint32_t nvirt = om.count.decode(dop);
  if (nvirt > P) return corrupt("more virtual vertices than vertices");
  uint32_t at = 0;
  for (uint32_t i = 0; i < nvirt; ++i) {
    uint32_t d = run_value(om.position, dop, kRunPositionCtx);
    if (d > P || at + static_cast<uint64_t>(d) >= P || (i > 0 && d == 0)) return corrupt("virtual vertex position out of range");
    at += d;
    is_virtual[at] = 1;
  }
  uint32_t nstitch = om.count.decode(dop);
  if (nstitch > P) return corrupt("more stitches than vertices");
  std::vector<uint32_t> stitch_to(P, kNone);
  at = 0;
  if (nstitch > 0) {  // §8.3.2: every position, then every target by its candidate rank
    std::vector<uint8_t> stitched(P, 0);
    std::vector<uint32_t> at_list(nstitch);
    for (uint32_t i = 0; i < nstitch; ++i) {
      const uint32_t d = run_value(om.position, dop, kRunPositionCtx);
      if (overrun() || at + static_cast<uint64_t>(d) >= P || (i > 0 && d == 0)) return corrupt("stitch position out of range");
      at += d;
      stitched[at] = 1;
      at_list[i] = at;
    }
    StitchCandidates sc(corner, twin, is_virtual, stitched, stitch_to);
    for (uint32_t d : at_list) {
      sc.gather(d);
      const uint32_t rank = om.rank[sc.context()].decode(dop);
      if (overrun() || rank == 0xFFFFFFFFu) return corrupt("stitch target rank out of range");
      uint32_t t;
      if (rank == 0) {
        const uint32_t dist = run_value(om.distance, dop, kRunDistanceCtx);
        if (dist >= d) return corrupt("stitch target out of range");
        t = d - dist - 1;
      } else {
        t = sc.at_rank(rank);
        if (t == kNone) return corrupt("stitch target rank out of range");
      }
      if (is_virtual[t] || stitched[t]) return corrupt("stitch to a vertex that carries no position");
      stitch_to[d] = t;
    }
  }
  uint32_t next_id = 0;
  for (uint32_t p = 0; p < P; ++p) {
    if (is_virtual[p]) continue;
    if (stitch_to[p] != kNone) {
      uint32_t q = stitch_to[p];
      if (is_virtual[q] || stitch_to[q] != kNone) return corrupt("stitch to a vertex that carries no position");
      out_id[p] = out_id[q];
    } else {
      out_id[p] = next_id++;
    }
  }
  if (next_id != vertex_count)
    return corrupt("connectivity gives " + std::to_string(next_id) + " vertices, the header says " +
                   std::to_string(vertex_count));
  // Pairs are mutual by construction (the walk pairs parent and child, the
  // loop pairs above); a half-edge that got no twin is the one way left.
  if (std::find(twin.begin(), twin.end(), kNone) != twin.end()) return corrupt("the cut surface does not close");
  layout.vertex_count = static_cast<uint32_t>(vertex_count);
  layout.parent.assign(vertex_count, kNone);
  for (uint32_t p = 0; p < P; ++p) {
    if (is_virtual[p] || stitch_to[p] != kNone) continue;
    if (parent[p] != kNone) {
      if (is_virtual[parent[p]]) return corrupt("a virtual vertex has children");
      layout.parent[out_id[p]] = out_id[parent[p]];
    }
  }
  // Side faces: kept verbatim (the topology stream's last list).
  const uint32_t nside = om.count.decode(dop);
  if (nside > face_count) return corrupt("more side faces than faces");
  std::vector<uint32_t> side, side_start(1, 0);
  for (uint32_t i = 0; i < nside; ++i) {
    uint32_t n = om.face_size.decode(dop);
    if (n > corner_count || side.size() + n > corner_count || overrun()) return corrupt("bad side face size");
    for (uint32_t j = 0; j < n; ++j) {
      side.push_back(om.index.decode(dop));
      if (side.back() >= vertex_count) return corrupt("side face corner out of range");
    }
    side_start.push_back(static_cast<uint32_t>(side.size()));
  }

  // Triangle corners: pre-order positions -> output vertex ids (kNone:
  // virtual); without virtual vertices and stitches they are the same. When
  // the triangles are copied to the output one by one (below), the copy does
  // it on the way: one pass over the corners instead of two.
  // Three ways to the output faces (below): the corners are the indices as
  // they are, or triangles are copied one by one, or polygons are glued.
  const bool remap = nvirt != 0 || nstitch != 0;
  const bool corners_are_faces = !polygons && nvirt == 0 && nside == 0;
  const bool copy_each = !polygons && !corners_are_faces;
  if (remap && !copy_each)
    for (uint32_t& x : corner) x = out_id[x];

  // Faces: triangles in decode order, polygons glued along flagged edges.
  out.face_offsets.assign(1, 0);
  out.indices.clear();
  const uint32_t NT = static_cast<uint32_t>(corner.size() / 3);
  out.face_offsets.reserve(std::min<uint64_t>(face_count, NT) + 1);
  out.indices.reserve(std::min<uint64_t>(corner_count, 3 * uint64_t{NT}));
  std::vector<uint32_t> node_vertex, node_next, edge_node;
  std::vector<uint32_t> group_root, root_node;
  if (polygons) {
    group_root.assign(NT, kNone);
    root_node.assign(NT, kNone);
    node_vertex.reserve(3 * static_cast<size_t>(NT));
    edge_node.assign(3 * static_cast<size_t>(NT), kNone);
  }
  auto push_face = [&](const uint32_t* c, size_t k) -> bool {
    if (out.face_offsets.size() > face_count || out.indices.size() + k > corner_count) return false;
    out.indices.insert(out.indices.end(), c, c + k);
    out.face_offsets.push_back(static_cast<uint32_t>(out.indices.size()));
    return true;
  };
  if (corners_are_faces) {
    // Every triangle is a face: the corners are the indices (the layout
    // reads them there).
    if (NT > face_count || 3 * uint64_t{NT} > corner_count) return corrupt("more faces than the header says");
    out.indices = std::move(corner);
    corner = std::vector<uint32_t>();
    layout.corner_ref = &out.indices;
    out.face_offsets.resize(size_t{NT} + 1);
    for (uint32_t k = 0; k <= NT; ++k) out.face_offsets[k] = 3 * k;
  } else if (copy_each) {
    // Triangles, skipping virtual ones, straight into the output.
    const size_t max_faces = std::min<uint64_t>({face_count, NT, corner_count / 3});
    out.face_offsets.resize(max_faces + 1);
    out.indices.resize(3 * max_faces);
    uint32_t* fo = out.face_offsets.data();
    uint32_t* ix = out.indices.data();
    size_t nf = 0;
    const uint32_t* id = out_id.data();
    for (uint32_t k = 0; k < NT; ++k) {
      uint32_t* c = &corner[3 * static_cast<size_t>(k)];
      if (remap) {
        c[0] = id[c[0]];
        c[1] = id[c[1]];
        c[2] = id[c[2]];
      }
      if (c[0] == kNone || c[1] == kNone || c[2] == kNone) continue;
      if (nf == max_faces) return corrupt("more faces than the header says");
      uint32_t* o = ix + 3 * nf;
      o[0] = c[0];  // three stores: std::copy of three became a memmove call
      o[1] = c[1];
      o[2] = c[2];
      ++nf;
      fo[nf] = static_cast<uint32_t>(3 * nf);
    }
    out.face_offsets.resize(nf + 1);
    out.indices.resize(3 * nf);
  }
  for (uint32_t k = 0; polygons && k < NT; ++k) {
    const uint32_t* c = &corner[3 * static_cast<size_t>(k)];
    if (c[0] == kNone || c[1] == kNone || c[2] == kNone) {
      if (tri_glued[k]) return corrupt("a virtual triangle is flagged as part of a polygon");
      continue;
    }
    if (!tri_glued[k]) {
      // A new polygon: its corner cycle starts as this triangle.
      uint32_t n0 = static_cast<uint32_t>(node_vertex.size());
      node_vertex.insert(node_vertex.end(), {c[0], c[1], c[2]});
      node_next.insert(node_next.end(), {n0 + 1, n0 + 2, n0});
      for (uint32_t i = 0; i < 3; ++i) edge_node[3 * static_cast<size_t>(k) + i] = n0 + i;
      group_root[k] = k;
      root_node[k] = n0;
    } else {
      // Glued to its parent along the parent's edge b->a: insert x between.
      uint32_t par = tri_parent[k];
      uint32_t nd = par == kNone ? kNone : edge_node[3 * static_cast<size_t>(par) + tri_slot[k]];
      if (nd == kNone || group_root[par] == kNone) return corrupt("a polygon edge flag glues to a missing triangle");
      uint32_t x = static_cast<uint32_t>(node_vertex.size());
      node_vertex.push_back(c[2]);
      node_next.push_back(node_next[nd]);
      node_next[nd] = x;
      edge_node[3 * static_cast<size_t>(k) + 1] = nd;
      edge_node[3 * static_cast<size_t>(k) + 2] = x;
      edge_node[3 * static_cast<size_t>(par) + tri_slot[k]] = kNone;  // now interior
      group_root[k] = group_root[par];
    }
  }
  if (polygons) {
    // Each polygon is emitted starting at its fan apex (the corner shared by
    // all its triangles), so that triangulating it again from its first
    // corner gives the same diagonals: re-encoding reproduces the bytes.
    std::vector<uint32_t> member_start(NT + 1, 0), members, poly, count;
    for (uint32_t k = 0; k < NT; ++k)
      if (group_root[k] != kNone) member_start[group_root[k] + 1]++;
    for (uint32_t k = 0; k < NT; ++k) member_start[k + 1] += member_start[k];
    members.resize(member_start[NT]);
    {
      std::vector<uint32_t> fill(member_start.begin(), member_start.end() - 1);
      for (uint32_t k = 0; k < NT; ++k)
        if (group_root[k] != kNone) members[fill[group_root[k]]++] = k;
    }
    for (uint32_t k = 0; k < NT; ++k) {
      if (group_root[k] != k) continue;
      const uint32_t size = member_start[k + 1] - member_start[k];
      poly.clear();
      uint32_t nd = root_node[k];
      do {
        poly.push_back(node_vertex[nd]);
        nd = node_next[nd];
      } while (nd != root_node[k] && poly.size() <= node_vertex.size());
      if (poly.size() != size + 2) return corrupt("a polygon does not close");
      if (size >= 2) {
        // The apex is a corner of every triangle of the fan: count corners.
        count.assign(poly.size(), 0);
        for (uint32_t i = member_start[k]; i < member_start[k + 1]; ++i) {
          const uint32_t* tv = &corner[3 * static_cast<size_t>(members[i])];
          for (int c = 0; c < 3; ++c) {
            auto it = std::find(poly.begin(), poly.end(), tv[c]);
            if (it != poly.end()) count[static_cast<size_t>(it - poly.begin())]++;
          }
        }
        size_t apex = static_cast<size_t>(std::max_element(count.begin(), count.end()) - count.begin());
        std::rotate(poly.begin(), poly.begin() + static_cast<std::ptrdiff_t>(apex), poly.end());
      }
      if (!push_face(poly.data(), poly.size())) return corrupt("more faces than the header says");
    }
  }

  // Side faces (decoded above), after the triangles and polygons.
  for (uint32_t i = 0; i < nside; ++i)
    if (!push_face(side.data() + side_start[i], side_start[i + 1] - side_start[i]))
      return corrupt("more faces than the header says");
  if (overrun()) return corrupt("connectivity streams are truncated");
  if (out.face_count() != face_count || out.indices.size() != corner_count)
    return corrupt("connectivity gives " + std::to_string(out.face_count()) + " faces and " +
                   std::to_string(out.indices.size()) + " corners, the header says " + std::to_string(face_count) +
                   " and " + std::to_string(corner_count));
  st.components = C;
  st.virtual_vertices = nvirt;
  st.stitches = nstitch;
  st.side_faces = nside;
  st.run_tables = tables;
  if (stats) *stats = st;
  return Status::Ok();
}

}  // namespace tsm
