// A glTF document held for transcoding (tsm encode / decode of glTF to
// glTF): the JSON as given (member order, extensions and extras kept) and
// the bytes of every buffer. Loads .gltf and .glb, reads accessors with
// every offset, stride and count checked, appends new data as buffer views,
// and saves as .glb or .gltf + .bin with the buffer views still in use
// packed into one buffer.
#pragma once
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gltf_types.hpp"
#include "tsm/status.hpp"

namespace tsm::gltf {

using ojson = nlohmann::ordered_json;

constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

struct Document {
  ojson json;
  std::vector<std::string> buffers;  // bytes of json["buffers"][i]
  std::string name;                  // the input, for messages
  std::string dir;                   // folder of external files ("" : none are read)
  // A JSON member of `obj` as an index, or -1 when absent; errors when it is
  // present but not an integer in 0..limit-1.
  Status index_of(const ojson& obj, const char* key, size_t limit, const std::string& where, int64_t& out) const;
  size_t count_of(const char* array) const;
  Status error(const std::string& what) const;
};

// Parses a .glb or .gltf and loads its buffers (GLB chunk, data: URIs, files
// beside the .gltf in `dir`).
Status load_document(std::string_view bytes, const std::string& name, const std::string& dir, Document& doc);

// Components of "SCALAR", "VEC2", "VEC3", "VEC4"; 0 for others.
uint32_t type_components(const std::string& type);
const char* type_for_components(uint32_t components);

// An accessor's values, as stored (integers as their integer value) or,
// for values(), with the spec's normalization applied.
struct AccessorData {
  int component_type = kFloat;
  uint32_t components = 1;
  bool normalized = false;
  size_t count = 0;
  std::vector<double> raw;  // count * components
  std::vector<float> values() const;
};

// Reads accessor `index` (dense and sparse; no buffer view: zeros).
Status read_accessor(const Document& doc, size_t index, AccessorData& out);
// Reads an indices accessor (SCALAR unsigned byte / short / int).
Status read_indices(const Document& doc, size_t index, std::vector<uint32_t>& out);

// Appends `bytes` as a new buffer (one per call) and a buffer view on it;
// returns the view's index. target 0: none; stride 0: none.
size_t add_buffer_view(Document& doc, std::string bytes, int target, size_t stride);
// The bytes of `count` values of `components` components of type
// `component_type` (integers from raw values, rounded and clamped), each
// element padded to a multiple of 4 bytes when `target` is vertex data.
std::string pack_values(const std::vector<double>& raw, int component_type, uint32_t components, int target,
                        size_t* stride);

// Adds / removes a name in extensionsUsed / extensionsRequired.
void use_extension(ojson& json, const std::string& name, bool required);
void drop_extension(ojson& json, const std::string& name);
// KHR_mesh_quantization out of extensionsUsed/Required when no mesh
// attribute it covers (POSITION, NORMAL, TANGENT, TEXCOORD_n, also in morph
// targets) has an integer component type any more.
void drop_unused_mesh_quantization(ojson& json);

// The document's image URIs naming files (not data: URIs).
std::vector<std::string> image_files(const Document& doc);

// Serializes: the buffer views referenced anywhere in the JSON ("bufferView"
// members) packed into one buffer, the others dropped; the generator set.
// binary: a GLB in `main`; else the JSON in `main` and the buffer in `bin`,
// which `bin_uri` names.
Status save_document(Document& doc, bool binary, const std::string& bin_uri, std::string& main, std::string& bin);

}  // namespace tsm::gltf
