// libFuzzer target: a mesh built from the fuzzer's bytes must encode, decode
// and compare equal under the oracle tsm::compare_meshes; encoding must be
// deterministic. Any mismatch aborts.
//
// Input layout (make_seeds.cpp writes seeds in it):
//   byte 0   quantization bits, 1 + b % 30; bit 7: with attributes (a u8
//            colour and a normal per vertex, an i32 per face, and a texture
//            coordinate per corner with seams and values shared far apart,
//            across segment borders too); with byte 3's bit 7 also split
//            vertices: about half the corners get a copy of their vertex
//   byte 1   level b % 10 (low nibble), position mode (b >> 4) % 4, bit 6:
//            also check that a second encode gives the same bytes, bit 7:
//            segments of at most 8 + byte 2 % 32 faces, also decoded
//            streaming in chunks of 1 + byte 3 % 64 bytes
//   byte 2   vertex count, 1 + b
//   byte 3   scale exponent, b % 164 - 40 (positions are scaled by 2^e)
//   then faces: a corner count 1 + b % 6, then that many vertex bytes (b % n).
// Position modes: 0 a lattice of distinct points, 1 pseudo-random points,
// 2 only three distinct points (coincident vertices), 3 the lattice far from
// the origin (coordinates much larger than the mesh).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "tsm/compare.hpp"
#include "tsm/tsm.hpp"

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_roundtrip: %s\n", what.c_str());
  __builtin_trap();
}

uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

void position(uint32_t i, int mode, float scale, float out[3]) {
  const float lattice[3] = {static_cast<float>(i % 7), static_cast<float>((i * 3) % 11),
                            static_cast<float>((i * 5) % 13)};
  for (int a = 0; a < 3; ++a) {
    float x = lattice[a];
    if (mode == 1) x = static_cast<float>(mix(i * 3u + static_cast<uint32_t>(a)) >> 40) / 16777216.0f;
    if (mode == 2) x = static_cast<float>((i % 3) * (a + 1));
    out[a] = x * scale;
    if (mode == 3) out[a] += 1.0e4f * scale;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  tsm::EncodeOptions options;
  options.quantization_bits = 1 + data[0] % 30;
  options.level = (data[1] & 15) % 10;
  // At least 8 faces per segment: one-face segments at level 9 took over the
  // 30 s limit under ASan on a loaded machine (0.06 s natively; the slowness
  // is the sanitizer's, not a hang).
  if (data[1] & 0x80) options.segment_faces = 8 + data[2] % 32;
  const int mode = (data[1] >> 4) % 4;
  const uint32_t nv = 1u + data[2];
  const float scale = std::ldexp(1.0f, data[3] % 164 - 40);
  tsm::Mesh m;
  for (uint32_t i = 0; i < nv; ++i) {
    float p[3];
    position(i, mode, scale, p);
    m.add_vertex(p[0], p[1], p[2]);
  }
  size_t at = 4;
  uint32_t corners[6];
  while (at < size) {
    const uint32_t n = 1 + data[at++] % 6;
    if (at + n > size) break;
    for (uint32_t i = 0; i < n; ++i) corners[i] = data[at++] % nv;
    m.add_face(corners, n);
  }
  uint32_t na = nv;  // vertices that carry attributes
  if ((data[0] & 0x80) && (data[3] & 0x80)) {
    // Split vertices (FORMAT.md §8.13, welded): about half the corners get
    // a copy of their vertex of their own (other attribute values at the
    // same position, as flat shading and seams make them).
    for (size_t k = 0; k < m.indices.size(); ++k)
      if (mix(k + 7) & 1) {
        const uint32_t v = m.indices[k];
        m.add_vertex(m.positions[3 * size_t{v}], m.positions[3 * size_t{v} + 1], m.positions[3 * size_t{v} + 2]);
        m.indices[k] = static_cast<uint32_t>(m.vertex_count() - 1);
      }
    na = static_cast<uint32_t>(m.vertex_count());
  }
  if (data[0] & 0x80) {
    tsm::Attribute c, n, f, t;
    c.name = "color";
    c.kind = tsm::AttributeKind::color;
    c.type = tsm::AttributeType::u8;
    c.components = 3;
    n.name = "normal";
    n.kind = tsm::AttributeKind::normal;
    n.components = 3;
    for (uint32_t i = 0; i < na; ++i) {
      for (uint32_t k = 0; k < 3; ++k) c.values.push_back(static_cast<float>(mix(i * 7u + k) & 255));
      for (uint32_t k = 0; k < 3; ++k) n.values.push_back(static_cast<float>(static_cast<int64_t>(mix(i * 5u + k) % 2001) - 1000));
    }
    f.name = "part";
    f.domain = tsm::AttributeDomain::face;
    f.type = tsm::AttributeType::i32;
    for (size_t k = 0; k < m.face_count(); ++k) f.values.push_back(static_cast<float>(static_cast<int64_t>(mix(k) % 4001) - 2000));
    m.attributes = {c, n, f};
    {
      t.name = "texcoord";
      t.kind = tsm::AttributeKind::texcoord;
      t.domain = tsm::AttributeDomain::corner;
      t.components = 2;
      for (size_t k = 0; k < m.corner_count(); ++k) {
        const uint64_t r = mix(k + 99);
        t.indices.push_back(r & 1 ? m.indices[k] : na + static_cast<uint32_t>(r % 5));
      }
      for (uint32_t j = 0; j < na + 5; ++j) {
        t.values.push_back(static_cast<float>(mix(j) % 1000) / 999.0f);
        t.values.push_back(static_cast<float>(mix(j + 1000) % 1000) / 999.0f);
      }
      m.attributes.push_back(t);
    }
  }
  if (!m.all_finite()) return 0;  // the encoder refuses those by design
  std::string bytes;
  tsm::Status s = tsm::encode(m, options, bytes);
  if (!s.ok()) fail("encode refused a valid mesh: " + s.to_string());
  std::string bytes2;
  if ((data[1] & 0x40) && (!tsm::encode(m, options, bytes2).ok() || bytes2 != bytes))
    fail("encoding is not deterministic");
  tsm::Mesh back;
  s = tsm::decode(bytes, back);
  if (!s.ok()) fail("decode refused the encoder's output: " + s.to_string());
  std::string why;
  if (!back.valid(&why)) fail("decoded an invalid mesh: " + why);
  tsm::FileInfo info;
  s = tsm::inspect(bytes, info);
  if (!s.ok()) fail("inspect refused the encoder's output: " + s.to_string());
  if (info.vertex_count != m.vertex_count() || info.face_count != m.face_count() || info.corner_count != m.corner_count())
    fail("inspect's counts differ from the mesh");
  tsm::CompareResult cr = tsm::compare_meshes(m, back, options.quantization_bits);
  if (!cr.equal) fail("oracle: the decoded mesh differs: " + cr.difference);
  // Canonical re-encoding: the decoded mesh codes to the same bytes. The
  // known exception (README "Canonical re-encoding") left out: vertices
  // sharing a grid cell, told apart only by their ids.
  if (data[1] & 0x40) {
    std::vector<std::array<float, 3>> cells(back.vertex_count());
    for (size_t v = 0; v < cells.size(); ++v)
      cells[v] = {back.positions[3 * v], back.positions[3 * v + 1], back.positions[3 * v + 2]};
    std::sort(cells.begin(), cells.end());
    std::string again;
    if (std::adjacent_find(cells.begin(), cells.end()) == cells.end() &&
        (!tsm::encode(back, options, again).ok() || again != bytes))
      fail("re-encoding the decoded mesh gives other bytes");
  }
  if (options.segment_faces) {
    tsm::StreamDecoder sd;
    const size_t chunk = 1 + data[3] % 64;
    for (size_t pos = 0; pos < bytes.size(); pos += chunk) {
      s = sd.feed(std::string_view(bytes).substr(pos, chunk));
      if (!s.ok()) fail("the stream decoder refused the encoder's output: " + s.to_string());
    }
    s = sd.finish();
    if (!s.ok()) fail("the stream decoder refused the encoder's output: " + s.to_string());
    const tsm::Mesh& sm = sd.mesh();
    if (sm.positions != back.positions || sm.indices != back.indices || sm.face_offsets != back.face_offsets)
      fail("streamed and whole decoding differ");
  }
  return 0;
}
