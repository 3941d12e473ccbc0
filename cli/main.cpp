// The tsm command-line tool: encode, decode, info, bench.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "tsm/tsm.hpp"

namespace fs = std::filesystem;
using namespace tsm;
using namespace tsm::cli;

namespace {

int fail(const Status& s) {
  std::fprintf(stderr, "tsm: error: %s\n", s.message().c_str());
  return exit_code_for(s);
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

std::string with_extension(const std::string& path, const std::string& ext) {
  fs::path p(path);
  return p.replace_extension(ext).string();
}

struct EncodeArgs {
  std::string input, output;
  int qbits = kDefaultQuantizationBits;
  int level = kDefaultLevel;
  bool force = false, quiet = false, allow_nonfinite = false;
};

int cmd_encode(const EncodeArgs& a) {
  std::string out = a.output.empty() ? with_extension(a.input, ".tsm") : a.output;
  if (same_file(a.input, out))
    return fail(Status(ErrorCode::invalid_argument, out + ": the output would overwrite the input; choose another -o"));
  if (!a.force && fs::exists(out) && format_from_extension(out) != MeshFormat::unknown)
    return fail(Status(ErrorCode::invalid_argument,
                       out + ": exists and looks like a mesh file; pass -f to overwrite it"));
  Stopwatch sw;
  Mesh mesh;
  ReadOptions ro;
  ro.allow_nonfinite = a.allow_nonfinite;
  ReadInfo info;
  Status s = read_mesh(a.input, mesh, ro, &info);
  if (!s.ok()) return fail(s);
  double read_ms = sw.ms();
  sw.reset();
  EncodeOptions eo;
  eo.quantization_bits = a.qbits;
  eo.level = a.level;
  std::string bytes;
  s = encode(mesh, eo, bytes);
  if (!s.ok()) return fail(Status(s.code(), a.input + ": " + s.message()));
  double enc_ms = sw.ms();
  s = write_file_atomic(out, bytes);
  if (!s.ok()) return fail(s);
  if (!a.quiet) {
    if (!info.notes.empty()) std::fprintf(stderr, "tsm: note: %s: %s\n", a.input.c_str(), info.notes.c_str());
    double bpv = mesh.vertex_count() ? 8.0 * static_cast<double>(bytes.size()) / static_cast<double>(mesh.vertex_count()) : 0;
    std::printf("%s: %s vertices, %s faces -> %s: %s bytes, %s bits/vertex (q=%d, level %d), read %s ms, encode %s ms\n",
                a.input.c_str(), thousands(mesh.vertex_count()).c_str(), thousands(mesh.face_count()).c_str(),
                out.c_str(), thousands(bytes.size()).c_str(), fixed(bpv, 2).c_str(), a.qbits, a.level,
                fixed(read_ms, 1).c_str(), fixed(enc_ms, 1).c_str());
  }
  return kExitOk;
}

struct DecodeArgs {
  std::string input, output;
  bool ascii = false, force = false, quiet = false;
  uint64_t max_vertices = 0, max_faces = 0;
};

int cmd_decode(const DecodeArgs& a) {
  std::string out = a.output.empty() ? with_extension(a.input, ".ply") : a.output;
  if (format_from_extension(out) != MeshFormat::ply && format_from_extension(out) != MeshFormat::obj)
    return fail(Status(ErrorCode::invalid_argument, out + ": output must end in .ply or .obj"));
  if (same_file(a.input, out))
    return fail(Status(ErrorCode::invalid_argument, out + ": the output would overwrite the input"));
  if (!a.force && fs::exists(out))
    return fail(Status(ErrorCode::invalid_argument, out + ": exists; pass -f to overwrite it"));
  std::string bytes;
  Status s = read_file(a.input, bytes);
  if (!s.ok()) return fail(s);
  Stopwatch sw;
  Mesh mesh;
  DecodeOptions d;
  d.max_vertices = a.max_vertices;
  d.max_faces = a.max_faces;
  s = decode(bytes, mesh, d);
  if (!s.ok()) return fail(Status(s.code(), a.input + ": " + s.message()));
  double dec_ms = sw.ms();
  WriteOptions wo;
  wo.ascii = a.ascii;
  s = write_mesh(out, mesh, wo);
  if (!s.ok()) return fail(s);
  if (!a.quiet)
    std::printf("%s: %s bytes -> %s: %s vertices, %s faces, decode %s ms\n", a.input.c_str(),
                thousands(bytes.size()).c_str(), out.c_str(), thousands(mesh.vertex_count()).c_str(),
                thousands(mesh.face_count()).c_str(), fixed(dec_ms, 1).c_str());
  return kExitOk;
}

int cmd_info(const std::string& input, bool json) {
  std::string bytes;
  Status s = read_file(input, bytes);
  if (!s.ok()) return fail(s);
  FileInfo fi;
  s = inspect(bytes, fi);
  if (!s.ok()) return fail(Status(s.code(), input + ": " + s.message()));
  const double v = fi.vertex_count ? static_cast<double>(fi.vertex_count) : 1.0;
  auto per_vertex = [v](uint64_t n) { return 8.0 * static_cast<double>(n) / v; };
  const double bpv = per_vertex(fi.file_bytes);
  const uint64_t side = fi.file_bytes - fi.connectivity_bytes - fi.geometry_bytes;  // header, framing, side sections
  if (json) {
    std::printf("{\"file\": \"%s\", \"format_version\": %u, \"bytes\": %llu, \"vertices\": %llu, \"faces\": %llu, "
                "\"corners\": %llu, \"quantization_bits\": %d, \"level\": %d, \"segments\": %u, "
                "\"bbox_min\": [%.9g, %.9g, %.9g], \"step\": %.9g, \"bits_per_vertex\": %.4f, "
                "\"connectivity_bits_per_vertex\": %.4f, \"geometry_bits_per_vertex\": %.4f, "
                "\"side_bits_per_vertex\": %.4f, \"components\": %llu, \"vertex_runs\": %llu, "
                "\"triangle_runs\": %llu, \"marching_bits\": %llu, \"jump_edges\": %llu, \"stitches\": %llu, "
                "\"virtual_vertices\": %llu, \"side_faces\": %llu, \"sections\": [",
                json_escape(input).c_str(), fi.format_version, static_cast<unsigned long long>(fi.file_bytes),
                static_cast<unsigned long long>(fi.vertex_count), static_cast<unsigned long long>(fi.face_count),
                static_cast<unsigned long long>(fi.corner_count), fi.quantization_bits, fi.level, fi.segment_count,
                fi.bbox_min[0], fi.bbox_min[1], fi.bbox_min[2], fi.step, bpv, per_vertex(fi.connectivity_bytes),
                per_vertex(fi.geometry_bytes), per_vertex(side), static_cast<unsigned long long>(fi.components),
                static_cast<unsigned long long>(fi.vertex_runs), static_cast<unsigned long long>(fi.triangle_runs),
                static_cast<unsigned long long>(fi.marching_bits), static_cast<unsigned long long>(fi.jump_edges),
                static_cast<unsigned long long>(fi.stitches), static_cast<unsigned long long>(fi.virtual_vertices),
                static_cast<unsigned long long>(fi.side_faces));
    for (size_t i = 0; i < fi.sections.size(); ++i) {
      const SectionInfo& si = fi.sections[i];
      std::printf("%s{\"id\": %u, \"name\": \"%s\", \"codec\": \"%s\", \"stored_bytes\": %llu, \"raw_bytes\": %llu}",
                  i ? ", " : "", si.id, si.name.c_str(), si.codec.c_str(),
                  static_cast<unsigned long long>(si.stored_bytes), static_cast<unsigned long long>(si.raw_bytes));
    }
    std::printf("]}\n");
    return kExitOk;
  }
  std::printf("%s: tsm format version %u, %s bytes\n", input.c_str(), fi.format_version,
              thousands(fi.file_bytes).c_str());
  std::printf("  vertices %s, faces %s, corners %s, segments %u\n", thousands(fi.vertex_count).c_str(),
              thousands(fi.face_count).c_str(), thousands(fi.corner_count).c_str(), fi.segment_count);
  std::printf("  quantization %d bits (step %.6g), level %d\n", fi.quantization_bits, fi.step, fi.level);
  std::printf("  bits/vertex: %.3f total = %.3f connectivity + %.3f geometry + %.3f header and side data\n", bpv,
              per_vertex(fi.connectivity_bytes), per_vertex(fi.geometry_bytes), per_vertex(side));
  std::printf("  topology: %s components, %s vertex runs, %s triangle runs, %s marching bits, %s jump edges,\n"
              "            %s stitches, %s virtual vertices, %s side faces\n",
              thousands(fi.components).c_str(), thousands(fi.vertex_runs).c_str(), thousands(fi.triangle_runs).c_str(),
              thousands(fi.marching_bits).c_str(), thousands(fi.jump_edges).c_str(), thousands(fi.stitches).c_str(),
              thousands(fi.virtual_vertices).c_str(), thousands(fi.side_faces).c_str());
  std::printf("  %-18s %-6s %12s %12s\n", "section", "codec", "stored", "raw");
  for (const SectionInfo& si : fi.sections)
    std::printf("  %-18s %-6s %12s %12s\n", si.name.c_str(), si.codec.c_str(), thousands(si.stored_bytes).c_str(),
                thousands(si.raw_bytes).c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tsm: triangle mesh compression by Topological Surgery (Taubin & Rossignac)"};
  app.set_version_flag("--version", std::string("tsm ") + version_string());
  app.require_subcommand(1);
  app.footer(
      "Examples:\n"
      "  tsm encode bunny.ply -o bunny.tsm -q 14\n"
      "  tsm decode bunny.tsm -o bunny.ply\n"
      "  tsm info bunny.tsm --json\n"
      "  tsm bench                       # the corpus beside the project, else the default mesh\n"
      "Exit codes: 0 ok, 2 bad command line, 3 bad input file, 4 I/O failure, 5 internal error.");

  EncodeArgs ea;
  CLI::App* enc = app.add_subcommand("encode", "Compress a mesh (PLY, OBJ, STL, OFF) into a .tsm file");
  enc->add_option("input", ea.input, "Mesh file to compress")->required()->check(CLI::ExistingFile);
  enc->add_option("-o,--output", ea.output, "Output .tsm file (default: input name with .tsm)");
  enc->add_option("-q,--quantization", ea.qbits, "Position quantization bits, 1..30")
      ->check(CLI::Range(1, 30))->capture_default_str();
  enc->add_option("-l,--level", ea.level, "Level 0 (fastest decode) .. 9 (smallest)")
      ->check(CLI::Range(0, 9))->capture_default_str();
  enc->add_flag("-f,--force", ea.force, "Overwrite an existing output that looks like a mesh file");
  enc->add_flag("--allow-nonfinite", ea.allow_nonfinite, "Read NaN/inf coordinates (the encoder still refuses them)");
  enc->add_flag("--quiet", ea.quiet, "Print nothing on success");
  enc->footer("Example: tsm encode dragon.ply -o dragon.tsm -q 14 -l 6");

  DecodeArgs da;
  CLI::App* dec = app.add_subcommand("decode", "Decompress a .tsm file into PLY or OBJ");
  dec->add_option("input", da.input, ".tsm file")->required()->check(CLI::ExistingFile);
  dec->add_option("-o,--output", da.output, "Output mesh, .ply (binary) or .obj (default: input name with .ply)");
  dec->add_flag("--ascii", da.ascii, "Write ASCII PLY instead of binary");
  dec->add_flag("-f,--force", da.force, "Overwrite an existing output file");
  dec->add_option("--max-vertices", da.max_vertices, "Refuse files with more vertices (memory bound)")
      ->check(CLI::NonNegativeNumber);
  dec->add_option("--max-faces", da.max_faces, "Refuse files with more faces (memory bound)")
      ->check(CLI::NonNegativeNumber);
  dec->add_flag("--quiet", da.quiet, "Print nothing on success");
  dec->footer("Example: tsm decode dragon.tsm -o dragon.ply");

  std::string info_input;
  bool info_json = false;
  CLI::App* inf = app.add_subcommand("info", "Show the header and sections of a .tsm file");
  inf->add_option("input", info_input, ".tsm file")->required()->check(CLI::ExistingFile);
  inf->add_flag("--json", info_json, "Machine-readable output");
  inf->footer("Example: tsm info dragon.tsm --json");

  std::vector<std::string> bench_meshes;
  bool bench_json = false, bench_quiet = false;
  std::vector<int> bench_q{11, 14};
  int bench_runs = 3, bench_level = kDefaultLevel;
  CLI::App* ben = app.add_subcommand("bench", "Compare tsm with Draco (cl7, cl10) on meshes, in one process");
  ben->add_option("meshes", bench_meshes, "Mesh files (default: the corpus beside the project, else the default mesh)");
  ben->add_option("-q,--quantization", bench_q, "Quantization bits to test (repeatable)")->check(CLI::Range(1, 30));
  ben->add_option("--runs", bench_runs, "Timed runs per measurement (median is shown)")->check(CLI::Range(1, 100));
  ben->add_option("-l,--level", bench_level, "tsm level")->check(CLI::Range(0, 9));
  ben->add_flag("--json", bench_json, "Print JSON instead of the Markdown table");
  ben->add_flag("--quiet", bench_quiet, "No progress lines on stderr");
  ben->footer("Example: tsm bench ../shared/corpus/bun_zipper.ply -q 11 -q 14 --runs 5");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : kExitUsage;
  }
  try {
    if (*enc) return cmd_encode(ea);
    if (*dec) return cmd_decode(da);
    if (*inf) return cmd_info(info_input, info_json);
    if (*ben) return run_bench(bench_meshes, bench_json, bench_q, bench_runs, bench_level, bench_quiet);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "tsm: error: out of memory\n");
    return kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tsm: internal error: %s\n", e.what());
    return kExitInternal;
  }
  return kExitUsage;
}
