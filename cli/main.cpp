// The tsm command-line tool: encode, decode, info, bench.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "commands.hpp"
#include "tsm/tsm.hpp"

using namespace tsm;
using namespace tsm::cli;

namespace {

// An existing file, or "-" for stdin.
const CLI::Validator kFileOrStdin(
    [](std::string& path) -> std::string {
      if (path == "-") return std::string();
      std::string copy = path;
      return CLI::ExistingFile(copy);
    },
    "FILE|-", "file or -");

// The options every file command shares.
void add_batch_options(CLI::App* cmd, BatchArgs& b, bool quiet) {
  cmd->add_option("-j,--jobs", b.jobs,
                  "Worker threads: files processed at once, or for one file its segments; 0 = number of cores")
      ->check(CLI::Range(0, 1024))->default_str("cores");
  cmd->add_flag("--json", b.json, "One JSON object per input file on stdout (JSON lines), success or failure");
  if (quiet) cmd->add_flag("--quiet", b.quiet, "Print nothing on success: no report, progress bar or summary");
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
      "  tsm encode meshes/*.ply -o packed/ -j 4     # many files: packed/NAME.tsm\n"
      "  tsm encode - --input-format obj < a.obj | tsm decode - --format ply > a.ply\n"
      "  tsm info bunny.tsm --json\n"
      "  tsm bench                                   # the corpus beside the project, else the default mesh\n"
      "Exit codes: 0 ok, 2 bad command line, 3 bad input file, 4 I/O failure, 5 internal error;\n"
      "for several files, the worst of them. `tsm COMMAND --help` shows each command's options.");

  EncodeArgs ea;
  CLI::App* enc = app.add_subcommand("encode", "Compress meshes (PLY, OBJ, STL, OFF, glTF/GLB) into .tsm files");
  enc->add_option("inputs", ea.inputs, "Mesh files to compress; - reads one mesh from stdin")
      ->required()->check(kFileOrStdin);
  enc->add_option("-o,--output", ea.output,
                  "Output: a .tsm file (one input), a folder (DIR/, or several inputs: DIR/NAME.tsm), or - for "
                  "stdout (default: beside each input, NAME.tsm; stdout for stdin)");
  enc->add_option("-q,--quantization", ea.qbits, "Position quantization bits, 1..30")
      ->check(CLI::Range(1, 30))->capture_default_str();
  enc->add_option("-l,--level", ea.level, "Level 0 (fastest decode) .. 9 (smallest): 0 decodes about 2x faster than Draco, 1-2 a little "
                 "slower and smaller (2 below Draco's default size on scans), 3-6 smaller, 7-9 smallest and slowest")
      ->check(CLI::Range(0, 9))->capture_default_str();
  enc->add_option("--normal-bits", ea.attribute_bits.normal, "Float normals: octahedral bits per axis, 1..24")
      ->check(CLI::Range(1, 24))->capture_default_str();
  enc->add_option("--texcoord-bits", ea.attribute_bits.texcoord, "Float texture coordinates: grid bits, 1..24")
      ->check(CLI::Range(1, 24))->capture_default_str();
  enc->add_option("--color-bits", ea.attribute_bits.color, "Float colours: grid bits, 1..24 (8/16-bit colours are exact)")
      ->check(CLI::Range(1, 24))->capture_default_str();
  enc->add_option("--generic-bits", ea.attribute_bits.generic,
                  "Other float attributes (e.g. PLY confidence): grid bits, 1..24 (integer ones are exact)")
      ->check(CLI::Range(1, 24))->capture_default_str();
  enc->add_option("--segment-faces", ea.segment_faces,
                  "Code meshes with more faces as segments of at most this many (streaming, parallel decoding); "
                  "0 = default (262144)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  enc->add_option("--format-version", ea.format_version,
                  "Write this format version: 11 (the newest; by default each file says the oldest version that "
                  "reads it), 10 for decoders of version 10 (non-manifold meshes without version 11's stitch targets "
                  "by candidates: 1% larger on the low-resolution dragons, twice as large on double-sided meshes), 9 for decoders of version 9 (levels 1-2 without version 10's fan predictor: "
                  "3-6% larger), 8 for decoders of version 8 (levels 0-2 without version 9's table-coded connectivity "
                  "run values: slower to decode, 0.2-1% smaller), 7 for decoders of version 7 (levels 0-2 without "
                  "version 8's table-coded residuals either: slower to decode, 1-2% smaller), 6 for decoders of version 6 (no lattice planes from the top: a few bytes more on "
                  "boxes), 5 for decoders of version 5 (no residual mixing either, which only levels 7-9 use), "
                  "or 4 for decoders of version 4 (no tangent step either; usually slightly larger)")
      ->check(CLI::Range(4, 11));
  enc->add_option("--input-format", ea.input_format,
                  "Read the inputs as this format instead of guessing from content and extension (needed for OBJ on stdin)")
      ->check(CLI::IsMember({"ply", "obj", "stl", "off", "gltf", "glb"}, CLI::ignore_case));
  enc->add_flag("-f,--force", ea.force, "Overwrite existing output files (never an input)");
  enc->add_flag("--allow-nonfinite", ea.allow_nonfinite, "Read NaN/inf coordinates (the encoder still refuses them)");
  add_batch_options(enc, ea, true);
  enc->footer(
      "Examples:\n"
      "  tsm encode dragon.ply -o dragon.tsm -q 14 -l 6\n"
      "  tsm encode meshes/*.ply meshes/*.obj -o packed/ -j 4     # packed/NAME.tsm for each\n"
      "  tsm encode --input-format obj - < part.obj > part.tsm    # stdin to stdout\n"
      "  tsm encode *.stl -o out/ --json --quiet | jq .bits_per_vertex\n"
      "An existing output is never replaced without -f, an input never. In a batch a failed file does not stop\n"
      "the others; failures are listed at the end and the exit code is the worst one (3 bad input, 4 I/O).");

  DecodeArgs da;
  CLI::App* dec = app.add_subcommand("decode", "Decompress .tsm files into " + output_formats_text());
  dec->add_option("inputs", da.inputs, ".tsm files; - reads one from stdin")->required()->check(kFileOrStdin);
  dec->add_option("-o,--output", da.output,
                  "Output: a " + output_extensions_text() + " file (one input), a folder (DIR/, or several inputs: DIR/NAME.ply), or - for "
                  "stdout (default: beside each input, NAME.ply; stdout for stdin)");
  dec->add_option("--format", da.format,
                  "Output format, " + output_formats_bar() + " (default: the extension of -o FILE, else ply)")
      ->check(CLI::IsMember(output_format_names(), CLI::ignore_case));
  dec->add_flag("--ascii", da.ascii, "Write ASCII PLY or STL instead of binary");
  dec->add_flag("-f,--force", da.force, "Overwrite existing output files (never an input)");
  dec->add_option("--max-vertices", da.max_vertices, "Refuse files with more vertices (memory bound)")
      ->check(CLI::NonNegativeNumber);
  dec->add_option("--max-faces", da.max_faces, "Refuse files with more faces (memory bound)")
      ->check(CLI::NonNegativeNumber);
  dec->add_option("--max-corners", da.max_corners,
                  "Refuse files with more face corners (default with --max-faces: 16 x that)")
      ->check(CLI::NonNegativeNumber);
  add_batch_options(dec, da, true);
  dec->footer(
      "Examples:\n"
      "  tsm decode dragon.tsm -o dragon.ply\n"
      "  tsm decode packed/*.tsm -o meshes/ --format obj -j 4    # meshes/NAME.obj for each\n"
      "  curl -s https://example.org/part.tsm | tsm decode - --format obj > part.obj\n"
      "  tsm encode - --input-format ply < in.ply | tsm decode - -o out.ply\n"
      "Outputs appear atomically (temporary file + rename): a failed or interrupted run leaves no partial file.");

  InfoArgs ia;
  CLI::App* inf = app.add_subcommand("info", "Show the header and sections of .tsm files");
  inf->add_option("inputs", ia.inputs, ".tsm files; - reads one from stdin")->required()->check(kFileOrStdin);
  add_batch_options(inf, ia, false);
  inf->footer(
      "Examples:\n"
      "  tsm info dragon.tsm\n"
      "  tsm info packed/*.tsm --json | jq -s 'map(.bits_per_vertex)'\n"
      "  tsm encode bunny.ply -o - | tsm info -");

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
  ben->footer(
      "Examples:\n"
      "  tsm bench ../shared/corpus/bun_zipper.ply -q 11 -q 14 --runs 5\n"
      "  tsm bench --json --quiet > bench.json");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : kExitUsage;
  }
  try {
    if (*enc) return cmd_encode(ea);
    if (*dec) return cmd_decode(da);
    if (*inf) return cmd_info(ia);
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
