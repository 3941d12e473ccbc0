// glTF to glTF for encode and decode: `tsm encode in.glb -o out.glb`
// compresses the triangle primitives with TSM_mesh_compression
// (format-spec/gltf/), `tsm decode out.glb -o plain.glb` writes them back as
// ordinary accessors; the rest of the document is kept (tsm/gltf_transcode.hpp).
// Other mesh files given to encode with a glTF output become a one-primitive
// glTF first.
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_util.hpp"
#include "commands.hpp"
#include "tsm/gltf_transcode.hpp"
#include "tsm/io.hpp"

namespace tsm::cli {

namespace {

namespace fs = std::filesystem;

int fail(const Status& s) {
  std::fprintf(stderr, "tsm: error: %s\n", printable(s.message()).c_str());
  return exit_code_for(s);
}

int refuse(const std::string& message) {
  std::fprintf(stderr, "tsm: error: %s\n", printable(message).c_str());
  return kExitUsage;
}

bool is_gltf_name(const std::string& path) {
  const MeshFormat f = format_from_extension(path);
  return f == MeshFormat::gltf || f == MeshFormat::glb;
}

// The checks both commands make before writing: one input file, one glTF
// output that is not the input and does not exist unless forced.
int check_files(const BatchArgs& a, const std::string& output, bool force, const char* command) {
  if (a.inputs.size() != 1 || a.inputs[0] == "-")
    return refuse(std::string(command) + " with a glTF output takes one input file (not stdin); run it once per file");
  if (a.json) return refuse("--json is not available with a glTF output; drop it");
  std::error_code ec;
  if (!fs::exists(a.inputs[0], ec)) return fail(Status(ErrorCode::io_error, a.inputs[0] + ": no such file"));
  if (fs::equivalent(a.inputs[0], output, ec)) return refuse(output + ": is the input; give another output name");
  if (!force && fs::exists(output, ec)) return refuse(output + ": already exists; pass -f (--force) to overwrite it");
  // A .gltf output's buffer file beside it.
  if (format_from_extension(output) == MeshFormat::gltf) {
    const fs::path bin = fs::path(output).replace_extension(".bin");
    if (fs::equivalent(a.inputs[0], bin, ec))
      return refuse(bin.string() + ": the .bin beside the output would be the input; give another output name");
    if (!force && fs::exists(bin, ec))
      return refuse(bin.string() + " (the output's buffer file): already exists; pass -f (--force) to overwrite it");
  }
  return kExitOk;
}

int run(const std::string& input, const std::string& output, const GltfTranscodeOptions& options, bool quiet,
        const char* verb) {
  GltfTranscodeReport report;
  Status s;
  if (is_gltf_name(input) || !options.compress) {
    s = transcode_gltf_file(input, output, options, &report);
  } else {
    // Another mesh format: one primitive of a plain glTF, then compressed.
    Mesh mesh;
    s = read_mesh(input, mesh);
    std::string plain;
    if (s.ok()) s = write_gltf(mesh, WriteOptions(), plain, true);
    GltfOutput out;
    const bool binary = format_from_extension(output) == MeshFormat::glb;
    const std::string bin_uri = fs::path(output).stem().string() + ".bin";
    if (s.ok()) s = transcode_gltf(plain, input, "", options, binary, bin_uri, out, &report);
    const fs::path dir = fs::path(output).parent_path();
    std::error_code ec;
    if (!dir.empty()) fs::create_directories(dir, ec);
    for (size_t i = 0; s.ok() && i < out.files.size(); ++i)
      s = write_file_atomic((dir / out.files[i].first).string(), out.files[i].second);
    if (s.ok()) s = write_file_atomic(output, out.main);
  }
  if (!s.ok()) return fail(s);
  if (quiet) return kExitOk;
  if (!report.notes.empty()) std::fprintf(stderr, "tsm: note: %s\n", printable(report.notes).c_str());
  std::error_code ec;
  const auto out_bytes = fs::file_size(output, ec);
  std::string what;
  if (options.compress)
    what = strf(", %s compressed (%s, %s; streams %s), %zu kept",
                count_of(report.primitives_compressed, "primitive", "primitives").c_str(),
                count_of(report.vertices, "vertex", "vertices").c_str(),
                count_of(report.triangles, "triangle", "triangles").c_str(),
                count_of(report.stream_bytes, "byte", "bytes").c_str(), report.primitives_kept);
  std::printf("%s: %s -> %s: %s%s\n", printable(input).c_str(), verb, printable(output).c_str(),
              count_of(static_cast<unsigned long long>(out_bytes), "byte", "bytes").c_str(), what.c_str());
  return kExitOk;
}

}  // namespace

bool gltf_output(const BatchArgs& a, const std::string& output) {
  return a.inputs.size() == 1 && a.inputs[0] != "-" && is_gltf_name(output);
}

int gltf_encode(const EncodeArgs& a) {
  if (int rc = check_files(a, a.output, a.force, "encode")) return rc;
  if (!a.max_error.empty()) return refuse("--max-error is not available with a glTF output; drop it");
  GltfTranscodeOptions o;
  o.fallback = a.fallback;
  o.encode.quantization_bits = a.qbits;
  o.encode.level = a.level;
  o.encode.segment_faces = a.segment_faces;
  o.encode.attribute_bits = a.attribute_bits;
  o.encode.keep_order = a.keep_order;
  o.encode.lossless = a.lossless;
  o.encode.allow_nonfinite = a.allow_nonfinite;
  o.encode.threads = static_cast<int>(a.jobs);
  return run(a.inputs[0], a.output, o, a.quiet, "compressed glTF");
}

int gltf_decode(const DecodeArgs& a) {
  if (int rc = check_files(a, a.output, a.force, "decode")) return rc;
  if (!is_gltf_name(a.inputs[0]))
    return refuse(a.inputs[0] +
                  ": decode writes glTF from a glTF (.glb / .gltf) input; a .tsm file decodes to "
                  "glTF through its own name: tsm decode NAME.tsm -o NAME.glb");
  GltfTranscodeOptions o;
  o.compress = false;
  return run(a.inputs[0], a.output, o, a.quiet, "plain glTF");
}

}  // namespace tsm::cli
