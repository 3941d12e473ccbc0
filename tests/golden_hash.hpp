// The golden files' canonical hash of a decoded mesh (tests/golden/): FNV-1a
// (64 bits) over every field of the mesh in a fixed order, little-endian:
// the vertex count and each position's float bits; the face count, the face
// offsets and the corners; per attribute its name, kind, domain, type,
// components, values (float bits) and corner indices; per metadata entry its
// key and value. Header-only, on the public mesh type alone, so the
// decoder-only program (decoder_only.cpp) checks the golden files too.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "tsm/mesh.hpp"

namespace tsm_golden {

class Fnv64 {
 public:
  void bytes(const void* p, size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ b[i]) * 0x100000001b3ull;
  }
  void u64(uint64_t v) {
    unsigned char b[8];
    for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 8);
  }
  void u32(uint32_t v) {
    unsigned char b[4];
    for (int i = 0; i < 4; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, 4);
  }
  void f32(float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    u32(v);
  }
  void str(const std::string& s) {
    u64(s.size());
    bytes(s.data(), s.size());
  }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

inline uint64_t mesh_hash(const tsm::Mesh& m) {
  Fnv64 h;
  h.u64(m.vertex_count());
  for (float x : m.positions) h.f32(x);
  h.u64(m.face_count());
  for (uint32_t x : m.face_offsets) h.u32(x);
  for (uint32_t x : m.indices) h.u32(x);
  h.u64(m.attributes.size());
  for (const tsm::Attribute& a : m.attributes) {
    h.str(a.name);
    h.u32(static_cast<uint32_t>(a.kind));
    h.u32(static_cast<uint32_t>(a.domain));
    h.u32(static_cast<uint32_t>(a.type));
    h.u32(a.components);
    h.u64(a.values.size());
    for (float x : a.values) h.f32(x);
    h.u64(a.indices.size());
    for (uint32_t x : a.indices) h.u32(x);
  }
  h.u64(m.metadata.size());
  for (const tsm::MetadataEntry& e : m.metadata) {
    h.str(e.key);
    h.str(e.value);
  }
  return h.value();
}

inline std::string hex(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

}  // namespace tsm_golden
