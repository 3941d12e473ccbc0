// The transcoder's stages (glTF in, glTF out), shared between their files:
// gltf_compressed_input.cpp decodes compressed input, gltf_extension_write.cpp
// compresses primitives into TSM_mesh_compression.
#pragma once
#include <string>
#include <vector>

#include "gltf_document.hpp"
#include "tsm/gltf_transcode.hpp"

namespace tsm::gltf {

// Turns TSM_mesh_compression, KHR_draco_mesh_compression and
// EXT/KHR_meshopt_compression data into ordinary accessors and views.
Status decompress_document(Document& doc);

// Gives accessor `acc` the values `raw` (count x components, stored values)
// in a new buffer view, in its own componentType; count and min / max (when
// it had them, or for vertex data) follow the data.
Status fill_accessor(Document& doc, size_t acc, const std::vector<double>& raw, uint32_t components, int target);
void set_min_max(ojson& accessor, const std::vector<double>& raw, uint32_t components);

// A morph target displacement a stream holds (TSM_mesh_compression.md,
// "targets"): its grid units times the step, as the float the accessor holds.
inline double target_delta(float units, double step) {
  return static_cast<double>(static_cast<float>(static_cast<double>(units) * step));
}

// What makes two primitives share a stream: the same indices, attributes
// and targets (object member order aside) and mode; "" for a primitive
// that is not an object.
std::string sharing_key(const ojson& prim);

// Compresses every triangle primitive into a TSM_mesh_compression stream.
Status compress_document(Document& doc, const GltfTranscodeOptions& options, GltfTranscodeReport& report);

}  // namespace tsm::gltf
