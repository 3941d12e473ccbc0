// The independent distance oracle: CGAL's bounded-error Hausdorff distance
// (Polygon_mesh_processing), for tests and benchmarks only. Header-only; the
// tsm libraries never include it.
#pragma once
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/distance.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <vector>

#include "tsm/mesh.hpp"

namespace tsm_oracle {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// The triangles of `m` (polygons as fans) as a CGAL surface mesh; vertices
// are duplicated where the soup is not manifold (the surface is the same).
inline SurfaceMesh to_cgal(const tsm::Mesh& m) {
  std::vector<Kernel::Point_3> points;
  for (size_t i = 0; i < m.vertex_count(); ++i)
    points.emplace_back(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
  std::vector<std::array<size_t, 3>> faces;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = m.face(f);
    for (uint32_t k = 2; k < m.face_size(f); ++k)
      if (c[0] != c[k - 1] && c[k - 1] != c[k] && c[0] != c[k]) faces.push_back({c[0], c[k - 1], c[k]});
  }
  CGAL::Polygon_mesh_processing::orient_polygon_soup(points, faces);
  SurfaceMesh out;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, out);
  return out;
}

// Symmetric Hausdorff distance between a and b, within `error_bound` of
// the true value (CGAL's bounded_error_symmetric_Hausdorff_distance).
inline double symmetric_hausdorff(const tsm::Mesh& a, const tsm::Mesh& b, double error_bound) {
  const SurfaceMesh ca = to_cgal(a), cb = to_cgal(b);
  return CGAL::Polygon_mesh_processing::bounded_error_symmetric_Hausdorff_distance<CGAL::Sequential_tag>(ca, cb,
                                                                                                         error_bound);
}

}  // namespace tsm_oracle
