// Core meshes as CGAL Surface_meshes, for the peers in the benchmarks.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>

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

// A triangle soup in CGAL's points: what a peer's output, or an input that
// is no valid Surface_mesh, is measured on.
struct Soup {
  std::vector<Kernel::Point_3> points;
  std::vector<std::vector<std::size_t>> triangles;
};

inline Soup soupOf(const Mesh& m) {
  Soup s;
  for (const Point3& p : positionsOf(m)) s.points.emplace_back(p[0], p[1], p[2]);
  for (const Triangle& t : trianglesOf(m))
    s.triangles.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  return s;
}

// Intersecting pairs of a soup that need not be a polygon mesh: CGAL's
// box_self_intersection_d and exact predicates, with the rule of
// PMP::self_intersections (faces sharing a vertex intersect if an opposite
// edge meets the other face; sharing an edge, if they fold onto each
// other). Degenerate faces are skipped and counted in `degenerate`.
inline long soupPairs(const Soup& s, long& degenerate) {
  using K = Kernel;
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  std::vector<K::Triangle_3> tris;
  std::vector<Box> boxes;
  degenerate = 0;
  for (std::size_t f = 0; f < s.triangles.size(); ++f) {
    const auto& t = s.triangles[f];
    tris.emplace_back(s.points[t[0]], s.points[t[1]], s.points[t[2]]);
    if (tris.back().is_degenerate())
      ++degenerate;
    else
      boxes.emplace_back(tris.back().bbox(), f);
  }
  long pairs = 0;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
    const auto &a = s.triangles[x.info()], &b = s.triangles[y.info()];
    const K::Triangle_3 &ta = tris[x.info()], &tb = tris[y.info()];
    int shared = 0, ia = -1, ib = -1;  // corners of a and b on a shared vertex
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (a[i] == b[j]) ++shared, ia = i, ib = j;
    bool hit = false;
    if (shared == 0) {
      hit = CGAL::do_intersect(ta, tb);
    } else if (shared == 1) {
      hit = CGAL::do_intersect(tb, K::Segment_3(ta[(ia + 1) % 3], ta[(ia + 2) % 3])) ||
            CGAL::do_intersect(ta, K::Segment_3(tb[(ib + 1) % 3], tb[(ib + 2) % 3]));
    } else if (shared == 2) {
      int apexA = 0, apexB = 0;  // the corners off the shared edge
      while (std::count(b.begin(), b.end(), a[apexA])) ++apexA;
      while (std::count(a.begin(), a.end(), b[apexB])) ++apexB;
      const K::Point_3 &p = ta[(apexA + 1) % 3], &q = ta[(apexA + 2) % 3];
      hit = CGAL::coplanar(p, q, ta[apexA], tb[apexB]) &&
            CGAL::coplanar_orientation(p, q, ta[apexA], tb[apexB]) == CGAL::POSITIVE;
    } else {
      hit = true;
    }
    pairs += hit;
  });
  return pairs;
}

}  // namespace meshmend::bench
