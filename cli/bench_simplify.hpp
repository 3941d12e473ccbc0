// `tsm bench --simplify`: error-bounded simplification of the scans beside
// meshoptimizer's simplifier at the same MEASURED distance.
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm::cli {

struct SimplifyRow {
  std::string name;
  double percent = 0;  // the bound, % of the bounding-box diagonal
  size_t faces_in = 0;
  size_t tsm_faces = 0;
  double tsm_ms = 0;
  double tsm_measured = 0, tsm_measured_bound = 0;  // symmetric Hausdorff, % of the diagonal: sampled, upper bound
  bool meshopt = false;
  size_t meshopt_faces = 0;
  double meshopt_ms = 0, meshopt_measured = 0, meshopt_own = 0;  // % of the diagonal
  std::string error;
};

// tsm simplify with the bound `percent`% of the diagonal (one thread), and
// the fewest triangles meshoptimizer's simplifier keeps whose sampled
// symmetric Hausdorff distance (tsm compare's, 10^6 samples a side) is
// within the same bound.
SimplifyRow bench_simplify(const Mesh& mesh, const std::string& name, double percent, bool quiet);

void print_simplify_table(const std::vector<SimplifyRow>& rows);
nlohmann::ordered_json simplify_rows_json(const std::vector<SimplifyRow>& rows);

}  // namespace tsm::cli
