// Forging helpers for .tsm containers, shared by the fuzzers and
// tests/test_corruption.cpp.
//
// Every part of a .tsm file that a payload decoder reads is covered by an
// XXH32 checksum (format-spec/FORMAT.md §4.1), so a blindly mutated input
// almost never gets past read_container() and the stream decoders behind it
// would go untested. These helpers let a fuzzer or a test change a file the
// way a forger would, with every length and checksum made to match:
//
//   fix_checksums(file)   rewrites every section checksum in place (the
//                         first one covers the header), judging nothing else;
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

// The end of the header (FORMAT.md §2-3): after the magic, the version
// varint, the three counts, the grid and level bytes, origin and maximum
// (16 bytes), with the level byte's bit 4 the segment count and, with the
// grid byte's exact flag, the exact grid's step and base. Sets `counts_end` to the end of the counts.
inline bool header_end(std::string_view file, size_t& p, size_t& counts_end) {
  uint64_t v = 0;
  p = 4;
  if (file.size() < p || !get_varint(file, p, v)) return false;
  for (int i = 0; i < 3; ++i)
    if (!get_varint(file, p, v)) return false;
  counts_end = p;
  if (file.size() - p < 18) return false;
  const bool exact = (static_cast<uint8_t>(file[p]) & 0x20) != 0;
  const bool segmented = (static_cast<uint8_t>(file[p + 1]) & 0x10) != 0;
  p += 18;
  if (segmented && !get_varint(file, p, v)) return false;
  if (!exact) return true;
  if (file.size() - p < 8) return false;
  p += 8;
  for (int i = 0; i < 3; ++i)
    if (!get_varint(file, p, v)) return false;
  return true;
}

// Returns the number of checksums rewritten (0 when the framing does not even
// reach the first section's checksum). Stops at the end marker or where the
// framing breaks; the checksums before that point are fixed either way. A
// section's checksum covers its bytes from its id on, the first section's
// from the file's first byte (FORMAT.md §4.1).
inline int fix_checksums(std::string& file) {
  size_t p = 0, counts_end = 0;
  if (!header_end(file, p, counts_end)) return 0;
  size_t covered_from = 0;
  int fixed = 0;
  while (p < file.size()) {
    uint64_t tag = 0, stored = 0, raw = 0;
    if (!get_varint(file, p, tag) || tag == 0) break;
    if (!get_varint(file, p, stored) || ((tag & 1) && !get_varint(file, p, raw))) break;
    if (stored > file.size() - p || file.size() - p - stored < 4) break;
    p += static_cast<size_t>(stored);
    set_u32(file, p, XXH32(file.data() + covered_from, p - covered_from, 0));
    p += 4;
    covered_from = p;
    ++fixed;
  }
  return fixed;
}

struct Section {
  uint16_t id = 0;
  uint8_t codec = 0;        // its low bit is written (the tag's)
  uint64_t raw_length = 0;  // written for codec 1 only
  std::string stored;
};

struct Container {
  std::string magic = "TSM\x1a";
  uint64_t version = 0;
  uint64_t counts[3] = {0, 0, 0};  // vertices, faces, corners
  std::string other_fields;        // the header fields after the counts, opaque
  std::vector<Section> sections;
  std::string trailer;  // bytes after the end marker (none in a valid file)
};

// Splits a file along its framing. Checksums are not verified (a forger's
// input need not have them right). Fails when the framing does not hold: a
// length running past the end, a missing end marker, a header cut off.
inline bool parse_container(std::string_view file, Container& c) {
  c = Container();
  size_t p = 0, counts_end = 0;
  if (!header_end(file, p, counts_end)) return false;
  c.magic = std::string(file.substr(0, 4));
  size_t q = 4;
  get_varint(file, q, c.version);
  for (uint64_t& n : c.counts) get_varint(file, q, n);
  c.other_fields = std::string(file.substr(counts_end, p - counts_end));
  for (;;) {
    uint64_t tag = 0, stored = 0;
    if (!get_varint(file, p, tag)) return false;
    if (tag == 0) break;
    Section s;
    s.id = static_cast<uint16_t>(tag >> 1);
    s.codec = static_cast<uint8_t>(tag & 1);
    if (!get_varint(file, p, stored) || (s.codec && !get_varint(file, p, s.raw_length))) return false;
    if (stored > file.size() - p || file.size() - p - stored < 4) return false;
    s.stored = std::string(file.substr(p, static_cast<size_t>(stored)));
    p += static_cast<size_t>(stored) + 4;
    c.sections.push_back(std::move(s));
  }
  c.trailer = std::string(file.substr(p));
  return true;
}

// Lays a container out with every length and checksum recomputed.
inline std::string build_container(const Container& c) {
  std::string s = c.magic;
  put_varint(s, c.version);
  for (uint64_t n : c.counts) put_varint(s, n);
  s += c.other_fields;
  size_t covered_from = 0;
  for (const Section& sec : c.sections) {
    put_varint(s, uint64_t{sec.id} << 1 | (sec.codec & 1u));
    put_varint(s, sec.stored.size());
    if (sec.codec & 1) put_varint(s, sec.raw_length);
    s += sec.stored;
    put_le(s, XXH32(s.data() + covered_from, s.size() - covered_from, 0), 4);
    covered_from = s.size();
  }
  s.push_back('\0');
  return s + c.trailer;
}

}  // namespace tsm_fuzz
