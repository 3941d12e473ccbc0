// Error-bounded simplification beside meshoptimizer's simplifier (issue 39's
// table): for each mesh and each bound (a percentage of the bounding-box
// diagonal), tsm's triangle count and time under the guaranteed bound, and
// the fewest triangles meshoptimizer reaches whose MEASURED symmetric
// Hausdorff distance is within the same bound (binary search on its target
// count, each result measured with tsm::measure_distance), with its time.
// With CGAL installed, both results are also measured by CGAL.
//
//   tsm_bench_simplify [--errors 0.1,0.5,1] [MESH...]   (default: the bunny)
#include <meshoptimizer.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tsm/distance.hpp"
#include "tsm/io.hpp"
#include "tsm/simplify.hpp"
#include "tsm/tsm.hpp"
#ifdef TSM_HAVE_CGAL
#include "cgal_oracle.hpp"
#endif

namespace {

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double measured(const tsm::Mesh& a, const tsm::Mesh& b, uint64_t samples, double* bound = nullptr) {
  tsm::DistanceOptions o;
  o.target_samples = samples;
  tsm::DistanceReport r;
  if (!tsm::measure_distance(a, b, o, r).ok()) return INFINITY;
  if (bound) *bound = r.hausdorff_bound;
  return r.hausdorff;
}

double cgal_distance(const tsm::Mesh& a, const tsm::Mesh& b, double diag) {
#ifdef TSM_HAVE_CGAL
  return tsm_oracle::symmetric_hausdorff(a, b, 1e-5 * diag);
#else
  (void)a, (void)b, (void)diag;
  return NAN;
#endif
}

struct Meshopt {
  tsm::Mesh mesh;
  double ms = 0;
  float own_error = 0;  // meshoptimizer's own estimate, in model units
};

Meshopt run_meshopt(const tsm::Mesh& in, size_t target_triangles, unsigned options) {
  Meshopt r;
  const std::vector<unsigned> given(in.indices.begin(), in.indices.end());
  std::vector<unsigned> idx(given.size()), out(given.size());
  // The scans repeat positions (split vertices, doubled faces), which
  // meshoptimizer would keep as seams: it gets an index buffer in which equal
  // positions are one vertex, as its documentation advises.
  meshopt_generateShadowIndexBuffer(idx.data(), given.data(), given.size(), in.positions.data(), in.vertex_count(),
                                    3 * sizeof(float), 3 * sizeof(float));
  const double t0 = now_ms();
  float err = 0;
  const size_t n = meshopt_simplify(out.data(), idx.data(), idx.size(), in.positions.data(), in.vertex_count(),
                                    3 * sizeof(float), 3 * target_triangles, 1.0f, options, &err);
  r.ms = now_ms() - t0;
  r.own_error = err * meshopt_simplifyScale(in.positions.data(), in.vertex_count(), 3 * sizeof(float));
  r.mesh.positions = in.positions;
  for (size_t i = 0; i + 2 < n; i += 3) r.mesh.add_triangle(out[i], out[i + 1], out[i + 2]);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> errors = {0.1, 0.5, 1.0};
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--errors" && i + 1 < argc) {
      errors.clear();
      for (const char* p = argv[++i]; *p;) {
        char* end;
        errors.push_back(std::strtod(p, &end));
        p = *end == ',' ? end + 1 : end;
        if (end == p && *p) break;
      }
    } else {
      meshes.push_back(a);
    }
  }
  if (meshes.empty()) meshes.push_back(std::string(TSM_CORPUS_DIR) + "/bun_zipper.ply");
  std::printf(
      "| mesh | bound | tsm triangles | tsm time | tsm measured (sampled / CGAL) | meshopt triangles | meshopt time "
      "| meshopt measured (sampled / CGAL) | meshopt own error |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : meshes) {
    tsm::Mesh in;
    if (!tsm::read_mesh(path, in).ok() || !in.all_triangles()) {
      std::fprintf(stderr, "%s: cannot read, or not all triangles\n", path.c_str());
      continue;
    }
    const double diag = tsm::bounding_box(in).diagonal();
    const std::string name = path.substr(path.find_last_of('/') + 1);
    for (double pct : errors) {
      const double e = pct / 100 * diag;
      tsm::SimplifyOptions o;
      o.max_error = e;
      tsm::Mesh out;
      double t0 = now_ms();
      tsm::simplify(in, o, out);
      const double tsm_ms = now_ms() - t0;
      const double tsm_d = measured(in, out, 1000000), tsm_c = cgal_distance(in, out, diag);
      // meshoptimizer: the fewest triangles whose measured distance is within
      // e, with its border free and locked (the better of the two).
      Meshopt m;
      bool have = false;
      for (unsigned options : {0u, unsigned(meshopt_SimplifyLockBorder)}) {
        size_t lo = std::max<size_t>(4, out.face_count() / 8), hi = in.face_count();
        while (hi - lo > std::max<size_t>(4, lo / 100)) {
          const size_t mid = lo + (hi - lo) / 2;
          if (measured(in, run_meshopt(in, mid, options).mesh, 200000) <= e)
            hi = mid;
          else
            lo = mid;
        }
        Meshopt c = run_meshopt(in, hi, options);
        // The final check with the full sampling; step up while it fails.
        while (measured(in, c.mesh, 1000000) > e && hi < in.face_count()) {
          hi += std::max<size_t>(4, hi / 100);
          c = run_meshopt(in, hi, options);
        }
        if (!have || c.mesh.face_count() < m.mesh.face_count()) m = c;
        have = true;
      }
      const double mo_d = measured(in, m.mesh, 1000000), mo_c = cgal_distance(in, m.mesh, diag);
      std::printf("| %s | %.2f%% | %zu | %.2f s | %.4f%% / %.4f%% | %zu | %.3f s | %.4f%% / %.4f%% | %.4f%% |\n",
                  name.c_str(), pct, out.face_count(), tsm_ms / 1000, 100 * tsm_d / diag, 100 * tsm_c / diag,
                  m.mesh.face_count(), m.ms / 1000, 100 * mo_d / diag, 100 * mo_c / diag, 100 * m.own_error / diag);
      std::fflush(stdout);
    }
  }
  return 0;
}
