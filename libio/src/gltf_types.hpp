// glTF's accessor component types and their sizes, for the pass-through
// reader (io_gltf.cpp) and the transcoder (gltf_document.cpp); no JSON here,
// so that io_gltf.cpp, which has tinygltf's own copy of nlohmann::json, can
// include it.
#pragma once
#include <cstddef>

namespace tsm::gltf {

constexpr int kByte = 5120;
constexpr int kUByte = 5121;
constexpr int kShort = 5122;
constexpr int kUShort = 5123;
constexpr int kUInt = 5125;
constexpr int kFloat = 5126;

// Bytes per component, 0 for an unknown component type.
size_t component_bytes(int component_type);

}  // namespace tsm::gltf
