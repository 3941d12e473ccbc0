// Writing the .tsm container (format-spec/FORMAT.md §2-4; the encoder's
// last step): magic, version, header, then the sections, each with its id,
// codec, lengths and XXH32 checksum, and the end marker. The method's
// streams (seed 004 §3-4: vertex tree, triangle tree, marching pattern,
// geometry) go in one section per segment (a mesh of one segment: the mesh
// section); side data is zstd-compressed where that wins. The only use of
// zstd's compressor. (Reading: container_read.cpp.)
#include <zstd.h>

#include "byte_io.hpp"
#include "container.hpp"

namespace tsm {

namespace {

void write_header_fields(ByteWriter& w, const Header& h) {
  w.varint(h.vertex_count);
  w.varint(h.face_count);
  w.varint(h.corner_count);
  w.u8(h.quantization_bits);
  w.u8(h.level);
  for (float o : h.origin) w.f32(o);
  w.f64(h.extent);
  w.varint(h.segment_count);
  if (h.flags & kHeaderExactGrid) {
    w.f64(h.exact_step);
    for (int64_t b : h.exact_base) w.varint((static_cast<uint64_t>(b) << 1) ^ static_cast<uint64_t>(b >> 63));
  }
}

}  // namespace

ContainerWriter::ContainerWriter(const Header& header) {
  ByteWriter w(out_);
  w.bytes(std::string_view(kMagic, 4));
  w.u16(header.version);
  w.u16(header.flags);
  std::string fields;
  ByteWriter fw(fields);
  write_header_fields(fw, header);
  w.varint(fields.size());
  w.bytes(fields);
  w.u32(checksum32(std::string_view(out_)));
}

void ContainerWriter::add_section(uint16_t id, std::string_view payload, int zstd_level) {
  std::string stored;
  SectionCodec codec = SectionCodec::raw;
  if (zstd_level > 0 && payload.size() > 64) {
    stored.resize(ZSTD_compressBound(payload.size()));
    size_t n = ZSTD_compress(stored.data(), stored.size(), payload.data(), payload.size(), zstd_level);
    if (!ZSTD_isError(n) && n < payload.size() && payload.size() <= n * kMaxExpansion) {
      stored.resize(n);
      codec = SectionCodec::zstd;
    }
  }
  if (codec == SectionCodec::raw) stored.assign(payload.data(), payload.size());
  ByteWriter w(out_);
  w.u16(id);
  w.u8(static_cast<uint8_t>(codec));
  w.varint(stored.size());
  w.varint(payload.size());
  w.u32(checksum32(stored));
  w.bytes(stored);
}

void append_raw_section(std::string& file, uint16_t id, std::string_view payload) {
  ByteWriter w(file);
  w.u16(id);
  w.u8(static_cast<uint8_t>(SectionCodec::raw));
  w.varint(payload.size());
  w.varint(payload.size());
  w.u32(checksum32(payload));
  w.bytes(payload);
}

std::string ContainerWriter::finish() {
  ByteWriter w(out_);
  w.u16(kSectionEnd);
  return std::move(out_);
}

std::string write_mesh_payload(const MeshPayload& p) {
  std::string out;
  ByteWriter w(out);
  write_streams(w, {p.vertex_tree, p.triangle_tree, p.topology, p.geometry}, p.attributes);
  return out;
}

std::string write_metadata(const std::vector<MetadataEntry>& entries) {
  std::string out;
  ByteWriter w(out);
  w.varint(entries.size());
  for (const MetadataEntry& e : entries) {
    w.u8(static_cast<uint8_t>(e.key.size()));
    w.bytes(e.key);
    w.varint(e.value.size());
    w.bytes(e.value);
  }
  return out;
}

}  // namespace tsm
