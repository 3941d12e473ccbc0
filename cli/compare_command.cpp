// tsm compare: the geometric distance between two meshes (tsm/distance.hpp),
// as text or one JSON object.
#include <cmath>
#include <cstdio>
#include <string>

#include "batch.hpp"
#include "cli_util.hpp"
#include "mesh_commands.hpp"
#include "tsm/distance.hpp"
#include "tsm/io.hpp"
#include "tsm/tsm.hpp"

namespace tsm::cli {

Status load_any_mesh(const std::string& path, Mesh& mesh) {
  std::string bytes;
  Status s = read_file(path, bytes);
  if (!s.ok()) return s;
  if (bytes.size() >= 4 && bytes.compare(0, 4, std::string("TSM\x1a", 4)) == 0) {
    s = decode(bytes, mesh);
    return s.ok() ? s : Status(s.code(), path + ": " + s.message());
  }
  return read_mesh(path, mesh);
}

namespace {

std::string pct(double v, double diag) { return diag > 0 ? fixed(100.0 * v / diag, 4) + "%" : std::string("-"); }

std::string distance_line(const char* what, double v, double diag) {
  return strf("  %-28s %.6g (%s of the diagonal)\n", what, v, pct(v, diag).c_str());
}

void add_side(JsonObject& o, const char* prefix, const OneSidedDistance& d) {
  const std::string p = prefix;
  o.num((p + "_max").c_str(), d.max, 9).num((p + "_bound").c_str(), d.bound, 9);
  o.num((p + "_mean").c_str(), d.mean, 9).num((p + "_rms").c_str(), d.rms, 9);
  o.num((p + "_samples").c_str(), static_cast<unsigned long long>(d.samples));
}

}  // namespace

int cmd_compare(const CompareArgs& a) {
  Mesh ma, mb;
  Status s = load_any_mesh(a.a, ma);
  if (s.ok()) s = load_any_mesh(a.b, mb);
  if (!s.ok()) {
    std::fprintf(stderr, "tsm: error: %s\n", printable(s.message()).c_str());
    return exit_code_for(s);
  }
  DistanceOptions o;
  o.spacing = a.spacing;
  o.target_samples = a.samples;
  DistanceReport r;
  Stopwatch sw;
  s = measure_distance(ma, mb, o, r);
  if (!s.ok()) {
    std::fprintf(stderr, "tsm: error: %s vs %s: %s\n", printable(a.a).c_str(), printable(a.b).c_str(),
                 s.message().c_str());
    return exit_code_for(Status(ErrorCode::parse_error, s.message()));
  }
  const double ms = sw.ms();
  const double diag = r.diagonal;
  if (a.json) {
    JsonObject j;
    j.str("a", a.a).str("b", a.b);
    j.num("triangles_a", static_cast<unsigned long long>(r.triangles_a));
    j.num("triangles_b", static_cast<unsigned long long>(r.triangles_b));
    j.num("diagonal", diag, 9).num("spacing", r.spacing, 9);
    j.num("hausdorff", r.hausdorff, 9).num("hausdorff_bound", r.hausdorff_bound, 9);
    j.num("hausdorff_percent", diag > 0 ? 100 * r.hausdorff / diag : 0.0, 6);
    j.num("hausdorff_bound_percent", diag > 0 ? 100 * r.hausdorff_bound / diag : 0.0, 6);
    add_side(j, "a_to_b", r.a_to_b);
    add_side(j, "b_to_a", r.b_to_a);
    j.num("area_a", r.area_a, 9).num("area_b", r.area_b, 9);
    j.num("area_ratio", r.area_a > 0 ? r.area_b / r.area_a : 0.0, 6);
    j.num("volume_a", r.volume_a, 9).num("volume_b", r.volume_b, 9);
    j.num("volume_ratio", r.volume_a != 0 ? r.volume_b / r.volume_a : 0.0, 6);
    j.num("normal_mean_deg", r.normal_mean_deg, 4).num("normal_max_deg", r.normal_max_deg, 4);
    j.num("ms", ms, 1);
    std::printf("%s\n", j.done().c_str());
    return kExitOk;
  }
  std::string t;
  t +=
      strf("A: %s (%s)\nB: %s (%s)\n", printable(a.a).c_str(), count_of(r.triangles_a, "triangle", "triangles").c_str(),
           printable(a.b).c_str(), count_of(r.triangles_b, "triangle", "triangles").c_str());
  t += strf("bounding-box diagonal of A: %.6g; sampling spacing %.3g (%s + %s samples)\n", diag, r.spacing,
            thousands(r.a_to_b.samples).c_str(), thousands(r.b_to_a.samples).c_str());
  t += distance_line("Hausdorff (symmetric)", r.hausdorff, diag);
  t += distance_line("  guaranteed at most", r.hausdorff_bound, diag);
  t += distance_line("A to B: max", r.a_to_b.max, diag);
  t += distance_line("        mean", r.a_to_b.mean, diag);
  t += distance_line("        RMS", r.a_to_b.rms, diag);
  t += distance_line("B to A: max", r.b_to_a.max, diag);
  t += distance_line("        mean", r.b_to_a.mean, diag);
  t += distance_line("        RMS", r.b_to_a.rms, diag);
  t += strf("  %-28s %.6g / %.6g = %.6f\n", "area B / A", r.area_b, r.area_a, r.area_a > 0 ? r.area_b / r.area_a : 0.0);
  t += strf("  %-28s %.6g / %.6g = %.6f\n", "volume B / A", r.volume_b, r.volume_a,
            r.volume_a != 0 ? r.volume_b / r.volume_a : 0.0);
  t += strf("  %-28s mean %.3f, max %.3f degrees\n", "normal deviation", r.normal_mean_deg, r.normal_max_deg);
  t += strf("measured in %s\n", duration_text(ms).c_str());
  std::fputs(t.c_str(), stdout);
  return kExitOk;
}

}  // namespace tsm::cli
