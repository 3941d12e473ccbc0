// Connectivity decoding (seed 004 §3-4 reversed; FORMAT.md §8.3-8.11): reads
// the three streams the encoder wrote (connectivity_encode.cpp): the
// topology stream's mode byte and, with tables, the run values' tables and
// bit stream (§8.3.1); the vertex tree's runs; per component the triangle
// tree's runs, marching bits and polygon-edge flags, walked into triangles
// over the bounding loop; then the virtual vertices, the stitches (targets
// by candidate rank, §8.3.2) and the side faces; and reassembles the exact
// input faces and the cut surface the geometry decoder walks.
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

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

}  // namespace

Status decode_connectivity(const ConnectivityStreams& in, uint64_t vertex_count, uint64_t face_count,
                           uint64_t corner_count, Mesh& out, GeometryLayout& layout, ConnectivityStats* stats) {
  // §8.3.1: the mode byte, and with tables the bit stream's length, the run
  // tables and the bit stream before the range-coded rest.
  std::string_view topology = in.topology;
  bool tables = false, welded = false;
  TableSet run_tables;
  BitReader run_bits;
  {
    ByteReader r(topology);
    uint8_t mode;
    if (!r.u8(mode)) return corrupt("topology stream is empty (no run coding mode)");
    if (mode > 3) return corrupt("topology mode " + std::to_string(mode) + " (bit 0 tables, bit 1 welded)");
    welded = (mode & 2) != 0;
    if (mode & 1) {
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
      if (loop_he[p] == kNone || o >= L || o == p || loop_twin[o] != p)
        return corrupt("the cut surface does not close");
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
    if (d > P || at + static_cast<uint64_t>(d) >= P || (i > 0 && d == 0))
      return corrupt("virtual vertex position out of range");
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
      if (overrun() || at + static_cast<uint64_t>(d) >= P || (i > 0 && d == 0))
        return corrupt("stitch position out of range");
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
  // Welded (§8.13): the ids are points, at most one per vertex; from here
  // on they are what the counts and bounds are about.
  if (welded && next_id <= vertex_count) vertex_count = next_id;
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
  // Side faces (the topology stream's last list): on edges (§8.3.3), then
  // verbatim.
  const uint32_t nside = om.count.decode(dop);
  if (nside > face_count) return corrupt("more side faces than faces");
  std::vector<uint32_t> side, side_start(1, 0);
  uint32_t nverbatim = nside;
  if (nside > 0 && dop.bit(om.on_edges)) {
    nverbatim = om.count.decode(dop);
    if (nverbatim >= nside) return corrupt("bad side face count");
    const uint32_t target = nside - nverbatim;
    uint32_t found = 0;
    std::vector<uint8_t> touched(vertex_count, 0);
    int prev = 0;
    bool bad = false;
    each_side_edge(
        corner, twin, [&](uint32_t p) { return out_id[p]; },
        [&](uint32_t u, uint32_t v) {
          const int any = dop.bit(om.edge_any[prev][touched[u] | touched[v]]);
          prev = any;
          if (!any) return !(bad = overrun());
          touched[u] = touched[v] = 1;
          uint32_t n = 1;
          if (dop.bit(om.edge_more)) {
            const uint32_t more = om.edge_count.decode(dop);
            if (more >= target) return !(bad = true);
            n = 2 + more;
          }
          if (n > target - found) return !(bad = true);
          int pe = 0;
          for (uint32_t j = 0; j < n; ++j) {
            pe = dop.bit(om.edge_end[pe]);
            const uint32_t r = pe ? v : u, o = pe ? u : v;
            side.insert(side.end(), {r, r, o});
            side_start.push_back(static_cast<uint32_t>(side.size()));
          }
          found += n;
          return !(bad = overrun()) && found < target;
        });
    if (bad || found != target) return corrupt("bad side faces on edges");
  }
  for (uint32_t i = 0; i < nverbatim; ++i) {
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
  st.welded = welded;
  st.points = welded ? vertex_count : 0;
  if (stats) *stats = st;
  return Status::Ok();
}

}  // namespace tsm
