// Small meshes built in code for the unit tests.
#pragma once

#include <cmath>
#include <vector>

#include "common/mesh.h"

namespace meshmend::testing {

// Positively oriented (outward normals) tetrahedron, volume 1/6.
inline Mesh tetrahedron() {
  return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                  {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

// Axis-aligned box [0,sx]x[0,sy]x[0,sz] with outward normals, 12 triangles.
inline Mesh box(double sx = 1, double sy = 1, double sz = 1) {
  std::vector<Point3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? sx : 0, i & 2 ? sy : 0, i & 4 ? sz : 0);
  return makeMesh(p, {{0, 2, 1},
                      {1, 2, 3},
                      {4, 5, 6},
                      {5, 7, 6},
                      {0, 1, 4},
                      {1, 5, 4},
                      {2, 6, 3},
                      {3, 6, 7},
                      {0, 4, 2},
                      {2, 4, 6},
                      {1, 3, 5},
                      {3, 7, 5}});
}

// Latitude-longitude sphere of radius r: `rings` latitude bands, `segments`
// longitudes; closed, genus 0, outward normals.
inline Mesh uvSphere(int rings, int segments, double r = 1, Point3 c = {0, 0, 0}) {
  std::vector<Point3> p{c + Point3(0, 0, r)};
  for (int i = 1; i < rings; ++i) {
    const double th = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * M_PI * j / segments;
      p.push_back(c + Point3(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph),
                             r * std::cos(th)));
    }
  }
  p.push_back(c + Point3(0, 0, -r));
  const int south = int(p.size()) - 1;
  auto at = [&](int ring, int seg) { return 1 + (ring - 1) * segments + (seg % segments); };
  std::vector<Triangle> t;
  for (int j = 0; j < segments; ++j) t.push_back({0, at(1, j), at(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) t.push_back({south, at(rings - 1, j + 1), at(rings - 1, j)});
  return makeMesh(p, t);
}

// A copy of `m` moved by `by`.
inline Mesh moved(const Mesh& m, Point3 by) {
  std::vector<Point3> p = positionsOf(m);
  for (Point3& q : p) q += by;
  return makeMesh(p, trianglesOf(m));
}

}  // namespace meshmend::testing
