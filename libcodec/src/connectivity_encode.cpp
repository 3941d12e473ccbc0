// Connectivity coding, the encoder's half (seed 004 §3-4, design notes
// §3-5): runs the stages (mesh_cut -> vertex_tree -> bounding_loop ->
// triangle_tree) and codes their output with the adaptive range coder in
// three streams:
//   vertex tree:   per component, the tree's runs (length, leaf bit, last bit
//                  for runs after their branching node's first)
//   triangle tree: per component, root position, runs (end type, march
//                  count), marching bits, polygon-edge flags
//   topology:      the run coding's mode byte, component count, jump edges,
//                  virtual vertices, stitches, side faces (degenerate faces
//                  kept verbatim)
// At the fast levels (FORMAT.md §8.3.1) the run values (vertex-run lengths,
// march counts, stitch and virtual-vertex positions, stitch distances) may
// go through static prefix codes instead (table_coder), stored after the
// mode byte: one lookup per value. Stitch targets are coded by their rank
// among candidates (§8.3.2). The decoder: connectivity_decode.cpp.
#include <algorithm>
#include <memory>

#include "byte_io.hpp"
#include "connectivity.hpp"
#include "connectivity_coding.hpp"
#include "range_coder.hpp"
#include "table_coder.hpp"

namespace tsm {

using namespace conn;

namespace {

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
  std::vector<uint32_t> virtual_pos;                    // ascending
  std::vector<std::pair<uint32_t, uint32_t>> stitches;  // (position, target), ascending positions
  uint32_t side_faces = 0;                              // all of them: on edges and verbatim
  std::vector<uint32_t> side;  // per verbatim side face: its size, then its corners (output ids)
  // Side faces on edges (§8.3.3): the edges up to the last with faces
  // (each_side_edge order) and per edge the faces with end 0 and end 1.
  std::vector<std::pair<uint32_t, uint32_t>> edge;
  std::vector<std::pair<uint32_t, uint32_t>> edge_n;
  uint32_t edge_faces = 0;
  uint32_t vertex_count = 0;
};

// The side faces on edges (FORMAT.md §8.3.3).
void code_edge_faces(RangeEncoder& e, TopologyModels& o, const TopologyTail& t) {
  e.bit(o.on_edges, t.edge_faces > 0);
  if (t.edge_faces == 0) return;
  o.count.encode(e, t.side_faces - t.edge_faces);
  std::vector<uint8_t> touched(t.vertex_count, 0);
  int prev = 0;
  for (size_t i = 0; i < t.edge.size(); ++i) {
    const auto [u, v] = t.edge[i];
    const auto [n0, n1] = t.edge_n[i];
    const int any = n0 + n1 > 0;
    e.bit(o.edge_any[prev][touched[u] | touched[v]], any);
    prev = any;
    if (!any) continue;
    touched[u] = touched[v] = 1;
    const uint32_t n = n0 + n1;
    e.bit(o.edge_more, n > 1);
    if (n > 1) o.edge_count.encode(e, n - 2);
    int pe = 0;
    for (uint32_t j = 0; j < n; ++j) {
      const int b = j >= n0;
      e.bit(o.edge_end[pe], b);
      pe = b;
    }
  }
}

// Codes the tail: with `sc`, stitch targets by their rank among the
// candidates (§8.3.2; positions all first), as the file has them; without,
// every target as a distance, after its position (what the encoder
// measures the run tables on and orders codings by, encode_connectivity).
void code_tail(RangeEncoder& e, TopologyModels& o, RunEncoder& r, const TopologyTail& t, StitchCandidates* sc = nullptr,
               std::vector<uint32_t>* target = nullptr) {
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
  if (t.side_faces > 0) code_edge_faces(e, o, t);
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

// What the streams are coded from once the cut surface is built: the
// vertex forest, each component's loop and triangle tree, and the topology
// stream's lists. encode_connectivity keeps it in ConnectivityEncoding::
// pending when asked for the surface only (CutHints::streams false), and
// code_connectivity_streams codes the streams from it later.
struct PendingStreams {
  RunCoding runs = RunCoding::adaptive;
  VertexForest f;
  bool polygons = false;
  std::vector<uint8_t> diagonal;             // the cut mesh's polygon-diagonal flags (with polygons)
  std::vector<ComponentLoop> loops;          // per component (empty below two vertices)
  std::vector<TriangleRuns> trees;           // per component (likewise)
  std::vector<uint32_t> pos_of;              // cut-mesh vertex -> pre-order position
  TopologyTail tail;
  std::vector<uint32_t> cut_corner, twin;    // with stitches: candidate_topology's cut surface
};

namespace {

// The three streams from `p`, run values coded as `runs` says (tables
// fall back to the adaptive models where they do not pay).
Status code_streams(const PendingStreams& p, RunCoding run_coding, ConnectivityEncoding& out) {
  const VertexForest& f = p.f;
  RangeEncoder ev, et, eo;
  RunEncoder runs;
  runs.tables = run_coding == RunCoding::tables;
  VertexTreeModels vm;
  TriangleTreeModels tm;
  TopologyModels om;
  ConnectivityStats& st = out.stats;
  const uint32_t C = static_cast<uint32_t>(p.loops.size());
  om.count.encode(eo, C);
  eo.bit(om.has_polygons, p.polygons);
  std::vector<uint32_t> last_child(f.order.size(), kNone);
  for (uint32_t q = 0; q < f.order.size(); ++q)
    if (f.parent[q] != kNone) last_child[f.parent[q]] = q;
  std::vector<uint32_t> kids_seen(f.order.size(), 0);  // runs started so far at each branching node
  std::vector<uint32_t> scratch_corner, scratch_twin, scratch_loop_he;
  st.vertex_runs = 0;
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
    // Jumps.
    const ComponentLoop& cl = p.loops[c];
    om.count.encode(eo, static_cast<uint32_t>(cl.jumps.size()));
    uint32_t prev_corner = 0;
    for (uint32_t i = 0; i < cl.jumps.size(); ++i) {
      om.corner.encode(eo, cl.jumps[i].corner - prev_corner);
      prev_corner = cl.jumps[i].corner;
    }
    for (uint32_t i = 0; i < cl.jumps.size(); ++i)
      if (cl.jumps[i].partner > i) om.partner.encode(eo, cl.jumps[i].partner - i - 1);
    // Triangle tree.
    const TriangleRuns& tr = p.trees[c];
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
      for (size_t q = 0; q < cl.loop.size(); ++q) local_loop[q] = p.pos_of[cl.loop[q]] - start;
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
    if (p.polygons) {
      int prev = 0;
      for (size_t k = 1; k < tr.triangle_order.size(); ++k) {
        int d = p.diagonal[3 * tr.triangle_order[k] + tr.parent_slot[k]];
        et.bit(tm.diagonal[prev], d);
        prev = d;
      }
    }
  }
  // The rest of the topology stream: virtual vertices, stitches, side
  // faces. Coded first with every stitch target as a distance (what the
  // choice of run tables below is measured on); with stitches, the coder's
  // state where the tail starts is kept for candidate_topology, which codes
  // the tail as the file has it.
  std::unique_ptr<CandidateTail> cand;
  if (!p.tail.stitches.empty()) {
    cand = std::make_unique<CandidateTail>();
    cand->coder = eo;
    cand->models = om;
    cand->runs = runs;
  }
  code_tail(eo, om, runs, p.tail);
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
    if (block.size() > adaptive + adaptive / 8) return code_streams(p, RunCoding::adaptive, out);
  }
  out.streams.topology = block + out.streams.topology;
  out.distance_topology.clear();
  if (cand) {  // the stitch targets by candidates, as the file has them
    cand->corner = p.cut_corner;
    cand->twin = p.twin;
    cand->positions = static_cast<uint32_t>(p.f.order.size());
    cand->tail = p.tail;
    out.distance_topology = std::move(out.streams.topology);
    out.streams.topology = candidate_topology(*cand);
  }
  st.bytes = out.streams.vertex_tree.size() + out.streams.triangle_tree.size() + out.streams.topology.size();
  return Status::Ok();
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
  auto pending = std::make_shared<PendingStreams>();
  PendingStreams& ps = *pending;
  ps.runs = hints.runs;
  ps.f = build_vertex_tree(m, hints.qpos, hints.midpoint_tree && hints.qpos, by_position, &out.root_tie);
  const VertexForest& f = ps.f;

  ConnectivityStats& st = out.stats;
  const uint32_t C = m.component_count();
  ps.polygons = prep.polygon_count > 0;
  ps.loops.resize(C);
  ps.trees.resize(C);

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
  std::vector<uint32_t> comp_tris;
  // Per cut-mesh vertex: its pre-order position.
  std::vector<uint32_t>& pos_of = ps.pos_of;
  pos_of.resize(m.vertex_count);
  for (uint32_t p = 0; p < f.order.size(); ++p) pos_of[f.order[p]] = p;
  // Triangles in decode order, and how each is rotated to start at its gate.
  std::vector<uint32_t> dec_tri, dec_of(m.triangle_count(), kNone);
  std::vector<uint8_t> rot(m.triangle_count(), 0);
  dec_tri.reserve(m.triangle_count());

  for (uint32_t c = 0; c < C; ++c) {
    const uint32_t start = f.component_start[c], end = f.component_start[c + 1];
    if (end - start < 2) continue;
    // Jumps and loop.
    comp_tris.assign(tris.begin() + tri_start[c], tris.begin() + tri_start[c + 1]);
    ComponentLoop& cl = ps.loops[c];
    cl = encoder_loop(m, f, c, comp_tris, cut_he, local);
    st.jump_edges += cl.jumps.size() / 2;
    // Triangle tree.
    TriangleRuns& tr = ps.trees[c];
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
    st.triangle_runs += tr.march.size();
    st.marching_bits += tr.bits.size();
  }
  if (ps.polygons) ps.diagonal = std::move(m.diagonal);

  // Vertex numbering: the first occurrence of an input vertex in pre-order
  // carries it; later ones are stitched to it; virtual vertices carry nothing.
  const uint32_t P = static_cast<uint32_t>(f.order.size());
  std::vector<uint32_t> first_pos(mesh.vertex_count(), kNone), out_id(P, kNone);
  TopologyTail& tail = ps.tail;  // the topology stream's lists from the virtual vertices on
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
  std::vector<uint32_t>& cut_corner = ps.cut_corner;
  cut_corner.resize(stitches.empty() ? 0 : g.corner.size());
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
    tail.vertex_count = g.vertex_count;
    // A triangle on two vertices (r, r, o) goes on an edge between them
    // (§8.3.3), when the cut surface has one: the first in each_side_edge
    // order; its end bit says which end r is.
    std::vector<uint64_t> on_edge;  // (edge key << 1 | end) per such face
    std::vector<uint32_t> verbatim;
    std::vector<uint64_t> keys;  // (u, v) with u < v, per enumerated edge, << 32 | index
    for (uint32_t face : prep.side_faces) {
      const uint32_t* c = mesh.face(face);
      if (mesh.face_size(face) == 3) {
        const uint32_t a = input_to_out[c[0]], b = input_to_out[c[1]], d = input_to_out[c[2]];
        uint32_t r = kNone, o = kNone;
        if (a == b && b != d)
          r = a, o = d;
        else if (b == d && d != a)
          r = b, o = a;
        else if (d == a && a != b)
          r = d, o = b;
        if (r != kNone) {
          on_edge.push_back((uint64_t{std::min(r, o)} << 32 | std::max(r, o)) << 1 | (r > o));
          continue;
        }
      }
      verbatim.push_back(face);
    }
    if (!on_edge.empty()) {
      std::vector<std::pair<uint64_t, uint32_t>> edges;  // (key, enumeration index)
      each_side_edge(
          g.corner, g.twin, [](uint32_t x) { return x; },
          [&](uint32_t u, uint32_t v) {
            tail.edge.emplace_back(u, v);
            edges.emplace_back(uint64_t{std::min(u, v)} << 32 | std::max(u, v), static_cast<uint32_t>(edges.size()));
            return true;
          });
      std::sort(edges.begin(), edges.end());  // the first of equal keys first
      tail.edge_n.assign(tail.edge.size(), {0, 0});
      size_t last = 0;
      for (uint64_t x : on_edge) {
        const uint64_t key = x >> 1;
        const auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(key, uint32_t{0}));
        if (it == edges.end() || it->first != key) continue;  // on no edge: verbatim (below)
        const uint32_t i = it->second;
        // end 0: r is the edge's start u
        const uint32_t r = (x & 1) ? static_cast<uint32_t>(key) : static_cast<uint32_t>(key >> 32);
        (r == tail.edge[i].first ? tail.edge_n[i].first : tail.edge_n[i].second)++;
        ++tail.edge_faces;
        last = std::max<size_t>(last, i + 1);
      }
      tail.edge.resize(last);
      tail.edge_n.resize(last);
      // The faces on no edge stay verbatim (in input order).
      verbatim.clear();
      for (uint32_t face : prep.side_faces) {
        const uint32_t* c = mesh.face(face);
        bool coded = false;
        if (mesh.face_size(face) == 3) {
          const uint32_t a = input_to_out[c[0]], b = input_to_out[c[1]], d = input_to_out[c[2]];
          const uint32_t lo = std::min({a, b, d}), hi = std::max({a, b, d});
          const bool two = lo != hi && (a == b || b == d || d == a);
          if (two) {
            const uint64_t key = uint64_t{lo} << 32 | hi;
            const auto it = std::lower_bound(edges.begin(), edges.end(), std::make_pair(key, uint32_t{0}));
            coded = it != edges.end() && it->first == key;
          }
        }
        if (!coded) verbatim.push_back(face);
      }
    }
    for (uint32_t face : verbatim) {
      tail.side.push_back(mesh.face_size(face));
      for (uint32_t i = 0; i < mesh.face_size(face); ++i) tail.side.push_back(input_to_out[mesh.face(face)[i]]);
    }
  }
  st.components = C;
  st.virtual_vertices = virtual_pos.size();
  st.stitches = stitches.size();
  st.side_faces = prep.side_faces.size();
  st.polygons = prep.polygon_count;
  if (!stitches.empty()) ps.twin = g.twin;
  out.pending = std::move(pending);
  // The streams now, unless the caller asked for the surface only (where
  // the decoded faces are the layout's triangles: no polygons, no side
  // faces).
  if (hints.streams || st.polygons != 0 || st.side_faces != 0) return code_connectivity_streams(out);
  return Status::Ok();
}

Status code_connectivity_streams(ConnectivityEncoding& ce) {
  if (!ce.pending) return Status::Ok();
  const std::shared_ptr<PendingStreams> p = std::move(ce.pending);
  return code_streams(*p, p->runs, ce);
}

}  // namespace tsm
