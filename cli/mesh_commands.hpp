// The tool's single-mesh geometry commands: compare (distance between two
// meshes) and simplify (error-bounded reduction).
#pragma once
#include <cstdint>
#include <string>

#include "tsm/mesh.hpp"
#include "tsm/status.hpp"

namespace tsm::cli {

struct CompareArgs {
  std::string a, b;
  bool json = false;
  double spacing = 0;
  uint64_t samples = 1000000;
};

// A mesh file of any format tsm reads, or a .tsm file (by its magic bytes).
Status load_any_mesh(const std::string& path, Mesh& mesh);

int cmd_compare(const CompareArgs& a);

}  // namespace tsm::cli
