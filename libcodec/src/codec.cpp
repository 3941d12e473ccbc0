// Encoder and decoder entry points: validate the mesh, quantize positions
// (design notes §6: the Draco grid), and lay the streams out in the container.
//
// Foundation codec (format version 1): positions as quantized u32 triples and
// faces as sizes plus delta-coded corner indices, both through zstd. The
// Topological Surgery streams (vertex tree, bounding loop, triangle tree,
// marching pattern, predicted geometry; seed 004 §3-4) replace these sections
// stage by stage; the interface stays.
#include <cmath>

#include "byte_io.hpp"
#include "container.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

const char* version_string() { return TSM_VERSION; }

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

uint64_t zigzag(int64_t v) { return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63); }
int64_t unzigzag(uint64_t v) { return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1); }

int zstd_level_for(int level) { return level <= 0 ? 1 : level >= 9 ? 19 : 3 + 2 * level; }

// Dequantization: x = origin + q * extent / (2^bits - 1), in double, rounded to float.
struct Dequantizer {
  double origin[3];
  double step;
  Dequantizer(const Header& h) {
    for (int a = 0; a < 3; ++a) origin[a] = h.origin[a];
    step = static_cast<double>(h.extent) / (std::ldexp(1.0, h.quantization_bits) - 1.0);
  }
  float operator()(uint32_t q, int a) const { return static_cast<float>(origin[a] + q * step); }
};

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

  const Grid grid = [&] {
    Grid g;
    g.bits = options.quantization_bits;
    for (int a = 0; a < 3; ++a) g.origin[a] = h.origin[a];
    g.step = h.extent > 0 ? static_cast<double>(h.extent) / (std::ldexp(1.0, g.bits) - 1.0) : 0.0;
    return g;
  }();
  const int64_t qmax = (int64_t{1} << options.quantization_bits) - 1;

  std::string positions;
  positions.reserve(12 * mesh.vertex_count());
  ByteWriter pw(positions);
  for (size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) {
      int64_t q = grid.quantize(mesh.positions[3 * v + a], a);
      pw.u32(static_cast<uint32_t>(q < 0 ? 0 : q > qmax ? qmax : q));
    }

  std::string faces;
  ByteWriter fw(faces);
  int64_t prev = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    fw.varint(mesh.face_size(f));
    for (uint32_t i = 0; i < mesh.face_size(f); ++i) {
      int64_t v = mesh.face(f)[i];
      fw.varint(zigzag(v - prev));
      prev = v;
    }
  }

  ContainerWriter cw(h);
  const int zl = zstd_level_for(options.level);
  cw.add_section(kSectionPositionsRaw, positions, zl);
  cw.add_section(kSectionFacesRaw, faces, zl);
  out = cw.finish();
  return Status::Ok();
}

Status decode(std::string_view bytes, Mesh& out, const DecodeOptions& options) {
  out.clear();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections));
  if (options.max_vertices && h.vertex_count > options.max_vertices)
    return Status(ErrorCode::limit_exceeded, "file has " + std::to_string(h.vertex_count) +
                                                 " vertices, above the caller's limit of " +
                                                 std::to_string(options.max_vertices));
  if (options.max_faces && h.face_count > options.max_faces)
    return Status(ErrorCode::limit_exceeded, "file has " + std::to_string(h.face_count) +
                                                 " faces, above the caller's limit of " +
                                                 std::to_string(options.max_faces));
  const Section* pos = nullptr;
  const Section* fac = nullptr;
  for (const Section& s : sections) {
    if (s.id == kSectionPositionsRaw) pos = &s;
    if (s.id == kSectionFacesRaw) fac = &s;
  }
  if (!pos || !fac) return corrupt("a required section (positions or faces) is missing");
  if (pos->data.size() / 12 != h.vertex_count || pos->data.size() % 12 != 0)
    return corrupt("positions section holds " + std::to_string(pos->data.size()) + " bytes, not 12 per vertex for " +
                   std::to_string(h.vertex_count) + " vertices");
  // Every face costs at least one byte of size plus one per corner.
  if (h.face_count > fac->data.size() || h.corner_count > fac->data.size() ||
      h.face_count + h.corner_count > fac->data.size() || h.corner_count > 0xffffffffu)
    return corrupt("face and corner counts exceed what the faces section can hold");

  const Dequantizer dq(h);
  const uint32_t qmax = static_cast<uint32_t>((uint64_t{1} << h.quantization_bits) - 1);
  out.positions.resize(3 * static_cast<size_t>(h.vertex_count));
  ByteReader pr(pos->data);
  for (size_t i = 0; i < out.positions.size(); ++i) {
    uint32_t q = 0;
    pr.u32(q);
    if (q > qmax) return corrupt("quantized coordinate out of range");
    out.positions[i] = dq(q, static_cast<int>(i % 3));
  }
  out.face_offsets.resize(static_cast<size_t>(h.face_count) + 1);
  out.indices.resize(static_cast<size_t>(h.corner_count));
  ByteReader fr(fac->data);
  int64_t prev = 0;
  uint64_t corner = 0;
  for (size_t f = 0; f < h.face_count; ++f) {
    uint64_t n = 0;
    if (!fr.varint(n) || n == 0 || n > h.corner_count - corner)
      return corrupt("face " + std::to_string(f) + ": bad corner count");
    for (uint64_t i = 0; i < n; ++i) {
      uint64_t d = 0;
      if (!fr.varint(d)) return corrupt("faces section is truncated");
      int64_t v = prev + unzigzag(d);
      if (v < 0 || static_cast<uint64_t>(v) >= h.vertex_count)
        return corrupt("face " + std::to_string(f) + " references a vertex out of range");
      out.indices[corner++] = static_cast<uint32_t>(v);
      prev = v;
    }
    out.face_offsets[f + 1] = static_cast<uint32_t>(corner);
  }
  if (corner != h.corner_count || fr.remaining() != 0) return corrupt("faces section does not match the header counts");
  return Status::Ok();
}

Status inspect(std::string_view bytes, FileInfo& info) {
  info = FileInfo();
  Header h;
  std::vector<Section> sections;
  TSM_RETURN_IF_ERROR(read_container(bytes, h, sections, /*decode_payloads=*/false));
  info.format_version = kFormatVersion;
  info.vertex_count = h.vertex_count;
  info.face_count = h.face_count;
  info.corner_count = h.corner_count;
  info.quantization_bits = h.quantization_bits;
  info.level = h.level;
  info.segment_count = h.segment_count;
  for (int a = 0; a < 3; ++a) info.bbox_min[a] = h.origin[a];
  info.step = static_cast<double>(h.extent) / (std::ldexp(1.0, h.quantization_bits) - 1.0);
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
  return Status::Ok();
}

}  // namespace tsm
