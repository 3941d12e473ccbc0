// Distance between two surfaces (Metro: Cignoni, Rocchini, Scopigno 1998):
// sample each surface on a regular barycentric grid per triangle, measure
// every sample's exact distance to the other surface through a BVH, and
// bound the distance between samples (see DistanceReport::hausdorff_bound).
#include "tsm/distance.hpp"

#include <algorithm>
#include <cmath>

#include "triangle_bvh.hpp"

namespace tsm {
namespace {

using geom::Vec3;

struct Side {
  OneSidedDistance d;
  double weighted_normal_angle = 0, max_normal_angle = 0, area = 0;
};

double triangle_area(Vec3 a, Vec3 b, Vec3 c) { return 0.5 * geom::length(geom::cross(b - a, c - a)); }

double signed_volume(const geom::TriangleSet& s) {
  double v = 0;
  for (size_t t = 0; t < s.size(); ++t) v += geom::dot(s.corner(t, 0), geom::cross(s.corner(t, 1), s.corner(t, 2)));
  return v / 6;
}

double longest_edge(Vec3 a, Vec3 b, Vec3 c) {
  return std::max({geom::length(b - a), geom::length(c - b), geom::length(a - c)});
}

// Grid segments per edge for triangle t at this spacing.
uint32_t segments(const geom::TriangleSet& s, size_t t, double spacing) {
  const double l = longest_edge(s.corner(t, 0), s.corner(t, 1), s.corner(t, 2));
  const double n = std::ceil(l / spacing);
  return static_cast<uint32_t>(std::clamp(n, 1.0, 4096.0));
}

// The spacing that gives about `target` samples over the set.
double auto_spacing(const geom::TriangleSet& s, uint64_t target) {
  // A grid of n segments has (n+1)(n+2)/2 points; search the spacing.
  double lo = 1e-12, hi = 0;
  for (size_t t = 0; t < s.size(); ++t) hi = std::max(hi, longest_edge(s.corner(t, 0), s.corner(t, 1), s.corner(t, 2)));
  if (!(hi > 0)) return 1;
  hi *= 2;
  lo = hi * 1e-6;
  for (int it = 0; it < 40; ++it) {
    const double mid = std::sqrt(lo * hi);
    uint64_t count = 0;
    for (size_t t = 0; t < s.size() && count <= target; ++t) {
      const uint64_t n = segments(s, t, mid);
      count += (n + 1) * (n + 2) / 2;
    }
    if (count > target)
      lo = mid;
    else
      hi = mid;
  }
  return hi;
}

double angle_deg(Vec3 a, Vec3 b) {
  const double la = geom::length(a), lb = geom::length(b);
  if (!(la > 0) || !(lb > 0)) return 0;
  const double c = std::clamp(geom::dot(a, b) / (la * lb), -1.0, 1.0);
  return std::acos(c) * (180.0 / M_PI);
}

// Samples X, measures against Y.
Side measure_side(const geom::TriangleSet& x, const geom::TriangleSet& y, const geom::TriangleBvh& bvh,
                  double spacing) {
  Side side;
  double sum = 0, sum2 = 0, weight = 0;
  std::vector<Vec3> pts;
  std::vector<double> dist;
  std::vector<int64_t> near;
  int64_t hint = -1;
  for (size_t t = 0; t < x.size(); ++t) {
    const Vec3 a = x.corner(t, 0), b = x.corner(t, 1), c = x.corner(t, 2);
    const uint32_t n = segments(x, t, spacing);
    const size_t count = static_cast<size_t>(n + 1) * (n + 2) / 2;
    pts.resize(count);
    dist.resize(count);
    near.resize(count);
    // Row i (0..n) from a towards c, point j (0..n-i) along it towards b.
    size_t k = 0;
    for (uint32_t i = 0; i <= n; ++i)
      for (uint32_t j = 0; j <= n - i; ++j, ++k) {
        const double u = static_cast<double>(j) / n, v = static_cast<double>(i) / n;
        pts[k] = a + (b - a) * u + (c - a) * v;
        double d2;
        hint = near[k] = bvh.nearest(pts[k], d2, hint);
        dist[k] = std::sqrt(d2);
      }
    const double area = triangle_area(a, b, c);
    const Vec3 normal = geom::cross(b - a, c - a);
    const double w = area / static_cast<double>(count);
    for (size_t q = 0; q < count; ++q) {
      sum += w * dist[q];
      sum2 += w * dist[q] * dist[q];
      side.d.max = std::max(side.d.max, dist[q]);
    }
    weight += area;
    side.d.samples += count;
    // Bound over each sub-triangle (corners p, q, r: indices into pts).
    const double cover = longest_edge(a, b, c) / n / std::sqrt(3.0);
    auto row = [n](uint32_t i) { return static_cast<size_t>(i) * (2 * n + 3 - i) / 2; };
    // The centroid's nearest triangle gives the normal deviation (corners on
    // an edge of Y have two nearest triangles) and a fourth candidate.
    const double sub_weight = area / (static_cast<double>(n) * n);
    auto bound = [&](size_t p, size_t q, size_t r) {
      const double lip = std::max({dist[p], dist[q], dist[r]}) + cover;
      double best = lip, d2;
      const int64_t mid = bvh.nearest((pts[p] + pts[q] + pts[r]) * (1.0 / 3), d2, near[p]);
      const double ang =
          angle_deg(normal, geom::cross(y.corner(mid, 1) - y.corner(mid, 0), y.corner(mid, 2) - y.corner(mid, 0)));
      side.weighted_normal_angle += sub_weight * ang;
      side.max_normal_angle = std::max(side.max_normal_angle, ang);
      for (int64_t tri : {mid, near[p], near[q], near[r]}) {
        const Vec3 ta = y.corner(tri, 0), tb = y.corner(tri, 1), tc = y.corner(tri, 2);
        const double m =
            std::max({geom::point_triangle_dist2(pts[p], ta, tb, tc), geom::point_triangle_dist2(pts[q], ta, tb, tc),
                      geom::point_triangle_dist2(pts[r], ta, tb, tc)});
        best = std::min(best, std::sqrt(m));
      }
      side.d.bound = std::max(side.d.bound, best);
    };
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = 0; j < n - i; ++j) {
        const size_t p = row(i) + j, q = p + 1, r = row(i + 1) + j;
        bound(p, q, r);
        if (j + 1 < n - i) bound(q, r + 1, r);
      }
  }
  side.area = weight;
  if (weight > 0) {
    side.d.mean = sum / weight;
    side.d.rms = std::sqrt(sum2 / weight);
    side.weighted_normal_angle /= weight;
  }
  side.d.bound = std::max(side.d.bound, side.d.max);
  return side;
}

bool finite_positions(const Mesh& m) {
  for (float v : m.positions)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

Status measure_distance(const Mesh& a, const Mesh& b, const DistanceOptions& options, DistanceReport& report) {
  report = DistanceReport{};
  if (!finite_positions(a) || !finite_positions(b))
    return Status(ErrorCode::invalid_argument, "a position is NaN or infinite: distances cannot be measured");
  const geom::TriangleSet sa = geom::triangles_of(a), sb = geom::triangles_of(b);
  if (sa.size() == 0 || sb.size() == 0)
    return Status(ErrorCode::invalid_argument, std::string("mesh ") + (sa.size() == 0 ? "A" : "B") +
                                                   " has no triangles: there is no surface to measure");
  if (!(options.spacing >= 0) || (options.spacing == 0 && options.target_samples == 0))
    return Status(ErrorCode::invalid_argument, "the sampling spacing must be positive (or 0 with a sample target)");
  const geom::TriangleBvh bvh_a(sa), bvh_b(sb);
  const double spacing_a = options.spacing > 0 ? options.spacing : auto_spacing(sa, options.target_samples);
  const double spacing_b = options.spacing > 0 ? options.spacing : auto_spacing(sb, options.target_samples);
  const Side ab = measure_side(sa, sb, bvh_b, spacing_a);
  const Side ba = measure_side(sb, sa, bvh_a, spacing_b);
  report.a_to_b = ab.d;
  report.b_to_a = ba.d;
  report.hausdorff = std::max(ab.d.max, ba.d.max);
  report.hausdorff_bound = std::max(ab.d.bound, ba.d.bound);
  report.spacing = std::max(spacing_a, spacing_b);
  report.diagonal = bounding_box(a).diagonal();
  report.area_a = ab.area;
  report.area_b = ba.area;
  report.volume_a = signed_volume(sa);
  report.volume_b = signed_volume(sb);
  report.normal_mean_deg = ab.weighted_normal_angle;
  report.normal_max_deg = ab.max_normal_angle;
  report.triangles_a = sa.size();
  report.triangles_b = sb.size();
  return Status::Ok();
}

}  // namespace tsm
