// Writing the .tsm container (format-spec/FORMAT.md §2-4; the encoder's
// last step): magic, version, header, then the sections, each with its id
// and codec, lengths, payload and XXH32 checksum (the first section's covers
// the header too), and the end marker. The method's
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
  float top = 0;
  const int axis = extent_axis(h.origin, 3, h.extent, top);
  const bool exact = (h.flags & kHeaderExactGrid) != 0;
  w.u8(static_cast<uint8_t>(h.quantization_bits | (exact ? kGridExact : 0) | axis << kGridAxisShift));
  w.u8(static_cast<uint8_t>(h.level | (h.segment_count > 1 ? kLevelSegmented : 0)));
  for (float o : h.origin) w.f32(o);
  w.f32(top);
  if (h.segment_count > 1) w.varint(h.segment_count);
  if (exact) {
    w.f64(h.exact_step);
    for (int64_t b : h.exact_base) w.varint((static_cast<uint64_t>(b) << 1) ^ static_cast<uint64_t>(b >> 63));
  }
}

// A section's framing, its stored bytes and its checksum, which covers
// `out` from `covered_from` (the section's first byte; for the first
// section, the file's) to the last stored byte.
void put_section(std::string& out, size_t covered_from, uint16_t id, SectionCodec codec, std::string_view stored,
                 uint64_t raw_bytes) {
  ByteWriter w(out);
  w.varint(uint64_t{id} << 1 | static_cast<uint64_t>(codec));
  w.varint(stored.size());
  if (codec == SectionCodec::zstd) w.varint(raw_bytes);
  w.bytes(stored);
  w.u32(checksum32(std::string_view(out).substr(covered_from)));
}

}  // namespace

ContainerWriter::ContainerWriter(const Header& header) {
  ByteWriter w(out_);
  w.bytes(std::string_view(kMagic, 4));
  w.varint(header.version);
  write_header_fields(w, header);
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
  put_section(out_, first_ ? 0 : out_.size(), id, codec, stored, payload.size());
  first_ = false;
}

void append_raw_section(std::string& file, uint16_t id, std::string_view payload) {
  put_section(file, file.size(), id, SectionCodec::raw, payload, payload.size());
}

std::string ContainerWriter::finish() {
  append_end_marker(out_);
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
