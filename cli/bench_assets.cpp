// `tsm bench` on glTF assets (see bench_assets.hpp): each tool compresses the
// same file at the same quantization; tsm in this process, draco_transcoder
// and gltfpack as the programs Debian installs (a column shows "-" and a note
// when one is missing or refuses the file). Decoding is timed the same way
// for all three: the compressed .glb turned into a plain glTF by tsm's
// transcoder in this process, whose Draco and meshoptimizer inputs go through
// those libraries' own decoders.
#include "bench_assets.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "bench_timing.hpp"
#include "cli_util.hpp"
#include "tsm/gltf_transcode.hpp"

extern char** environ;

namespace tsm::cli {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

namespace {

constexpr int kNormalBits = 8, kTexcoordBits = 10, kColorBits = 8;

bool slurp(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  out = ss.str();
  return static_cast<bool>(in) || in.eof();
}

uint32_t load_u32(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = v << 8 | static_cast<unsigned char>(s[at + static_cast<size_t>(i)]);
  return v;
}

// The JSON chunk of a GLB, or "" when the bytes are not one.
std::string glb_json(const std::string& glb) {
  if (glb.size() < 20 || load_u32(glb, 0) != 0x46546C67 || load_u32(glb, 16) != 0x4E4F534A) return {};
  const size_t length = load_u32(glb, 12);
  if (length > glb.size() - 20) return {};
  return glb.substr(20, length);
}

// Medians of `runs` decodes of a compressed .glb to a plain one.
void time_decode(const std::string& glb, const std::string& name, const std::string& dir, int runs, AssetTool& t) {
  GltfTranscodeOptions plain;
  plain.compress = false;
  plain.encode.threads = 1;
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    GltfOutput out;
    Stopwatch sw;
    const Status s = transcode_gltf(glb, name, dir, plain, true, "", out);
    ms.push_back(sw.ms());
    if (!s.ok()) {
      t.error = "decoding: " + s.message();
      return;
    }
  }
  t.decode_ms = bench::median(ms);
}

// A compressed .glb a program wrote: its sizes and decode time.
void measure_tool_output(const std::string& out_path, const std::string& dir, int runs, AssetTool& t) {
  std::string glb;
  if (!slurp(out_path, glb) || glb.empty()) {
    t.error = "no output";
    return;
  }
  t.glb_bytes = glb.size();
  t.geometry_bytes = glb_geometry_bytes(glb);
  t.ok = true;
  t.file = out_path;
  time_decode(glb, fs::path(out_path).filename().string(), dir, runs, t);
}

void bench_program(const std::vector<std::string>& args, const std::string& out_path, const std::string& dir, int runs,
                   AssetTool& t) {
  const std::string log = out_path + ".log";
  const int rc = run_program(args, log);
  if (rc == -1) {
    t.error = args[0] + " is not installed (scripts/setup.sh installs it)";
    return;
  }
  if (rc != 0) {
    t.error = args[0] + " failed (exit " + std::to_string(rc) + "): " + last_line(log);
    return;
  }
  measure_tool_output(out_path, dir, runs, t);
}

void bench_tsm(const std::string& input, const std::string& name, const std::string& dir, int q, int level, int runs,
               AssetRow& row) {
  GltfTranscodeOptions opt;
  opt.encode.quantization_bits = q;
  opt.encode.level = level;
  opt.encode.threads = 1;
  opt.encode.attribute_bits.normal = kNormalBits;
  opt.encode.attribute_bits.texcoord = kTexcoordBits;
  opt.encode.attribute_bits.color = kColorBits;
  // TANGENT is a generic float attribute to tsm: at the normals' bits, as Draco's -qtg is given.
  opt.encode.attribute_bits.generic = kNormalBits;
  std::vector<double> ms;
  GltfOutput out;
  for (int i = 0; i < runs; ++i) {
    GltfTranscodeReport report;
    out = GltfOutput();
    Stopwatch sw;
    const Status s = transcode_gltf(input, name, dir, opt, true, "", out, &report);
    ms.push_back(sw.ms());
    if (!s.ok()) {
      row.tsm.error = s.message();
      return;
    }
    row.vertices = report.vertices;
    row.triangles = report.triangles;
  }
  row.tsm.encode_ms = bench::median(ms);
  row.tsm.glb_bytes = out.main.size();
  row.tsm.geometry_bytes = glb_geometry_bytes(out.main);
  row.tsm.ok = true;
  time_decode(out.main, name, "", runs, row.tsm);
  std::ofstream(row.tsm.file, std::ios::binary) << out.main;
}

std::string cell_bytes(const AssetTool& t, size_t bytes) { return t.ok ? thousands(bytes) : std::string("-"); }

std::string cell_ms(double ms) { return ms >= 0 ? fixed(ms, 1) : std::string("-"); }

std::string cell_ratio(const AssetTool& a, const AssetTool& b) {
  if (!a.ok || !b.ok || b.geometry_bytes == 0) return "-";
  return fixed(static_cast<double>(a.geometry_bytes) / static_cast<double>(b.geometry_bytes), 2);
}

}  // namespace

// Runs a program (searched on PATH) with its output to `log`; its exit code,
// or -1 when it cannot be started.
int run_program(const std::vector<std::string>& args, const std::string& log) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// What a program said when it failed, for the note under the table: its
// first line naming an error, else its last non-empty line.
std::string last_line(const std::string& log) {
  std::string text, line, last;
  slurp(log, text);
  std::istringstream in(text);
  while (std::getline(in, line)) {
    if (line.find("rror") != std::string::npos) return line;
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  }
  return last;
}


bool is_gltf_path(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".glb" || ext == ".gltf";
}

// o[key] when o is an object holding it, else null (never a temporary).
const ojson& member(const ojson& o, const char* key) {
  static const ojson none;
  if (!o.is_object()) return none;
  const auto it = o.find(key);
  return it == o.end() ? none : *it;
}

bool gltf_has_node_cycle(const std::string& path) {
  std::string text;
  if (!is_gltf_path(path) || !slurp(path, text)) return false;
  const std::string glb = glb_json(text);
  const ojson doc = ojson::parse(glb.empty() ? text : glb, nullptr, false);
  const ojson& nodes = member(doc, "nodes");
  if (!nodes.is_array()) return false;
  // Depth-first from every node, without recursion: 0 unseen, 1 on the path, 2 done.
  std::vector<int> state(nodes.size(), 0);
  for (size_t root = 0; root < nodes.size(); ++root) {
    if (state[root] != 0) continue;
    std::vector<std::pair<size_t, size_t>> path_stack = {{root, 0}};  // node, next child
    state[root] = 1;
    while (!path_stack.empty()) {
      auto& [node, next] = path_stack.back();
      const ojson& children = member(nodes[node], "children");
      if (!children.is_array() || next >= children.size()) {
        state[node] = 2;
        path_stack.pop_back();
        continue;
      }
      const ojson& c = children[next++];
      if (!c.is_number_unsigned() || c.get<size_t>() >= nodes.size()) continue;
      const size_t child = c.get<size_t>();
      if (state[child] == 1) return true;
      if (state[child] == 0) {
        state[child] = 1;
        path_stack.emplace_back(child, 0);
      }
    }
  }
  return false;
}

std::vector<std::string> with_folders_expanded(const std::vector<std::string>& paths) {
  std::vector<std::string> out;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (!fs::is_directory(p, ec)) {
      out.push_back(p);
      continue;
    }
    std::vector<std::string> found;
    for (const auto& e : fs::recursive_directory_iterator(p, ec))
      if (e.is_regular_file() && is_gltf_path(e.path().string())) found.push_back(e.path().string());
    std::sort(found.begin(), found.end());
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}


size_t glb_geometry_bytes(const std::string& glb) {
  const ojson doc = ojson::parse(glb_json(glb), nullptr, false);
  const ojson& accessors = member(doc, "accessors");
  const ojson& views = member(doc, "bufferViews");
  if (!views.is_array()) return 0;
  std::set<size_t> used;
  auto add_view = [&](const ojson& v) {
    if (v.is_number_unsigned() && v.get<size_t>() < views.size()) used.insert(v.get<size_t>());
  };
  auto add_accessor = [&](const ojson& a) {
    if (a.is_number_unsigned() && accessors.is_array() && a.get<size_t>() < accessors.size())
      add_view(member(accessors[a.get<size_t>()], "bufferView"));
  };
  auto add_accessors = [&](const ojson& map) {
    if (map.is_object())
      for (const ojson& a : map) add_accessor(a);
  };
  const ojson& meshes = member(doc, "meshes");
  if (!meshes.is_array()) return 0;
  for (const ojson& mesh : meshes) {
    const ojson& prims = member(mesh, "primitives");
    if (!prims.is_array()) continue;
    for (const ojson& prim : prims) {
      add_accessors(member(prim, "attributes"));
      add_accessor(member(prim, "indices"));
      const ojson& targets = member(prim, "targets");
      if (targets.is_array())
        for (const ojson& t : targets) add_accessors(t);
      const ojson& exts = member(prim, "extensions");
      for (const char* ext : {"TSM_mesh_compression", "KHR_draco_mesh_compression"})
        add_view(member(member(exts, ext), "bufferView"));
    }
  }
  size_t bytes = 0;
  for (size_t v : used) {
    const ojson& exts = member(views[v], "extensions");
    const ojson& meshopt = member(exts, "EXT_meshopt_compression").is_object()
                               ? member(exts, "EXT_meshopt_compression")
                               : member(exts, "KHR_meshopt_compression");
    const ojson& length = member(meshopt.is_object() ? meshopt : views[v], "byteLength");
    if (length.is_number_unsigned()) bytes += length.get<size_t>();
  }
  return bytes;
}

// The asset's bytes: a .glb, or a .gltf with the buffers and images it names
// by relative URI.
size_t asset_bytes(const std::string& path, const std::string& text) {
  size_t bytes = text.size();
  if (!glb_json(text).empty()) return bytes;
  const ojson doc = ojson::parse(text, nullptr, false);
  for (const char* list : {"buffers", "images"}) {
    const ojson& items = member(doc, list);
    if (!items.is_array()) continue;
    for (const ojson& item : items) {
      const ojson& uri = member(item, "uri");
      if (!uri.is_string() || uri.get<std::string>().rfind("data:", 0) == 0) continue;
      std::error_code ec;
      const auto size = fs::file_size(fs::path(path).parent_path() / uri.get<std::string>(), ec);
      if (!ec) bytes += static_cast<size_t>(size);
    }
  }
  return bytes;
}

AssetRow bench_asset(const std::string& path, int q, int level, int runs, bool quiet, const std::string& work_dir) {
  AssetRow row;
  row.name = fs::path(path).filename().string();
  row.q = q;
  std::string input;
  if (!slurp(path, input)) {
    row.tsm.error = row.draco.error = row.gltfpack.error = "cannot read " + path;
    return row;
  }
  row.input_bytes = asset_bytes(path, input);
  // A folder of its own in the work folder: the three outputs (and images a tool writes beside them).
  std::string tmpl = work_dir + "/asset-XXXXXX";
  if (!mkdtemp(tmpl.data())) {
    row.tsm.error = row.draco.error = row.gltfpack.error = "cannot make a folder in " + work_dir;
    return row;
  }
  const std::string tmp = tmpl;
  const std::string dir = fs::path(path).parent_path().string();
  if (!quiet) std::fprintf(stderr, "tsm bench: %s q=%d: tsm glTF\n", row.name.c_str(), q);
  row.tsm.file = tmp + "/tsm.glb";
  bench_tsm(input, path, dir.empty() ? "." : dir, q, level, runs, row);
  if (!row.tsm.ok) row.tsm.file.clear();
  const std::string qs = std::to_string(q), nb = std::to_string(kNormalBits), tb = std::to_string(kTexcoordBits),
                    cb = std::to_string(kColorBits);
  if (!quiet) std::fprintf(stderr, "tsm bench: %s q=%d: draco_transcoder, gltfpack -cc\n", row.name.c_str(), q);
  bench_program({"draco_transcoder", "-i", path, "-o", tmp + "/draco.glb", "-qp", qs, "-qn", nb, "-qtg", nb, "-qt", tb,
                 "-qc", cb},
                tmp + "/draco.glb", tmp, runs, row.draco);
  bench_program({"gltfpack", "-cc", "-i", path, "-o", tmp + "/meshopt.glb", "-vp", qs, "-vn", nb, "-vt", tb, "-vc", cb},
                tmp + "/meshopt.glb", tmp, runs, row.gltfpack);
  return row;
}

bool browser_times(std::vector<AssetRow>& rows, const std::string& work_dir, int runs, std::string& error) {
#ifdef TSM_SOURCE_DIR
  const std::string script = std::string(TSM_SOURCE_DIR) + "/web/test/gltf-bench.mjs";
#else
  const std::string script;
#endif
  const std::string setup = "it needs Node, Chromium and the web decoder built from the source tree (bash web/test.sh "
                            "sets them up)";
  if (script.empty() || !fs::exists(script)) {
    error = "no web/test/gltf-bench.mjs beside this tsm: " + setup;
    return false;
  }
  ojson index = ojson::array();
  for (size_t i = 0; i < rows.size(); ++i) {
    ojson files = ojson::object();
    for (const auto& [key, t] : {std::pair<const char*, const AssetTool*>{"tsm", &rows[i].tsm},
                                 {"draco", &rows[i].draco},
                                 {"meshopt", &rows[i].gltfpack}})
      if (t->ok && !t->file.empty()) files[key] = t->file;
    index.push_back({{"name", std::to_string(i)}, {"files", files}});
  }
  const std::string index_path = work_dir + "/index.json", result_path = work_dir + "/browser.json";
  std::ofstream(index_path) << index.dump();
  const int rc = run_program({"node", script, "--index", index_path, "--reps", std::to_string(std::max(5 * runs, 15))},
                             result_path);
  if (rc != 0) {
    error = rc == -1 ? "node is not installed: " + setup
                     : "web/test/gltf-bench.mjs failed (exit " + std::to_string(rc) + "): " + last_line(result_path) +
                           "; " + setup;
    return false;
  }
  // The result is the last line that is a JSON object (the page's errors, if any, come before it).
  std::string text, line, json_line;
  slurp(result_path, text);
  std::istringstream lines(text);
  while (std::getline(lines, line))
    if (!line.empty() && line[0] == '{') json_line = line;
  const ojson result = ojson::parse(json_line, nullptr, false);
  const ojson& got = member(result, "rows");
  if (!got.is_array()) {
    error = "web/test/gltf-bench.mjs printed no result: " + last_line(result_path);
    return false;
  }
  for (const ojson& r : got) {
    const ojson& name = member(r, "name");
    if (!name.is_string()) continue;
    const size_t i = std::stoul(name.get<std::string>());
    if (i >= rows.size()) continue;
    for (const auto& [key, t] : {std::pair<const char*, AssetTool*>{"tsm", &rows[i].tsm},
                                 {"draco", &rows[i].draco},
                                 {"meshopt", &rows[i].gltfpack}}) {
      const ojson& ms = member(member(r, key), "ms");
      if (ms.is_number()) t->browser_ms = ms.get<double>();
    }
  }
  return true;
}

void print_asset_table(const std::vector<AssetRow>& rows, bool browser) {
  std::printf(
      "\nglTF assets: each file compressed whole; positions at q bits, normals and tangents %d (tsm's other "
      "float attributes too), texture coordinates %d, colours %d bits in every tool (other attributes at each "
      "tool's default). Geometry: "
      "the bytes of the buffer views the meshes use. Decode: the compressed .glb to a plain glTF, in this "
      "process, one thread, ms.%s\n\n",
      kNormalBits, kTexcoordBits, kColorBits,
      browser ? " Browser: the geometry decoded into typed arrays in headless Chromium by tsm's wasm decoder, draco3d "
                "and meshoptimizer's MeshoptDecoder (web/test/gltf-bench.mjs), median ms."
              : "");
  std::printf(
      "| asset | V | T | q | input bytes | tsm .glb | Draco .glb | gltfpack .glb | tsm geometry | Draco "
      "geometry | gltfpack geometry | geometry tsm/Draco | geometry tsm/gltfpack | tsm decode ms | Draco "
      "decode ms | gltfpack decode ms |%s\n",
      browser ? " tsm browser ms | draco3d browser ms | meshopt browser ms |" : "");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|%s\n",
              browser ? "---:|---:|---:|" : "");
  for (const AssetRow& r : rows) {
    std::printf("| %s | %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |", r.name.c_str(),
                thousands(r.vertices).c_str(), thousands(r.triangles).c_str(), r.q, thousands(r.input_bytes).c_str(),
                cell_bytes(r.tsm, r.tsm.glb_bytes).c_str(), cell_bytes(r.draco, r.draco.glb_bytes).c_str(),
                cell_bytes(r.gltfpack, r.gltfpack.glb_bytes).c_str(), cell_bytes(r.tsm, r.tsm.geometry_bytes).c_str(),
                cell_bytes(r.draco, r.draco.geometry_bytes).c_str(),
                cell_bytes(r.gltfpack, r.gltfpack.geometry_bytes).c_str(), cell_ratio(r.tsm, r.draco).c_str(),
                cell_ratio(r.tsm, r.gltfpack).c_str(), cell_ms(r.tsm.decode_ms).c_str(),
                cell_ms(r.draco.decode_ms).c_str(), cell_ms(r.gltfpack.decode_ms).c_str());
    if (browser)
      std::printf(" %s | %s | %s |", cell_ms(r.tsm.browser_ms).c_str(), cell_ms(r.draco.browser_ms).c_str(),
                  cell_ms(r.gltfpack.browser_ms).c_str());
    std::printf("\n");
  }
  for (const AssetRow& r : rows)
    for (const auto& [tool, t] :
         {std::pair<const char*, const AssetTool*>{"tsm", &r.tsm}, {"Draco", &r.draco}, {"gltfpack", &r.gltfpack}})
      if (!t->error.empty()) std::printf("\n%s q=%d, %s: %s\n", r.name.c_str(), r.q, tool, printable(t->error).c_str());
}

ojson asset_rows_json(const std::vector<AssetRow>& rows) {
  ojson out = ojson::array();
  auto tool = [](const AssetTool& t) {
    ojson o = ojson::object();
    o["ok"] = t.ok;
    if (t.ok) {
      o["glb_bytes"] = t.glb_bytes;
      o["geometry_bytes"] = t.geometry_bytes;
    }
    if (t.encode_ms >= 0) o["encode_ms"] = std::round(t.encode_ms * 1e3) / 1e3;
    if (t.decode_ms >= 0) o["decode_ms"] = std::round(t.decode_ms * 1e3) / 1e3;
    if (t.browser_ms >= 0) o["browser_decode_ms"] = std::round(t.browser_ms * 1e3) / 1e3;
    if (!t.error.empty()) o["error"] = t.error;
    return o;
  };
  for (const AssetRow& r : rows)
    out.push_back({{"asset", r.name},
                   {"q", r.q},
                   {"vertices", r.vertices},
                   {"triangles", r.triangles},
                   {"input_bytes", r.input_bytes},
                   {"tsm", tool(r.tsm)},
                   {"draco_transcoder", tool(r.draco)},
                   {"gltfpack", tool(r.gltfpack)}});
  return out;
}

}  // namespace tsm::cli
