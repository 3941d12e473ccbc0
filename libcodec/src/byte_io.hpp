// Internal: bounds-checked little-endian byte reading and writing, shared by
// the container and every coded stream. A ByteReader never reads past its end:
// each read reports failure instead, and callers turn that into corrupt_data.
#pragma once
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <string_view>

namespace tsm {

class ByteWriter {
 public:
  explicit ByteWriter(std::string& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u16(uint16_t v) { le(v, 2); }
  void u32(uint32_t v) { le(v, 4); }
  void u64(uint64_t v) { le(v, 8); }
  void f64(double v) { uint64_t b; std::memcpy(&b, &v, 8); u64(b); }
  void f32(float v) { uint32_t b; std::memcpy(&b, &v, 4); u32(b); }
  // Unsigned LEB128 (7 bits per byte, high bit = more).
  void varint(uint64_t v) {
    while (v >= 0x80) { u8(static_cast<uint8_t>(v | 0x80)); v >>= 7; }
    u8(static_cast<uint8_t>(v));
  }
  void bytes(std::string_view b) { out_.append(b.data(), b.size()); }
  size_t size() const { return out_.size(); }
  std::string& buffer() { return out_; }

 private:
  void le(uint64_t v, int n) { for (int i = 0; i < n; ++i) out_.push_back(static_cast<char>(v >> (8 * i))); }
  std::string& out_;
};

class ByteReader {
 public:
  ByteReader() = default;
  explicit ByteReader(std::string_view data) : p_(reinterpret_cast<const uint8_t*>(data.data())), end_(p_ + data.size()), begin_(p_) {}
  size_t remaining() const { return static_cast<size_t>(end_ - p_); }
  size_t offset() const { return static_cast<size_t>(p_ - begin_); }
  bool u8(uint8_t& v) { if (remaining() < 1) return false; v = *p_++; return true; }
  bool u16(uint16_t& v) { uint64_t t; if (!le(t, 2)) return false; v = static_cast<uint16_t>(t); return true; }
  bool u32(uint32_t& v) { uint64_t t; if (!le(t, 4)) return false; v = static_cast<uint32_t>(t); return true; }
  bool u64(uint64_t& v) { return le(v, 8); }
  bool f64(double& v) { uint64_t b; if (!u64(b)) return false; std::memcpy(&v, &b, 8); return true; }
  bool f32(float& v) { uint32_t b; if (!u32(b)) return false; std::memcpy(&v, &b, 4); return true; }
  // At most 10 bytes; rejects overlong encodings that overflow 64 bits.
  bool varint(uint64_t& v) {
    v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      uint8_t b;
      if (!u8(b)) return false;
      if (shift == 63 && (b & 0x7e)) return false;
      v |= static_cast<uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return true;
    }
    return false;
  }
  bool bytes(size_t n, std::string_view& out) {
    if (remaining() < n) return false;
    out = std::string_view(reinterpret_cast<const char*>(p_), n);
    p_ += n;
    return true;
  }

 private:
  bool le(uint64_t& v, int n) {
    if (remaining() < static_cast<size_t>(n)) return false;
    v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(p_[i]) << (8 * i);
    p_ += n;
    return true;
  }
  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  const uint8_t* begin_ = nullptr;
};

// A grid's extent as the file stores it (FORMAT.md §3 and §8.12): the
// component whose extent is the largest and that component's maximum
// `top`, so extent = f64(top) - f64(origin[axis]). An extent computed as
// such a difference of two floats (the encoders') always has an axis; for
// any other, axis 0 with top = origin[0] is returned.
inline int extent_axis(const float* origin, int components, double extent, float& top) {
  for (int a = 0; a < components; ++a) {
    top = static_cast<float>(static_cast<double>(origin[a]) + extent);
    if (static_cast<double>(top) - static_cast<double>(origin[a]) == extent) return a;
  }
  top = origin[0];
  return 0;
}

// Streams one after another behind their byte lengths (a segment payload,
// FORMAT.md §4.5, and the mesh section, §4.7): the lengths as varints, the
// streams, then `rest`, whose length is what remains.
inline void write_streams(ByteWriter& w, std::initializer_list<std::string_view> streams, std::string_view rest) {
  for (std::string_view s : streams) w.varint(s.size());
  for (std::string_view s : streams) w.bytes(s);
  w.bytes(rest);
}

// Reads what write_streams wrote into *parts[0 .. N) and `rest`.
enum class StreamsRead { ok, lengths_truncated, stream_past_end };
template <size_t N>
StreamsRead read_streams(ByteReader& r, std::string_view* const (&parts)[N], std::string_view& rest) {
  uint64_t len[N];
  for (size_t i = 0; i < N; ++i)
    if (!r.varint(len[i])) return StreamsRead::lengths_truncated;
  for (size_t i = 0; i < N; ++i)
    if (len[i] > r.remaining() || !r.bytes(static_cast<size_t>(len[i]), *parts[i])) return StreamsRead::stream_past_end;
  r.bytes(r.remaining(), rest);
  return StreamsRead::ok;
}

}  // namespace tsm
