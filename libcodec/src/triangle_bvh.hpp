// Nearest-triangle queries for the distance measurement (distance.cpp) and
// the error-bounded simplifier (simplify.cpp): exact point-to-triangle
// distance, and a bounding-volume hierarchy over a triangle set.
#pragma once
#include <cstdint>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm::geom {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(Vec3 a);
Vec3 lerp(Vec3 a, Vec3 b, double t);
// Each coordinate rounded to the nearest float. Through a volatile: GCC 12's
// SLP vectorizer folds adjacent double -> float -> double round trips into
// plain copies (x and y came back unrounded), so a point written as floats
// would differ from the one a bound was proven for.
Vec3 to_float(Vec3 p);

// Squared distance from p to the triangle (a, b, c) (degenerate ones too).
double point_triangle_dist2(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

// The triangles of a mesh: polygons split as fans, faces with fewer than
// three corners left out. face_of[t] is the mesh face triangle t came from.
struct TriangleSet {
  std::vector<Vec3> points;       // the mesh's positions
  std::vector<uint32_t> corners;  // 3 per triangle
  std::vector<uint32_t> face_of;
  size_t size() const { return corners.size() / 3; }
  Vec3 corner(size_t t, int k) const { return points[corners[3 * t + k]]; }
};
TriangleSet triangles_of(const Mesh& mesh);

// A BVH over a TriangleSet (kept by reference: it must outlive the BVH).
class TriangleBvh {
 public:
  explicit TriangleBvh(const TriangleSet& set);
  // The nearest triangle to p: its index and squared distance. `hint` (a
  // triangle index, or -1) seeds the search with a known upper bound.
  // An empty set gives -1 and +inf.
  int64_t nearest(Vec3 p, double& dist2, int64_t hint = -1) const;
  // Calls visit(t) for every triangle whose box is within `r` of the box
  // [lo, hi]; stops when visit returns true (and returns true then).
  template <typename F>
  bool any_near(Vec3 lo, Vec3 hi, double r, F visit) const;

 private:
  struct Node {
    float lo[3], hi[3];
    uint32_t first, count;  // leaf: triangles order_[first..first+count); inner: count = 0, children first, first+1
  };
  struct Box {
    float lo[3], hi[3];
  };
  static Box triangle_box(const TriangleSet& set, size_t t);
  void build(uint32_t node, uint32_t begin, uint32_t end, std::vector<Vec3>& centroid, const std::vector<Box>& box);
  static double box_dist2(const float* lo, const float* hi, Vec3 p) {
    const double q[3] = {p.x, p.y, p.z};
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = q[a] < lo[a] ? lo[a] - q[a] : q[a] > hi[a] ? q[a] - hi[a] : 0.0;
      d2 += d * d;
    }
    return d2;
  }
  static double box_dist2(const Node& n, Vec3 p) { return box_dist2(n.lo, n.hi, p); }
  static double box_dist2(const Box& b, Vec3 p) { return box_dist2(b.lo, b.hi, p); }

  // The distance to the triangle at position i of order_.
  double leaf_dist2(uint32_t i, Vec3 p) const {
    if (!float_corners_.empty()) {
      const float* c = &float_corners_[9 * static_cast<size_t>(i)];
      return point_triangle_dist2(p, {c[0], c[1], c[2]}, {c[3], c[4], c[5]}, {c[6], c[7], c[8]});
    }
    const uint32_t t = order_[i];
    return point_triangle_dist2(p, set_.corner(t, 0), set_.corner(t, 1), set_.corner(t, 2));
  }

  const TriangleSet& set_;
  std::vector<Node> nodes_;
  std::vector<uint32_t> order_;
  std::vector<Box> leaf_box_;  // per position in order_: its triangle's box
  // Per position in order_: its triangle's corners as floats, side by side
  // (a leaf's triangles in one or two cache lines, not through the point
  // indices); empty when a corner is not exactly a float (then set_ is read).
  std::vector<float> float_corners_;
};

template <typename F>
bool TriangleBvh::any_near(Vec3 lo, Vec3 hi, double r, F visit) const {
  if (nodes_.empty()) return false;
  uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (n.lo[0] > hi.x + r || n.hi[0] < lo.x - r || n.lo[1] > hi.y + r || n.hi[1] < lo.y - r || n.lo[2] > hi.z + r ||
        n.hi[2] < lo.z - r)
      continue;
    if (n.count > 0) {
      for (uint32_t i = n.first; i < n.first + n.count; ++i)
        if (visit(order_[i])) return true;
    } else if (top + 2 <= 128) {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
  }
  return false;
}

}  // namespace tsm::geom
