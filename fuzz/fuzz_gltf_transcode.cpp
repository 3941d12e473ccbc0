// libFuzzer target: the glTF transcoder (tsm/gltf_transcode.hpp) on arbitrary
// bytes, as `tsm decode x.glb` and `tsm encode x.glb -o y.glb` meet them: a
// document with TSM_mesh_compression streams (or Draco / meshopt ones when
// built in) decoded to a plain glTF, and a document compressed. Refusals must
// carry a message and never be internal errors; what the transcoder
// compresses it must decode, and compress again the same way. (Decoding
// passes primitives without an extension through as they are: a broken one
// stays broken, so a plain output is not required to compress.)
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "tsm/gltf_transcode.hpp"

namespace {

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_gltf_transcode: %s\n", what.c_str());
  __builtin_trap();
}

bool run(std::string_view bytes, const char* name, bool compress, tsm::GltfOutput& out,
         tsm::GltfTranscodeReport& report) {
  tsm::GltfTranscodeOptions options;
  options.compress = compress;
  // Level 2 and one thread: the default level's trials took most of an
  // execution's time under the sanitizers (fuzz_roundtrip runs every level).
  options.encode.level = 2;
  options.encode.threads = 1;
  // No folder: a document naming external files is refused, never read.
  const tsm::Status s = tsm::transcode_gltf(bytes, name, "", options, true, "", out, &report);
  if (s.code() == tsm::ErrorCode::internal) fail(std::string(name) + ": internal error: " + s.to_string());
  if (!s.ok() && s.message().empty()) fail(std::string(name) + ": refused without a message");
  return s.ok();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  tsm::GltfOutput plain;
  tsm::GltfTranscodeReport report;
  (void)run(bytes, "fuzz.glb", false, plain, report);
  // Compressing: what the transcoder compressed decodes, and the decoded
  // document compresses again into as many streams, vertices and triangles.
  tsm::GltfOutput packed, again, repacked;
  tsm::GltfTranscodeReport r1, r2, r3;
  if (size > (size_t(1) << 16) || !run(bytes, "fuzz.glb", true, packed, r1)) return 0;
  if (!run(packed.main, "packed.glb", false, again, r2)) fail("the transcoder refused its own compressed output");
  if (!run(again.main, "again.glb", true, repacked, r3)) fail("the transcoder refused its own decoded output");
  if (r3.primitives_compressed != r1.primitives_compressed || r3.vertices != r1.vertices ||
      r3.triangles != r1.triangles)
    fail("compressing the decoded document gave " + std::to_string(r3.primitives_compressed) + " streams, " +
         std::to_string(r3.vertices) + " vertices, " + std::to_string(r3.triangles) + " triangles, the first time " +
         std::to_string(r1.primitives_compressed) + ", " + std::to_string(r1.vertices) + ", " +
         std::to_string(r1.triangles));
  return 0;
}
