// The tool's single-mesh geometry commands: compare (distance between two
// meshes) and simplify (error-bounded reduction).
#pragma once
#include <cstdint>
#include <string>

#include "tsm/mesh.hpp"
#include "tsm/simplify.hpp"
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

struct SimplifyArgs {
  std::string input, output;
  std::string max_error;  // "E" in model units or "E%" of the bounding-box diagonal; "" = none
  uint64_t faces = 0;
  double ratio = 0;
  bool json = false, quiet = false, force = false;
};

int cmd_compare(const CompareArgs& a);
int cmd_simplify(const SimplifyArgs& a);

// "0.5%" -> 0.5, percent; "0.002" -> 0.002. False unless a positive number.
bool parse_max_error(const std::string& text, double& value, bool& percent);
// Simplifies `in` as the command line asks: --max-error text (units or %),
// --faces, --ratio (the larger face target wins); a progress line on a
// terminal when `progress`. error_units gets the bound in model units (0: none);
// the simplifier gets it less `reserve` (what quantization adds afterwards).
Status simplify_for_cli(const Mesh& in, const std::string& max_error, uint64_t faces, double ratio, bool progress,
                        Mesh& out, SimplifyReport& report, double& error_units, double reserve = 0);

}  // namespace tsm::cli
