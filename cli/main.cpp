// The tsm command-line tool: encode, decode, info, bench, compare, simplify.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "commands.hpp"
#include "mesh_commands.hpp"
#include "tsm/tsm.hpp"

using namespace tsm;
using namespace tsm::cli;

namespace {

// Input files are not checked here: a missing file or a folder is one
// failing input of the batch (exit code 4), never a reason to stop the
// others (see commands.cpp).

// Edit distance between two names (case-insensitive; insertions,
// deletions, substitutions and swaps of neighbours count 1), for suggestions.
size_t edit_distance(const std::string& a, const std::string& b) {
  auto low = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; };
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (low(a[i - 1]) == low(b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && low(a[i - 1]) == low(b[j - 2]) && low(a[i - 2]) == low(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// The nearest of `names` to `word`, or "" when none is near enough to be a
// likely misspelling.
std::string nearest(const std::string& word, const std::vector<std::string>& names) {
  std::string best;
  size_t best_d = std::string::npos;
  for (const std::string& n : names) {
    const size_t d = edit_distance(word, n);
    if (d < best_d) best_d = d, best = n;
  }
  return best_d <= std::max<size_t>(1, std::min(word.size(), best.size()) / 3) ? best : std::string();
}

// All the names of an option, as the user types them: "-q/--quantization".
std::string option_names(const CLI::Option* o) {
  std::string r;
  for (const std::string& s : o->get_snames()) r += (r.empty() ? "-" : "/-") + s;
  for (const std::string& l : o->get_lnames()) r += (r.empty() ? "--" : "/--") + l;
  return r;
}

// A suggestion for an unknown option of `cmd`: the option whose long name is
// nearest (a misspelling), that it begins (an abbreviation), or whose short
// name is its first letter when the rest names what it sets ("--qbits": -q,
// "Position quantization bits"); "" when nothing fits.
std::string suggest_option(const CLI::App* cmd, const std::string& unknown) {
  std::string word = unknown.substr(unknown.find_first_not_of('-'));
  std::vector<std::string> longs;
  for (const CLI::Option* o : cmd->get_options())
    for (const std::string& l : o->get_lnames()) longs.push_back(l);
  const CLI::Option* found = nullptr;
  const std::string near = nearest(word, longs);
  for (const CLI::Option* o : cmd->get_options()) {
    for (const std::string& l : o->get_lnames())
      if ((!near.empty() && l == near) || (near.empty() && word.size() >= 2 && l.compare(0, word.size(), word) == 0))
        found = found ? found : o;
  }
  if (!found && word.size() > 1) {
    // The word's parts ("format-version": format, version), and the first
    // part without its first letter ("qbits": bits).
    std::vector<std::string> parts;
    for (size_t at = 0; at < word.size();) {
      const size_t end = std::min(word.find('-', at), word.find('_', at));
      parts.push_back(word.substr(at, end == std::string::npos ? std::string::npos : end - at));
      if (end == std::string::npos) break;
      at = end + 1;
    }
    parts.push_back(parts[0].substr(1));
    for (const CLI::Option* o : cmd->get_options()) {
      std::string about = o->get_description();
      for (const std::string& l : o->get_lnames()) about += " " + l;
      for (char& c : about) c = c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
      bool named = false;
      for (const std::string& p : parts) named = named || (p.size() >= 3 && about.find(p) != std::string::npos);
      for (const std::string& sn : o->get_snames())
        if (named && sn.size() == 1 && sn[0] == word[0]) found = found ? found : o;
    }
  }
  return found ? option_names(found) : std::string();
}

// Looks for what CLI11 would only call "not expected" or "a subcommand is
// required": a misspelt command, an unknown option. Returns true (message
// printed) when the command line is refused.
bool refuse_unknown_words(const CLI::App& app, int argc, char** argv) {
  std::vector<std::string> commands;
  for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; })) commands.push_back(c->get_name());
  std::string all;
  for (size_t i = 0; i < commands.size(); ++i)
    all += (i == 0 ? "" : i + 1 == commands.size() ? " or " : ", ") + commands[i];
  if (argc < 2) {
    std::fprintf(stderr, "tsm: error: give a command: %s (tsm --help shows what each does)\n", all.c_str());
    return true;
  }
  const std::string first = argv[1];
  if (first.empty() || first[0] == '-') return false;  // --help, --version, or CLI11 says what is wrong
  const CLI::App* cmd = nullptr;
  for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; }))
    if (c->get_name() == first) cmd = c;
  if (!cmd) {
    const std::string near = nearest(first, commands);
    if (!near.empty())
      std::fprintf(stderr, "tsm: error: unknown command '%s'; did you mean 'tsm %s'? (the commands: %s)\n",
                   printable(first).c_str(), near.c_str(), all.c_str());
    else
      std::fprintf(stderr, "tsm: error: unknown command '%s'; the commands are %s (tsm --help shows them)\n",
                   printable(first).c_str(), all.c_str());
    return true;
  }
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;  // the rest are file names
    if (arg.size() < 2 || arg[0] != '-') continue;
    if (arg[1] >= '0' && arg[1] <= '9') continue;  // a negative number: the option before it says
    std::string name = arg[1] == '-' ? arg.substr(0, arg.find('=')) : arg.substr(0, 2);
    if (cmd->get_option_no_throw(name) || name == "--help" || name == "-h") continue;
    const std::string hint = suggest_option(cmd, name);
    std::fprintf(stderr, "tsm: error: unknown option %s for tsm %s%s (tsm %s --help lists the options)\n",
                 printable(name).c_str(), first.c_str(), hint.empty() ? "" : ("; did you mean " + hint + "?").c_str(),
                 first.c_str());
    return true;
  }
  return false;
}

// The options every file command shares.
void add_batch_options(CLI::App* cmd, BatchArgs& b, bool quiet) {
  cmd->add_option("-j,--jobs", b.jobs,
                  "Worker threads: files processed at once, or for one file its segments; 0 = number of cores")
      ->check(CLI::Range(0, 1024))->default_str("cores");
  cmd->add_flag("--json", b.json,
                "One JSON object per input file on stdout (JSON lines), success or failure; bytes of a file name "
                "that are not UTF-8 show as U+FFFD");
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
      "  tsm simplify bunny.ply -o small.ply --max-error 0.5%\n"
      "  tsm compare bunny.ply small.ply             # Hausdorff, mean, RMS distances\n"
      "Exit codes: 0 ok, 2 bad command line, 3 bad input file, 4 I/O failure (an input missing,\n"
      "a folder or unreadable; an output not writable), 5 internal error;\n"
      "for several files, the worst of them. `tsm COMMAND --help` shows each command's options.");

  EncodeArgs ea;
  CLI::App* enc = app.add_subcommand("encode", "Compress meshes (PLY, OBJ, STL, OFF, glTF/GLB) into .tsm files");
  enc->add_option("inputs", ea.inputs, "Mesh files to compress; - reads one mesh from stdin")
      ->required();
  enc->add_option("-o,--output", ea.output,
                  "Output: a .tsm file (one input; missing folders are created), a folder (DIR/, or several inputs: "
                  "DIR/NAME.tsm), or - for stdout (default: beside each input, NAME.tsm; stdout for stdin)");
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
  enc->add_option("--input-format", ea.input_format,
                  "Read the inputs as this format instead of guessing from content and extension (needed for OBJ on stdin)")
      ->check(CLI::IsMember({"ply", "obj", "stl", "off", "gltf", "glb"}, CLI::ignore_case));
  enc->add_option("--max-error", ea.max_error,
                  "Simplify first (tsm simplify): the result stays within this distance of the input, in model units "
                  "or E% of the bounding-box diagonal");
  enc->add_flag("--progressive", ea.progressive,
                "A progressive file: a coarse base mesh, then batches of vertex splits, so that any prefix decodes to "
                "the whole shape at some level of detail (positions and faces only)");
  enc->add_flag("--drop-attributes", ea.drop_attributes,
                "Code positions and faces only, leaving out normals, colours, texture coordinates and the like "
                "(progressive files carry none)");
  enc->add_flag("--keep-order", ea.keep_order,
                "The decoded mesh keeps the input's vertex order, face order and first corners (costs bytes)");
  enc->add_flag("--lossless", ea.lossless,
                "Every float32 coordinate comes back bit for bit (not with -q: there is no quantization grid)");
  enc->add_flag("-f,--force", ea.force, "Overwrite existing output files (never an input)");
  enc->add_flag("--fallback", ea.fallback,
                "glTF output: keep an uncompressed copy of each compressed primitive, for viewers without "
                "TSM_mesh_compression");
  enc->add_flag("--allow-nonfinite", ea.allow_nonfinite,
                "Let the readers accept NaN/inf values; with --lossless they are kept exactly (without it the encoder "
                "refuses them)");
  add_batch_options(enc, ea, true);
  enc->footer(
      "Examples:\n"
      "  tsm encode dragon.ply -o dragon.tsm -q 14 -l 6\n"
      "  tsm encode scene.glb -o small.glb -q 11 --normal-bits 8    # glTF with TSM_mesh_compression\n"
      "  tsm encode meshes/*.ply meshes/*.obj -o packed/ -j 4     # packed/NAME.tsm for each\n"
      "  tsm encode --input-format obj - < part.obj > part.tsm    # stdin to stdout\n"
      "  tsm encode *.stl -o out/ --json --quiet | jq .bits_per_vertex\n"
      "An existing output is never replaced without -f, an input never. In a batch a failed file does not stop\n"
      "the others; failures are listed at the end and the exit code is the worst one (3 bad input, 4 I/O).");

  DecodeArgs da;
  CLI::App* dec = app.add_subcommand("decode", "Decompress .tsm files into " + output_formats_text());
  dec->add_option("inputs", da.inputs, ".tsm files; - reads one from stdin")->required();
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
  dec->add_flag("--partial", da.partial,
                "Progressive files: write the finest level of detail a truncated file holds instead of failing");
  dec->add_option("--max-bytes", da.max_bytes,
                  "Progressive files: decode only the levels within the first N bytes")
      ->check(CLI::NonNegativeNumber);
  dec->add_option("--max-error", da.stop_error,
                  "Progressive files: stop at the first level within this distance of the full mesh (model units, "
                  "as the encoder measured it; tsm info lists them)")
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
  inf->add_option("inputs", ia.inputs, ".tsm files; - reads one from stdin")->required();
  add_batch_options(inf, ia, false);
  inf->footer(
      "Examples:\n"
      "  tsm info dragon.tsm\n"
      "  tsm info packed/*.tsm --json | jq -s 'map(.bits_per_vertex)'\n"
      "  tsm encode bunny.ply -o - | tsm info -");

  std::vector<std::string> bench_meshes;
  bool bench_json = false, bench_quiet = false, bench_browser = false;
  std::vector<int> bench_q{11, 14};
  std::vector<double> bench_simplify;
  int bench_runs = 3, bench_level = kDefaultLevel;
  CLI::App* ben = app.add_subcommand(
      "bench", "Compare tsm with Draco (cl7, cl10) on meshes, and with draco_transcoder and gltfpack on glTF assets");
  ben->add_option("meshes", bench_meshes, "Mesh files (default: the corpus beside the project, else the default mesh)");
  ben->add_option("-q,--quantization", bench_q, "Quantization bits to test (repeatable)")->check(CLI::Range(1, 30));
  ben->add_option("--runs", bench_runs, "Timed runs per measurement (median is shown)")->check(CLI::Range(1, 100));
  ben->add_option("-l,--level", bench_level, "tsm level")->check(CLI::Range(0, 9));
  ben->add_flag("--json", bench_json, "Print JSON instead of the Markdown table");
  ben->add_flag("--quiet", bench_quiet, "No progress lines on stderr");
  ben->add_flag("--browser", bench_browser,
                "glTF assets: also decode time in headless Chromium beside draco3d and meshopt (needs the source "
                "tree's web/ set up: bash web/test.sh)");
  ben->add_option("--simplify", bench_simplify,
                  "Meshes other than glTF: also simplify under these bounds (% of the diagonal, e.g. 0.1,0.5,1) "
                  "beside meshoptimizer's simplifier at the same measured distance")
      ->delimiter(',')
      ->check(CLI::Range(1e-6, 100.0));
  ben->footer(
      "Examples:\n"
      "  tsm bench ../shared/corpus/bun_zipper.ply -q 11 -q 14 --runs 5\n"
      "  tsm bench ../shared/corpus/bun_zipper.ply -q 14 --simplify 0.1,0.5,1\n"
      "  tsm bench --json --quiet > bench.json");

  CompareArgs ca;
  CLI::App* cmp = app.add_subcommand("compare", "Measure the distance between two meshes (Hausdorff, mean, RMS, area, volume, normals)");
  cmp->add_option("a", ca.a, "The reference mesh (any format tsm reads, or .tsm)")->required();
  cmp->add_option("b", ca.b, "The mesh measured against it")->required();
  cmp->add_flag("--json", ca.json, "Print one JSON object instead of the text report");
  cmp->add_option("--samples", ca.samples, "About this many samples on each surface (ignored with --spacing)")
      ->check(CLI::Range(uint64_t{1000}, uint64_t{1000000000}))->capture_default_str();
  cmp->add_option("--spacing", ca.spacing, "Sample grid edge length in model units (default: from --samples)")
      ->check(CLI::PositiveNumber);
  cmp->footer(
      "Examples:\n"
      "  tsm compare bunny.ply bunny_small.ply\n"
      "  tsm compare bunny.ply bunny.tsm --json | jq .hausdorff_percent\n"
      "The Hausdorff distance is shown as the sampled maximum and a guaranteed upper bound; percentages are of A's\n"
      "bounding-box diagonal.");

  SimplifyArgs sa;
  CLI::App* sim = app.add_subcommand("simplify", "Reduce a mesh's triangles within a guaranteed maximum error");
  sim->add_option("input", sa.input, "The mesh (any format tsm reads, or .tsm)")->required();
  sim->add_option("-o,--output", sa.output, "The result: .ply, .obj, .stl, .off, .gltf, .glb or .tsm")->required();
  sim->add_option("--max-error", sa.max_error,
                  "Largest distance allowed between the input and the result (symmetric Hausdorff): model units, or "
                  "E% of the bounding-box diagonal");
  sim->add_option("--faces", sa.faces, "Stop at this many triangles (with --max-error: or where the bound stops it)")
      ->check(CLI::PositiveNumber);
  sim->add_option("--ratio", sa.ratio, "Stop at this fraction of the triangles, 0..1")->check(CLI::Range(0.0, 1.0));
  sim->add_flag("--json", sa.json, "Print one JSON object instead of the text report");
  sim->add_flag("--quiet", sa.quiet, "Print nothing on success");
  sim->add_flag("-f,--force", sa.force, "Replace an existing output file");
  sim->footer(
      "Examples:\n"
      "  tsm simplify bunny.ply -o bunny_small.ply --max-error 0.5%\n"
      "  tsm simplify dragon.ply -o dragon.tsm --max-error 0.001 --faces 50000\n"
      "  tsm compare bunny.ply bunny_small.ply     # measure the result\n"
      "With --max-error the result is guaranteed within that distance of the input (every point of either\n"
      "surface); --faces / --ratio alone stop at a count with no bound.");

  if (refuse_unknown_words(app, argc, argv)) return kExitUsage;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : kExitUsage;
  }
  if (*enc && ea.lossless && enc->count("-q") > 0) {
    std::fprintf(stderr,
                 "tsm: error: -q sets a quantization grid, and --lossless uses none (every float32 coordinate comes "
                 "back bit for bit): drop -q, or drop --lossless to quantize\n");
    return kExitUsage;
  }
  try {
    if (*enc) return cmd_encode(ea);
    if (*dec) return cmd_decode(da);
    if (*inf) return cmd_info(ia);
    if (*cmp) return cmd_compare(ca);
    if (*sim) return cmd_simplify(sa);
    if (*ben) return run_bench(bench_meshes, bench_json, bench_q, bench_runs, bench_level, bench_quiet, bench_browser,
                                 bench_simplify);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "tsm: error: out of memory\n");
    return kExitInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tsm: internal error: %s\n", e.what());
    return kExitInternal;
  }
  return kExitUsage;
}
