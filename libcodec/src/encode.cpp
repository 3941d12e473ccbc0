// Encoding (seed 004 §3-4; FORMAT.md): the encoder's entry point: validate
// the mesh, quantize positions on the Draco grid (design notes §6), cut it
// into segments (the segments of a file coded in parallel), run the
// connectivity stages on each part, code positions in decoded vertex order
// and attributes in the decoder's order, keep the codings that re-encode
// to their own bytes (canonical rounds) and the smallest of those tried,
// and lay the streams out as container sections.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "attributes.hpp"
#include "codec_shared.hpp"
#include "connectivity.hpp"
#include "container.hpp"
#include "exact_grid.hpp"
#include "geometry_predict.hpp"
#include "order_coding.hpp"
#include "parallel.hpp"
#include "progressive_encode.hpp"
#include "byte_io.hpp"
#include "range_coder.hpp"
#include "segments.hpp"
#include "split_layout.hpp"
#include "tsm/quantization.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

namespace {

// FORMAT.md §8.12.1: the fast levels' attribute residuals through tables
// where they pay.
bool attribute_tables(const EncodeOptions& options) { return options.level <= kTableLevel; }

// Encoder: one part (the whole mesh or a segment) coded.
struct EncodedPart {
  ConnectivityStreams streams;
  std::string geometry;
  std::string attributes;
  std::vector<uint32_t> order;     // output vertex id -> the part's input vertex id
  std::vector<uint8_t> contexts;   // per output vertex, for the references stream
  // A segment's attributes are coded after the parallel pass (their values
  // may be earlier segments'), from what that pass keeps here.
  Mesh part;                        // the segment's mesh with its attributes
  std::vector<std::vector<uint32_t>> value_origin;  // per attribute, per part value: the mesh's value
  Mesh faces;                       // as the decoder gives them
  std::vector<uint8_t> ref_out;     // per output vertex: a reference
  std::vector<uint32_t> q;          // own vertices' grid indices
  std::vector<uint32_t> vertex_from;  // welded: output vertex id -> input vertex id (else `order`)
  Status status;
};

// The attribute payload of a part from what encode_part kept (`imported`,
// `own_values`: see AttributeInput; null for a whole mesh).
Status encode_part_attributes(const Mesh& part, const std::vector<AttributeHeader>& headers,
                              const std::vector<std::vector<uint32_t>>* imported,
                              std::vector<std::vector<uint32_t>>* own_values, bool tables, EncodedPart& p,
                              uint64_t per_vertex = 0) {
  AttributeInput ai;
  ai.per_vertex = per_vertex;
  ai.part = &part;
  ai.order = &p.order;
  ai.is_ref = &p.ref_out;
  ai.faces = &p.faces;
  ai.q = &p.q;
  ai.segmented = imported != nullptr;
  ai.imported = imported;
  ai.own_values = own_values;
  ai.tables = tables;
  return encode_attributes(headers, ai, p.attributes);
}

// What the geometry coder sees of a part: its own vertices only (mark: per
// output vertex, kNone own, 0 a reference), their grid indices in output
// order, and the layout.
struct OwnView {
  std::vector<uint32_t> mark, q;
  GeometryLayout layout;
};

// The view's marks and grid indices (own_view without the layout).
void own_points(const ConnectivityEncoding& ce, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                OwnView& w) {
  const size_t n = ce.vertex_order.size();
  w.mark.assign(n, kNone);
  if (!is_ref.empty())
    for (size_t v = 0; v < n; ++v)
      if (is_ref[ce.vertex_order[v]]) w.mark[v] = 0;
  w.q.resize(3 * n);
  size_t k = 0;
  for (size_t v = 0; v < n; ++v)
    if (w.mark[v] == kNone) {
      const uint32_t* p = &qin[3 * static_cast<size_t>(ce.vertex_order[v])];
      w.q[k] = p[0];
      w.q[k + 1] = p[1];
      w.q[k + 2] = p[2];
      k += 3;
    }
  w.q.resize(k);
}

OwnView own_view(const ConnectivityEncoding& ce, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref) {
  OwnView w;
  own_points(ce, qin, is_ref, w);
  w.layout = is_ref.empty() ? ce.layout : own_layout(ce.layout, w.mark);
  return w;
}

// True when the vertices on no triangle already come in the order the cut
// gives them when sorted (stably) by `key`, their anchor's output id.
bool in_anchor_order(const ConnectivityEncoding& ce, const std::vector<uint32_t>& key) {
  const GeometryLayout& g = ce.layout;
  std::vector<uint8_t> on_triangle(g.vertex_count, 0);
  for (uint32_t v : g.corners())
    if (v != kNone) on_triangle[v] = 1;
  uint32_t last = 0;
  for (uint32_t v = 0; v < g.vertex_count; ++v) {
    if (on_triangle[v]) continue;
    const uint32_t k = key[ce.vertex_order[v]];
    if (k < last) return false;
    last = k;
  }
  return true;
}

// FORMAT.md §8.3.1: below the mixing levels, a part of kRunTableFaces
// faces or more codes its run values through tables where they pay (every
// value is below 2^30 when vertices + 2 corners are below 2^28); smaller
// parts keep the adaptive models, whose few values cost less than tables.
// (At the default level tables cost ~0.3% of the file and decode the
// connectivity's runs several times faster.)
constexpr size_t kRunTableFaces = 256;
RunCoding run_coding(const Mesh& part, const EncodeOptions& options) {
  const bool fits = part.vertex_count() + 2 * part.corner_count() < (size_t{1} << 28);
  return options.level < kMixLevel && fits && part.face_count() >= kRunTableFaces ? RunCoding::tables
                                                                                     : RunCoding::adaptive;
}

// How a part's vertex trees are built (encode_part tries several).
struct TreeChoice {
  int root_rule = 0;      // CutHints::root_rule
  bool midpoint = false;  // the midpoint-distance Kruskal tree instead of the layered spiral
};

CutHints part_hints(const Mesh& mesh, const std::vector<uint32_t>& qin, const EncodeOptions& options,
                    TreeChoice tree) {
  CutHints hints;
  hints.qpos = &qin;
  hints.root_rule = tree.root_rule;
  hints.midpoint_tree = tree.midpoint;
  hints.runs = run_coding(mesh, options);
  return hints;
}

// Per input vertex on no triangle, the output id of its anchor, a nearby
// surface vertex that predicts it (kNone: none); empty when none has one.
std::vector<uint32_t> anchor_keys(const Mesh& mesh, const ConnectivityEncoding& ce, const OwnView& view, int bits) {
  std::vector<uint32_t> anchor = find_anchors(view.layout, view.q, bits);
  if (std::none_of(anchor.begin(), anchor.end(), [](uint32_t x) { return x != kNone; })) return {};
  std::vector<uint32_t> own_to_output;
  for (uint32_t v = 0; v < view.mark.size(); ++v)
    if (view.mark[v] == kNone) own_to_output.push_back(v);
  std::vector<uint32_t> by_input(mesh.vertex_count(), kNone);
  for (size_t r = 0; r < anchor.size(); ++r)
    if (anchor[r] != kNone) by_input[ce.vertex_order[own_to_output[r]]] = own_to_output[anchor[r]];
  return by_input;
}

// The output vertices on no triangle (on_triangle[v] == 0) take their input
// ids in the cut's order: stably by anchor `key`, then grid position.
void order_off_triangles(const std::vector<uint32_t>& qin, const std::vector<uint32_t>& key,
                         const std::vector<uint8_t>& on_triangle, ConnectivityEncoding& ce) {
  std::vector<uint32_t> at, ids;
  for (uint32_t v = 0; v < ce.layout.vertex_count; ++v)
    if (!on_triangle[v]) at.push_back(v), ids.push_back(ce.vertex_order[v]);
  std::stable_sort(ids.begin(), ids.end(), [&](uint32_t a, uint32_t b) {
    if (key[a] != key[b]) return key[a] < key[b];
    return std::lexicographical_compare(&qin[3 * size_t{a}], &qin[3 * size_t{a}] + 3, &qin[3 * size_t{b}],
                                        &qin[3 * size_t{b}] + 3);
  });
  for (size_t k = 0; k < at.size(); ++k) ce.vertex_order[at[k]] = ids[k];
}

// Puts the output vertices on no triangle in the order the cut gives them
// with anchors (stably by anchor `key`, then grid position): a vertex on no
// triangle is a component of its own, coded alike wherever it comes, so
// when no face names one (no side face: then the topology stream would
// change) the second pass would code the same streams in this order.
// Returns false when a face names one.
bool sort_by_anchor(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint32_t>& key,
                    ConnectivityEncoding& ce) {
  const uint32_t n = ce.layout.vertex_count;
  std::vector<uint8_t> on_triangle(n, 0), input_on(mesh.vertex_count(), 0);
  for (uint32_t v : ce.layout.corners())
    if (v != kNone) on_triangle[v] = 1;
  for (uint32_t v = 0; v < n; ++v) input_on[ce.vertex_order[v]] = on_triangle[v];
  for (uint32_t v : mesh.indices)
    if (!input_on[v]) return false;
  order_off_triangles(qin, key, on_triangle, ce);
  return true;
}

// The anchor step of part_connectivity on its first pass `ce`: when vertices
// on no triangle have an anchor, a second pass that orders them by it (or
// the same order found without coding again, sort_by_anchor).
Status anchor_step(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                   int bits, CutHints hints, ConnectivityEncoding& ce, OwnView& view) {
  const std::vector<uint32_t> by_input = anchor_keys(mesh, ce, view, bits);
  if (!by_input.empty()) {
    if (in_anchor_order(ce, by_input) || sort_by_anchor(mesh, qin, by_input, ce)) {
      // The cut would keep its order (a decoded mesh, in canonical rounds)
      // or sort_by_anchor found it: the second pass would code the same
      // streams, so only hand the anchors to the geometry coder.
      for (uint32_t v = 0; v < ce.layout.vertex_count; ++v) ce.layout.anchor[v] = by_input[ce.vertex_order[v]];
      if (is_ref.empty()) {
        // Only vertices on no triangle moved: the view's layout is ce's
        // (no copy of its corners) with these anchors.
        own_points(ce, qin, is_ref, view);
        view.layout.anchor = ce.layout.anchor;
        return Status::Ok();
      }
    } else {
      ce = ConnectivityEncoding();
      hints.anchor = &by_input;
      TSM_RETURN_IF_ERROR(encode_connectivity(mesh, ce, hints));
      if (ce.root_tie) return Status::Ok();  // the caller drops this rule
    }
    view = own_view(ce, qin, is_ref);
  }
  return Status::Ok();
}

// The connectivity of a part with the given tree, then (with `anchors`)
// the anchor step; with `streams` false, the cut surface only where
// encode_connectivity allows it (CutHints::streams).
Status part_connectivity(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                         const EncodeOptions& options, TreeChoice tree, ConnectivityEncoding& ce, OwnView& view,
                         bool anchors = true, bool streams = true) {
  CutHints hints = part_hints(mesh, qin, options, tree);
  hints.streams = streams;
  TSM_RETURN_IF_ERROR(encode_connectivity(mesh, ce, hints));
  view = own_view(ce, qin, is_ref);
  return anchors ? anchor_step(mesh, qin, is_ref, options.quantization_bits, hints, ce, view) : Status::Ok();
}

// Canonical re-encoding: a decoded mesh must encode to the bytes
// it came from. The coder's choices follow vertex ids and face order, and
// the decoder's order reproduces them, except where vertices were split and
// stitched back: there the decoded order lets the cut find another copy of
// a split vertex first. So a part with stitches is coded as its decoded
// self would be: decode the streams, code that mesh, and repeat until
// decoding gives back the faces coded, corner for corner (the cut orders
// components that share vertices as the decoder numbers them, so the
// decoded mesh usually is that point: dragon res2 after one round, res3 and
// res4 after two, where edges of four uses pair otherwise).
// At that point output vertex v may simply be the coded mesh's vertex v,
// whatever order the coder chose: the decoded faces name the same ids at
// the same corners. That matters for a symmetric mesh (the Moebius strip),
// whose coder order is a symmetry of its faces (its mirror image): taken as
// it is, it would permute the positions on every re-encoding.
// Some tangles of non-manifold faces (random soups; faces also given
// reversed) never settle: the rounds come back to a mesh coded before and
// go round a cycle. Every member of the cycle leads round the same cycle,
// so the member whose streams are smallest (then first in byte order) is
// coded: a decoded mesh, itself on the cycle, finds the same one.
// Others settle only after many rounds (a random tangle of 325 faces on 16
// vertices: 20), and a part cut off before it settles re-encodes to other
// bytes. So small parts get up to 256 rounds, larger ones as many as 2^20
// faces' coding allows, at least 16 (the corpus's stitched meshes: 1-2).
int canonical_rounds(size_t faces) {
  return static_cast<int>(std::clamp<size_t>((size_t{1} << 20) / (faces + 1), 16, 256));
}

bool same_faces(const Mesh& a, const Mesh& b) { return a.indices == b.indices && a.face_offsets == b.face_offsets; }

// The faces decode_connectivity gives for `ce`'s streams (indices and face
// offsets), decoded, or read off the layout when every face is a triangle
// of the cut surface (no polygons, no side faces): there the decoder's
// faces are the layout's triangles in decode order, less those on a virtual
// vertex (the geometry coder sees the same layout on both sides).
Status decoded_faces(const ConnectivityEncoding& ce, const Mesh& mesh, Mesh& out) {
  if (ce.stats.polygons != 0 || ce.stats.side_faces != 0) {
    GeometryLayout scratch;
    return decode_connectivity(ce.streams, mesh.vertex_count(), mesh.face_count(), mesh.corner_count(), out, scratch);
  }
  const std::vector<uint32_t>& corner = ce.layout.corners();
  out.indices.clear();
  out.indices.reserve(mesh.corner_count());
  for (size_t k = 0; k + 2 < corner.size(); k += 3)
    if (corner[k] != kNone && corner[k + 1] != kNone && corner[k + 2] != kNone)
      out.indices.insert(out.indices.end(), corner.begin() + static_cast<std::ptrdiff_t>(k),
                         corner.begin() + static_cast<std::ptrdiff_t>(k + 3));
  out.face_offsets.resize(out.indices.size() / 3 + 1);
  for (size_t f = 0; f < out.face_offsets.size(); ++f) out.face_offsets[f] = static_cast<uint32_t>(3 * f);
  return Status::Ok();
}

// The order of the codings on a cycle: by their streams' size, then bytes,
// with the stitch targets coded as distances (ConnectivityEncoding::
// distance_topology; any fixed order would do, this one keeps the bytes
// files have had).
struct CycleKey {
  std::string vertex_tree, triangle_tree, topology;
};
CycleKey cycle_key(const ConnectivityEncoding& ce) {
  const ConnectivityStreams& s = ce.streams;
  return {s.vertex_tree, s.triangle_tree, ce.distance_topology.empty() ? s.topology : ce.distance_topology};
}
bool key_before(const CycleKey& a, const CycleKey& b) {
  const size_t na = a.vertex_tree.size() + a.triangle_tree.size() + a.topology.size();
  const size_t nb = b.vertex_tree.size() + b.triangle_tree.size() + b.topology.size();
  if (na != nb) return na < nb;
  return std::tie(a.vertex_tree, a.triangle_tree, a.topology) < std::tie(b.vertex_tree, b.triangle_tree, b.topology);
}

// canonical_connectivity without the streams of the coding it settles on
// where they are not coded yet: each round's cut surface is enough to find
// its decoded faces, and only the last round's streams are in the file.
Status canonical_surface(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                         const EncodeOptions& options, TreeChoice tree, ConnectivityEncoding& ce, OwnView& view) {
  const size_t n = mesh.vertex_count();
  std::vector<uint32_t> base;  // ids of the mesh `ce` codes -> the part's input ids (empty: the same)
  Mesh coded;                  // that mesh (faces only), once it is not `mesh`
  std::vector<uint32_t> q;
  std::vector<uint8_t> ref;
  // Codes a mesh whose ids are the part's input ids through `base`.
  auto code = [&](const Mesh& faces, bool anchors = true, bool streams = true) -> Status {
    ce = ConnectivityEncoding();
    if (base.empty()) return part_connectivity(faces, qin, is_ref, options, tree, ce, view, anchors, streams);
    q.resize(3 * n);
    for (size_t v = 0; v < n; ++v)
      for (int a = 0; a < 3; ++a) q[3 * v + a] = qin[3 * static_cast<size_t>(base[v]) + a];
    if (!is_ref.empty()) {
      ref.resize(n);
      for (size_t v = 0; v < n; ++v) ref[v] = is_ref[base[v]];
    }
    return part_connectivity(faces, q, is_ref.empty() ? is_ref : ref, options, tree, ce, view, true, streams);
  };
  // Round 0 without its anchor step first. That step only orders the
  // vertices on no triangle (stably by anchor, then position), which no
  // face names unless side faces do: a part with stitches whose decoded
  // self is another mesh is coded again from that mesh, so for round 1 it
  // is enough to put round 0's vertex order in the step's order (then
  // round 1's step finds its order kept and codes once). Round 0 is coded
  // whole when its decoded self is the mesh itself, when side faces name
  // such vertices, and when round 0 is on a cycle (whose order compares
  // round 0's streams).
  TSM_RETURN_IF_ERROR(code(mesh, false, false));
  if (tree.root_rule != 0 || ce.stats.stitches == 0)  // (root rules: only tried on parts without stitches)
    return anchor_step(mesh, qin, is_ref, options.quantization_bits, part_hints(mesh, qin, options, tree), ce,
                       view);
  Mesh decoded0;
  TSM_RETURN_IF_ERROR(decoded_faces(ce, mesh, decoded0));
  // (Vertices on no triangle that side faces name: the step changes those
  // faces, so round 0 is coded whole as well.)
  std::vector<uint8_t> on_triangle(n, 0);
  for (uint32_t v : ce.layout.corners())
    if (v != kNone) on_triangle[v] = 1;
  const bool side_named = std::any_of(decoded0.indices.begin(), decoded0.indices.end(),
                                      [&](uint32_t v) { return !on_triangle[v]; });
  const bool full_round0 = side_named || same_faces(decoded0, mesh);
  if (full_round0) {
    // (code(mesh) again, with the anchor step: the step on this coding.)
    TSM_RETURN_IF_ERROR(
        anchor_step(mesh, qin, is_ref, options.quantization_bits, part_hints(mesh, qin, options, tree), ce, view));
    if (ce.stats.stitches == 0) return Status::Ok();
  } else {
    // What the step would change for round 1: unless their anchors are in
    // order already (then the step keeps them), the order of the output
    // vertices on no triangle, sorted as its cut sorts them (stably by
    // anchor, then grid position).
    const std::vector<uint32_t> key = anchor_keys(mesh, ce, view, options.quantization_bits);
    if (!key.empty() && !in_anchor_order(ce, key)) order_off_triangles(qin, key, on_triangle, ce);
  }
  // Per round r: the mesh it coded (round 0: `mesh`, not copied), its
  // streams (none where they were not coded: found again if a cycle needs
  // them) and its base.
  std::vector<Mesh> coded_in;
  std::vector<std::optional<CycleKey>> key_of;
  std::vector<std::vector<uint32_t>> base_of;
  auto coded_by = [&](size_t r) -> const Mesh& { return r == 0 ? mesh : coded_in[r - 1]; };
  const int rounds = canonical_rounds(mesh.face_count());
  for (int round = 0; round < rounds; ++round) {
    Mesh decoded;
    if (round == 0 && !full_round0)
      decoded = std::move(decoded0);
    else
      TSM_RETURN_IF_ERROR(decoded_faces(ce, mesh, decoded));
    const Mesh& now = round == 0 ? mesh : coded;
    if (same_faces(decoded, now)) {
      // Output vertex v as `now`'s vertex v, when every vertex is on a face
      // (a vertex on none is placed by its anchor, which the order found).
      std::vector<uint8_t> on_face(n, 0);
      for (uint32_t v : now.indices) on_face[v] = 1;
      if (std::all_of(on_face.begin(), on_face.end(), [](uint8_t x) { return x != 0; })) {
        std::iota(ce.vertex_order.begin(), ce.vertex_order.end(), 0u);
        view = round == 0 ? own_view(ce, qin, is_ref) : own_view(ce, q, is_ref.empty() ? is_ref : ref);
      }
      break;
    }
    if (round > 0) coded_in.push_back(std::move(coded));
    // (Round 0 without its anchor step: its streams are not the ones a
    // cycle compares.)
    if (ce.pending || (round == 0 && !full_round0))
      key_of.emplace_back();
    else
      key_of.push_back(cycle_key(ce));
    base_of.push_back(base);
    // Back at a mesh coded in round i: the cycle is rounds i..round.
    size_t i = 0;
    while (i <= static_cast<size_t>(round) && !same_faces(decoded, coded_by(i))) ++i;
    if (i <= static_cast<size_t>(round)) {
      // The streams of the cycle's rounds that have none yet (round 0 with
      // its anchor step), coded again for the cycle's order.
      for (size_t k = i; k <= static_cast<size_t>(round); ++k) {
        if (key_of[k]) continue;
        ConnectivityEncoding now_ce = std::move(ce);
        OwnView now_view = std::move(view);
        std::vector<uint32_t> now_base = std::move(base);
        base = base_of[k];
        TSM_RETURN_IF_ERROR(code(coded_by(k)));
        key_of[k] = cycle_key(ce);
        ce = std::move(now_ce);
        view = std::move(now_view);
        base = std::move(now_base);
      }
      size_t best = i;
      for (size_t k = i + 1; k <= static_cast<size_t>(round); ++k)
        if (key_before(*key_of[k], *key_of[best])) best = k;
      if (best != static_cast<size_t>(round)) {  // (else `ce` is it)
        base = base_of[best];
        TSM_RETURN_IF_ERROR(code(coded_by(best)));
      }
      break;
    }
    std::vector<uint32_t> next(n);
    for (size_t v = 0; v < n; ++v) next[v] = base.empty() ? ce.vertex_order[v] : base[ce.vertex_order[v]];
    base = std::move(next);
    coded = std::move(decoded);
    coded.positions.assign(3 * n, 0.0f);  // the coder reads the grid indices, not these
    TSM_RETURN_IF_ERROR(code(coded, true, false));
  }
  if (!base.empty())
    for (uint32_t& x : ce.vertex_order) x = base[x];  // back to the part's input ids
  return Status::Ok();
}

Status canonical_connectivity(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                              const EncodeOptions& options, TreeChoice tree, ConnectivityEncoding& ce, OwnView& view) {
  TSM_RETURN_IF_ERROR(canonical_surface(mesh, qin, is_ref, options, tree, ce, view));
  return code_connectivity_streams(ce);
}

// The connectivity codings encode_part has tried for a part: a tree choice
// that codes the same streams in the same vertex order as one before (small
// components, where several rules pick the same roots; faces that are all
// degenerate) gives the same part, so it is not coded again.
using TriedCodings = std::vector<std::pair<ConnectivityStreams, std::vector<uint32_t>>>;

bool same_streams(const ConnectivityStreams& a, const ConnectivityStreams& b) {
  return a.vertex_tree == b.vertex_tree && a.triangle_tree == b.triangle_tree && a.topology == b.topology;
}

// A part coded with the given vertex trees; `usable` is false when that
// choice is left out (encode_part), and then only the default tree is coded
// on. `tried`: the codings so far, when encode_part compares several.
// qin: grid indices per part input vertex; is_ref: per part input vertex,
// 1 when an earlier segment holds it (empty: none).
Status encode_part_from(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                        const std::vector<AttributeHeader>& headers, const EncodeOptions& options, TreeChoice tree,
                        EncodedPart& out, bool& usable, bool& stitched, TriedCodings* tried) {
  const int bits = options.quantization_bits;
  ConnectivityEncoding ce;
  OwnView view;
  TSM_RETURN_IF_ERROR(canonical_connectivity(mesh, qin, is_ref, options, tree, ce, view));
  stitched = ce.stats.stitches != 0;
  usable = !ce.root_tie && !stitched;
  if (usable && tried) {
    for (const auto& [streams, order] : *tried)
      if (same_streams(streams, ce.streams) && order == ce.vertex_order) usable = false;
    if (usable) tried->emplace_back(ce.streams, ce.vertex_order);
  }
  const bool default_tree = tree.root_rule == 0 && !tree.midpoint;
  if (!usable && !default_tree) return Status::Ok();
  std::vector<uint32_t>& mark = view.mark;
  std::vector<uint32_t>& q = view.q;
  GeometryLayout& layout = view.layout;
  const Lattice lattice = find_lattice(q, layout.vertex_count);
  out.geometry = encode_geometry(layout, q, bits, options.level, &lattice);
  if (!headers.empty()) {
    // The faces as the decoder will give them, to code face and corner
    // values in its order.
    TSM_RETURN_IF_ERROR(decoded_faces(ce, mesh, out.faces));
    out.ref_out.resize(mark.size());
    for (size_t v = 0; v < mark.size(); ++v) out.ref_out[v] = mark[v] != kNone;
    out.q = std::move(q);
  }
  if (!is_ref.empty()) out.contexts = reference_contexts(ce.layout);
  out.order = std::move(ce.vertex_order);
  out.streams = std::move(ce.streams);
  if (!headers.empty() && is_ref.empty())  // a whole mesh: its attributes now
    TSM_RETURN_IF_ERROR(encode_part_attributes(mesh, headers, nullptr, nullptr, attribute_tables(options), out));
  return Status::Ok();
}

// Where the vertex trees start changes a file by up to 2-3% on some meshes
// (the bunny at q = 11: 42,130 to 43,460 bytes over seven roots; the
// dragons by +-0.3%): the march, and with it the greedy geometry order and
// the attribute order, grows from the root. At level 7-8 the encoder also
// codes the part from the two ends of its axis of largest extent
// (CutHints::root_rule), at level 9 from all six extremes and the smallest
// id, each with the layered spiral and with the midpoint-distance tree, and
// keeps the smallest part (streams, geometry and attributes): the first
// coding (smallest-id root, spiral) unless another is smaller, the first of
// those on a tie. Canonical: in a decoded mesh the chosen root is the
// smallest id (with the same reference edge) and the positions are the
// same, so its candidates are codings this mesh had too, none earlier in
// the order and smaller, and the same one wins.
// Left out: a rule whose root or reference edge ties on position (it would
// follow ids), and parts with stitches (their canonical rounds re-code the
// decoded mesh; they keep the smallest-id spiral).
constexpr int kRootSearchLevel = 7;
// A small mesh coded whole (at most kSmallSearchFaces faces, one segment)
// gets level 9's search from level 3 on: 14 codings of a few hundred faces
// take milliseconds and save 1-8% on such meshes (corpus edge files:
// cube_att.ply 97 -> 89 bytes at q = 11). The test is on the mesh's own face
// count, which a decoded mesh has too, so re-encoding gives the same bytes.
// Not for segments: a mesh cut into 1,000-face segments would take about 6x
// as long to encode (the bunny: 0.5 -> 2.8 s) for 0.7%.
constexpr size_t kSmallSearchFaces = 1024;
constexpr int kSmallSearchLevel = 3;

size_t part_bytes(const EncodedPart& p) {
  return p.streams.vertex_tree.size() + p.streams.triangle_tree.size() + p.streams.topology.size() +
         p.geometry.size() + p.attributes.size();
}

Status encode_part(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                   const std::vector<AttributeHeader>& headers, const EncodeOptions& options, EncodedPart& out) {
  bool usable = true, stitched = false;
  TriedCodings tried;
  const bool small = options.level >= kSmallSearchLevel && is_ref.empty() && mesh.face_count() <= kSmallSearchFaces;
  const bool search = options.level >= kRootSearchLevel || small;
  TSM_RETURN_IF_ERROR(encode_part_from(mesh, qin, is_ref, headers, options, TreeChoice(), out, usable, stitched,
                                       search ? &tried : nullptr));
  if (!search || stitched || mesh.face_count() == 0) return Status::Ok();
  std::vector<TreeChoice> trees;
  if (options.level >= 9 || small) {
    // Every rule with each tree: a decoded mesh's smallest-id root is the
    // chosen one, so its (tree, rule 0) is this mesh's (tree, chosen rule),
    // which must be among the candidates for the same one to win there.
    for (bool midpoint : {false, true})
      for (int rule = midpoint ? 0 : 1; rule <= 6; ++rule) trees.push_back({rule, midpoint});
  } else {
    uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < qin.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], qin[i]);
      hi[i % 3] = std::max(hi[i % 3], qin[i]);
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    trees = {{2 * axis + 1, false}, {2 * axis + 2, false}};
  }
  size_t best = part_bytes(out);
  for (const TreeChoice& tree : trees) {
    EncodedPart alt;
    TSM_RETURN_IF_ERROR(encode_part_from(mesh, qin, is_ref, headers, options, tree, alt, usable, stitched, &tried));
    if (!usable) continue;
    const size_t size = part_bytes(alt);
    if (size < best) {
      best = size;
      // What encode_part_from fills (the caller's other fields stay).
      out.streams = std::move(alt.streams);
      out.geometry = std::move(alt.geometry);
      out.attributes = std::move(alt.attributes);
      out.order = std::move(alt.order);
      out.contexts = std::move(alt.contexts);
      out.faces = std::move(alt.faces);
      out.ref_out = std::move(alt.ref_out);
      out.q = std::move(alt.q);
    }
  }
  return Status::Ok();
}

// A segment's attributes: the values of its vertices (`in`, in the part's
// numbering) and faces (`faces`, corners from `rot`); a corner attribute
// keeps the values its corners use (in input order), and the last segment
// also those no corner uses. A value
// used on both sides of a border is stored in each segment that uses it.
std::vector<Attribute> segment_attributes(const Mesh& mesh, const std::vector<uint32_t>& in,
                                          const std::vector<uint32_t>& faces, const std::vector<uint32_t>& rot,
                                          bool last, std::vector<std::vector<uint32_t>>& origin) {
  std::vector<Attribute> out;
  origin.assign(mesh.attributes.size(), {});
  for (const Attribute& a : mesh.attributes) {
    Attribute b = described_like(a);
    const size_t c = a.components;
    auto take = [&](size_t j) { b.values.insert(b.values.end(), a.values.begin() + c * j, a.values.begin() + c * (j + 1)); };
    if (a.domain == AttributeDomain::vertex) {
      for (uint32_t v : in) take(v);
    } else if (a.domain == AttributeDomain::face) {
      for (uint32_t f : faces) take(f);
    } else {
      std::vector<uint32_t> local(a.value_count(), kNone);
      std::vector<uint8_t> used_anywhere;
      if (last) {
        used_anywhere.assign(a.value_count(), 0);
        for (uint32_t x : a.indices) used_anywhere[x] = 1;
      }
      std::vector<uint8_t> mine(a.value_count(), 0);
      for (uint32_t f : faces)
        for (uint32_t i = mesh.face_offsets[f]; i < mesh.face_offsets[f + 1]; ++i) mine[a.indices[i]] = 1;
      for (size_t j = 0; j < a.value_count(); ++j)
        if (mine[j] || (last && !used_anywhere[j])) {
          local[j] = static_cast<uint32_t>(b.value_count());
          origin[out.size()].push_back(static_cast<uint32_t>(j));
          take(j);
        }
      for (size_t t = 0; t < faces.size(); ++t) {
        const uint32_t f = faces[t], n = mesh.face_size(f);
        for (uint32_t j = 0; j < n; ++j) b.indices.push_back(local[a.indices[mesh.face_offsets[f] + (rot[t] + j) % n]]);
      }
    }
    out.push_back(std::move(b));
  }
  return out;
}

// A segment's own numbering, the one a decoded file gives again (it numbers
// the vertices otherwise, those of earlier segments first, and re-encoding
// must give the same bytes): `in` (its vertices, input ids) reordered by
// grid position, then their neighbours' cells (a hash), then input id, and
// `local` from input id to that numbering; returns its faces ordered by
// their corner cycles in that numbering, each from its smallest rotation
// (`rot`: the corner it starts at; identical faces by input id).
std::vector<uint32_t> canonical_part_order(const Mesh& mesh, const std::vector<uint32_t>& qin,
                                           std::vector<uint32_t>& in, const std::vector<uint32_t>& faces,
                                           std::unordered_map<uint32_t, uint32_t>& local, std::vector<uint32_t>& rot) {
  auto pos = [&](uint32_t v) { return &qin[3 * static_cast<size_t>(v)]; };
  local.clear();
  local.reserve(in.size());
  for (uint32_t i = 0; i < in.size(); ++i) local.emplace(in[i], i);
  // Vertices in one grid cell (frequent at low q) are told apart by their
  // neighbours' cells: an order-free hash of (cell of the next corner, cell
  // of the previous corner) over the vertex's corners.
  auto cell = [&](uint32_t v) { return cell_hash(pos(v)); };
  std::vector<uint64_t> around(in.size(), 0);
  for (uint32_t f : faces) {
    const uint32_t* c = mesh.face(f);
    const uint32_t n = mesh.face_size(f);
    for (uint32_t j = 0; j < n; ++j)
      around[local[c[j]]] += mix64(cell(c[(j + 1) % n]) + 3 * mix64(cell(c[(j + n - 1) % n])));
  }
  std::vector<uint32_t> idx(in.size());
  std::iota(idx.begin(), idx.end(), 0u);
  std::sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) {
    const uint32_t *pa = pos(in[a]), *pb = pos(in[b]);
    for (int c = 0; c < 3; ++c)
      if (pa[c] != pb[c]) return pa[c] < pb[c];
    return around[a] != around[b] ? around[a] < around[b] : in[a] < in[b];
  });
  {
    std::vector<uint32_t> sorted(in.size());
    for (size_t i = 0; i < idx.size(); ++i) sorted[i] = in[idx[i]];
    in = std::move(sorted);
    for (uint32_t i = 0; i < in.size(); ++i) local[in[i]] = i;
  }
  // Corner cycles in the new numbering, from their smallest rotation, one
  // after another.
  std::vector<uint32_t> cyc, start(faces.size() + 1, 0), first(faces.size()), tmp;
  for (size_t i = 0; i < faces.size(); ++i) {
    const uint32_t* c = mesh.face(faces[i]);
    const uint32_t n = mesh.face_size(faces[i]);
    tmp.resize(n);
    for (uint32_t j = 0; j < n; ++j) tmp[j] = local[c[j]];
    first[i] = smallest_rotation(tmp.data(), n);
    for (uint32_t j = 0; j < n; ++j) cyc.push_back(tmp[(first[i] + j) % n]);
    start[i + 1] = static_cast<uint32_t>(cyc.size());
  }
  idx.resize(faces.size());
  std::iota(idx.begin(), idx.end(), 0u);
  std::sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) {
    const bool less = std::lexicographical_compare(cyc.begin() + start[a], cyc.begin() + start[a + 1],
                                                   cyc.begin() + start[b], cyc.begin() + start[b + 1]);
    const bool more = std::lexicographical_compare(cyc.begin() + start[b], cyc.begin() + start[b + 1],
                                                   cyc.begin() + start[a], cyc.begin() + start[a + 1]);
    return less || (!more && faces[a] < faces[b]);
  });
  std::vector<uint32_t> out(faces.size());
  rot.resize(faces.size());
  for (size_t i = 0; i < idx.size(); ++i) {
    out[i] = faces[idx[i]];
    rot[i] = first[idx[i]];
  }
  return out;
}

// The segmented file's parts: each segment's mesh with its own vertex ids
// (the vertices its faces use, the last one also the vertices on no face,
// numbered by canonical_part_order), coded in parallel; then the
// references, which need the final ids of the segments before.
Status encode_segments(const Mesh& mesh, const std::vector<uint32_t>& qin,
                       const std::vector<std::vector<uint32_t>>& segments, const std::vector<AttributeHeader>& headers,
                       const EncodeOptions& options, ContainerWriter& cw, std::vector<uint32_t>& vertex_from) {
  const size_t S = segments.size();
  const uint32_t V = static_cast<uint32_t>(mesh.vertex_count());
  std::vector<uint32_t> owner(V, kNone);
  for (size_t k = 0; k < S; ++k)
    for (uint32_t f : segments[k])
      for (uint32_t i = 0; i < mesh.face_size(f); ++i) {
        uint32_t& o = owner[mesh.face(f)[i]];
        if (o == kNone) o = static_cast<uint32_t>(k);
      }
  std::vector<std::vector<uint32_t>> inputs(S);  // per segment: its vertices (input ids)
  std::vector<EncodedPart> parts(S);
  size_t failed = 0;
  const Status threw = parallel_for(S, options.threads, [&](size_t k) {
    std::vector<uint32_t>& in = inputs[k];
    for (uint32_t f : segments[k])
      for (uint32_t i = 0; i < mesh.face_size(f); ++i) in.push_back(mesh.face(f)[i]);
    if (k + 1 == S)
      for (uint32_t v = 0; v < V; ++v)
        if (owner[v] == kNone) in.push_back(v);
    std::sort(in.begin(), in.end());
    in.erase(std::unique(in.begin(), in.end()), in.end());
    std::unordered_map<uint32_t, uint32_t> local;  // input id -> part id
    std::vector<uint32_t> rot;
    const std::vector<uint32_t> faces = canonical_part_order(mesh, qin, in, segments[k], local, rot);
    Mesh part;
    std::vector<uint32_t> q(3 * in.size());
    std::vector<uint8_t> is_ref(in.size());
    part.positions.resize(3 * in.size());
    for (uint32_t i = 0; i < in.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        part.positions[3 * i + a] = mesh.positions[3 * static_cast<size_t>(in[i]) + a];
        q[3 * i + a] = qin[3 * static_cast<size_t>(in[i]) + a];
      }
      is_ref[i] = owner[in[i]] != kNone && owner[in[i]] < k;
    }
    std::vector<uint32_t> corners;
    for (size_t t = 0; t < faces.size(); ++t) {
      corners.clear();
      const uint32_t n = mesh.face_size(faces[t]);
      for (uint32_t i = 0; i < n; ++i) corners.push_back(local[mesh.face(faces[t])[(rot[t] + i) % n]]);
      part.add_face(corners.data(), corners.size());
    }
    part.attributes = segment_attributes(mesh, in, faces, rot, k + 1 == S, parts[k].value_origin);
    parts[k].status = encode_part(part, q, is_ref, headers, options, parts[k]);
    parts[k].part = std::move(part);
  }, &failed);
  if (!threw.ok()) parts[failed].status = threw;
  // Per corner attribute, per value of the mesh: its id in the file's value
  // list once a segment has added it.
  std::vector<std::vector<uint32_t>> value_id(mesh.attributes.size());
  std::vector<uint32_t> value_count(mesh.attributes.size(), 0);
  for (size_t i = 0; i < mesh.attributes.size(); ++i)
    if (mesh.attributes[i].domain == AttributeDomain::corner) value_id[i].assign(mesh.attributes[i].value_count(), kNone);
  std::vector<uint32_t> final_id(V, kNone);
  uint32_t next = 0;
  for (size_t k = 0; k < S; ++k) {
    EncodedPart& p = parts[k];
    if (!p.status.ok())
      return Status(p.status.code(), "segment " + std::to_string(k) + ": " + p.status.message());
    std::vector<uint32_t> global(p.order.size(), kNone);
    uint64_t refs = 0;
    for (size_t v = 0; v < p.order.size(); ++v) {
      const uint32_t x = inputs[k][p.order[v]];
      if (owner[x] == k || owner[x] == kNone) {
        final_id[x] = next++;
      } else {
        global[v] = final_id[x];
        ++refs;
      }
    }
    const std::string references = encode_references(p.contexts, global);
    if (!headers.empty()) {
      std::vector<std::vector<uint32_t>> imported(headers.size()), own_values;
      for (size_t i = 0; i < headers.size(); ++i)
        if (!value_id[i].empty())
          for (uint32_t x : p.value_origin[i]) imported[i].push_back(value_id[i][x]);
      TSM_RETURN_IF_ERROR(encode_part_attributes(p.part, headers, &imported, &own_values, attribute_tables(options), p));
      for (size_t i = 0; i < headers.size(); ++i)
        if (!value_id[i].empty())
          for (uint32_t local : own_values[i]) value_id[i][p.value_origin[i][local]] = value_count[i]++;
    }
    SegmentPayload sp;
    sp.vertex_count = p.order.size();
    sp.face_count = segments[k].size();
    uint64_t corners = 0;
    for (uint32_t f : segments[k]) corners += mesh.face_size(f);
    sp.corner_count = corners;
    sp.reference_count = refs;
    sp.vertex_tree = p.streams.vertex_tree;
    sp.triangle_tree = p.streams.triangle_tree;
    sp.topology = p.streams.topology;
    sp.references = references;
    sp.geometry = p.geometry;
    sp.attributes = p.attributes;
    cw.add_section(kSectionSegment, write_segment(sp), 0);
    p = EncodedPart();
  }
  vertex_from.assign(V, kNone);
  for (uint32_t x = 0; x < V; ++x) vertex_from[final_id[x]] = x;
  return Status::Ok();
}

// Per face of `a` (faces on the same ids as `b`'s, as multisets of corner
// cycles), the face of `b` with the same cycle and the rotation that takes
// b's corners to a's: b's corner (start + k) mod n is a's corner k. Equal
// cycles pair in face order.
bool match_faces(const Mesh& a, const Mesh& b, std::vector<uint32_t>& face, std::vector<uint32_t>& shift) {
  if (a.face_count() != b.face_count()) return false;
  auto sorted = [](const Mesh& m, std::vector<uint32_t>& rot) {
    std::vector<uint32_t> f(m.face_count());
    std::iota(f.begin(), f.end(), 0u);
    rot.resize(m.face_count());
    for (uint32_t i = 0; i < m.face_count(); ++i) rot[i] = smallest_rotation(m.face(i), m.face_size(i));
    std::stable_sort(f.begin(), f.end(), [&](uint32_t x, uint32_t y) {
      const uint32_t nx = m.face_size(x), ny = m.face_size(y);
      if (nx != ny) return nx < ny;
      for (uint32_t k = 0; k < nx; ++k) {
        const uint32_t u = m.face(x)[(rot[x] + k) % nx], v = m.face(y)[(rot[y] + k) % ny];
        if (u != v) return u < v;
      }
      return false;
    });
    return f;
  };
  std::vector<uint32_t> ra, rb;
  const std::vector<uint32_t> fa = sorted(a, ra), fb = sorted(b, rb);
  face.assign(a.face_count(), kNone);
  shift.assign(a.face_count(), 0);
  for (size_t i = 0; i < fa.size(); ++i) {
    const uint32_t x = fa[i], y = fb[i], n = a.face_size(x);
    if (b.face_size(y) != n) return false;
    for (uint32_t k = 0; k < n; ++k)
      if (a.face(x)[(ra[x] + k) % n] != b.face(y)[(rb[y] + k) % n]) return false;
    face[x] = y;
    shift[x] = (rb[y] + n - ra[x]) % n;
  }
  return true;
}

// FORMAT.md §8.13: a mesh with attributes whose faces use several vertices
// at one grid position is coded welded: one point per grid position among
// the vertices on faces (numbered by their first vertex; a vertex on no face
// is a point of its own), the connectivity and the positions on the points,
// then the split stream saying which vertex each corner was, then the
// attributes of the vertices as usual. The decoder numbers the vertices
// point by point, so a decoded mesh welds to the same points in the same
// order (canonical re-encoding). `welded` is false when no two vertices on
// faces share a grid position (nothing is coded then).
Status encode_welded(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<AttributeHeader>& headers,
                     const EncodeOptions& options, EncodedPart& out, bool& welded, uint8_t order_flags = 0) {
  welded = false;
  const uint32_t V = static_cast<uint32_t>(mesh.vertex_count());
  std::vector<uint8_t> used(V, 0);
  for (uint32_t x : mesh.indices) used[x] = 1;
  std::vector<uint32_t> by_q;
  for (uint32_t v = 0; v < V; ++v)
    if (used[v]) by_q.push_back(v);
  std::stable_sort(by_q.begin(), by_q.end(), [&](uint32_t x, uint32_t y) {
    return std::lexicographical_compare(&qin[3 * size_t{x}], &qin[3 * size_t{x}] + 3, &qin[3 * size_t{y}],
                                        &qin[3 * size_t{y}] + 3);
  });
  std::vector<uint32_t> leader(V, kNone), point(V, kNone), rep;
  for (size_t i = 0; i < by_q.size(); ++i) {
    const bool same = i > 0 && std::equal(&qin[3 * size_t{by_q[i]}], &qin[3 * size_t{by_q[i]}] + 3,
                                          &qin[3 * size_t{by_q[i - 1]}]);
    leader[by_q[i]] = same ? leader[by_q[i - 1]] : by_q[i];
  }
  for (uint32_t v = 0; v < V; ++v) {
    if (used[v] && leader[v] != v) {
      point[v] = point[leader[v]];
    } else {
      point[v] = static_cast<uint32_t>(rep.size());
      rep.push_back(v);
    }
  }
  if (rep.size() == V) return Status::Ok();
  const uint32_t np = static_cast<uint32_t>(rep.size());
  Mesh wm;
  std::vector<uint32_t> qw(3 * size_t{np});
  wm.positions.resize(3 * size_t{np});
  for (uint32_t p = 0; p < np; ++p)
    for (int a = 0; a < 3; ++a) {
      wm.positions[3 * size_t{p} + a] = mesh.positions[3 * size_t{rep[p]} + a];
      qw[3 * size_t{p} + a] = qin[3 * size_t{rep[p]} + a];
    }
  wm.face_offsets = mesh.face_offsets;
  wm.indices.resize(mesh.indices.size());
  for (size_t k = 0; k < mesh.indices.size(); ++k) wm.indices[k] = point[mesh.indices[k]];
  EncodedPart pw;
  TSM_RETURN_IF_ERROR(encode_part(wm, qw, {}, {}, options, pw));
  pw.streams.topology[0] = static_cast<char>(pw.streams.topology[0] | 2);
  Mesh dec;
  GeometryLayout scratch;
  TSM_RETURN_IF_ERROR(decode_connectivity(pw.streams, V, wm.face_count(), wm.corner_count(), dec, scratch));
  // The decoded faces on w's points, matched to the input faces.
  Mesh on_w = dec;
  for (uint32_t& x : on_w.indices) x = pw.order[x];
  std::vector<uint32_t> face, shift;
  if (!match_faces(on_w, wm, face, shift)) return Status(ErrorCode::internal, "welded faces do not match the input's");
  std::vector<uint32_t> corner_vertex(dec.indices.size());
  for (uint32_t f = 0; f < dec.face_count(); ++f) {
    const uint32_t n = dec.face_size(f), g = face[f];
    for (uint32_t k = 0; k < n; ++k) corner_vertex[dec.face_offsets[f] + k] = mesh.face(g)[(shift[f] + k) % n];
  }
  std::vector<uint32_t> point_vertex(np), walk_out, walk_point;
  for (uint32_t o = 0; o < np; ++o) point_vertex[o] = rep[pw.order[o]];
  std::vector<uint32_t> indices, q_out(3 * size_t{np});
  for (uint32_t o = 0; o < np; ++o)
    for (int a = 0; a < 3; ++a) q_out[3 * size_t{o} + a] = qw[3 * size_t{pw.order[o]} + a];
  // Value classes: vertices of one point whose vertex attributes are equal
  // on their grids (a copy is coded as such, its values not again). Corner
  // attributes with one value per vertex are coded as vertex attributes
  // (§8.12, predictor bit 4) and take part; with other corner attributes,
  // whose coding follows the vertices' sharing of corner values, there are
  // no copies (on the originals alone those would cost more: the corpus's
  // OBJ exports nearly twice).
  std::vector<uint32_t> value_class(V);
  std::iota(value_class.begin(), value_class.end(), 0u);
  const uint64_t per_vertex = per_vertex_corner_attributes(mesh);
  const Mesh on_vertices = corner_attributes_on_vertices(mesh, per_vertex);
  bool corner_attributes = false;
  for (size_t i = 0; i < headers.size(); ++i)
    corner_attributes = corner_attributes || (headers[i].domain == AttributeDomain::corner && !(per_vertex >> i & 1));
  if (!corner_attributes) {
    std::vector<std::vector<int32_t>> key(V);
    for (size_t i = 0; i < headers.size(); ++i) {
      if (on_vertices.attributes[i].domain != AttributeDomain::vertex) continue;
      const Attribute& at = on_vertices.attributes[i];
      std::vector<int32_t> k(attribute_key_size(headers[i]));
      for (uint32_t v = 0; v < V; ++v) {
        attribute_key(headers[i], &at.values[size_t{at.components} * v], k.data());
        key[v].insert(key[v].end(), k.begin(), k.end());
      }
    }
    std::vector<uint32_t> ids(V);
    std::iota(ids.begin(), ids.end(), 0u);
    std::stable_sort(ids.begin(), ids.end(), [&](uint32_t x, uint32_t y) {
      return std::tie(point[x], key[x]) < std::tie(point[y], key[y]);
    });
    for (size_t i = 0; i < ids.size(); ++i)
      value_class[ids[i]] = i > 0 && point[ids[i]] == point[ids[i - 1]] && key[ids[i]] == key[ids[i - 1]]
                                ? value_class[ids[i - 1]]
                                : ids[i];
  }
  std::vector<uint32_t> walk_input, walk_orig;
  const std::string split = encode_split_layout(dec, np, q_out, corner_vertex, point_vertex, value_class, walk_input,
                                                walk_out, walk_point, walk_orig, indices);
  out.streams = std::move(pw.streams);
  out.geometry = std::move(pw.geometry);
  // The attributes of the originals (the vertices that are not copies), in
  // walk order (as the faces make them: a face's texture coordinates and
  // normals together) or in output order (point by point: what a position
  // carries whatever the face, such as skin weights, repeats there),
  // whichever is smaller; the corners name the originals.
  // The input with every corner on its vertex's original (what the
  // attribute coder matches the decoded faces against).
  Mesh on_originals = on_vertices;
  {
    std::vector<uint32_t> walk_of(V);
    for (uint32_t w = 0; w < V; ++w) walk_of[walk_input[w]] = w;
    for (uint32_t& x : on_originals.indices) x = walk_input[walk_orig[walk_of[x]]];
  }
  EncodedPart by_walk, by_point;
  for (int point_order = 0; point_order < 2; ++point_order) {
    EncodedPart& e = point_order ? by_point : by_walk;
    std::vector<uint32_t> list;  // walk vertices that are originals, in the order coded
    for (uint32_t w = 0; w < V; ++w)
      if (walk_orig[w] == w) list.push_back(w);
    if (point_order)
      std::sort(list.begin(), list.end(), [&](uint32_t x, uint32_t y) { return walk_out[x] < walk_out[y]; });
    std::vector<uint32_t> rank(V, kNone);
    for (uint32_t k = 0; k < list.size(); ++k) rank[list[k]] = k;
    e.faces = dec;
    for (size_t k = 0; k < indices.size(); ++k) e.faces.indices[k] = rank[walk_orig[indices[k]]];
    e.order.resize(list.size());
    e.ref_out.assign(list.size(), 0);
    e.q.resize(3 * list.size());
    for (uint32_t k = 0; k < list.size(); ++k) {
      e.order[k] = walk_input[list[k]];
      for (int a = 0; a < 3; ++a) e.q[3 * size_t{k} + a] = qin[3 * size_t{e.order[k]} + a];
    }
    TSM_RETURN_IF_ERROR(
        encode_part_attributes(on_originals, headers, nullptr, nullptr, attribute_tables(options), e, per_vertex));
  }
  const bool point_order = by_point.attributes.size() < by_walk.attributes.size();
  EncodedPart& best = point_order ? by_point : by_walk;
  out.order = std::move(best.order);
  out.faces = std::move(best.faces);
  out.q = std::move(best.q);
  std::string head;
  ByteWriter bw(head);
  bw.varint(split.size());
  bw.bytes(split);
  bw.u8(static_cast<uint8_t>((point_order ? 1 : 0) | order_flags));
  out.attributes = head + best.attributes;
  out.vertex_from.assign(V, kNone);
  for (size_t w = 0; w < walk_out.size(); ++w) out.vertex_from[walk_out[w]] = walk_input[w];
  welded = true;
  return Status::Ok();
}

// Whether the corner attributes of `mesh` can go through the split route
// (FORMAT.md §8.13, points out): some corner attribute whose values are
// shared by index, every vertex on a face, and per corner attribute every
// value used (the decoder rebuilds the lists from the corners).
bool split_route_fits(const Mesh& mesh, const std::vector<AttributeHeader>& headers) {
  const uint64_t per_vertex = per_vertex_corner_attributes(mesh);
  bool indexed = false;
  for (size_t i = 0; i < headers.size(); ++i)
    indexed = indexed || (headers[i].domain == AttributeDomain::corner && !(per_vertex >> i & 1));
  if (!indexed) return false;
  std::vector<uint8_t> used(mesh.vertex_count(), 0);
  for (uint32_t x : mesh.indices) used[x] = 1;
  if (std::find(used.begin(), used.end(), 0) != used.end()) return false;
  for (const Attribute& a : mesh.attributes) {
    if (a.domain != AttributeDomain::corner) continue;
    std::vector<uint8_t> uses(a.value_count(), 0);
    for (uint32_t x : a.indices) uses[x] = 1;
    if (std::find(uses.begin(), uses.end(), 0) != uses.end()) return false;
  }
  return true;
}

// The split vertices of an indexed mesh: one per distinct (vertex, corner
// value ids) combination, numbered by vertex and then by the first corner
// using them (as the decoder numbers a welded part's vertices, so a decoded
// mesh splits to the same vertices). Corner attributes become one value per
// split vertex; `first` gets per split vertex the first corner using it.
Mesh split_vertices(const Mesh& mesh, std::vector<uint32_t>& first) {
  std::vector<size_t> corner_attrs;
  for (size_t i = 0; i < mesh.attributes.size(); ++i)
    if (mesh.attributes[i].domain == AttributeDomain::corner) corner_attrs.push_back(i);
  std::map<std::vector<uint32_t>, uint32_t> id;
  std::vector<uint32_t> corner_split(mesh.indices.size()), first_corner;
  std::vector<uint32_t> key(1 + corner_attrs.size());
  for (size_t k = 0; k < mesh.indices.size(); ++k) {
    key[0] = mesh.indices[k];
    for (size_t j = 0; j < corner_attrs.size(); ++j) key[1 + j] = mesh.attributes[corner_attrs[j]].indices[k];
    auto it = id.emplace(key, static_cast<uint32_t>(id.size())).first;
    if (it->second == first_corner.size()) first_corner.push_back(static_cast<uint32_t>(k));
    corner_split[k] = it->second;
  }
  const uint32_t n = static_cast<uint32_t>(first_corner.size());
  std::vector<uint32_t> order(n), rank(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    return mesh.indices[first_corner[x]] < mesh.indices[first_corner[y]];
  });
  for (uint32_t r = 0; r < n; ++r) rank[order[r]] = r;
  Mesh s;
  std::vector<uint32_t> from(n);
  first.resize(n);
  s.positions.resize(3 * size_t{n});
  for (uint32_t r = 0; r < n; ++r) {
    first[r] = first_corner[order[r]];
    from[r] = mesh.indices[first[r]];
    std::copy_n(&mesh.positions[3 * size_t{from[r]}], 3, &s.positions[3 * size_t{r}]);
  }
  s.face_offsets = mesh.face_offsets;
  s.indices.resize(mesh.indices.size());
  for (size_t k = 0; k < mesh.indices.size(); ++k) s.indices[k] = rank[corner_split[k]];
  s.metadata = mesh.metadata;
  for (const Attribute& a : mesh.attributes) {
    Attribute b = described_like(a);
    const size_t c = a.components;
    if (a.domain == AttributeDomain::face) {
      b.values = a.values;
    } else {
      b.values.resize(c * n);
      for (uint32_t r = 0; r < n; ++r) {
        const uint32_t k = first_corner[order[r]];
        const size_t v = a.domain == AttributeDomain::vertex ? from[r] : a.indices[k];
        std::copy_n(&a.values[c * v], c, &b.values[c * size_t{r}]);
      }
      if (a.domain == AttributeDomain::corner) b.indices = s.indices;
    }
    s.attributes.push_back(std::move(b));
  }
  return s;
}

// FORMAT.md §8.13, points out: per input vertex its rank among the input
// vertices at its grid position (by id), and the input vertices in the
// decoder's output order: by point (in the order the output split vertices
// `split_input`, given as input vertices, first reach them), then by rank.
std::vector<uint32_t> point_ranks(const Mesh& mesh, const std::vector<uint32_t>& qin,
                                  const std::vector<uint32_t>& split_input, std::vector<uint32_t>& output_order) {
  using Grid3 = std::array<uint32_t, 3>;
  auto grid = [&](uint32_t v) { return Grid3{qin[3 * v], qin[3 * v + 1], qin[3 * v + 2]}; };
  std::map<Grid3, std::vector<uint32_t>> at;
  std::vector<uint32_t> rank(mesh.vertex_count());
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    std::vector<uint32_t>& here = at[grid(v)];
    rank[v] = static_cast<uint32_t>(here.size());
    here.push_back(v);
  }
  output_order.clear();
  for (uint32_t v : split_input) {
    std::vector<uint32_t>& here = at[grid(v)];
    output_order.insert(output_order.end(), here.begin(), here.end());
    here.clear();
  }
  return rank;
}

// FORMAT.md §8.13, points out: per value of a corner attribute its rank
// among the values equal to it on the grid, by index in the list.
std::vector<uint32_t> value_ranks(const Attribute& a, const AttributeHeader& h) {
  std::map<std::vector<int32_t>, uint32_t> count;
  std::vector<uint32_t> rank(a.value_count());
  std::vector<int32_t> key(attribute_key_size(h));
  for (size_t x = 0; x < a.value_count(); ++x) {
    attribute_key(h, &a.values[size_t{a.components} * x], key.data());
    rank[x] = count[key]++;
  }
  return rank;
}

// FORMAT.md §8.13, points out: the rank stream, per output split vertex
// (`split_of`: its split vertex; `first`: per split vertex its first
// corner; `split_corners`: per corner of `mesh` its split vertex): the point
// ranks where a point has several split vertices, each in a model chosen by
// its neighbours' ranks coded so far, then per corner attribute coded per
// vertex (`per_vertex`) the value ranks where a value is shared. Empty when
// every rank is 0.
std::string rank_stream(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint32_t>& split_of,
                        const std::vector<uint32_t>& first, const std::vector<uint32_t>& split_corners,
                        const std::vector<uint32_t>& point_rank, const std::vector<AttributeHeader>& headers,
                        uint64_t per_vertex) {
  const size_t n = split_of.size();
  RangeEncoder e;
  UIntModel point_model[3], value_model;
  std::vector<uint32_t> out_of(n);
  for (size_t o = 0; o < n; ++o) out_of[split_of[o]] = static_cast<uint32_t>(o);
  Mesh faces;
  faces.face_offsets = mesh.face_offsets;
  faces.indices.resize(split_corners.size());
  for (size_t k = 0; k < split_corners.size(); ++k) faces.indices[k] = out_of[split_corners[k]];
  const RankNeighbours neighbours = rank_neighbours(faces, n);
  bool any = false;
  std::map<std::array<uint32_t, 3>, uint32_t> share;
  auto grid = [&](size_t o) {
    const uint32_t v = mesh.indices[first[split_of[o]]];
    return std::array<uint32_t, 3>{qin[3 * v], qin[3 * v + 1], qin[3 * v + 2]};
  };
  for (size_t o = 0; o < n; ++o) ++share[grid(o)];
  std::vector<uint32_t> coded(n, kNone);
  for (size_t o = 0; o < n; ++o) {
    if (share[grid(o)] < 2) continue;
    const uint32_t r = point_rank[mesh.indices[first[split_of[o]]]];
    point_model[neighbours_say(neighbours, static_cast<uint32_t>(o), coded)].encode(e, r);
    coded[o] = r;
    any = any || r != 0;
  }
  for (size_t i = 0; i < mesh.attributes.size(); ++i) {
    const Attribute& a = mesh.attributes[i];
    if (a.domain != AttributeDomain::corner || !(per_vertex >> i & 1)) continue;
    const std::vector<uint32_t> rank = value_ranks(a, headers[i]);
    std::vector<std::vector<int32_t>> keys(n, std::vector<int32_t>(attribute_key_size(headers[i])));
    std::map<std::vector<int32_t>, uint32_t> count;
    for (size_t o = 0; o < n; ++o) {
      attribute_key(headers[i], &a.values[size_t{a.components} * a.indices[first[split_of[o]]]], keys[o].data());
      ++count[keys[o]];
    }
    for (size_t o = 0; o < n; ++o) {
      if (count[keys[o]] < 2) continue;
      const uint32_t r = rank[a.indices[first[split_of[o]]]];
      value_model.encode(e, r);
      any = any || r != 0;
    }
  }
  return any ? e.finish() : std::string();
}

// The mesh in an order of its own, the same for any ordering of it (a
// decoded file's included, up to vertices and values equal on the grid):
// vertices by grid position, each face turned to start at its smallest
// corner, faces by their corners' positions and corner values. The split
// route is kept or not by its size, and a decoded file must make the same
// choice as its input (canonical re-encoding). `perm`: per vertex of the
// result its input vertex.
Mesh in_own_order(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<AttributeHeader>& headers,
                  std::vector<uint32_t>& perm) {
  const uint32_t V = static_cast<uint32_t>(mesh.vertex_count());
  perm.resize(V);
  std::iota(perm.begin(), perm.end(), 0u);
  auto grid = [&](uint32_t v) {
    return std::array<uint32_t, 3>{qin[3 * size_t{v}], qin[3 * size_t{v} + 1], qin[3 * size_t{v} + 2]};
  };
  std::stable_sort(perm.begin(), perm.end(), [&](uint32_t a, uint32_t b) { return grid(a) < grid(b); });
  std::vector<uint32_t> at(V);
  for (uint32_t i = 0; i < V; ++i) at[perm[i]] = i;
  // Per corner: its vertex's new id and its values' grid integers.
  const size_t K = mesh.indices.size();
  std::vector<std::vector<int32_t>> key(K);
  for (size_t k = 0; k < K; ++k) {
    key[k].push_back(static_cast<int32_t>(at[mesh.indices[k]]));
    for (size_t i = 0; i < mesh.attributes.size(); ++i) {
      const Attribute& a = mesh.attributes[i];
      if (a.domain != AttributeDomain::corner) continue;
      std::vector<int32_t> x(attribute_key_size(headers[i]));
      attribute_key(headers[i], &a.values[size_t{a.components} * a.indices[k]], x.data());
      key[k].insert(key[k].end(), x.begin(), x.end());
    }
  }
  const uint32_t F = static_cast<uint32_t>(mesh.face_count());
  std::vector<uint32_t> first(F), order(F);
  for (uint32_t f = 0; f < F; ++f) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t j = 1; j < n; ++j)
      if (key[o + j] < key[o + first[f]]) first[f] = j;
  }
  // Faces compared corner by corner from their first, the shorter first on a
  // tie (without building each face's key list per comparison).
  auto face_less = [&](uint32_t a, uint32_t b) {
    const uint32_t oa = mesh.face_offsets[a], na = mesh.face_size(a);
    const uint32_t ob = mesh.face_offsets[b], nb = mesh.face_size(b);
    for (uint32_t j = 0; j < std::min(na, nb); ++j) {
      const std::vector<int32_t>& ka = key[oa + (first[a] + j) % na];
      const std::vector<int32_t>& kb = key[ob + (first[b] + j) % nb];
      if (ka != kb) return ka < kb;
    }
    return na < nb;
  };
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), face_less);
  Mesh out = mesh;
  for (uint32_t i = 0; i < V; ++i) std::copy_n(&mesh.positions[3 * size_t{perm[i]}], 3, &out.positions[3 * size_t{i}]);
  std::vector<uint32_t> from(K);  // per new corner, its input corner
  out.face_offsets.assign(1, 0);
  for (uint32_t f : order) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t j = 0; j < n; ++j) from[out.face_offsets.back() + j] = o + (first[f] + j) % n;
    out.face_offsets.push_back(out.face_offsets.back() + n);
  }
  for (size_t k = 0; k < K; ++k) out.indices[k] = at[mesh.indices[from[k]]];
  for (size_t i = 0; i < mesh.attributes.size(); ++i) {
    const Attribute& a = mesh.attributes[i];
    Attribute& b = out.attributes[i];
    const size_t c = a.components;
    if (a.domain == AttributeDomain::vertex) {
      for (uint32_t v = 0; v < V; ++v) std::copy_n(&a.values[c * perm[v]], c, &b.values[c * v]);
    } else if (a.domain == AttributeDomain::face) {
      for (uint32_t f = 0; f < F; ++f) std::copy_n(&a.values[c * order[f]], c, &b.values[c * f]);
    } else {
      for (size_t k = 0; k < K; ++k) b.indices[k] = a.indices[from[k]];
    }
  }
  return out;
}

// FORMAT.md §8.13, points out: a mesh whose corner attributes are index
// lists (OBJ vt/vn, PLY per-corner lists) coded as the split vertices a
// glTF exporter would make, through the welded path, with the ranks that
// tell apart input vertices sharing a grid position and values equal on
// their grid; the decoder gives back one vertex per (point, rank) and the
// value lists. `vertex_from`: per output vertex, its input vertex. `done`
// is false when nothing was coded.
Status encode_split_route(const Mesh& input, const std::vector<uint32_t>& qinput, const EncodeOptions& options,
                          EncodedPart& out, std::vector<uint32_t>& vertex_from, uint64_t& split_count, bool& done) {
  done = false;
  std::vector<uint32_t> perm;
  const Mesh mesh = in_own_order(input, qinput, attribute_headers(input, options.attribute_bits), perm);
  std::vector<uint32_t> qin(qinput.size());
  for (size_t v = 0; v < perm.size(); ++v) std::copy_n(&qinput[3 * size_t{perm[v]}], 3, &qin[3 * v]);
  std::vector<uint32_t> first;
  const Mesh s = split_vertices(mesh, first);
  if (s.vertex_count() == mesh.vertex_count()) return Status::Ok();
  std::vector<uint32_t> qs(3 * s.vertex_count());
  for (size_t v = 0; v < s.vertex_count(); ++v) std::copy_n(&qin[3 * size_t{mesh.indices[first[v]]}], 3, &qs[3 * v]);
  const std::vector<AttributeHeader> headers = attribute_headers(s, options.attribute_bits);
  if (per_vertex_corner_attributes(s) == 0) return Status::Ok();
  bool welded = false;
  TSM_RETURN_IF_ERROR(encode_welded(s, qs, headers, options, out, welded, 2));
  if (!welded) return Status::Ok();
  std::vector<uint32_t> split_input(out.vertex_from.size());
  for (size_t o = 0; o < split_input.size(); ++o) split_input[o] = mesh.indices[first[out.vertex_from[o]]];
  const std::vector<uint32_t> point_rank = point_ranks(mesh, qin, split_input, vertex_from);
  if (vertex_from.size() != mesh.vertex_count())
    return Status(ErrorCode::internal, "the split route's points do not map to the input's vertices");
  for (uint32_t& v : vertex_from) v = perm[v];
  const std::string ranks =
      rank_stream(mesh, qin, out.vertex_from, first, s.indices, point_rank,
                  attribute_headers(mesh, options.attribute_bits), per_vertex_corner_attributes(s));
  // The rank stream goes after the order byte (the split stream's length,
  // the stream, the byte), which says so by its bit 2.
  if (!ranks.empty()) {
    ByteReader r(out.attributes);
    uint64_t len = 0;
    if (!r.varint(len)) return Status(ErrorCode::internal, "the welded part lost its split stream");
    const size_t at = r.offset() + static_cast<size_t>(len) + 1;
    out.attributes[at - 1] = static_cast<char>(out.attributes[at - 1] | 4);
    std::string head;
    ByteWriter bw(head);
    bw.varint(ranks.size());
    bw.bytes(ranks);
    out.attributes.insert(at, head);
  }
  split_count = s.vertex_count();
  done = true;
  return Status::Ok();
}

// FORMAT.md §5.1: a lossless file's grid, chosen for the mesh, with its
// bits in place of the options' quantization bits.
bool attributes_finite(const Mesh& mesh) {
  for (const Attribute& a : mesh.attributes)
    for (float x : a.values)
      if (!std::isfinite(x)) return false;
  return true;
}

BoundingBox finite_box(const Mesh& mesh) {
  BoundingBox box;
  bool any[3] = {false, false, false};
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const float x = mesh.positions[i];
    const size_t a = i % 3;
    if (!std::isfinite(x)) continue;
    box.min[a] = any[a] ? std::min(box.min[a], x) : x;
    box.max[a] = any[a] ? std::max(box.max[a], x) : x;
    any[a] = true;
  }
  return box;
}

// The file's sections without the end marker (`cw`), per output vertex its
// input id (`vertex_from`), and for a lossless file its grid (`exact`).
Status encode_sections(const Mesh& mesh, const EncodeOptions& options_in, std::optional<ContainerWriter>& cw_out,
                       std::vector<uint32_t>& vertex_from, ExactGrid& exact) {
  EncodeOptions options = options_in;
  if (options.lossless) {
    exact = choose_exact_grid(mesh);
    options.quantization_bits = exact.bits;
  }
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "mesh is invalid: " + why);
  if (options.quantization_bits < 1 || options.quantization_bits > 30)
    return Status(ErrorCode::invalid_argument,
                  "quantization bits must be 1..30, got " + std::to_string(options.quantization_bits));
  if (options.level < 0 || options.level > 9)
    return Status(ErrorCode::invalid_argument, "level must be 0..9, got " + std::to_string(options.level));
  if (!mesh.all_finite() && !(options.lossless && options.allow_nonfinite && attributes_finite(mesh)))
    return Status(ErrorCode::invalid_argument,
                  options.lossless && !attributes_finite(mesh)
                      ? "mesh has NaN or infinite attribute values, which no quantization grid can hold; fix or drop "
                        "them first"
                  : options.lossless
                      ? "mesh has NaN or infinite coordinates; pass --allow-nonfinite (EncodeOptions::allow_nonfinite) "
                        "to keep them exactly, or fix or drop those vertices"
                      : "mesh has NaN or infinite coordinates, which no quantization grid can hold; encode with "
                        "--lossless --allow-nonfinite to keep them, or fix or drop those vertices first");

  Header h;
  h.version = kFormatVersion;
  h.vertex_count = mesh.vertex_count();
  h.face_count = mesh.face_count();
  h.corner_count = mesh.corner_count();
  h.quantization_bits = static_cast<uint8_t>(options.quantization_bits);
  h.level = static_cast<uint8_t>(options.level);
  BoundingBox box = options.lossless ? finite_box(mesh) : bounding_box(mesh);
  // On a grid a -0 minimum decodes as +0 (origin + 0 x step): +0 as the
  // origin, so a decoded mesh re-encodes to the same bytes (a lossless file
  // keeps -0 itself).
  for (int a = 0; a < 3; ++a) h.origin[a] = options.lossless ? box.min[a] : box.min[a] + 0.0f;
  h.extent = box.largest_extent();
  if (!std::isfinite(h.extent))
    return Status(ErrorCode::invalid_argument, "mesh extent overflows a float; scale the mesh down");

  Grid grid;
  grid.bits = options.quantization_bits;
  for (int a = 0; a < 3; ++a) grid.origin[a] = h.origin[a];
  grid.step = grid_step(h);
  const int64_t qmax = (int64_t{1} << options.quantization_bits) - 1;
  std::vector<uint32_t> qin(3 * mesh.vertex_count());  // by input id
  for (size_t i = 0; i < qin.size(); ++i) {
    int64_t x = grid.quantize(mesh.positions[i], static_cast<int>(i % 3));
    qin[i] = static_cast<uint32_t>(x < 0 ? 0 : x > qmax ? qmax : x);
  }
  if (options.lossless) {
    h.flags = kHeaderExactGrid;
    h.exact_step = exact.step;
    for (int a = 0; a < 3; ++a) h.exact_base[a] = exact.base[a];
    for (size_t i = 0; i < qin.size(); ++i) qin[i] = exact_index(exact, mesh.positions[i], static_cast<int>(i % 3));
  }
  for (const Attribute& a : mesh.attributes)
    if (a.type != AttributeType::f32)
      for (float x : a.values)
        if (x != std::floor(x) || std::fabs(x) >= static_cast<float>(1 << 30))
          return Status(ErrorCode::invalid_argument,
                        "attribute '" + a.name + "' is of an integer type but holds " + std::to_string(x) +
                            " (integers of magnitude below 2^30 only: the difference of two must fit in 32 bits)");
  if (mesh.attributes.size() > 64)
    return Status(ErrorCode::invalid_argument, "more than 64 attributes");
  const AttributeQuantization& ab = options.attribute_bits;
  for (int b : {ab.normal, ab.texcoord, ab.color, ab.generic})
    if (b < 1 || b > 24)
      return Status(ErrorCode::invalid_argument, "attribute quantization bits must be 1..24, got " + std::to_string(b));
  const std::vector<AttributeHeader> headers = attribute_headers(mesh, ab);
  const uint32_t max_faces = options.segment_faces ? options.segment_faces : kDefaultSegmentFaces;
  const std::vector<std::vector<uint32_t>> segments = split_faces(mesh, qin, max_faces);
  h.segment_count = static_cast<uint32_t>(segments.size());
  std::string mesh_section;
  if (segments.size() == 1) {
    EncodedPart p;
    bool welded = false;
    if (!headers.empty()) TSM_RETURN_IF_ERROR(encode_welded(mesh, qin, headers, options, p, welded));
    if (!welded) TSM_RETURN_IF_ERROR(encode_part(mesh, qin, {}, headers, options, p));
    MeshPayload mp{p.streams.vertex_tree, p.streams.triangle_tree, p.streams.topology, p.geometry, p.attributes};
    mesh_section = write_mesh_payload(mp);
    vertex_from = welded ? std::move(p.vertex_from) : std::move(p.order);
    // Index-list corner attributes: also as split vertices, kept when smaller.
    if (!options.lossless && !options.keep_order && split_route_fits(mesh, headers)) {
      EncodedPart ps;
      std::vector<uint32_t> from;
      uint64_t split_count = 0;
      bool done = false;
      TSM_RETURN_IF_ERROR(encode_split_route(mesh, qin, options, ps, from, split_count, done));
      MeshPayload ms{ps.streams.vertex_tree, ps.streams.triangle_tree, ps.streams.topology, ps.geometry, ps.attributes};
      std::string section = done ? write_mesh_payload(ms) : std::string();
      if (done && section.size() < mesh_section.size()) {
        mesh_section = std::move(section);
        vertex_from = std::move(from);
        h.vertex_count = split_count;
      }
    }
  }
  ContainerWriter& cw = cw_out.emplace(h);
  // Metadata first, so that a streaming client has it before any geometry.
  if (!mesh.metadata.empty()) {
    const std::string md = write_metadata(mesh.metadata);
    cw.add_section(kSectionMetadata, md, md.size() > (1u << 20) ? 3 : 9);
  }
  if (segments.size() == 1) {
    cw.add_section(kSectionMesh, mesh_section, 0);
  } else {
    TSM_RETURN_IF_ERROR(encode_segments(mesh, qin, segments, headers, options, cw, vertex_from));
  }
  return Status::Ok();
}

// EncodeMapping of a file (`bytes`, without an order section) decoded as
// `decoded`: the faces on input ids matched to the input's faces.
Status file_mapping(const Mesh& mesh, const Mesh& decoded, std::vector<uint32_t> vertex_from, EncodeMapping& m) {
  if (vertex_from.size() != mesh.vertex_count() || decoded.vertex_count() != mesh.vertex_count())
    return Status(ErrorCode::internal, "the decoded vertices do not map to the input's");
  Mesh on_input;
  on_input.face_offsets = decoded.face_offsets;
  on_input.indices.reserve(decoded.indices.size());
  for (uint32_t x : decoded.indices) on_input.indices.push_back(vertex_from[x]);
  std::vector<uint32_t> face, shift;
  if (!match_faces(on_input, mesh, face, shift))
    return Status(ErrorCode::internal, "the decoded faces do not match the input's");
  m.vertex_from = std::move(vertex_from);
  m.face_from = std::move(face);
  m.first_corner = std::move(shift);
  return Status::Ok();
}

void identity_mapping(const Mesh& mesh, EncodeMapping& m) {
  m.vertex_from.resize(mesh.vertex_count());
  std::iota(m.vertex_from.begin(), m.vertex_from.end(), 0u);
  m.face_from.resize(mesh.face_count());
  std::iota(m.face_from.begin(), m.face_from.end(), 0u);
  m.first_corner.assign(mesh.face_count(), 0);
}

}  // namespace

Status encode(const Mesh& mesh, const EncodeOptions& options, std::string& out, EncodeMapping* mapping) {
  if (options.progressive) {
    if (options.keep_order || options.lossless || mapping)
      return Status(ErrorCode::invalid_argument,
                    "a progressive file keeps neither the input order nor exact coordinates, and has no vertex "
                    "mapping yet: drop the progressive option or keep_order / lossless / the mapping");
    std::string why;
    if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "mesh is invalid: " + why);
    if (options.quantization_bits >= 1 && options.quantization_bits <= 30 && mesh.all_finite())
      return encode_progressive(mesh, options, out);
  }
  std::optional<ContainerWriter> cw;
  std::vector<uint32_t> vertex_from;
  ExactGrid exact;
  TSM_RETURN_IF_ERROR(encode_sections(mesh, options, cw, vertex_from, exact));
  if (options.lossless) {
    // The coordinates in decoded order, for the exceptions (FORMAT.md §5.1).
    std::vector<float> decoded_order(mesh.positions.size());
    for (size_t v = 0; v < vertex_from.size(); ++v)
      for (int a = 0; a < 3; ++a) decoded_order[3 * v + a] = mesh.positions[3 * size_t{vertex_from[v]} + a];
    const std::string ex = encode_exceptions(exact, decoded_order);
    if (ex.size() > 1) cw->add_section(kSectionExceptions, ex, 19);
  }
  if (!mapping && !options.keep_order) {
    out = cw->finish();
    return Status::Ok();
  }
  // The mapping follows the decoder's faces: decode the file as it stands.
  ContainerWriter plain = *cw;
  std::string bytes = plain.finish();
  Mesh decoded;
  DecodeOptions dopt;
  dopt.threads = options.threads;
  TSM_RETURN_IF_ERROR(decode(bytes, decoded, dopt));
  EncodeMapping m;
  TSM_RETURN_IF_ERROR(file_mapping(mesh, decoded, std::move(vertex_from), m));
  if (!options.keep_order) {
    out = std::move(bytes);
    *mapping = std::move(m);
    return Status::Ok();
  }
  cw->add_section(kSectionOrder, encode_order(decoded, m.vertex_from, m.face_from, m.first_corner), 0);
  out = cw->finish();
  if (mapping) identity_mapping(mesh, *mapping);
  return Status::Ok();
}

}  // namespace tsm
