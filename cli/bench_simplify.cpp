// `tsm bench --simplify`: how few triangles each simplifier keeps under the
// same bound. tsm's bound is a guarantee; meshoptimizer's simplifier takes a
// triangle count, so it is searched for the fewest triangles whose measured
// distance (sampled, the same measurement for both) is within the bound.
#include "bench_simplify.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bench_meshopt.hpp"
#include "bench_timing.hpp"
#include "cli_util.hpp"
#include "tsm/distance.hpp"
#include "tsm/simplify.hpp"

namespace tsm::cli {

namespace {

// Sampled symmetric Hausdorff distance and its guaranteed upper bound.
bool measure(const Mesh& a, const Mesh& b, uint64_t samples, double& sampled, double& bound) {
  DistanceOptions o;
  o.target_samples = samples;
  DistanceReport r;
  if (!measure_distance(a, b, o, r).ok()) return false;
  sampled = r.hausdorff;
  bound = r.hausdorff_bound;
  return true;
}

}  // namespace

SimplifyRow bench_simplify(const Mesh& mesh, const std::string& name, double percent, bool quiet) {
  SimplifyRow row;
  row.name = name;
  row.percent = percent;
  row.faces_in = mesh.face_count();
  const double diag = bounding_box(mesh).diagonal();
  const double e = percent / 100 * diag;
  // Samples a side: 10^6, fewer on small meshes (100 per triangle); the
  // search takes a fifth.
  const uint64_t samples = std::clamp<uint64_t>(100 * uint64_t(mesh.face_count()), 20000, 1000000);
  if (!(diag > 0)) {
    row.error = "the mesh has no extent";
    return row;
  }
  if (!quiet) std::fprintf(stderr, "tsm bench: %s %g%%: tsm simplify\n", name.c_str(), percent);
  SimplifyOptions so;
  so.max_error = e;
  Mesh out;
  const double t0 = bench::thread_cpu_ms();
  const Status s = simplify(mesh, so, out);
  row.tsm_ms = bench::thread_cpu_ms() - t0;
  if (!s.ok()) {
    row.error = "simplify: " + s.message();
    return row;
  }
  row.tsm_faces = out.face_count();
  double sampled = 0, bound = 0;
  if (!measure(mesh, out, samples, sampled, bound)) {
    row.error = "the distance could not be measured";
    return row;
  }
  row.tsm_measured = 100 * sampled / diag;
  row.tsm_measured_bound = 100 * bound / diag;
  if (!bench::meshopt_available() || !mesh.all_triangles()) return row;
  if (!quiet) std::fprintf(stderr, "tsm bench: %s %g%%: meshoptimizer at the same measured distance\n", name.c_str(), percent);
  // The search measures with fewer samples; the result is measured as tsm's.
  auto measure_with = [](uint64_t n) {
    return [n](const Mesh& a, const Mesh& b) {
      double d = 0, ub = 0;
      return measure(a, b, n, d, ub) ? d : INFINITY;
    };
  };
  bench::MeshoptRun m =
      bench::meshopt_within(mesh, e, out.face_count() / 8, measure_with(samples / 5), measure_with(samples));
  if (!m.ok || !measure(mesh, m.mesh, samples, sampled, bound)) return row;
  row.meshopt = true;
  row.meshopt_faces = m.mesh.face_count();
  row.meshopt_ms = m.ms;
  row.meshopt_measured = 100 * sampled / diag;
  row.meshopt_own = 100 * m.own_error / diag;
  return row;
}

void print_simplify_table(const std::vector<SimplifyRow>& rows) {
  std::printf(
      "\nSimplification under a bound (%% of the bounding-box diagonal): tsm's bound is guaranteed; meshoptimizer "
      "keeps the fewest triangles whose measured distance is within it (binary search on its target count). "
      "Measured: symmetric Hausdorff distance sampled by tsm compare (10^6 samples a side, 100 per triangle on smaller meshes; in brackets the "
      "measurement's own upper bound). meshoptimizer at the full count: no reduction stays within the bound. "
      "Times: CPU seconds of the one thread each simplifier runs on.\n\n");
  std::printf(
      "| mesh | triangles | bound | tsm triangles | tsm s | tsm measured (bound) | meshopt triangles | meshopt s "
      "| meshopt measured | meshopt own estimate | tsm/meshopt triangles |\n"
      "|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n");
  for (const SimplifyRow& r : rows) {
    if (!r.error.empty()) {
      std::printf("| %s | %s | %g%% | failed: %s | | | | | | | |\n", r.name.c_str(), thousands(r.faces_in).c_str(),
                  r.percent, r.error.c_str());
      continue;
    }
    auto pct = [](double v) { return fixed(v, 3) + "%"; };
    std::printf("| %s | %s | %g%% | %s | %s | %s (%s) | %s | %s | %s | %s | %s |\n", r.name.c_str(),
                thousands(r.faces_in).c_str(), r.percent, thousands(r.tsm_faces).c_str(),
                fixed(r.tsm_ms / 1000, 2).c_str(), pct(r.tsm_measured).c_str(), pct(r.tsm_measured_bound).c_str(),
                r.meshopt ? thousands(r.meshopt_faces).c_str() : "-",
                r.meshopt ? fixed(r.meshopt_ms / 1000, 3).c_str() : "-",
                r.meshopt ? pct(r.meshopt_measured).c_str() : "-", r.meshopt ? pct(r.meshopt_own).c_str() : "-",
                r.meshopt && r.meshopt_faces
                    ? fixed(static_cast<double>(r.tsm_faces) / static_cast<double>(r.meshopt_faces), 2).c_str()
                    : "-");
  }
  bool any_meshopt = false;
  for (const SimplifyRow& r : rows) any_meshopt = any_meshopt || r.meshopt;
  if (!any_meshopt)
    std::printf("\nmeshoptimizer is not built in (install libmeshoptimizer-dev and reconfigure for its columns).\n");
}

nlohmann::ordered_json simplify_rows_json(const std::vector<SimplifyRow>& rows) {
  using ojson = nlohmann::ordered_json;
  auto rounded = [](double v, double scale) { return std::isfinite(v) ? ojson(std::round(v * scale) / scale) : ojson(); };
  ojson out = ojson::array();
  for (const SimplifyRow& r : rows) {
    ojson o = ojson::object();
    o["mesh"] = r.name;
    o["faces"] = r.faces_in;
    o["bound_percent"] = r.percent;
    if (!r.error.empty()) {
      o["error"] = r.error;
      out.push_back(std::move(o));
      continue;
    }
    o["tsm_faces"] = r.tsm_faces;
    o["tsm_ms"] = rounded(r.tsm_ms, 1e3);
    o["tsm_measured_percent"] = rounded(r.tsm_measured, 1e5);
    o["tsm_measured_bound_percent"] = rounded(r.tsm_measured_bound, 1e5);
    if (r.meshopt) {
      o["meshopt_faces"] = r.meshopt_faces;
      o["meshopt_ms"] = rounded(r.meshopt_ms, 1e3);
      o["meshopt_measured_percent"] = rounded(r.meshopt_measured, 1e5);
      o["meshopt_own_estimate_percent"] = rounded(r.meshopt_own, 1e5);
    }
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace tsm::cli
