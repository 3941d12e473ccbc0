// Reading the .tsm container (format-spec/FORMAT.md §2-4; the decoder's
// first step): magic, version, header, then self-delimiting sections, each
// with an id and codec (raw or zstd), its lengths, its payload and an XXH32
// checksum of its bytes (the first section's covers the header too, so the
// header is verified with it), ended by an end marker; the mesh section's streams and the metadata.
// Sections are read in order, so a decoder can start on a section as soon
// as its bytes are in. (Writing: container_write.cpp.)
//
// Every length is checked against the bytes that remain before anything is
// allocated, and every section's checksum is verified before it is used.
#include "container.hpp"

#define XXH_STATIC_LINKING_ONLY  // XXH32_state_t on the stack
#include <xxhash.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <zstd.h>

#include "byte_io.hpp"

namespace tsm {

const char* section_name(uint16_t id) {
  switch (id) {
    case kSectionEnd: return "end";
    case kSectionSegment: return "segment";
    case kSectionReserved8: return "reserved";
    case kSectionMetadata: return "metadata";
    case kSectionMesh: return "mesh";
    case kSectionOrder: return "order";
    case kSectionRefinement: return "refinement";
    case kSectionLoose: return "loose";
    case kSectionExceptions: return "exceptions";
  }
  return id >= kSectionReservedFirst && id <= kSectionReservedLast ? "reserved" : "unknown";
}

uint32_t checksum32(std::string_view bytes) { return XXH32(bytes.data(), bytes.size(), 0); }

uint32_t checksum32(std::string_view first, std::string_view second) {
  if (first.empty()) return checksum32(second);
  XXH32_state_t state;
  XXH32_reset(&state, 0);
  XXH32_update(&state, first.data(), first.size());
  XXH32_update(&state, second.data(), second.size());
  return XXH32_digest(&state);
}

namespace {

Status corrupt(const std::string& what) { return Status(ErrorCode::corrupt_data, what); }

Status corrupt_at(size_t at, uint16_t id, const std::string& what) {
  return corrupt("section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) + ": " + what);
}

}  // namespace

Status read_header(std::string_view bytes, size_t& offset, Header& header, std::string& missing) {
  missing.clear();
  ByteReader r(bytes);
  std::string_view magic;
  // Refuse a wrong signature from the first bytes that show it.
  const size_t have = std::min<size_t>(bytes.size(), 4);
  if (bytes.substr(0, have) != std::string_view(kMagic, have))
    return corrupt("not a .tsm file (bad magic; expected the bytes 'TSM' 0x1A)");
  // A varint that fails with bytes left after it is invalid; one cut off
  // by the end of the bytes at hand has consumed them all.
  uint64_t version = 0;
  if (!r.bytes(4, magic) || !r.varint(version)) {
    if (magic.size() == 4 && r.remaining() > 0) return corrupt("the format version is not a valid varint");
    missing = "file ends inside the header";
    return Status::Ok();
  }
  if (version != kFormatVersion)
    return Status(ErrorCode::unsupported, "format version " + std::to_string(version) +
                                              ": this decoder reads only format version " +
                                              std::to_string(kFormatVersion) +
                                              " (tsm keeps one format until 1.0; re-encode from the source mesh)");
  header.version = kFormatVersion;
  // A read cut off by the end of the bytes leaves fewer than 8 of them
  // (the widest fixed field): with more, a varint is invalid.
  uint8_t grid = 0, level = 0;
  float top = 0;
  uint64_t segments = 1;
  bool ok = r.varint(header.vertex_count) && r.varint(header.face_count) && r.varint(header.corner_count) &&
            r.u8(grid) && r.u8(level);
  for (float& o : header.origin) ok = ok && r.f32(o);
  ok = ok && r.f32(top) && (!(level & kLevelSegmented) || r.varint(segments));
  header.flags = (grid & kGridExact) ? kHeaderExactGrid : 0;
  if (ok && (grid & kGridExact)) {
    ok = r.f64(header.exact_step);
    for (int64_t& b : header.exact_base) {
      uint64_t z = 0;
      ok = ok && r.varint(z);
      b = static_cast<int64_t>(z >> 1) ^ -static_cast<int64_t>(z & 1);
    }
  }
  if (!ok) {
    if (r.remaining() >= 8) return corrupt("header fields are not valid varints");
    missing = "file ends inside the header";
    return Status::Ok();
  }
  header.quantization_bits = grid & kGridBitsMask;
  header.level = level & kLevelMask;
  if (level & ~(kLevelMask | kLevelSegmented)) return corrupt("header level byte has bits 5-7 set");
  const int axis = grid >> kGridAxisShift;
  if (axis > 2) return corrupt("header grid byte names axis 3");
  if (header.quantization_bits < 1 || header.quantization_bits > 30)
    return corrupt("quantization bits " + std::to_string(header.quantization_bits) + " outside 1..30");
  for (float o : header.origin)
    if (!std::isfinite(o)) return corrupt("header origin is not a finite number");
  header.extent = static_cast<double>(top) - static_cast<double>(header.origin[axis]);
  if (!std::isfinite(top) || !(header.extent >= 0))
    return corrupt("header bounding-box maximum is not a finite number at or above the origin");
  if ((grid & kGridExact) && !(header.exact_step > 0 && std::isfinite(header.exact_step)))
    return corrupt("the exact grid's step is not a finite positive number");
  for (int64_t b : header.exact_base)
    if (b > (int64_t{1} << 62) || b < -(int64_t{1} << 62)) return corrupt("the exact grid's base is out of range");
  if ((level & kLevelSegmented) && (segments < 2 || segments > 0xffffffffu)) return corrupt("bad segment count");
  header.segment_count = static_cast<uint32_t>(segments);
  offset = r.offset();
  return Status::Ok();
}

uint64_t section_framing_bytes(const Section& s) {
  auto varint_bytes = [](uint64_t v) {
    uint64_t n = 1;
    for (; v >= 0x80; v >>= 7) ++n;
    return n;
  };
  const uint64_t tag = uint64_t{s.id} << 1 | static_cast<uint64_t>(s.codec);
  return varint_bytes(tag) + varint_bytes(s.stored_bytes) +
         (s.codec == SectionCodec::zstd ? varint_bytes(s.raw_bytes) : 0) + 4;
}

Status read_section(std::string_view bytes, size_t& offset, Section& s, bool decode_payload, std::string& missing,
                    size_t base, std::string_view header) {
  missing.clear();
  const size_t at = base + offset;
  ByteReader r(bytes.substr(offset));
  uint64_t tag = 0;
  if (!r.varint(tag)) {
    if (r.remaining() > 0) return corrupt("section at byte " + std::to_string(at) + ": bad id");
    missing = "file ends before the end marker (truncated at byte " + std::to_string(at) + ")";
    return Status::Ok();
  }
  if (tag >> 1 > 0xffff) return corrupt("section at byte " + std::to_string(at) + ": id above 65535");
  s = Section();
  s.id = static_cast<uint16_t>(tag >> 1);
  const uint16_t id = s.id;
  if (tag == kSectionEnd) {
    offset += r.offset();
    return Status::Ok();
  }
  if (id == kSectionEnd) return corrupt("section at byte " + std::to_string(at) + ": a zstd-coded end marker");
  const bool zstd = (tag & 1) != 0;
  uint64_t stored_len = 0, raw_len = 0;
  // A varint cut off by the end of the bytes has consumed them all: one
  // that fails with bytes left is invalid.
  if (!r.varint(stored_len) || (zstd && !r.varint(raw_len))) {
    if (r.remaining() > 0) return corrupt("section at byte " + std::to_string(at) + ": bad length field");
    missing = "section at byte " + std::to_string(at) + ": truncated section header";
    return Status::Ok();
  }
  if (!zstd) raw_len = stored_len;
  if (raw_len > stored_len * kMaxExpansion)
    return corrupt_at(at, id, "implausible raw length " + std::to_string(raw_len));
  std::string_view stored;
  uint32_t csum = 0;
  if (!r.bytes(static_cast<size_t>(std::min<uint64_t>(stored_len, SIZE_MAX)), stored) || !r.u32(csum)) {
    missing = "section '" + std::string(section_name(id)) + "' at byte " + std::to_string(at) + ": length " +
              std::to_string(stored_len) + " runs past the end of the file (" + std::to_string(r.remaining()) +
              " bytes left)";
    return Status::Ok();
  }
  if (checksum32(header, bytes.substr(offset, r.offset() - 4)) != csum)
    return corrupt_at(at, id, "checksum mismatch (the file is damaged)");
  s.codec = zstd ? SectionCodec::zstd : SectionCodec::raw;
  s.stored_bytes = stored_len;
  s.raw_bytes = raw_len;
  s.offset = at;
  if (decode_payload) {
    if (s.codec == SectionCodec::raw) {
      s.data.assign(stored.data(), stored.size());
    } else {
      s.data.resize(static_cast<size_t>(raw_len));
      size_t n = ZSTD_decompress(s.data.data(), s.data.size(), stored.data(), stored.size());
      if (ZSTD_isError(n) || n != raw_len)
        return corrupt_at(at, id, "zstd payload does not decode to " + std::to_string(raw_len) + " bytes");
    }
  }
  offset += r.offset();
  return Status::Ok();
}

Status SectionRules::admit(const Section& s, const Header& h) {
  const size_t at = s.offset;
  const uint32_t segment_count = h.segment_count;
  if (s.id == kSectionSegment) {
    if (segment_count == 1) return corrupt_at(at, s.id, "a segment section in a file of one segment");
    if (++segments > segment_count)
      return corrupt_at(at, s.id, "more segment sections than the header's " + std::to_string(segment_count));
    return Status::Ok();
  }
  if ((s.id >= kSectionReservedFirst && s.id <= kSectionReservedLast) || s.id == kSectionReserved8)
    return corrupt_at(at, s.id, "reserved section id " + std::to_string(s.id) +
                                    " (a mesh's streams belong in the mesh or segment sections)");
  if (segment_count > 1 && s.id == kSectionMesh)
    return corrupt_at(at, s.id, "a whole-mesh section in a file of " + std::to_string(segment_count) + " segments");
  if (s.id == kSectionLoose && refinements == 0) return corrupt_at(at, s.id, "loose vertices before any refinement");
  // A progressive file keeps neither the input's order nor exact coordinates (FORMAT.md §4.8).
  const bool whole_mesh_only = s.id == kSectionOrder || s.id == kSectionExceptions;
  if (whole_mesh_only && refinements > 0) return corrupt_at(at, s.id, "in a progressive file");
  if (s.id == kSectionRefinement && (std::find(seen.begin(), seen.end(), kSectionOrder) != seen.end() ||
                                     std::find(seen.begin(), seen.end(), kSectionExceptions) != seen.end()))
    return corrupt_at(at, s.id, "a refinement in a keep-order or lossless file");
  if (s.id == kSectionRefinement) {
    if (std::find(seen.begin(), seen.end(), kSectionLoose) != seen.end())
      return corrupt_at(at, s.id, "a refinement after the loose vertices");
    const bool base_in = segment_count == 1 ? std::find(seen.begin(), seen.end(), kSectionMesh) != seen.end()
                                            : segments == segment_count;
    if (!base_in) return corrupt_at(at, s.id, "a refinement before the base mesh's last section");
    if (++refinements > kMaxRefinements) return corrupt_at(at, s.id, "too many refinement sections");
    return Status::Ok();
  }
  for (uint16_t prev : seen)
    if (prev == s.id) return corrupt_at(at, s.id, "appears twice");
  seen.push_back(s.id);
  if (seen.size() > 4096) return corrupt("too many sections");
  return Status::Ok();
}

Status read_mesh_payload(std::string_view bytes, MeshPayload& p) {
  ByteReader r(bytes);
  std::string_view* const parts[4] = {&p.vertex_tree, &p.triangle_tree, &p.topology, &p.geometry};
  switch (read_streams(r, parts, p.attributes)) {
    case StreamsRead::lengths_truncated: return corrupt("mesh section: truncated stream lengths");
    case StreamsRead::stream_past_end: return corrupt("mesh section: a stream runs past the section's end");
    case StreamsRead::ok: break;
  }
  return Status::Ok();
}

Status read_container(std::string_view bytes, Header& header, std::vector<Section>& sections,
                      bool decode_payloads) {
  sections.clear();
  size_t offset = 0;
  std::string missing;
  TSM_RETURN_IF_ERROR(read_header(bytes, offset, header, missing));
  if (!missing.empty()) return corrupt(missing);
  const std::string_view head = bytes.substr(0, offset);
  SectionRules rules;
  for (bool first = true;; first = false) {
    Section s;
    TSM_RETURN_IF_ERROR(read_section(bytes, offset, s, decode_payloads, missing, 0, first ? head : std::string_view()));
    if (!missing.empty()) return corrupt(missing);
    if (s.id == kSectionEnd) break;
    TSM_RETURN_IF_ERROR(rules.admit(s, header));
    sections.push_back(std::move(s));
  }
  if (offset != bytes.size())
    return corrupt(std::to_string(bytes.size() - offset) + " unexpected bytes after the end marker");
  return Status::Ok();
}

Status read_metadata(std::string_view payload, std::vector<MetadataEntry>& entries) {
  entries.clear();
  ByteReader r(payload);
  uint64_t count = 0;
  // Each entry takes at least 3 bytes (key length, a key byte, value length).
  if (!r.varint(count) || count > r.remaining() / 3) return corrupt("metadata: bad entry count");
  entries.reserve(static_cast<size_t>(count));
  for (uint64_t i = 0; i < count; ++i) {
    uint8_t key_len = 0;
    uint64_t value_len = 0;
    std::string_view key, value;
    if (!r.u8(key_len) || key_len == 0 || !r.bytes(key_len, key) || !r.varint(value_len) ||
        value_len > r.remaining() || !r.bytes(static_cast<size_t>(value_len), value))
      return corrupt("metadata: entry " + std::to_string(i) + " is truncated or has an empty key");
    entries.push_back({std::string(key), std::string(value)});
  }
  if (r.remaining() != 0) return corrupt("metadata: " + std::to_string(r.remaining()) + " bytes after the last entry");
  std::vector<std::string_view> keys;
  keys.reserve(entries.size());
  for (const MetadataEntry& e : entries) keys.push_back(e.key);
  std::sort(keys.begin(), keys.end());
  for (size_t i = 1; i < keys.size(); ++i)
    if (keys[i] == keys[i - 1]) return corrupt("metadata: key '" + std::string(keys[i]) + "' appears twice");
  return Status::Ok();
}

}  // namespace tsm
