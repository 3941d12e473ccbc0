// libFuzzer target: decoding arbitrary bytes must return a Status, never
// crash, hang or allocate beyond what the input justifies. A decoded mesh
// must be valid.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tsm/tsm.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tsm::Mesh mesh;
  tsm::DecodeOptions options;
  options.max_vertices = 1u << 20;
  options.max_faces = 1u << 21;
  tsm::Status s = tsm::decode(std::string_view(reinterpret_cast<const char*>(data), size), mesh, options);
  if (s.ok() && !mesh.valid()) __builtin_trap();
  tsm::FileInfo info;
  (void)tsm::inspect(std::string_view(reinterpret_cast<const char*>(data), size), info);
  return 0;
}
