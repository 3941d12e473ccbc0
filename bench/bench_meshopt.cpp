// meshoptimizer's simplifier under a measured distance (see bench_meshopt.hpp).
#include "bench_meshopt.hpp"

#include <algorithm>
#include <vector>

#include "bench_timing.hpp"
#ifdef TSM_HAVE_MESHOPT
#include <meshoptimizer.h>
#endif

namespace tsm::bench {

#ifdef TSM_HAVE_MESHOPT

bool meshopt_available() { return true; }

namespace {

MeshoptRun run_meshopt(const Mesh& in, size_t target_triangles, unsigned options) {
  MeshoptRun r;
  const std::vector<unsigned> given(in.indices.begin(), in.indices.end());
  std::vector<unsigned> idx(given.size()), out(given.size());
  // The scans repeat positions (split vertices, doubled faces), which
  // meshoptimizer would keep as seams: it gets an index buffer in which equal
  // positions are one vertex, as its documentation advises.
  meshopt_generateShadowIndexBuffer(idx.data(), given.data(), given.size(), in.positions.data(), in.vertex_count(),
                                    3 * sizeof(float), 3 * sizeof(float));
  const double t0 = thread_cpu_ms();
  float err = 0;
  const size_t n = meshopt_simplify(out.data(), idx.data(), idx.size(), in.positions.data(), in.vertex_count(),
                                    3 * sizeof(float), 3 * target_triangles, 1.0f, options, &err);
  r.ms = thread_cpu_ms() - t0;
  r.own_error = err * meshopt_simplifyScale(in.positions.data(), in.vertex_count(), 3 * sizeof(float));
  r.mesh.positions = in.positions;
  for (size_t i = 0; i + 2 < n; i += 3) r.mesh.add_triangle(out[i], out[i + 1], out[i + 2]);
  r.ok = true;
  return r;
}

}  // namespace

MeshoptRun meshopt_within(const Mesh& in, double max_error, size_t lowest, const MeasureFn& search,
                          const MeasureFn& measure) {
  MeshoptRun best;
  for (unsigned options : {0u, unsigned(meshopt_SimplifyLockBorder)}) {
    size_t lo = std::max<size_t>(4, lowest), hi = in.face_count();
    while (hi - lo > std::max<size_t>(4, lo / 100)) {
      const size_t mid = lo + (hi - lo) / 2;
      if (search(in, run_meshopt(in, mid, options).mesh) <= max_error)
        hi = mid;
      else
        lo = mid;
    }
    MeshoptRun r = run_meshopt(in, hi, options);
    r.measured = measure(in, r.mesh);
    // meshoptimizer's counts are targets, not promises: step up while over.
    while (r.measured > max_error && hi < in.face_count()) {
      hi += std::max<size_t>(4, hi / 100);
      r = run_meshopt(in, hi, options);
      r.measured = measure(in, r.mesh);
    }
    if (!best.ok || r.mesh.face_count() < best.mesh.face_count()) best = std::move(r);
  }
  return best;
}

#else

bool meshopt_available() { return false; }

MeshoptRun meshopt_within(const Mesh&, double, size_t, const MeasureFn&, const MeasureFn&) {
  return {};
}

#endif

}  // namespace tsm::bench
