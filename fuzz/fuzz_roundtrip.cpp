// libFuzzer target: a mesh built from the fuzzer's bytes (vertex count, then
// faces of 1..6 corners over those vertices) must encode, decode and compare
// equal under the oracle.
#include <cstddef>
#include <cstdint>
#include <string>

#include "tsm/tsm.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  tsm::Mesh m;
  uint32_t nv = 1 + data[0] % 64;
  for (uint32_t i = 0; i < nv; ++i)
    m.add_vertex(static_cast<float>(i % 7), static_cast<float>((i * 3) % 11), static_cast<float>((i * 5) % 13));
  size_t at = 1;
  uint32_t corners[6];
  while (at < size) {
    uint32_t n = 1 + data[at++] % 6;
    if (at + n > size) break;
    for (uint32_t i = 0; i < n; ++i) corners[i] = data[at++] % nv;
    m.add_face(corners, n);
  }
  std::string bytes;
  if (!tsm::encode(m, tsm::EncodeOptions{}, bytes).ok()) __builtin_trap();
  tsm::Mesh back;
  if (!tsm::decode(bytes, back).ok()) __builtin_trap();
  if (!tsm::compare_meshes(m, back, tsm::kDefaultQuantizationBits).equal) __builtin_trap();
  return 0;
}
