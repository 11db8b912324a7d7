// Core meshes as CGAL Surface_meshes, for the peers in the benchmarks.
#pragma once

#include <stdexcept>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>

#include "common/base/mesh.h"

namespace meshmend::bench {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// Throws std::runtime_error when CGAL's Surface_mesh refuses the soup
// (non-manifold edges or vertices, inconsistent orientation).
inline SurfaceMesh toSurfaceMesh(const Mesh& m) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  std::vector<Kernel::Point_3> points;
  for (const Point3& p : positionsOf(m)) points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> polygons;
  for (const Triangle& t : trianglesOf(m))
    polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    throw std::runtime_error("not a polygon mesh for CGAL's Surface_mesh");
  SurfaceMesh tm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, tm);
  return tm;
}

}  // namespace meshmend::bench
