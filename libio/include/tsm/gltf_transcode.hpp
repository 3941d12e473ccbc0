// tsm: glTF to glTF. Compresses the triangle primitives of a glTF document
// with the TSM_mesh_compression extension (format-spec/gltf/), or writes a
// plain glTF from a compressed one, keeping the rest of the document (scene
// graph, materials, textures and images, skins, animations, morph targets,
// extras, other extensions). Input compressed with TSM_mesh_compression,
// KHR_draco_mesh_compression or EXT/KHR_meshopt_compression is decoded first
// (the last two need Draco / meshoptimizer at build time).
#pragma once
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tsm/status.hpp"
#include "tsm/tsm.hpp"

namespace tsm {

struct GltfTranscodeOptions {
  bool compress = true;   // false: every primitive as plain accessors (tsm decode)
  bool fallback = false;  // keep an uncompressed copy beside each stream
  EncodeOptions encode;
};

struct GltfTranscodeReport {
  size_t primitives_compressed = 0;
  size_t primitives_kept = 0;  // not triangles, or not compressible (see notes)
  // Of the compressed ones: primitives naming an earlier one's accessors,
  // which name its stream (coded once) and its accessors.
  size_t primitives_shared = 0;
  size_t vertices = 0, triangles = 0;  // of the compressed primitives (a shared stream once)
  size_t stream_bytes = 0;             // sum of the tsm streams
  std::string notes;
  void add_note(const std::string& note) {
    if (note.empty()) return;
    if (!notes.empty()) notes += "; ";
    notes += note;
  }
};

struct GltfOutput {
  std::string main;  // the .glb, or the .gltf JSON
  // Files the output names beside it: the .gltf's buffer (bin_uri) and the
  // images it names by relative URI (copied from the input's folder).
  std::vector<std::pair<std::string, std::string>> files;
};

// bytes: a .gltf or .glb; name: for messages; dir: the folder of its external
// files ("" refuses them). binary: write a GLB (external images embedded),
// else a .gltf whose buffer is the file bin_uri.
Status transcode_gltf(std::string_view bytes, const std::string& name, const std::string& dir,
                      const GltfTranscodeOptions& options, bool binary, const std::string& bin_uri, GltfOutput& out,
                      GltfTranscodeReport* report = nullptr);

// Files: reads `input`, writes `output` (.glb or .gltf by its name; for a
// .gltf also NAME.bin beside it, and the images the document names by
// relative URI, copied when the output is in another folder and never over
// an existing file), each atomically. The caller decides whether `output`
// and NAME.bin may be replaced.
Status transcode_gltf_file(const std::string& input, const std::string& output, const GltfTranscodeOptions& options,
                           GltfTranscodeReport* report = nullptr);

}  // namespace tsm
