// `tsm bench` on glTF assets: the compressed .glb and its geometry bytes for
// tsm (TSM_mesh_compression), Draco through glTF (draco_transcoder) and
// meshoptimizer (gltfpack -cc), at the same quantization where each tool
// allows, and the time each file takes to become a plain glTF again.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace tsm::cli {

struct AssetTool {
  bool ok = false;
  size_t glb_bytes = 0, geometry_bytes = 0;
  double encode_ms = -1, decode_ms = -1;  // encode_ms: tsm only (the others run as programs)
  double browser_ms = -1;                 // geometry decoded in headless Chromium (--browser)
  std::string file;                       // the compressed .glb, in the bench's work folder
  std::string error;                      // why there is no figure
};

struct AssetRow {
  std::string name;
  int q = 0;
  size_t input_bytes = 0, vertices = 0, triangles = 0;
  AssetTool tsm, draco, gltfpack;
};

// A .glb or .gltf by its name.
bool is_gltf_path(const std::string& path);

// True for a .gltf / .glb whose nodes' children form a cycle (invalid
// glTF, e.g. assimp-testmodels' RecursiveNodes.gltf): Draco's glTF reader,
// run in this process, recurses on it until the stack overflows.
bool gltf_has_node_cycle(const std::string& path);

// The bench's inputs with each folder replaced by the .gltf / .glb files in
// it and below it, sorted (a collection such as Debian's assimp-testmodels,
// /usr/share/assimp/models/glTF2); files as they are.
std::vector<std::string> with_folders_expanded(const std::vector<std::string>& paths);

// Bytes of the buffer views a GLB's mesh primitives use: their accessors'
// views, the views of TSM_mesh_compression and KHR_draco_mesh_compression,
// and for views compressed with EXT/KHR_meshopt_compression the compressed
// length. 0 when the bytes are not a GLB.
size_t glb_geometry_bytes(const std::string& glb);

// Positions at q bits, normals and tangents 8, texture coordinates 10,
// colours 8 for all three tools; one thread; medians of `runs`. The
// compressed files are written into `work_dir` (the caller's, removed by it).
AssetRow bench_asset(const std::string& path, int q, int level, int runs, bool quiet, const std::string& work_dir);

// Geometry decode times in headless Chromium (tsm's wasm decoder, draco3d,
// meshoptimizer's decoder) of the rows' files, through the source tree's
// web/test/gltf-bench.mjs; false and `error` when that cannot run.
bool browser_times(std::vector<AssetRow>& rows, const std::string& work_dir, int runs, std::string& error);

// Runs a program (searched on PATH) with its output and errors to `log`;
// its exit code, or -1 when it cannot be started.
int run_program(const std::vector<std::string>& args, const std::string& log);

// What a program said when it failed, for a note under a table: the log's
// first line naming an error, else its last non-empty line.
std::string last_line(const std::string& log);

void print_asset_table(const std::vector<AssetRow>& rows, bool browser);
nlohmann::ordered_json asset_rows_json(const std::vector<AssetRow>& rows);

}  // namespace tsm::cli
