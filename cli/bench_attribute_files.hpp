// `tsm bench` on meshes with attributes (normals, texture coordinates,
// colours): tsm beside Draco's encoder at the same quantization on each
// attribute, the bytes each attribute costs in the tsm file, and whether
// tsm's round trip is exact by the oracle, attributes included.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm::cli {

struct AttributeFileRow {
  std::string name;
  int q = 0;
  size_t vertices = 0, points = 0, faces = 0;  // points: distinct positions
  std::string attributes;                      // "normal (corner), texcoord (vertex)"
  size_t tsm_bytes = 0;
  std::string tsm_parts;  // "connectivity 120, geometry 300, normal 80, ..."
  bool tsm_exact = false;
  std::string tsm_diff;
  // Draco: the smallest of its encodings of the same values (the file itself
  // when Draco reads it, the mesh written with one vertex per split vertex,
  // and written with shared value lists) that keeps every attribute.
  size_t draco_bytes = 0;
  std::string draco_inputs;  // each input's bytes, or why it does not count
  std::string error;       // why there is no tsm figure
};

// Whether the mesh has a normal, texture coordinate or colour per vertex or
// per corner (what both tools code).
bool has_common_attributes(const Mesh& mesh);

// One row: `mesh` (read from `path`) keeps its normals, texture coordinates
// and colours, other attributes dropped as Draco's readers drop them;
// positions at q bits, normals 8, texture coordinates 10, colours 8 for both
// tools (draco_encoder -cl 10). Scratch files go into `work_dir`.
AttributeFileRow bench_attribute_file(const std::string& path, const Mesh& mesh, int q, int level, bool quiet,
                                      const std::string& work_dir);

void print_attribute_file_table(const std::vector<AttributeFileRow>& rows);
nlohmann::ordered_json attribute_file_rows_json(const std::vector<AttributeFileRow>& rows);

}  // namespace tsm::cli
