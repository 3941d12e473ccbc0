// Nearest-triangle queries (see triangle_bvh.hpp): exact point-to-triangle
// distance (Ericson, Real-Time Collision Detection 5.1.5) and a median-split
// bounding-volume hierarchy searched nearest-child first.
#include "triangle_bvh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tsm::geom {

double length(Vec3 a) { return std::sqrt(dot(a, a)); }
Vec3 lerp(Vec3 a, Vec3 b, double t) { return a + (b - a) * t; }

namespace {
double round_to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}
}  // namespace

Vec3 to_float(Vec3 p) { return {round_to_float(p.x), round_to_float(p.y), round_to_float(p.z)}; }

double point_triangle_dist2(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto d2_to = [&](Vec3 q) {
    const Vec3 d = p - q;
    return dot(d, d);
  };
  if (d1 <= 0 && d2 <= 0) return d2_to(a);
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return d2_to(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double den = d1 - d3;
    return d2_to(den > 0 ? a + ab * (d1 / den) : a);
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return d2_to(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double den = d2 - d6;
    return d2_to(den > 0 ? a + ac * (d2 / den) : a);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double den = (d4 - d3) + (d5 - d6);
    return d2_to(den > 0 ? b + (c - b) * ((d4 - d3) / den) : b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // Degenerate (collinear) triangle: the nearest of its three edges.
    auto seg = [&](Vec3 s, Vec3 e) {
      const Vec3 d = e - s;
      const double dd = dot(d, d);
      const double t = dd > 0 ? std::clamp(dot(p - s, d) / dd, 0.0, 1.0) : 0.0;
      return d2_to(s + d * t);
    };
    return std::min({seg(a, b), seg(b, c), seg(c, a)});
  }
  const double v = vb / sum, w = vc / sum;
  return d2_to(a + ab * v + ac * w);
}

TriangleSet triangles_of(const Mesh& mesh) {
  TriangleSet s;
  s.points.resize(mesh.vertex_count());
  for (size_t i = 0; i < s.points.size(); ++i)
    s.points[i] = {mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]};
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t n = mesh.face_size(f);
    const uint32_t* c = mesh.face(f);
    for (uint32_t k = 2; k < n; ++k) {
      s.corners.insert(s.corners.end(), {c[0], c[k - 1], c[k]});
      s.face_of.push_back(static_cast<uint32_t>(f));
    }
  }
  return s;
}

TriangleBvh::TriangleBvh(const TriangleSet& set) : set_(set) {
  const size_t n = set.size();
  if (n == 0) return;
  order_.resize(n);
  std::vector<Vec3> centroid(n);
  std::vector<Box> box(n);
  for (size_t t = 0; t < n; ++t) {
    order_[t] = static_cast<uint32_t>(t);
    centroid[t] = (set.corner(t, 0) + set.corner(t, 1) + set.corner(t, 2)) * (1.0 / 3);
    box[t] = triangle_box(set, t);
  }
  nodes_.reserve(2 * n / 2 + 1);
  nodes_.push_back({});
  build(0, 0, static_cast<uint32_t>(n), centroid, box);
  leaf_box_.resize(n);
  for (size_t i = 0; i < n; ++i) leaf_box_[i] = box[order_[i]];
  float_corners_.resize(9 * n);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const Vec3 c = set.corner(order_[i], k), r = to_float(c);
      if (r.x != c.x || r.y != c.y || r.z != c.z) {
        float_corners_.clear();  // not exact as floats: the doubles are read instead
        float_corners_.shrink_to_fit();
        return;
      }
      float* f = &float_corners_[9 * i + 3 * k];
      f[0] = static_cast<float>(r.x), f[1] = static_cast<float>(r.y), f[2] = static_cast<float>(r.z);
    }
}

// A float box holding the double triangle: each bound rounded outwards once.
TriangleBvh::Box TriangleBvh::triangle_box(const TriangleSet& set, size_t t) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  Box b;
  for (int a = 0; a < 3; ++a) b.lo[a] = inf, b.hi[a] = -inf;
  for (int k = 0; k < 3; ++k) {
    const Vec3 p = set.corner(t, k);
    const double q[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      const float f = static_cast<float>(q[a]);
      b.lo[a] = std::min(b.lo[a], static_cast<double>(f) <= q[a] ? f : std::nextafter(f, -inf));
      b.hi[a] = std::max(b.hi[a], static_cast<double>(f) >= q[a] ? f : std::nextafter(f, inf));
    }
  }
  return b;
}

void TriangleBvh::build(uint32_t node, uint32_t begin, uint32_t end, std::vector<Vec3>& centroid,
                        const std::vector<Box>& box) {
  float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                 std::numeric_limits<float>::max()};
  float hi[3] = {-lo[0], -lo[0], -lo[0]};
  double clo[3] = {1e300, 1e300, 1e300}, chi[3] = {-1e300, -1e300, -1e300};
  for (uint32_t i = begin; i < end; ++i) {
    const uint32_t t = order_[i];
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], box[t].lo[a]), hi[a] = std::max(hi[a], box[t].hi[a]);
    const double c[3] = {centroid[t].x, centroid[t].y, centroid[t].z};
    for (int a = 0; a < 3; ++a) clo[a] = std::min(clo[a], c[a]), chi[a] = std::max(chi[a], c[a]);
  }
  Node& n = nodes_[node];
  for (int a = 0; a < 3; ++a) n.lo[a] = lo[a], n.hi[a] = hi[a];
  if (end - begin <= 4) {
    n.first = begin;
    n.count = end - begin;
    return;
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
  const uint32_t mid = begin + (end - begin) / 2;
  auto key = [&](uint32_t t) { return axis == 0 ? centroid[t].x : axis == 1 ? centroid[t].y : centroid[t].z; };
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](uint32_t x, uint32_t y) { return key(x) < key(y); });
  const uint32_t child = static_cast<uint32_t>(nodes_.size());
  nodes_[node].first = child;
  nodes_[node].count = 0;
  nodes_.push_back({});
  nodes_.push_back({});
  build(child, begin, mid, centroid, box);
  build(child + 1, mid, end, centroid, box);
}

int64_t TriangleBvh::nearest(Vec3 p, double& dist2, int64_t hint) const {
  dist2 = std::numeric_limits<double>::infinity();
  int64_t best = -1;
  if (nodes_.empty()) return best;
  if (hint >= 0 && static_cast<size_t>(hint) < set_.size()) {
    best = hint;
    dist2 = point_triangle_dist2(p, set_.corner(hint, 0), set_.corner(hint, 1), set_.corner(hint, 2));
  }
  struct Item {
    uint32_t node;
    double d2;
  };
  Item stack[128];
  int top = 0;
  stack[top++] = {0, box_dist2(nodes_[0], p)};
  while (top > 0) {
    const Item it = stack[--top];
    if (it.d2 >= dist2) continue;
    const Node& n = nodes_[it.node];
    if (n.count > 0) {
      for (uint32_t i = n.first; i < n.first + n.count; ++i) {
        if (box_dist2(leaf_box_[i], p) >= dist2) continue;  // cheaper than the exact distance
        const double d2 = leaf_dist2(i, p);
        if (d2 < dist2) dist2 = d2, best = order_[i];
      }
      continue;
    }
    const double a = box_dist2(nodes_[n.first], p), b = box_dist2(nodes_[n.first + 1], p);
    // The nearer child is searched first (pushed last).
    if (a < b) {
      if (b < dist2) stack[top++] = {n.first + 1, b};
      if (a < dist2) stack[top++] = {n.first, a};
    } else {
      if (a < dist2) stack[top++] = {n.first, a};
      if (b < dist2) stack[top++] = {n.first + 1, b};
    }
  }
  return best;
}

}  // namespace tsm::geom
