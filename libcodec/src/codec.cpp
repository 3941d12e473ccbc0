// Encoder and decoder entry points: validate the mesh, run the connectivity
// stages (seed 004 §3-4), quantize positions on the Draco grid (design notes
// §6) and code them in decoded vertex order, and lay the streams out as
// container sections.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>
#include <unordered_map>
#ifndef TSM_NO_THREADS
#include <thread>
#endif

#include "attributes.hpp"
#include "connectivity.hpp"
#include "container.hpp"
#include "geometry_predict.hpp"
#include "range_coder.hpp"
#include "segments.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

const char* version_string() { return TSM_VERSION; }

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

double grid_step(const Header& h) {
  return h.extent > 0 ? h.extent / (std::ldexp(1.0, h.quantization_bits) - 1.0) : 0.0;
}

const Section* find_section(const std::vector<Section>& sections, uint16_t id) {
  for (const Section& s : sections)
    if (s.id == id) return &s;
  return nullptr;
}

// One part of a file: the whole mesh (the mesh section, §4.7) or one
// segment (§4.5).
struct PartCounts {
  uint64_t vertex_count = 0, face_count = 0, corner_count = 0, reference_count = 0;
};
struct PartStreams {
  std::string_view vertex_tree, triangle_tree, topology, references, geometry;
  bool segmented = false;  // has a references stream
  std::string_view attributes;  // empty: none
};

// A modelled binary decision costs at least 0.0028146 bits (range_coder.hpp:
// probabilities stay within 64/32768 of certainty), so a stream of n bytes
// (plus the 8 zero bytes a decoder may read past its end) holds at most
// max_decisions(n) = 2843 (n + 8) decisions. Every own vertex costs at least
// 3 in the geometry stream, every vertex of a segment 1 in its references
// stream, every triangle of the cut surface at least 1 in the triangle-tree
// stream (a marching bit or a run's end), every side-face corner at least 6
// in the topology stream: counts beyond that are forged, refused before
// allocating.
uint64_t decisions(std::string_view stream) { return max_decisions(stream.size()); }

Status check_budget(const PartCounts& c, const PartStreams& s) {
  if (c.vertex_count >= 0x3FFFFFFFu || c.corner_count >= 0x3FFFFFFFu || c.face_count > c.corner_count)
    return corrupt("vertex, face or corner count out of range");
  if (c.reference_count > c.vertex_count) return corrupt("more references than vertices");
  if (c.vertex_count - c.reference_count > decisions(s.geometry) / 3)
    return corrupt("the header's " + std::to_string(c.vertex_count - c.reference_count) +
                   " vertices cannot be coded in a geometry section of this size");
  if (s.segmented && c.vertex_count > decisions(s.references))
    return corrupt("the segment's " + std::to_string(c.vertex_count) +
                   " vertices cannot be flagged in a references stream of this size");
  if (c.corner_count > 3 * decisions(s.triangle_tree) + decisions(s.topology) / 6)
    return corrupt("the header's " + std::to_string(c.corner_count) +
                   " corners cannot be coded in connectivity sections of this size");
  return Status::Ok();
}

Status check_user_limits(const Header& h, const DecodeOptions& options) {
  if (options.max_vertices && h.vertex_count > options.max_vertices)
    return Status(ErrorCode::limit_exceeded, "file has " + std::to_string(h.vertex_count) +
                                                 " vertices, above the caller's limit of " +
                                                 std::to_string(options.max_vertices));
  if (options.max_faces && h.face_count > options.max_faces)
    return Status(ErrorCode::limit_exceeded, "file has " + std::to_string(h.face_count) +
                                                 " faces, above the caller's limit of " +
                                                 std::to_string(options.max_faces));
  const uint64_t max_corners = options.max_corners ? options.max_corners : 16 * options.max_faces;
  if (max_corners && h.corner_count > max_corners)
    return Status(ErrorCode::limit_exceeded, "file has " + std::to_string(h.corner_count) +
                                                 " face corners, above the caller's limit of " +
                                                 std::to_string(max_corners));
  if (h.vertex_count >= 0x3FFFFFFFu || h.corner_count >= 0x3FFFFFFFu || h.face_count > h.corner_count)
    return corrupt("vertex, face or corner count out of range");
  return Status::Ok();
}

// What a decoded part holds before it joins the mesh.
struct DecodedPart {
  PartCounts counts;
  Mesh faces;                    // corners are the part's output vertex ids
  std::vector<uint32_t> q;       // grid indices, 3 per own vertex
  std::vector<uint32_t> global;  // per part vertex: the earlier segment's vertex it is, kNone if own
  std::vector<std::vector<uint32_t>> alias;  // per attribute, per corner value: an earlier segment's value, or kNone
  ConnectivityStats cstats;
  GeometryStats gstats;
  uint32_t table_coded_attributes = 0;  // attributes whose residuals are table-coded
  Status status;
};

Status decode_part(const PartStreams& s, uint64_t earlier_vertices, int bits, DecodedPart& out) {
  TSM_RETURN_IF_ERROR(check_budget(out.counts, s));
  ConnectivityStreams cs;
  cs.vertex_tree.assign(s.vertex_tree);
  cs.triangle_tree.assign(s.triangle_tree);
  cs.topology.assign(s.topology);
  GeometryLayout layout;
  const PartCounts& c = out.counts;
  TSM_RETURN_IF_ERROR(
      decode_connectivity(cs, c.vertex_count, c.face_count, c.corner_count, out.faces, layout, &out.cstats));
  if (!s.segmented) {
    if (!s.attributes.empty()) out.global.assign(c.vertex_count, kNone);  // only attributes look (all own)
    TSM_RETURN_IF_ERROR(decode_geometry(s.geometry, layout, bits, out.q, &out.gstats));
  } else {
    TSM_RETURN_IF_ERROR(
        decode_references(s.references, reference_contexts(layout), c.reference_count, earlier_vertices, out.global));
    TSM_RETURN_IF_ERROR(
        decode_geometry(s.geometry, own_layout(layout, out.global), bits, out.q, &out.gstats));
  }
  AttributePart ap;
  ap.faces = &out.faces;
  ap.global = &out.global;
  ap.q = &out.q;
  ap.segmented = s.segmented;
  ap.table_coded = &out.table_coded_attributes;
  return decode_attributes(s.attributes, ap, out.faces.attributes, &out.alias);
}

// Runs f(0..n-1) on up to `threads` threads (0 = one per core); each index
// once. Serial where threads are not available.
template <class F>
void parallel_for(size_t n, int threads, F&& f) {
#ifndef TSM_NO_THREADS
  size_t t = threads > 0 ? static_cast<size_t>(threads) : std::max(1u, std::thread::hardware_concurrency());
  t = std::min(t, n);
  if (t > 1) {
    std::atomic<size_t> next{0};
    auto work = [&] {
      for (size_t i; (i = next.fetch_add(1)) < n;) f(i);
    };
    std::vector<std::thread> pool;
    for (size_t k = 1; k < t; ++k) pool.emplace_back(work);
    work();
    for (std::thread& th : pool) th.join();
    return;
  }
#else
  (void)threads;
#endif
  for (size_t i = 0; i < n; ++i) f(i);
}

// A segment section as a part: its streams (views into the section) and counts.
Status read_part(const Section& sec, PartStreams& s, PartCounts& c) {
  SegmentPayload p;
  TSM_RETURN_IF_ERROR(read_segment(sec.data, p));
  s = PartStreams{p.vertex_tree, p.triangle_tree, p.topology, p.references, p.geometry, true, p.attributes};
  c = PartCounts{p.vertex_count, p.face_count, p.corner_count, p.reference_count};
  return Status::Ok();
}

// The file's parts, from its parsed sections.
Status collect_parts(const Header& h, const std::vector<Section>& sections, std::vector<PartStreams>& streams,
                     std::vector<DecodedPart>& parts) {
  if (h.segment_count == 1) {
    PartStreams s;
    const Section* sec = find_section(sections, kSectionMesh);
    if (!sec) return corrupt("the mesh section is missing");
    MeshPayload p;
    TSM_RETURN_IF_ERROR(read_mesh_payload(sec->data, p));
    s.vertex_tree = p.vertex_tree;
    s.triangle_tree = p.triangle_tree;
    s.topology = p.topology;
    s.geometry = p.geometry;
    s.attributes = p.attributes;
    streams.assign(1, s);
    parts.resize(1);
    parts[0].counts = PartCounts{h.vertex_count, h.face_count, h.corner_count, 0};
    return Status::Ok();
  }
  PartCounts sum;
  for (const Section& sec : sections) {
    if (sec.id != kSectionSegment) continue;
    PartStreams s;
    PartCounts c;
    TSM_RETURN_IF_ERROR(read_part(sec, s, c));
    streams.push_back(s);
    parts.emplace_back();
    parts.back().counts = c;
    sum.vertex_count += c.vertex_count - c.reference_count;
    sum.face_count += c.face_count;
    sum.corner_count += c.corner_count;
  }
  if (parts.size() != h.segment_count)
    return corrupt("the header announces " + std::to_string(h.segment_count) + " segments, the file holds " +
                   std::to_string(parts.size()));
  if (sum.vertex_count != h.vertex_count || sum.face_count != h.face_count || sum.corner_count != h.corner_count)
    return corrupt("the segments' vertex, face or corner counts do not add up to the header's");
  return Status::Ok();
}

// A grid index as a coordinate (FORMAT.md §5).
float grid_value(const Header& h, double step, int axis, uint32_t q) {
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  const double o = static_cast<double>(h.origin[axis]);
  double x = o + static_cast<double>(q) * step;
  // A grid point may lie up to half a step past the largest input
  // coordinate; near the float limit, clamp (the input was within range).
  x = x > kFloatMax ? kFloatMax : x < -kFloatMax ? -kFloatMax : x;
  float c = static_cast<float>(x);
  // On an axis shorter than the extent, the float nearest a grid point may
  // lie just past origin + extent; then the float below it, so that the
  // decoded mesh has the extent it was coded with and coding it again
  // takes the same grid (canonical re-encoding).
  while (static_cast<double>(c) - o > h.extent) c = std::nextafter(c, -std::numeric_limits<float>::infinity());
  return c;
}

// The parts of a file carry the same attributes (names, kinds, domains,
// types, components), each with its own values.
Status check_same_attributes(const Mesh& out, bool first, const std::vector<Attribute>& part) {
  if (first) return Status::Ok();
  bool same = part.size() == out.attributes.size();
  for (size_t i = 0; same && i < part.size(); ++i) same = same_description(part[i], out.attributes[i]);
  return same ? Status::Ok() : corrupt("the segments disagree on the attributes they carry");
}

// Appends a decoded part to the mesh: its own vertices get the next ids,
// its faces follow the faces so far, its attribute values follow theirs.
// Frees the part's buffers.
Status append_part(const Header& h, DecodedPart& part, Mesh& out, bool first) {
  TSM_RETURN_IF_ERROR(check_same_attributes(out, first, part.faces.attributes));
  const double step = grid_step(h);
  const uint32_t base = static_cast<uint32_t>(out.vertex_count());
  if (first) {
    out.attributes = std::move(part.faces.attributes);
  } else {
    for (size_t i = 0; i < out.attributes.size(); ++i) {
      Attribute &o = out.attributes[i], &p = part.faces.attributes[i];
      const uint32_t value_base = static_cast<uint32_t>(o.value_count());
      const std::vector<uint32_t>* alias = i < part.alias.size() && !part.alias[i].empty() ? &part.alias[i] : nullptr;
      if (!alias) {
        o.values.insert(o.values.end(), p.values.begin(), p.values.end());
        for (uint32_t x : p.indices) o.indices.push_back(value_base + x);
        continue;
      }
      // Values of earlier segments are not added again: their corners use the earlier ones.
      std::vector<uint32_t> id(alias->size());
      uint32_t next = value_base;
      for (size_t j = 0; j < id.size(); ++j) {
        const uint32_t a = (*alias)[j];
        if (a == kNone) {
          id[j] = next++;
          o.values.insert(o.values.end(), p.values.begin() + static_cast<std::ptrdiff_t>(p.components * j),
                          p.values.begin() + static_cast<std::ptrdiff_t>(p.components * (j + 1)));
        } else if (a < value_base) {
          id[j] = a;
        } else {
          return corrupt("attribute '" + p.name + "': a value names value " + std::to_string(a) +
                         " of the segments before, which hold " + std::to_string(value_base));
        }
      }
      for (uint32_t x : p.indices) o.indices.push_back(id[x]);
    }
  }
  if (first)
    for (const std::vector<uint32_t>& alias : part.alias)
      for (uint32_t a : alias)
        if (a != kNone) return corrupt("the first segment names values of segments before it");
  out.positions.resize(out.positions.size() + part.q.size());
  float* pos = out.positions.data() + 3 * static_cast<size_t>(base);
  const uint32_t* q = part.q.data();
  for (size_t v = 0, nv = part.q.size() / 3; v < nv; ++v, q += 3, pos += 3)
    for (int axis = 0; axis < 3; ++axis) pos[axis] = grid_value(h, step, axis, q[axis]);
  if (first) {  // the first part has no references: its faces as they are, no copy
    out.face_offsets = std::move(part.faces.face_offsets);
    out.indices = std::move(part.faces.indices);
  } else {
    std::vector<uint32_t> id(part.global.size());
    uint32_t own = 0;
    for (size_t v = 0; v < id.size(); ++v) id[v] = part.global[v] != kNone ? part.global[v] : base + own++;
    const uint32_t corner_base = static_cast<uint32_t>(out.indices.size());
    out.indices.reserve(out.indices.size() + part.faces.indices.size());
    for (uint32_t x : part.faces.indices) out.indices.push_back(id[x]);
    out.face_offsets.reserve(out.face_offsets.size() + part.faces.face_count());
    for (size_t f = 1; f < part.faces.face_offsets.size(); ++f)
      out.face_offsets.push_back(corner_base + part.faces.face_offsets[f]);
  }
  part.faces.clear();
  part.q = std::vector<uint32_t>();
  part.global = std::vector<uint32_t>();
  return Status::Ok();
}

Status decode_parts(const Header& h, std::vector<Section>& sections, int threads, std::vector<DecodedPart>& parts,
                    std::vector<PartStreams>& streams) {
  TSM_RETURN_IF_ERROR(collect_parts(h, sections, streams, parts));
  std::vector<uint64_t> earlier(parts.size(), 0);
  for (size_t k = 1; k < parts.size(); ++k)
    earlier[k] = earlier[k - 1] + parts[k - 1].counts.vertex_count - parts[k - 1].counts.reference_count;
  parallel_for(parts.size(), threads, [&](size_t k) {
    parts[k].status = decode_part(streams[k], earlier[k], h.quantization_bits, parts[k]);
  });
  for (size_t k = 0; k < parts.size(); ++k)
    if (!parts[k].status.ok())
      return parts.size() == 1 ? parts[k].status
                               : Status(parts[k].status.code(),
                                        "segment " + std::to_string(k) + ": " + parts[k].status.message());
  return Status::Ok();
}

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
  Status status;
};

// The attribute payload of a part from what encode_part kept (`imported`,
// `own_values`: see AttributeInput; null for a whole mesh).
Status encode_part_attributes(const Mesh& part, const std::vector<AttributeHeader>& headers,
                              const std::vector<std::vector<uint32_t>>* imported,
                              std::vector<std::vector<uint32_t>>* own_values, bool tables, EncodedPart& p) {
  AttributeInput ai;
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

OwnView own_view(const ConnectivityEncoding& ce, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref) {
  OwnView w;
  const size_t n = ce.vertex_order.size();
  w.mark.assign(n, kNone);
  if (!is_ref.empty())
    for (size_t v = 0; v < n; ++v)
      if (is_ref[ce.vertex_order[v]]) w.mark[v] = 0;
  for (size_t v = 0; v < n; ++v)
    if (w.mark[v] == kNone)
      for (int a = 0; a < 3; ++a) w.q.push_back(qin[3 * static_cast<size_t>(ce.vertex_order[v]) + a]);
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

// FORMAT.md §8.3.1: at the fast levels, a part of kRunTableFaces faces or
// more codes its run values through tables where they pay (every value is
// below 2^30 when vertices + 2 corners are below 2^28); smaller parts keep
// the adaptive models, whose few values cost less than tables.
constexpr size_t kRunTableFaces = 256;
RunCoding run_coding(const Mesh& part, const EncodeOptions& options) {
  const bool fits = part.vertex_count() + 2 * part.corner_count() < (size_t{1} << 28);
  return options.level <= kTableLevel && fits && part.face_count() >= kRunTableFaces ? RunCoding::tables
                                                                                     : RunCoding::adaptive;
}

// How a part's vertex trees are built (encode_part tries several).
struct TreeChoice {
  int root_rule = 0;      // CutHints::root_rule
  bool midpoint = false;  // the midpoint-distance Kruskal tree instead of the layered spiral
};

// The connectivity of a part with the given tree, then, when vertices on no
// triangle have a nearby surface vertex to predict them (their anchor), a
// second pass that orders them by it.
Status part_connectivity(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                         const EncodeOptions& options, TreeChoice tree, ConnectivityEncoding& ce, OwnView& view) {
  CutHints hints;
  hints.qpos = &qin;
  hints.root_rule = tree.root_rule;
  hints.midpoint_tree = tree.midpoint;
  hints.runs = run_coding(mesh, options);
  TSM_RETURN_IF_ERROR(encode_connectivity(mesh, ce, hints));
  view = own_view(ce, qin, is_ref);
  std::vector<uint32_t> anchor = find_anchors(view.layout, view.q, options.quantization_bits);
  if (std::any_of(anchor.begin(), anchor.end(), [](uint32_t x) { return x != kNone; })) {
    std::vector<uint32_t> own_to_output;
    for (uint32_t v = 0; v < view.mark.size(); ++v)
      if (view.mark[v] == kNone) own_to_output.push_back(v);
    std::vector<uint32_t> by_input(mesh.vertex_count(), kNone);
    for (size_t r = 0; r < anchor.size(); ++r)
      if (anchor[r] != kNone) by_input[ce.vertex_order[own_to_output[r]]] = own_to_output[anchor[r]];
    if (in_anchor_order(ce, by_input)) {
      // The cut would keep its order (a decoded mesh, in canonical rounds):
      // the second pass would code the same streams, so only hand the
      // anchors to the geometry coder.
      for (uint32_t v = 0; v < ce.layout.vertex_count; ++v) ce.layout.anchor[v] = by_input[ce.vertex_order[v]];
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

// Canonical re-encoding (issue 3): a decoded mesh must encode to the bytes
// it came from. The coder's choices follow vertex ids and face order, and
// the decoder's order reproduces them, except where vertices were split and
// stitched back: there the decoded order lets the cut find another copy of
// a split vertex first. So a part with stitches is coded as its decoded
// self would be: decode the streams, code that mesh, and repeat until
// decoding gives back the faces coded, corner for corner (the corpus's
// stitched meshes reach it after at most one round, the dragons included).
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
// faces' coding allows, at least 16 (the corpus's stitched meshes: 1).
int canonical_rounds(size_t faces) {
  return static_cast<int>(std::clamp<size_t>((size_t{1} << 20) / (faces + 1), 16, 256));
}

bool same_faces(const Mesh& a, const Mesh& b) { return a.indices == b.indices && a.face_offsets == b.face_offsets; }

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

Status canonical_connectivity(const Mesh& mesh, const std::vector<uint32_t>& qin, const std::vector<uint8_t>& is_ref,
                              const EncodeOptions& options, TreeChoice tree, ConnectivityEncoding& ce, OwnView& view) {
  const size_t n = mesh.vertex_count();
  std::vector<uint32_t> base;  // ids of the mesh `ce` codes -> the part's input ids (empty: the same)
  Mesh coded;                  // that mesh (faces only), once it is not `mesh`
  std::vector<uint32_t> q;
  std::vector<uint8_t> ref;
  // Codes a mesh whose ids are the part's input ids through `base`.
  auto code = [&](const Mesh& faces) -> Status {
    ce = ConnectivityEncoding();
    if (base.empty()) return part_connectivity(faces, qin, is_ref, options, tree, ce, view);
    q.resize(3 * n);
    for (size_t v = 0; v < n; ++v)
      for (int a = 0; a < 3; ++a) q[3 * v + a] = qin[3 * static_cast<size_t>(base[v]) + a];
    if (!is_ref.empty()) {
      ref.resize(n);
      for (size_t v = 0; v < n; ++v) ref[v] = is_ref[base[v]];
    }
    return part_connectivity(faces, q, is_ref.empty() ? is_ref : ref, options, tree, ce, view);
  };
  TSM_RETURN_IF_ERROR(code(mesh));
  if (tree.root_rule != 0) return Status::Ok();  // only tried on parts without stitches (encode_part)
  if (ce.stats.stitches == 0) return Status::Ok();
  // Per round r: the mesh it coded (round 0: `mesh`, not copied), its
  // streams and its base.
  std::vector<Mesh> coded_in;
  std::vector<CycleKey> key_of;
  std::vector<std::vector<uint32_t>> base_of;
  auto coded_by = [&](size_t r) -> const Mesh& { return r == 0 ? mesh : coded_in[r - 1]; };
  const int rounds = canonical_rounds(mesh.face_count());
  for (int round = 0; round < rounds; ++round) {
    Mesh decoded;
    GeometryLayout scratch;
    TSM_RETURN_IF_ERROR(decode_connectivity(ce.streams, n, mesh.face_count(), mesh.corner_count(), decoded, scratch));
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
    key_of.push_back(cycle_key(ce));
    base_of.push_back(base);
    // Back at a mesh coded in round i: the cycle is rounds i..round.
    size_t i = 0;
    while (i <= static_cast<size_t>(round) && !same_faces(decoded, coded_by(i))) ++i;
    if (i <= static_cast<size_t>(round)) {
      size_t best = i;
      for (size_t k = i + 1; k <= static_cast<size_t>(round); ++k)
        if (key_before(key_of[k], key_of[best])) best = k;
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
    TSM_RETURN_IF_ERROR(code(coded));
  }
  if (!base.empty())
    for (uint32_t& x : ce.vertex_order) x = base[x];  // back to the part's input ids
  return Status::Ok();
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
    GeometryLayout scratch;
    TSM_RETURN_IF_ERROR(decode_connectivity(ce.streams, mesh.vertex_count(), mesh.face_count(), mesh.corner_count(),
                                            out.faces, scratch));
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
                       const EncodeOptions& options, ContainerWriter& cw) {
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
  parallel_for(S, options.threads, [&](size_t k) {
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
  });
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
    TSM_RETURN_IF_ERROR(p.status);
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
  return Status::Ok();
}

}  // namespace

Status encode(const Mesh& mesh, const EncodeOptions& options, std::string& out) {
  std::string why;
  if (!mesh.valid(&why)) return Status(ErrorCode::invalid_argument, "mesh is invalid: " + why);
  if (options.quantization_bits < 1 || options.quantization_bits > 30)
    return Status(ErrorCode::invalid_argument,
                  "quantization bits must be 1..30, got " + std::to_string(options.quantization_bits));
  if (options.level < 0 || options.level > 9)
    return Status(ErrorCode::invalid_argument, "level must be 0..9, got " + std::to_string(options.level));
  if (!mesh.all_finite())
    return Status(ErrorCode::invalid_argument,
                  "mesh has NaN or infinite coordinates, which no quantization grid can hold; fix or drop those "
                  "vertices first");

  Header h;
  h.version = kFormatVersion;
  h.vertex_count = mesh.vertex_count();
  h.face_count = mesh.face_count();
  h.corner_count = mesh.corner_count();
  h.quantization_bits = static_cast<uint8_t>(options.quantization_bits);
  h.level = static_cast<uint8_t>(options.level);
  BoundingBox box = bounding_box(mesh);
  for (int a = 0; a < 3; ++a) h.origin[a] = box.min[a];
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
  ContainerWriter cw(h);
  // Metadata first, so that a streaming client has it before any geometry.
  if (!mesh.metadata.empty()) {
    const std::string md = write_metadata(mesh.metadata);
    cw.add_section(kSectionMetadata, md, md.size() > (1u << 20) ? 3 : 9);
  }
  if (segments.size() == 1) {
    EncodedPart p;
    TSM_RETURN_IF_ERROR(encode_part(mesh, qin, {}, headers, options, p));
    MeshPayload mp{p.streams.vertex_tree, p.streams.triangle_tree, p.streams.topology, p.geometry, p.attributes};
    cw.add_section(kSectionMesh, write_mesh_payload(mp), 0);
  } else {
    TSM_RETURN_IF_ERROR(encode_segments(mesh, qin, segments, headers, options, cw));
  }
  out = cw.finish();
  return Status::Ok();
}

Status decode(std::string_view bytes, Mesh& out, const DecodeOptions& options) {
  out.clear();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections));
  TSM_RETURN_IF_ERROR(check_user_limits(h, options));
  std::vector<DecodedPart> parts;
  std::vector<PartStreams> streams;
  TSM_RETURN_IF_ERROR(decode_parts(h, sections, options.threads, parts, streams));
  if (parts.size() > 1) out.reserve(h.vertex_count, h.face_count, h.corner_count);
  for (size_t k = 0; k < parts.size(); ++k) TSM_RETURN_IF_ERROR(append_part(h, parts[k], out, k == 0));
  if (const Section* md = find_section(sections, kSectionMetadata)) TSM_RETURN_IF_ERROR(read_metadata(md->data, out.metadata));
  return Status::Ok();
}

Status inspect(std::string_view bytes, FileInfo& info) {
  info = FileInfo();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections));
  info.format_version = h.version;
  info.vertex_count = h.vertex_count;
  info.face_count = h.face_count;
  info.corner_count = h.corner_count;
  info.quantization_bits = h.quantization_bits;
  info.level = h.level;
  info.segment_count = h.segment_count;
  for (int a = 0; a < 3; ++a) info.bbox_min[a] = h.origin[a];
  info.step = grid_step(h);
  info.file_bytes = bytes.size();
  for (const Section& s : sections) {
    SectionInfo si;
    si.id = s.id;
    si.name = section_name(s.id);
    si.codec = s.codec == SectionCodec::zstd ? "zstd" : "raw";
    si.stored_bytes = s.stored_bytes;
    si.raw_bytes = s.raw_bytes;
    info.sections.push_back(si);
  }
  std::vector<DecodedPart> parts;
  std::vector<PartStreams> streams;
  TSM_RETURN_IF_ERROR(decode_parts(h, sections, 1, parts, streams));
  for (size_t k = 0; k < parts.size(); ++k) {
    const PartStreams& s = streams[k];
    info.connectivity_bytes += s.vertex_tree.size() + s.triangle_tree.size() + s.topology.size();
    info.geometry_bytes += s.geometry.size();
    info.reference_bytes += s.references.size();
    const ConnectivityStats& st = parts[k].cstats;
    info.components += st.components;
    info.vertex_runs += st.vertex_runs;
    info.triangle_runs += st.triangle_runs;
    info.jump_edges += st.jump_edges;
    info.stitches += st.stitches;
    info.virtual_vertices += st.virtual_vertices;
    info.side_faces += st.side_faces;
    info.marching_bits += st.marching_bits;
    info.run_table_parts += st.run_tables;
    info.table_coded_attributes += parts[k].table_coded_attributes;
    info.references += parts[k].counts.reference_count;
    SegmentSummary sum;
    sum.vertices = parts[k].counts.vertex_count;
    sum.references = parts[k].counts.reference_count;
    sum.faces = parts[k].counts.face_count;
    info.segments.push_back(sum);
  }
  info.other_bytes = bytes.size() - info.connectivity_bytes - info.geometry_bytes;
  // The first segment's predictor stands for the file (each segment chooses its own).
  const GeometryStats& gs = parts[0].gstats;
  info.geometry_predictor = gs.predictor == Predictor::ancestors ? "ancestors"
                            : gs.predictor == Predictor::gate    ? "gate"
                            : gs.predictor == Predictor::spread  ? "spread"
                            : gs.predictor == Predictor::fan     ? "fan"
                            : gs.predictor == Predictor::raw     ? "raw"
                                                                 : "parallelograms";
  if (gs.tangent) info.geometry_predictor += "+tangent";
  if (gs.mix) info.geometry_predictor += "+mix";
  if (gs.top) info.geometry_predictor += "+top";
  if (gs.tables) info.geometry_predictor += "+tables";
  info.ancestors = gs.ancestors;
  for (int a = 0; a < 3; ++a) info.lattice_planes[a] = gs.lattice_planes[a];
  return Status::Ok();
}

// Streaming: sections are read as their bytes arrive; a segment is decoded
// as soon as its section is complete (a file of one segment at its end).
struct StreamDecoder::Impl {
  DecodeOptions options;
  std::string buf;      // bytes received and not yet consumed
  size_t base = 0;      // file offset of buf[0]
  bool have_header = false, ended = false;
  Header h;
  SectionRules rules;
  std::vector<Section> whole;  // a one-segment file's sections, until the end marker
  Mesh mesh;
  uint32_t done = 0;
  uint64_t faces = 0, corners = 0;
  Status failed;

  Status part_done(DecodedPart& part, const PartStreams& s) {
    TSM_RETURN_IF_ERROR(decode_part(s, mesh.vertex_count(), h.quantization_bits, part));
    TSM_RETURN_IF_ERROR(append_part(h, part, mesh, done == 0));
    ++done;
    return Status::Ok();
  }

  Status segment(const Section& sec) {
    PartStreams s;
    DecodedPart part;
    TSM_RETURN_IF_ERROR(read_part(sec, s, part.counts));
    const PartCounts& p = part.counts;
    // Against the header before anything is allocated: the header's counts
    // passed the caller's limits.
    const uint64_t own = p.vertex_count - std::min(p.reference_count, p.vertex_count);
    if (mesh.vertex_count() + own > h.vertex_count || faces + p.face_count > h.face_count ||
        corners + p.corner_count > h.corner_count)
      return corrupt("segment " + std::to_string(done) + " holds more vertices, faces or corners than the header");
    faces += p.face_count;
    corners += p.corner_count;
    Status st = part_done(part, s);
    if (!st.ok()) return Status(st.code(), "segment " + std::to_string(done) + ": " + st.message());
    return Status::Ok();
  }

  Status end() {
    ended = true;
    if (h.segment_count == 1) {
      std::vector<DecodedPart> parts;
      std::vector<PartStreams> streams;
      TSM_RETURN_IF_ERROR(collect_parts(h, whole, streams, parts));
      TSM_RETURN_IF_ERROR(part_done(parts[0], streams[0]));
      whole.clear();
      return Status::Ok();
    }
    if (done != h.segment_count)
      return corrupt("the header announces " + std::to_string(h.segment_count) + " segments, the file holds " +
                     std::to_string(done));
    if (mesh.vertex_count() != h.vertex_count || faces != h.face_count || corners != h.corner_count)
      return corrupt("the segments' vertex, face or corner counts do not add up to the header's");
    return Status::Ok();
  }

  Status feed(std::string_view bytes) {
    if (ended && !bytes.empty())
      return corrupt(std::to_string(bytes.size()) + " unexpected bytes after the end marker");
    buf.append(bytes.data(), bytes.size());
    size_t pos = 0;
    std::string missing;
    if (!have_header) {
      TSM_RETURN_IF_ERROR(read_header(buf, pos, h, missing));
      if (!missing.empty()) return Status::Ok();
      TSM_RETURN_IF_ERROR(check_user_limits(h, options));
      have_header = true;
    }
    while (!ended) {
      Section s;
      TSM_RETURN_IF_ERROR(read_section(buf, pos, s, true, missing, base));
      if (!missing.empty()) break;
      if (s.id == kSectionEnd) {
        if (pos != buf.size())
          return corrupt(std::to_string(buf.size() - pos) + " unexpected bytes after the end marker");
        TSM_RETURN_IF_ERROR(end());
        break;
      }
      TSM_RETURN_IF_ERROR(rules.admit(s, h));
      if (s.id == kSectionMetadata)
        TSM_RETURN_IF_ERROR(read_metadata(s.data, mesh.metadata));
      else if (s.id == kSectionSegment)
        TSM_RETURN_IF_ERROR(segment(s));
      else if (h.segment_count == 1)
        whole.push_back(std::move(s));
    }
    buf.erase(0, pos);
    base += pos;
    return Status::Ok();
  }
};

StreamDecoder::StreamDecoder(const DecodeOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
}
StreamDecoder::~StreamDecoder() = default;

Status StreamDecoder::feed(std::string_view bytes) {
  if (!impl_->failed.ok()) return impl_->failed;
  Status s = impl_->feed(bytes);
  if (!s.ok()) impl_->failed = s;
  return s;
}

Status StreamDecoder::finish() {
  if (!impl_->failed.ok()) return impl_->failed;
  if (impl_->ended) return Status::Ok();
  std::string missing;
  if (!impl_->have_header) {
    size_t pos = 0;
    Header h;
    Status s = read_header(impl_->buf, pos, h, missing);
    impl_->failed = s.ok() ? corrupt(missing.empty() ? "file ends inside the header" : missing) : s;
  } else {
    size_t pos = 0;
    Section s;
    Status st = read_section(impl_->buf, pos, s, false, missing, impl_->base);
    impl_->failed = st.ok() ? corrupt(missing.empty() ? "file ends before the end marker" : missing) : st;
  }
  return impl_->failed;
}

uint32_t StreamDecoder::segment_count() const { return impl_->have_header ? impl_->h.segment_count : 0; }
uint32_t StreamDecoder::segments_done() const { return impl_->done; }
bool StreamDecoder::done() const { return impl_->ended && impl_->failed.ok(); }
const Mesh& StreamDecoder::mesh() const { return impl_->mesh; }
Mesh StreamDecoder::take_mesh() { return std::move(impl_->mesh); }

}  // namespace tsm
