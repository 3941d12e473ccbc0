// Forging helpers for .tsm containers, shared by the fuzzers and
// tests/test_corruption.cpp.
//
// Every part of a .tsm file that a payload decoder reads is covered by an
// XXH32 checksum (format-spec/FORMAT.md §3, §4.1), so a blindly mutated input
// almost never gets past read_container() and the stream decoders behind it
// would go untested. These helpers let a fuzzer or a test change a file the
// way a forger would, with every length and checksum made to match:
//
//   fix_checksums(file)   rewrites the header checksum and every section
//                         checksum in place, judging nothing else;
//   parse_container / build_container
//                         split a file into preamble, the three header counts
//                         (vertices, faces, corners: the first three header
//                         fields), the other header fields (opaque) and the
//                         sections (id, codec, raw length, stored bytes), and
//                         lay it out again with lengths and checksums
//                         recomputed.
//
// Only the container framing (FORMAT.md §2-4) is assumed, not the payloads,
// so this keeps working while the sections' contents change.
#pragma once
#include <xxhash.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tsm_fuzz {

inline bool get_varint(std::string_view s, size_t& p, uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 70; shift += 7) {
    if (p >= s.size()) return false;
    const uint8_t b = static_cast<uint8_t>(s[p++]);
    if (shift < 64) v |= static_cast<uint64_t>(b & 0x7f) << shift;
    if (!(b & 0x80)) return true;
  }
  return false;
}

inline void put_varint(std::string& s, uint64_t v) {
  while (v >= 0x80) {
    s.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  s.push_back(static_cast<char>(v));
}

inline void put_le(std::string& s, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) s.push_back(static_cast<char>(v >> (8 * i)));
}

inline uint64_t get_le(std::string_view s, size_t p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(s[p + static_cast<size_t>(i)])) << (8 * i);
  return v;
}

inline void set_u32(std::string& s, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) s[at + static_cast<size_t>(i)] = static_cast<char>(v >> (8 * i));
}

// Returns the number of checksums rewritten (0 when the framing does not even
// reach the header checksum). Stops at the end marker or where the framing
// breaks; the checksums before that point are fixed either way.
inline int fix_checksums(std::string& file) {
  size_t p = 8;  // magic, version, flags
  uint64_t header_len = 0;
  if (file.size() < p || !get_varint(file, p, header_len) || header_len > file.size() - p) return 0;
  p += static_cast<size_t>(header_len);
  if (file.size() - p < 4) return 0;
  set_u32(file, p, XXH32(file.data(), p, 0));
  p += 4;
  int fixed = 1;
  while (file.size() - p >= 2) {
    const uint16_t id = static_cast<uint16_t>(get_le(file, p, 2));
    p += 2;
    if (id == 0) break;
    uint64_t stored = 0, raw = 0;
    if (p >= file.size()) break;
    ++p;  // codec
    if (!get_varint(file, p, stored) || !get_varint(file, p, raw)) break;
    if (file.size() - p < 4) break;
    const size_t sum_at = p;
    p += 4;
    if (stored > file.size() - p) break;
    set_u32(file, sum_at, XXH32(file.data() + p, static_cast<size_t>(stored), 0));
    ++fixed;
    p += static_cast<size_t>(stored);
  }
  return fixed;
}

struct Section {
  uint16_t id = 0;
  uint8_t codec = 0;
  uint64_t raw_length = 0;  // written as is for codec != 0; raw sections get the stored length
  std::string stored;
};

struct Container {
  std::string magic = "TSM\x1a";
  uint16_t version = 0, flags = 0;
  uint64_t counts[3] = {0, 0, 0};  // vertices, faces, corners
  std::string other_fields;        // the header fields after the counts, opaque
  std::vector<Section> sections;
  std::string trailer;  // bytes after the end marker (none in a valid file)
};

// Splits a file along its framing. Checksums are not verified (a forger's
// input need not have them right). Fails when the framing does not hold: a
// length running past the end, a missing end marker, header fields that do
// not start with three varints.
inline bool parse_container(std::string_view file, Container& c) {
  c = Container();
  if (file.size() < 8) return false;
  c.magic = std::string(file.substr(0, 4));
  c.version = static_cast<uint16_t>(get_le(file, 4, 2));
  c.flags = static_cast<uint16_t>(get_le(file, 6, 2));
  size_t p = 8;
  uint64_t len = 0;
  if (!get_varint(file, p, len) || len > file.size() - p) return false;
  const size_t fields_end = p + static_cast<size_t>(len);
  const std::string_view fields = file.substr(0, fields_end);
  for (uint64_t& n : c.counts)
    if (!get_varint(fields, p, n)) return false;
  c.other_fields = std::string(file.substr(p, fields_end - p));
  p = fields_end;
  if (file.size() - p < 4) return false;
  p += 4;
  for (;;) {
    if (file.size() - p < 2) return false;
    Section s;
    s.id = static_cast<uint16_t>(get_le(file, p, 2));
    p += 2;
    if (s.id == 0) break;
    uint64_t stored = 0;
    if (p >= file.size()) return false;
    s.codec = static_cast<uint8_t>(file[p++]);
    if (!get_varint(file, p, stored) || !get_varint(file, p, s.raw_length)) return false;
    if (file.size() - p < 4) return false;
    p += 4;
    if (stored > file.size() - p) return false;
    s.stored = std::string(file.substr(p, static_cast<size_t>(stored)));
    p += static_cast<size_t>(stored);
    c.sections.push_back(std::move(s));
  }
  c.trailer = std::string(file.substr(p));
  return true;
}

// Lays a container out with every length and checksum recomputed.
inline std::string build_container(const Container& c) {
  std::string s = c.magic;
  put_le(s, c.version, 2);
  put_le(s, c.flags, 2);
  std::string fields;
  for (uint64_t n : c.counts) put_varint(fields, n);
  fields += c.other_fields;
  put_varint(s, fields.size());
  s += fields;
  put_le(s, XXH32(s.data(), s.size(), 0), 4);
  for (const Section& sec : c.sections) {
    put_le(s, sec.id, 2);
    s.push_back(static_cast<char>(sec.codec));
    put_varint(s, sec.stored.size());
    put_varint(s, sec.codec == 0 ? sec.stored.size() : sec.raw_length);
    put_le(s, XXH32(sec.stored.data(), sec.stored.size(), 0), 4);
    s += sec.stored;
  }
  put_le(s, 0, 2);
  return s + c.trailer;
}

}  // namespace tsm_fuzz
