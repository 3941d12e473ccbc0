// Encoder and decoder entry points: validate the mesh, run the connectivity
// stages (seed 004 §3-4), quantize positions on the Draco grid (design notes
// §6) and code them in decoded vertex order, and lay the streams out as
// container sections.
#include <algorithm>
#include <cmath>
#include <limits>

#include "connectivity.hpp"
#include "container.hpp"
#include "geometry_predict.hpp"
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

Status read_streams(std::vector<Section>& sections, ConnectivityStreams& cs) {
  Section* parts[3] = {nullptr, nullptr, nullptr};
  for (Section& s : sections) {
    if (s.id == kSectionVertexTree) parts[0] = &s;
    if (s.id == kSectionTriangleTree) parts[1] = &s;
    if (s.id == kSectionTopology) parts[2] = &s;
  }
  if (!parts[0] || !parts[1] || !parts[2]) return corrupt("a connectivity section is missing");
  cs.vertex_tree = std::move(parts[0]->data);
  cs.triangle_tree = std::move(parts[1]->data);
  cs.topology = std::move(parts[2]->data);
  return Status::Ok();
}

// A modelled binary decision costs at least -log2(4065/4096) = 0.011 bits
// (12-bit probabilities adapted by 1/32), so a stream of n bytes (plus the 8
// zero bytes a decoder may read past its end) holds at most 730 (n + 8)
// decisions. Every vertex costs at least 3 in the geometry stream, every
// triangle of the cut surface at least 1 in the triangle-tree stream (a
// marching bit or a run's end), every side-face corner at least 6 in the
// topology stream: counts beyond that are forged, refused before allocating.
uint64_t decisions(const std::vector<Section>& sections, uint16_t id) {
  const Section* s = find_section(sections, id);
  return s ? 730 * (static_cast<uint64_t>(s->data.size()) + 8) : 0;
}

Status check_limits(const Header& h, const std::vector<Section>& sections, const DecodeOptions& options) {
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
  if (h.vertex_count > decisions(sections, kSectionGeometry) / 3)
    return corrupt("the header's " + std::to_string(h.vertex_count) +
                   " vertices cannot be coded in a geometry section of this size");
  if (h.corner_count > 3 * decisions(sections, kSectionTriangleTree) + decisions(sections, kSectionTopology) / 6)
    return corrupt("the header's " + std::to_string(h.corner_count) +
                   " corners cannot be coded in connectivity sections of this size");
  return Status::Ok();
}

// The payload of a parsed container (shared by decode and inspect): faces
// into `out`, grid indices (3 per output vertex) into `q`.
Status decode_payload(const Header& h, std::vector<Section>& sections, const DecodeOptions& options, Mesh& out,
                      std::vector<uint32_t>& q, ConnectivityStats* cstats, GeometryStats* gstats) {
  TSM_RETURN_IF_ERROR(check_limits(h, sections, options));
  ConnectivityStreams cs;
  TSM_RETURN_IF_ERROR(read_streams(sections, cs));
  const Section* geo = find_section(sections, kSectionGeometry);
  if (!geo) return corrupt("the geometry section is missing");
  GeometryLayout layout;
  TSM_RETURN_IF_ERROR(decode_connectivity(cs, h.vertex_count, h.face_count, h.corner_count, out, layout, cstats));
  return decode_geometry(geo->data, layout, h.quantization_bits, q, gstats);
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
  auto reorder = [&](const ConnectivityEncoding& c) {  // by output id
    std::vector<uint32_t> q(qin.size());
    for (size_t v = 0; v < c.vertex_order.size(); ++v)
      for (int a = 0; a < 3; ++a) q[3 * v + a] = qin[3 * static_cast<size_t>(c.vertex_order[v]) + a];
    return q;
  };

  ConnectivityEncoding ce;
  CutHints hints;
  hints.qpos = &qin;
  TSM_RETURN_IF_ERROR(encode_connectivity(mesh, ce, hints));
  if (options.level >= 9) {
    // The midpoint-distance Kruskal tree instead of the layered spiral, kept
    // if its connectivity is smaller (on the corpus it never is).
    ConnectivityEncoding alt;
    hints.midpoint_tree = true;
    TSM_RETURN_IF_ERROR(encode_connectivity(mesh, alt, hints));
    if (alt.stats.bytes < ce.stats.bytes)
      ce = std::move(alt);
    else
      hints.midpoint_tree = false;
  }
  std::vector<uint32_t> q = reorder(ce);
  // Vertices on no triangle go last, ordered by a nearby surface vertex
  // that predicts them: a second pass with those anchors.
  std::vector<uint32_t> anchor = find_anchors(ce.layout, q, options.quantization_bits);
  if (std::any_of(anchor.begin(), anchor.end(), [](uint32_t x) { return x != kNone; })) {
    std::vector<uint32_t> by_input(mesh.vertex_count(), kNone);
    for (size_t v = 0; v < anchor.size(); ++v) by_input[ce.vertex_order[v]] = anchor[v];
    ce = ConnectivityEncoding();
    hints.anchor = &by_input;
    TSM_RETURN_IF_ERROR(encode_connectivity(mesh, ce, hints));
    q = reorder(ce);
  }
  const Lattice lattice = find_lattice(q, static_cast<uint32_t>(mesh.vertex_count()));
  std::string geometry = encode_geometry(ce.layout, q, options.quantization_bits, options.level, &lattice);

  ContainerWriter cw(h);
  cw.add_section(kSectionVertexTree, ce.streams.vertex_tree, 0);
  cw.add_section(kSectionTriangleTree, ce.streams.triangle_tree, 0);
  cw.add_section(kSectionTopology, ce.streams.topology, 0);
  cw.add_section(kSectionGeometry, geometry, 0);
  out = cw.finish();
  return Status::Ok();
}

Status decode(std::string_view bytes, Mesh& out, const DecodeOptions& options) {
  out.clear();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections));
  std::vector<uint32_t> q;
  TSM_RETURN_IF_ERROR(decode_payload(h, sections, options, out, q, nullptr, nullptr));
  const double step = grid_step(h);
  out.positions.resize(q.size());
  constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
  for (size_t i = 0; i < q.size(); ++i) {
    double x = static_cast<double>(h.origin[i % 3]) + static_cast<double>(q[i]) * step;
    // A grid point may lie up to half a step past the largest input
    // coordinate; near the float limit, clamp (the input was within range).
    x = x > kFloatMax ? kFloatMax : x < -kFloatMax ? -kFloatMax : x;
    out.positions[i] = static_cast<float>(x);
  }
  return Status::Ok();
}

Status inspect(std::string_view bytes, FileInfo& info) {
  info = FileInfo();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections));
  info.format_version = kFormatVersion;
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
    if (s.id == kSectionVertexTree || s.id == kSectionTriangleTree || s.id == kSectionTopology)
      info.connectivity_bytes += s.stored_bytes;
    else if (s.id == kSectionGeometry)
      info.geometry_bytes += s.stored_bytes;
    else
      info.other_bytes += s.stored_bytes;
  }
  Mesh faces;
  std::vector<uint32_t> q;
  ConnectivityStats st;
  GeometryStats gs;
  TSM_RETURN_IF_ERROR(decode_payload(h, sections, DecodeOptions(), faces, q, &st, &gs));
  info.components = st.components;
  info.vertex_runs = st.vertex_runs;
  info.triangle_runs = st.triangle_runs;
  info.jump_edges = st.jump_edges;
  info.stitches = st.stitches;
  info.virtual_vertices = st.virtual_vertices;
  info.side_faces = st.side_faces;
  info.marching_bits = st.marching_bits;
  info.geometry_predictor = gs.predictor == Predictor::ancestors ? "ancestors"
                            : gs.predictor == Predictor::gate    ? "gate"
                                                                 : "parallelograms";
  info.ancestors = gs.ancestors;
  for (int a = 0; a < 3; ++a) info.lattice_planes[a] = gs.lattice_planes[a];
  return Status::Ok();
}

}  // namespace tsm
