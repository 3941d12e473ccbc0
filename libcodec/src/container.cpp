// The .tsm container (format-spec/FORMAT.md §2-3): magic, version, header,
// then self-delimiting sections, each with an id, a codec (raw or zstd), its
// lengths and an XXH32 checksum, ended by an end marker. The method's streams
// (seed 004 §3-4: vertex tree, triangle tree, marching pattern, geometry) are
// sections; side data is zstd-compressed where that wins. Sections are read in
// order, so a decoder can start on a section as soon as its bytes are in.
//
// Every length is checked against the bytes that remain before anything is
// allocated, and every section's checksum is verified before it is used.
#include "container.hpp"

#include <xxhash.h>
#include <cmath>
#include <limits>
#include <zstd.h>

#include "byte_io.hpp"

namespace tsm {

const char* section_name(uint16_t id) {
  switch (id) {
    case kSectionEnd: return "end";
    case kSectionVertexTree: return "vertex-tree";
    case kSectionTriangleTree: return "triangle-tree";
    case kSectionTopology: return "topology";
    case kSectionGeometry: return "geometry";
  }
  return "unknown";
}

uint32_t checksum32(std::string_view bytes) { return XXH32(bytes.data(), bytes.size(), 0); }

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
}

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

}  // namespace

ContainerWriter::ContainerWriter(const Header& header) {
  ByteWriter w(out_);
  w.bytes(std::string_view(kMagic, 4));
  w.u16(kFormatVersion);
  w.u16(0);  // flags
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

std::string ContainerWriter::finish() {
  ByteWriter w(out_);
  w.u16(kSectionEnd);
  return std::move(out_);
}

Status read_container(std::string_view bytes, Header& header, std::vector<Section>& sections,
                      bool decode_payloads) {
  sections.clear();
  ByteReader r(bytes);
  std::string_view magic;
  if (!r.bytes(4, magic) || magic != std::string_view(kMagic, 4))
    return corrupt("not a .tsm file (bad magic; expected the bytes 'TSM' 0x1A)");
  uint16_t version = 0, flags = 0;
  if (!r.u16(version) || !r.u16(flags)) return corrupt("file ends inside the header");
  if (version != kFormatVersion)
    return Status(ErrorCode::unsupported, "format version " + std::to_string(version) +
                                              " is not supported by this decoder (it reads version " +
                                              std::to_string(kFormatVersion) + ")");
  if (flags != 0) return corrupt("unknown header flags " + std::to_string(flags));
  uint64_t header_len = 0;
  std::string_view fields;
  if (!r.varint(header_len) || header_len > r.remaining() || !r.bytes(static_cast<size_t>(header_len), fields))
    return corrupt("header length runs past the end of the file");
  size_t header_end = r.offset();
  uint32_t sum = 0;
  if (!r.u32(sum)) return corrupt("file ends before the header checksum");
  if (sum != checksum32(bytes.substr(0, header_end))) return corrupt("header checksum mismatch");
  ByteReader h(fields);
  uint64_t segments = 0;
  bool ok = h.varint(header.vertex_count) && h.varint(header.face_count) && h.varint(header.corner_count) &&
            h.u8(header.quantization_bits) && h.u8(header.level);
  for (float& o : header.origin) ok = ok && h.f32(o);
  ok = ok && h.f64(header.extent) && h.varint(segments);
  if (!ok) return corrupt("header fields are truncated");
  if (segments == 0 || segments > 0xffffffffu) return corrupt("bad segment count");
  header.segment_count = static_cast<uint32_t>(segments);
  for (float o : header.origin)
    if (!std::isfinite(o)) return corrupt("header origin is not a finite number");
  if (!std::isfinite(header.extent) || header.extent < 0 || header.extent > 6.9e38)
    return corrupt("header extent is not a finite, non-negative number");
  if (header.quantization_bits < 1 || header.quantization_bits > 30)
    return corrupt("quantization bits " + std::to_string(header.quantization_bits) + " outside 1..30");

  for (;;) {
    size_t at = r.offset();
    uint16_t id = 0;
    if (!r.u16(id)) return corrupt("file ends before the end marker (truncated at byte " + std::to_string(at) + ")");
    if (id == kSectionEnd) break;
    uint8_t codec = 0;
    uint64_t stored_len = 0, raw_len = 0;
    uint32_t csum = 0;
    if (!r.u8(codec) || !r.varint(stored_len) || !r.varint(raw_len) || !r.u32(csum))
      return corrupt("section at byte " + std::to_string(at) + ": truncated section header");
    if (codec > 1) return corrupt("section at byte " + std::to_string(at) + ": unknown codec " + std::to_string(codec));
    if (stored_len > r.remaining())
      return corrupt("section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) + ": length " +
                     std::to_string(stored_len) + " runs past the end of the file (" + std::to_string(r.remaining()) +
                     " bytes left)");
    if (codec == 0 ? raw_len != stored_len : raw_len > stored_len * kMaxExpansion)
      return corrupt("section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) +
                     ": implausible raw length " + std::to_string(raw_len));
    std::string_view stored;
    r.bytes(static_cast<size_t>(stored_len), stored);
    if (checksum32(stored) != csum)
      return corrupt("section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) +
                     ": checksum mismatch (the file is damaged)");
    for (const Section& prev : sections)
      if (prev.id == id)
        return corrupt("section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) +
                       " appears twice");
    Section s;
    s.id = id;
    s.codec = static_cast<SectionCodec>(codec);
    s.stored_bytes = stored_len;
    s.raw_bytes = raw_len;
    if (decode_payloads) {
      if (s.codec == SectionCodec::raw) {
        s.data.assign(stored.data(), stored.size());
      } else {
        s.data.resize(static_cast<size_t>(raw_len));
        size_t n = ZSTD_decompress(s.data.data(), s.data.size(), stored.data(), stored.size());
        if (ZSTD_isError(n) || n != raw_len)
          return corrupt("section '" + std::string(section_name(id)) + "': zstd payload does not decode to " +
                         std::to_string(raw_len) + " bytes");
      }
    } else {
      s.data.clear();
    }
    sections.push_back(std::move(s));
    if (sections.size() > 4096) return corrupt("too many sections");
  }
  if (r.remaining() != 0)
    return corrupt(std::to_string(r.remaining()) + " unexpected bytes after the end marker");
  return Status::Ok();
}

}  // namespace tsm
