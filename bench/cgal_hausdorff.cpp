// tsm_cgal_hausdorff A B [ERROR]: the symmetric Hausdorff distance between two
// meshes measured by CGAL (the independent check of `tsm compare` and of the
// simplifier's bound), within ERROR (default 1e-4) of the bounding-box
// diagonal of A. Prints one JSON line.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_timing.hpp"
#include "cgal_oracle.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace {

bool load(const std::string& path, tsm::Mesh& m) {
  std::string bytes;
  tsm::Status s = tsm::read_file(path, bytes);
  if (s.ok()) s = bytes.compare(0, 4, std::string("TSM\x1a", 4)) == 0 ? tsm::decode(bytes, m) : tsm::read_mesh(path, m);
  if (!s.ok()) std::fprintf(stderr, "tsm_cgal_hausdorff: %s: %s\n", path.c_str(), s.message().c_str());
  return s.ok();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: tsm_cgal_hausdorff A B [ERROR (fraction of the diagonal, default 1e-4)]\n");
    return 2;
  }
  tsm::Mesh a, b;
  if (!load(argv[1], a) || !load(argv[2], b)) return 3;
  const double rel = argc > 3 ? std::atof(argv[3]) : 1e-4;
  const tsm::BoundingBox box = tsm::bounding_box(a);
  double d2 = 0;
  for (int k = 0; k < 3; ++k) d2 += (double(box.max[k]) - box.min[k]) * (double(box.max[k]) - box.min[k]);
  const double diag = std::sqrt(d2);
  const auto t0 = std::chrono::steady_clock::now();
  const double h = tsm_oracle::symmetric_hausdorff(a, b, rel * diag);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "{\"a\": \"%s\", \"b\": \"%s\", \"hausdorff\": %.9g, \"hausdorff_percent\": %.6f, \"error_bound\": %.3g, "
      "\"diagonal\": %.9g, \"ms\": %.1f}\n",
      argv[1], argv[2], h, 100 * h / diag, rel * diag, diag, ms);
  return 0;
}
