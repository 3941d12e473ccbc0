// Decoding (seed 004 §3-4 reversed; FORMAT.md §9): the decoder's entry
// points: read the container, decode each part's connectivity, geometry
// and attributes (the segments of a file in parallel, or one by one as
// their bytes arrive, StreamDecoder), put the grid indices back on the
// grid (FORMAT.md §5) and join the parts into one mesh; and inspect(), which
// decodes for the figures of `tsm info`.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "attributes.hpp"
#include "byte_io.hpp"
#include "codec_shared.hpp"
#include "connectivity.hpp"
#include "container.hpp"
#include "exact_grid.hpp"
#include "geometry_predict.hpp"
#include "order_coding.hpp"
#include "parallel.hpp"
#include "progressive.hpp"
#include "progressive_decode.hpp"
#include "range_coder.hpp"
#include "segments.hpp"
#include "split_layout.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

const char* version_string() { return TSM_VERSION; }

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

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
// stream (a marching bit or a run's end), every side face at least 1 in the
// topology stream (a face on an edge: its end bit, for 3 corners; a verbatim
// one at least 6 per corner): counts beyond that are forged, refused before
// allocating.
uint64_t decisions(std::string_view stream) { return max_decisions(stream.size()); }

Status check_budget(const PartCounts& c, const PartStreams& s) {
  if (c.vertex_count >= 0x3FFFFFFFu || c.corner_count >= 0x3FFFFFFFu || c.face_count > c.corner_count)
    return corrupt("vertex, face or corner count out of range");
  if (c.reference_count > c.vertex_count) return corrupt("more references than vertices");
  // Welded (§8.13): the geometry codes the points; every vertex beyond its
  // point's first costs a decision of the split stream, in the attributes.
  const bool welded = !s.topology.empty() && (static_cast<uint8_t>(s.topology[0]) & 2) != 0;
  const uint64_t split = welded ? decisions(s.attributes) : 0;
  if (c.vertex_count - c.reference_count > decisions(s.geometry) / 3 + split)
    return corrupt("the header's " + std::to_string(c.vertex_count - c.reference_count) +
                   " vertices cannot be coded in a geometry section of this size");
  if (s.segmented && c.vertex_count > decisions(s.references))
    return corrupt("the segment's " + std::to_string(c.vertex_count) +
                   " vertices cannot be flagged in a references stream of this size");
  if (c.corner_count > 3 * decisions(s.triangle_tree) + 3 * decisions(s.topology))
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
  std::vector<AttributeCost> attribute_costs;  // filled for inspect() only
  std::vector<uint32_t> split_q, split_corners;  // welded: per output vertex, per corner (walk ids)
  uint64_t per_vertex = 0;                       // bit i: corner attribute i coded per vertex (§8.12)
  std::vector<uint32_t> split_point;             // points out (§8.13): per output vertex, its point
  std::vector<uint32_t> point_q;                 // points out: the points' grid indices
  std::string_view rank_stream;                  // points out: the ranks (empty: all 0)
  uint64_t merged_vertices = 0;                  // points out: split vertices less output vertices
  bool want_costs = false;
  Status status;
};

// FORMAT.md §8.13: a welded part's attribute payload opens with the split
// stream (its length first) and the order byte. The split stream turns the
// faces' points into walk vertices; the attributes are decoded on the
// originals (`list`: walk vertices that copy no other, in walk order or in
// output order), the corners naming their vertices' originals.
Status split_welded(std::string_view& attributes, uint64_t vertex_count, uint32_t points, DecodedPart& out,
                    std::vector<uint32_t>& walk_out, std::vector<uint32_t>& walk_orig, std::vector<uint32_t>& list) {
  ByteReader r(attributes);
  uint64_t len = 0;
  std::string_view split;
  if (!r.varint(len) || len > r.remaining() || !r.bytes(static_cast<size_t>(len), split))
    return corrupt("a welded part's split stream is cut off");
  uint8_t order = 0;
  if (!r.u8(order) || order > 7 || order == 4 || order == 5)
    return corrupt("a welded part's attribute order byte is missing, above 7, or says ranks without points out");
  if ((order & 4) &&
      (!r.varint(len) || len == 0 || len > r.remaining() || !r.bytes(static_cast<size_t>(len), out.rank_stream)))
    return corrupt("a points-out part's rank stream is empty or cut off");
  attributes = attributes.substr(r.offset());
  std::vector<uint32_t> walk_point;
  std::vector<uint32_t> point_q = std::move(out.q);
  TSM_RETURN_IF_ERROR(
      decode_split_layout(split, vertex_count, points, point_q, out.faces, walk_out, walk_point, walk_orig));
  const size_t n = walk_out.size();
  list.clear();
  for (uint32_t w = 0; w < n; ++w)
    if (walk_orig[w] == w) list.push_back(w);
  if (order & 1) std::sort(list.begin(), list.end(), [&](uint32_t x, uint32_t y) { return walk_out[x] < walk_out[y]; });
  std::vector<uint32_t> rank(n, kNone);
  for (uint32_t k = 0; k < list.size(); ++k) rank[list[k]] = k;
  // The faces on the originals for the attributes; the positions per output vertex.
  std::vector<uint32_t> corner_walk = out.faces.indices;
  for (uint32_t& x : out.faces.indices) x = rank[walk_orig[x]];
  out.q.assign(3 * list.size(), 0);
  for (size_t k = 0; k < list.size(); ++k)
    for (int a = 0; a < 3; ++a) out.q[3 * k + a] = point_q[3 * size_t{walk_point[list[k]]} + a];
  out.split_q.assign(3 * n, 0);
  for (size_t w = 0; w < n; ++w)
    for (int a = 0; a < 3; ++a) out.split_q[3 * size_t{walk_out[w]} + a] = point_q[3 * size_t{walk_point[w]} + a];
  out.split_corners = std::move(corner_walk);
  out.global.assign(list.size(), kNone);  // the attributes' vertices
  if (order & 2) {
    out.split_point.assign(n, 0);
    for (size_t w = 0; w < n; ++w) out.split_point[walk_out[w]] = walk_point[w];
    out.point_q = std::move(point_q);
  }
  return Status::Ok();
}

// FORMAT.md §8.13, points out: the ranks. Per output vertex whose point
// has more than one output vertex, its rank among the input vertices at
// that point (in a model chosen by its neighbours' ranks decoded so far); then per corner attribute coded per vertex, per output vertex
// whose value (binary32 bits) is shared by another, its rank among the
// input values equal to it. Each rank is below the count sharing it.
Status decode_ranks(const DecodedPart& out, std::vector<uint32_t>& point_rank,
                    std::vector<std::vector<uint32_t>>& value_rank) {
  const std::vector<uint32_t>& point = out.split_point;
  const size_t np = out.point_q.size() / 3, n = point.size();
  point_rank.assign(n, 0);
  value_rank.assign(out.faces.attributes.size(), std::vector<uint32_t>());
  if (out.rank_stream.empty()) return Status::Ok();
  RangeDecoder d(out.rank_stream);
  UIntModel point_model[3], value_model;
  std::vector<uint32_t> share(np, 0);
  for (uint32_t p : point) ++share[p];
  const RankNeighbours neighbours = rank_neighbours(out.faces, n);
  std::vector<uint32_t> coded(n, kNone);
  for (size_t o = 0; o < n; ++o) {
    if (share[point[o]] < 2) continue;
    point_rank[o] = point_model[neighbours_say(neighbours, static_cast<uint32_t>(o), coded)].decode(d);
    if (point_rank[o] >= share[point[o]]) return corrupt("a points-out rank is not below its point's vertex count");
    coded[o] = point_rank[o];
  }
  for (size_t i = 0; i < out.faces.attributes.size(); ++i) {
    const Attribute& at = out.faces.attributes[i];
    const size_t k = at.components;
    if (at.domain != AttributeDomain::corner || !(out.per_vertex >> i & 1) || at.values.size() != k * n) continue;
    std::map<std::vector<uint32_t>, uint32_t> count;
    std::vector<std::vector<uint32_t>> bits(n, std::vector<uint32_t>(k));
    for (size_t o = 0; o < n; ++o) {
      std::memcpy(bits[o].data(), &at.values[k * o], 4 * k);
      ++count[bits[o]];
    }
    value_rank[i].assign(n, 0);
    for (size_t o = 0; o < n; ++o) {
      const uint32_t c = count[bits[o]];
      if (c < 2) continue;
      value_rank[i][o] = value_model.decode(d);
      if (value_rank[i][o] >= c) return corrupt("a points-out value rank is not below its value's count");
    }
  }
  if (d.overrun() > RangeDecoder::kMaxOverrun) return corrupt("a points-out rank stream is cut off");
  return Status::Ok();
}

// FORMAT.md §8.13, points out: a corner attribute's value list from its
// values per output vertex (`rank`: per output vertex, empty when all 0).
// The corners in order: a value (binary32 bits) not listed yet is listed
// with every rank the output vertices give it, ranks ascending; each corner
// uses the entry of its vertex's (value, rank).
void rebuild_value_list(Attribute& at, const std::vector<uint32_t>& rank) {
  const size_t k = at.components, n = at.values.size() / k;
  std::map<std::vector<uint32_t>, std::vector<uint32_t>> ranks;  // per value: its ranks, ascending, unique
  std::vector<std::vector<uint32_t>> bits(n, std::vector<uint32_t>(k));
  for (size_t o = 0; o < n; ++o) {
    std::memcpy(bits[o].data(), &at.values[k * o], 4 * k);
    ranks[bits[o]].push_back(rank.empty() ? 0 : rank[o]);
  }
  for (auto& [value, list] : ranks) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  std::map<std::vector<uint32_t>, uint32_t> base;  // per listed value: the entry of its lowest rank
  std::vector<float> values;
  for (uint32_t& x : at.indices) {
    const std::vector<uint32_t>& list = ranks[bits[x]];
    auto it = base.find(bits[x]);
    if (it == base.end()) {
      it = base.emplace(bits[x], static_cast<uint32_t>(values.size() / k)).first;
      for (size_t j = 0; j < list.size(); ++j)
        values.insert(values.end(), at.values.begin() + static_cast<std::ptrdiff_t>(k * x),
                      at.values.begin() + static_cast<std::ptrdiff_t>(k * (x + 1)));
    }
    const uint32_t r = rank.empty() ? 0 : rank[x];
    x = it->second + static_cast<uint32_t>(std::lower_bound(list.begin(), list.end(), r) - list.begin());
  }
  at.values = std::move(values);
}

// FORMAT.md §8.13, points out: one output vertex per (point, rank), in
// that order (the split vertices were the corners' value combinations of
// an indexed mesh). A vertex attribute takes the value of the vertex's
// first split vertex; a corner attribute coded per vertex gets its value
// list back: the distinct (value as float bits, rank) in the order the
// corners first use them.
Status points_out(DecodedPart& out) {
  std::vector<uint32_t> point_rank;
  std::vector<std::vector<uint32_t>> value_rank;
  TSM_RETURN_IF_ERROR(decode_ranks(out, point_rank, value_rank));
  const std::vector<uint32_t>& point = out.split_point;
  const size_t n = point.size();
  std::vector<uint64_t> keys(n);
  for (size_t o = 0; o < n; ++o) keys[o] = uint64_t{point[o]} << 32 | point_rank[o];
  std::vector<uint64_t> sorted = keys;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  const size_t nv = sorted.size();
  std::vector<uint32_t> vid(n), first(nv, kNone);
  for (uint32_t o = 0; o < n; ++o) {
    vid[o] = static_cast<uint32_t>(std::lower_bound(sorted.begin(), sorted.end(), keys[o]) - sorted.begin());
    if (first[vid[o]] == kNone) first[vid[o]] = o;
  }
  for (size_t i = 0; i < out.faces.attributes.size(); ++i) {
    Attribute& at = out.faces.attributes[i];
    const size_t k = at.components;
    if (at.values.size() != k * n) continue;
    if (at.domain == AttributeDomain::vertex) {
      std::vector<float> values(k * nv);
      for (size_t v = 0; v < nv; ++v)
        std::copy_n(at.values.begin() + static_cast<std::ptrdiff_t>(first[v] * k), k,
                    values.begin() + static_cast<std::ptrdiff_t>(v * k));
      at.values = std::move(values);
    } else if (out.per_vertex >> i & 1) {
      rebuild_value_list(at, value_rank[i]);
    }
  }
  for (uint32_t& x : out.faces.indices) x = vid[x];
  out.q.assign(3 * nv, 0);
  for (size_t v = 0; v < nv; ++v)
    for (int a = 0; a < 3; ++a) out.q[3 * v + a] = out.point_q[3 * size_t{point[first[v]]} + a];
  out.point_q = std::vector<uint32_t>();
  out.global.assign(nv, kNone);
  out.split_point = std::vector<uint32_t>();
  out.merged_vertices = n - nv;
  return Status::Ok();
}

// After a welded part's attributes: the output vertices (positions, the
// faces' corners, every vertex attribute's values from its original's, a
// corner attribute coded per vertex likewise, each corner using its vertex's).
void to_output(const std::vector<uint32_t>& walk_out, const std::vector<uint32_t>& walk_orig,
               const std::vector<uint32_t>& list, DecodedPart& out) {
  const size_t n = walk_out.size();
  std::vector<uint32_t> rank(n, kNone);
  for (uint32_t k = 0; k < list.size(); ++k) rank[list[k]] = k;
  out.q = std::move(out.split_q);
  out.global.assign(n, kNone);
  out.faces.indices = std::move(out.split_corners);
  for (uint32_t& x : out.faces.indices) x = walk_out[x];
  for (size_t i = 0; i < out.faces.attributes.size(); ++i) {
    Attribute& at = out.faces.attributes[i];
    const bool per_vertex = out.per_vertex >> i & 1;
    if (per_vertex) at.indices = out.faces.indices;
    if (at.domain != AttributeDomain::vertex && !per_vertex) continue;
    const size_t k = at.components;
    if (at.values.size() != k * list.size()) continue;
    std::vector<float> values(k * n);
    for (size_t w = 0; w < n; ++w) {
      const size_t from = rank[walk_orig[w]];
      std::copy(at.values.begin() + static_cast<std::ptrdiff_t>(from * k),
                at.values.begin() + static_cast<std::ptrdiff_t>((from + 1) * k),
                values.begin() + static_cast<std::ptrdiff_t>(walk_out[w] * k));
    }
    at.values = std::move(values);
  }
}

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
  std::string_view attributes = s.attributes;
  std::vector<uint32_t> walk_out, walk_orig, list;  // welded: per walk vertex its output id and original
  if (out.cstats.welded && s.segmented) return corrupt("a segment's topology mode says welded (§8.13)");
  if (!s.segmented) {
    if (!s.attributes.empty()) out.global.assign(c.vertex_count, kNone);  // only attributes look (all own)
    TSM_RETURN_IF_ERROR(decode_geometry(s.geometry, layout, bits, out.q, &out.gstats));
    if (out.cstats.welded)
      TSM_RETURN_IF_ERROR(split_welded(attributes, c.vertex_count, layout.vertex_count, out, walk_out, walk_orig, list));
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
  if (out.want_costs) ap.costs = &out.attribute_costs;
  ap.per_vertex = &out.per_vertex;
  TSM_RETURN_IF_ERROR(decode_attributes(attributes, ap, out.faces.attributes, &out.alias));
  if (out.cstats.welded) to_output(walk_out, walk_orig, list, out);
  if (!out.split_point.empty()) TSM_RETURN_IF_ERROR(points_out(out));
  return Status::Ok();
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

// A grid index as a coordinate on the Draco grid: origin o, step, the
// header's extent (grid_value below; append_part's loop calls it inline).
inline float draco_grid_value(double o, double step, double extent, uint32_t q) {
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  double x = o + static_cast<double>(q) * step;
  // A grid point may lie up to half a step past the largest input
  // coordinate; near the float limit, clamp (the input was within range).
  x = x > kFloatMax ? kFloatMax : x < -kFloatMax ? -kFloatMax : x;
  float c = static_cast<float>(x);
  // On an axis shorter than the extent, the float nearest a grid point may
  // lie just past origin + extent; then the float below it, so that the
  // decoded mesh has the extent it was coded with and coding it again
  // takes the same grid (canonical re-encoding).
  while (static_cast<double>(c) - o > extent) c = std::nextafter(c, -std::numeric_limits<float>::infinity());
  return c;
}

}  // namespace

// A grid index as a coordinate (FORMAT.md §5).
float grid_value(const Header& h, double step, int axis, uint32_t q) {
  if (h.flags & kHeaderExactGrid) return exact_value(h.exact_step, h.exact_base[axis], q);  // §5.1
  return draco_grid_value(static_cast<double>(h.origin[axis]), step, h.extent, q);
}

namespace {

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
  const size_t nv = part.q.size() / 3;
  if (h.flags & kHeaderExactGrid) {
    for (size_t v = 0; v < nv; ++v, q += 3, pos += 3)
      for (int axis = 0; axis < 3; ++axis) pos[axis] = grid_value(h, step, axis, q[axis]);
  } else {
    const double o[3] = {h.origin[0], h.origin[1], h.origin[2]};
    for (size_t v = 0; v < nv; ++v, q += 3, pos += 3)
      for (int axis = 0; axis < 3; ++axis) pos[axis] = draco_grid_value(o[axis], step, h.extent, q[axis]);
  }
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
                    std::vector<PartStreams>& streams, bool attribute_costs = false) {
  TSM_RETURN_IF_ERROR(collect_parts(h, sections, streams, parts));
  for (DecodedPart& p : parts) p.want_costs = attribute_costs;
  std::vector<uint64_t> earlier(parts.size(), 0);
  for (size_t k = 1; k < parts.size(); ++k)
    earlier[k] = earlier[k - 1] + parts[k - 1].counts.vertex_count - parts[k - 1].counts.reference_count;
  size_t failed = 0;
  const Status threw = parallel_for(
      parts.size(), threads,
      [&](size_t k) { parts[k].status = decode_part(streams[k], earlier[k], h.quantization_bits, parts[k]); },
      &failed);
  if (!threw.ok()) parts[failed].status = threw;
  for (size_t k = 0; k < parts.size(); ++k)
    if (!parts[k].status.ok())
      return parts.size() == 1 ? parts[k].status
                               : Status(parts[k].status.code(),
                                        "segment " + std::to_string(k) + ": " + parts[k].status.message());
  return Status::Ok();
}

}  // namespace

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
  const Section* ex = find_section(sections, kSectionExceptions);
  if (ex && (h.flags & kHeaderExactGrid)) TSM_RETURN_IF_ERROR(apply_exceptions(ex->data, out.positions));
  if (const Section* order = find_section(sections, kSectionOrder)) TSM_RETURN_IF_ERROR(decode_order(order->data, out));
  return apply_refinements(h, sections, out, options);
}

namespace {

// Sums one part's attribute costs into the file's list (every part codes the
// same attributes in the same order; a part without attributes adds none).
void add_attribute_costs(const std::vector<AttributeCost>& costs, std::vector<AttributeInfo>& out) {
  static const char* const kCodings[3] = {"exact", "grid", "octahedral"};
  for (size_t i = 0; i < costs.size(); ++i) {
    const AttributeHeader& h = costs[i].header;
    if (i == out.size()) {
      AttributeInfo a;
      a.name = h.name;
      a.kind = h.kind;
      a.domain = h.domain;
      a.type = h.type;
      a.components = h.components;
      a.coding = kCodings[static_cast<size_t>(h.quant) % 3];
      a.bits = h.quant == AttributeQuant::exact ? 0 : h.bits;
      out.push_back(a);
    }
    out[i].tables = out[i].tables || costs[i].tables;
    out[i].coded_bytes += (costs[i].coded_bits + 7) / 8;
  }
}

}  // namespace

namespace {

// A progressive file's batches (FORMAT.md §4.8): their headers (the
// counts follow from the split counts; decode() checks the splits).
Status inspect_batches(const Header& h, const std::vector<Section>& sections, FileInfo& info) {
  uint64_t vertices = h.vertex_count, faces = h.face_count;
  for (const Section& s : sections) {
    if (s.id == kSectionLoose) {
      ByteReader r(s.data);
      if (!r.varint(info.loose_vertices) || !r.varint(info.loose_faces)) return corrupt("loose section: truncated");
    }
    if (s.id != kSectionRefinement) continue;
    BatchHeader bh;
    std::string_view stream;
    TSM_RETURN_IF_ERROR(read_batch(s.data, bh, stream));
    if (info.batches.empty()) info.base_error = bh.error_before;
    vertices += bh.splits;
    faces += 2 * bh.splits - bh.border;
    FileInfo::Batch b;
    b.bytes = section_framing_bytes(s) + s.stored_bytes;
    b.vertices = vertices;
    b.faces = faces;
    b.error = bh.error_after;
    info.batches.push_back(b);
  }
  return Status::Ok();
}

}  // namespace

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
  info.step = (h.flags & kHeaderExactGrid) ? h.exact_step : grid_step(h);
  info.file_bytes = bytes.size();
  info.lossless = (h.flags & kHeaderExactGrid) != 0;
  for (const Section& s : sections) {
    if (s.id == kSectionOrder) info.keep_order = true;
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
  TSM_RETURN_IF_ERROR(decode_parts(h, sections, 1, parts, streams, true));
  for (size_t k = 0; k < parts.size(); ++k) {
    const PartStreams& s = streams[k];
    info.attribute_bytes += s.attributes.size();
    add_attribute_costs(parts[k].attribute_costs, info.attributes);
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
    info.welded_points += st.points;
    info.table_coded_attributes += parts[k].table_coded_attributes;
    info.references += parts[k].counts.reference_count;
    // A points-out part (§8.13): the header counts its split vertices.
    info.vertex_count -= parts[k].merged_vertices;
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
  return inspect_batches(h, sections, info);
}

// Streaming: sections are read as their bytes arrive; a segment is decoded
// as soon as its section is complete (a file of one segment at its end).
struct StreamDecoder::Impl {
  DecodeOptions options;
  std::string buf;      // bytes received and not yet consumed
  size_t base = 0;      // file offset of buf[0]
  bool have_header = false, ended = false;
  std::string head;     // preamble and header, until the first section (its checksum covers them) is in
  Header h;
  SectionRules rules;
  std::vector<Section> whole;  // a one-segment file's sections, until the end marker
  Section order;               // the order section (id 0: none), applied at the end
  Section exceptions;          // the exceptions section (id 0: none), applied at the end
  Mesh mesh;
  uint32_t done = 0;
  uint64_t faces = 0, corners = 0;
  LevelMesh level;      // progressive files: the level the batches refine
  uint32_t batches = 0;
  bool base_ready = false;  // the base mesh is whole (progressive files, before the end marker)
  double error = -1;        // the current level's error (model units), -1 unknown
  bool stop_levels = false, pending = false;
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

  // The base mesh is whole: a file of one segment decodes its sections
  // now; a file of several checks the segments' sums.
  Status base_done() {
    if (h.segment_count == 1) {
      std::vector<DecodedPart> parts;
      std::vector<PartStreams> streams;
      TSM_RETURN_IF_ERROR(collect_parts(h, whole, streams, parts));
      TSM_RETURN_IF_ERROR(part_done(parts[0], streams[0]));
      whole.clear();
    } else {
      if (done != h.segment_count)
        return corrupt("the header announces " + std::to_string(h.segment_count) + " segments, the file holds " +
                       std::to_string(done));
      if (mesh.vertex_count() != h.vertex_count || faces != h.face_count || corners != h.corner_count)
        return corrupt("the segments' vertex, face or corner counts do not add up to the header's");
    }
    // A lossless file's exact coordinates and a keep-order file's order, once the mesh is whole.
    if (exceptions.id == kSectionExceptions && (h.flags & kHeaderExactGrid)) TSM_RETURN_IF_ERROR(apply_exceptions(exceptions.data, mesh.positions));
    return order.id == kSectionOrder ? decode_order(order.data, mesh) : Status::Ok();
  }

  Status end() {
    ended = true;
    return base_ready ? Status::Ok() : base_done();
  }

  // The base mesh of a progressive file is whole: it is the first level.
  // Its error is the next batch's error_before, known when that batch's
  // bytes are in already.
  Status base_level(size_t pos) {
    TSM_RETURN_IF_ERROR(base_done());
    level.init(mesh, h);
    base_ready = true;
    Section s;
    std::string missing;
    TSM_RETURN_IF_ERROR(read_section(buf, pos, s, true, missing, base));
    BatchHeader bh;
    std::string_view stream;
    if (missing.empty() && read_batch(s.data, bh, stream).ok()) error = bh.error_before;
    return Status::Ok();
  }

  // A progressive file's batch of vertex splits (FORMAT.md §4.8), applied
  // at once: mesh() is the next level of detail.
  Status refinement(const Section& s) {
    if (!base_ready) TSM_RETURN_IF_ERROR(base_level(buf.size()));
    BatchHeader bh;
    std::string_view stream;
    TSM_RETURN_IF_ERROR(read_batch(s.data, bh, stream));
    Status st = decode_batch(s.data, level, BatchLimits{options.max_vertices, options.max_faces});
    if (!st.ok()) return Status(st.code(), "batch " + std::to_string(batches) + ": " + st.message());
    ++batches;
    error = bh.error_after;
    return Status::Ok();
  }

  // The next section's id, when its first bytes are in (0 otherwise).
  uint16_t next_id(size_t pos) const {
    ByteReader r(std::string_view(buf).substr(std::min(pos, buf.size())));
    uint64_t tag = 0;
    return r.varint(tag) && tag >> 1 <= 0xffff ? static_cast<uint16_t>(tag >> 1) : 0;
  }

  // The base is shown as soon as it is whole and a refinement section
  // begins, before that section's bytes are all in.
  bool base_now_whole(size_t pos) const {
    const bool segments_in =
        h.segment_count == 1
            ? std::any_of(whole.begin(), whole.end(), [](const Section& w) { return w.id == kSectionMesh; })
            : done == h.segment_count;
    return !base_ready && segments_in && next_id(pos) == kSectionRefinement;
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
      // The caller's limits apply at once; the header's checksum comes
      // with the first section.
      TSM_RETURN_IF_ERROR(check_user_limits(h, options));
      head = buf.substr(0, pos);
      have_header = true;
    }
    pending = false;
    while (!ended) {
      if (base_now_whole(pos)) {
        TSM_RETURN_IF_ERROR(base_level(pos));
        if (stop_levels) {
          pending = pos < buf.size();
          break;
        }
      }
      Section s;
      TSM_RETURN_IF_ERROR(read_section(buf, pos, s, true, missing, base, head));
      if (!missing.empty()) break;
      head.clear();  // the first section's checksum has verified the header
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
      else if (s.id == kSectionRefinement) {
        TSM_RETURN_IF_ERROR(refinement(s));
        if (stop_levels) {
          pending = pos < buf.size();
          break;
        }
      } else if (s.id == kSectionLoose && batches > 0)
        TSM_RETURN_IF_ERROR(decode_loose(s.data, level, BatchLimits{options.max_vertices, options.max_faces}));
      else if (s.id == kSectionOrder)
        order = std::move(s);
      else if (s.id == kSectionExceptions)
        exceptions = std::move(s);
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
  while (impl_->pending && !impl_->ended) TSM_RETURN_IF_ERROR(feed({}));
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
    Status st = read_section(impl_->buf, pos, s, false, missing, impl_->base, impl_->head);
    impl_->failed = st.ok() ? corrupt(missing.empty() ? "file ends before the end marker" : missing) : st;
  }
  return impl_->failed;
}

uint32_t StreamDecoder::segment_count() const { return impl_->have_header ? impl_->h.segment_count : 0; }
uint32_t StreamDecoder::segments_done() const { return impl_->done; }
uint32_t StreamDecoder::batches_done() const { return impl_->batches; }
bool StreamDecoder::done() const { return impl_->ended && impl_->failed.ok(); }
bool StreamDecoder::progressive() const { return impl_->base_ready; }
double StreamDecoder::level_error() const { return impl_->error; }
void StreamDecoder::stop_at_levels(bool on) { impl_->stop_levels = on; }
bool StreamDecoder::level_pending() const { return impl_->pending && impl_->failed.ok(); }
const Mesh& StreamDecoder::mesh() const { return impl_->mesh; }
Mesh StreamDecoder::take_mesh() { return std::move(impl_->mesh); }

}  // namespace tsm
