// The generated classes of meshes that break repair filters on CAD exports
// and broken scans (the C++ side of tests/robustness_shapes.py, which the
// integration suites use): coordinates from 1e-30 to near FLT_MAX, coplanar
// contact between parts, non-manifold and inconsistently oriented exports,
// STL soups with T-junctions, walls with holes, spindle and self-touching
// tori, and an OpenSCAD-like export of overlapping solids never united.
#pragma once

#include <cfloat>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "mesh_builders.h"

namespace meshmend::testing {

// Several meshes in one (indices offset), as an export writes separate solids.
inline Mesh combined(const std::vector<Mesh>& parts) {
  std::vector<Point3> p;
  std::vector<Triangle> t;
  for (const Mesh& m : parts) {
    const int offset = int(p.size());
    for (const Point3& q : positionsOf(m)) p.push_back(q);
    for (Triangle f : trianglesOf(m)) {
      for (int& v : f) v += offset;
      t.push_back(f);
    }
  }
  return makeMesh(p, t);
}

// The box [lo, hi] (outward faces).
inline Mesh boxAt(Point3 lo, Point3 hi) {
  Mesh b = box(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  return moved(b, lo);
}

// Vertices with equal coordinates merged (faces re-pointed).
inline Mesh welded(const Mesh& m) {
  Mesh w = m;
  weldCoincidentVertices(w);
  return w;
}

// A torus around z, R the radius of its centre circle, r of its tube. R < r:
// a spindle torus, whose meridians all pass through the two points where the
// tube meets the axis (none of them a vertex); R == r: a horn torus,
// touching itself at the centre. `squeeze` scales y.
inline Mesh torusOf(double R, double r, int around, int tube, double squeeze = 1) {
  std::vector<Point3> p;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      const double u = 2 * M_PI * i / around, v = 2 * M_PI * j / tube;
      const double rad = R + r * std::cos(v);
      p.emplace_back(rad * std::cos(u), rad * std::sin(u) * squeeze, r * std::sin(v));
    }
  auto at = [&](int i, int j) { return (i % around) * tube + (j % tube); };
  std::vector<Triangle> t;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return makeMesh(p, t);
}

// A torus whose centre curve is an ellipse with semi-axes a (x) and b (y):
// with b equal to the tube radius r, the walls of the hole touch along the y
// axis; with b < r they pass through each other there (squeezed).
inline Mesh squeezedTorus(double a, double b, double r, int around = 48, int tube = 24) {
  std::vector<Point3> p;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      const double u = 2 * M_PI * i / around, v = 2 * M_PI * j / tube;
      const Point3 c(a * std::cos(u), b * std::sin(u), 0);
      Point3 n(b * std::cos(u), a * std::sin(u), 0);
      n /= n.Norm();
      p.push_back(c + n * (r * std::cos(v)) + Point3(0, 0, r * std::sin(v)));
    }
  auto at = [&](int i, int j) { return (i % around) * tube + (j % tube); };
  std::vector<Triangle> t;
  for (int i = 0; i < around; ++i)
    for (int j = 0; j < tube; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return makeMesh(p, t);
}

inline Mesh scaledBy(const Mesh& m, double s) {
  std::vector<Point3> p = positionsOf(m);
  for (Point3& q : p) q *= s;
  return makeMesh(p, trianglesOf(m));
}

// Every face with its own three vertices, as an STL stores them.
inline Mesh soupOf(const Mesh& m) {
  const std::vector<Point3> P = positionsOf(m);
  std::vector<Point3> p;
  std::vector<Triangle> t;
  for (const Triangle& f : trianglesOf(m)) {
    const int n = int(p.size());
    for (int v : f) p.push_back(P[v]);
    t.push_back({n, n + 1, n + 2});
  }
  return makeMesh(p, t);
}

inline Mesh withFlippedFaces(const Mesh& m, const std::vector<int>& faces) {
  std::vector<Triangle> t = trianglesOf(m);
  for (int f : faces) std::swap(t[f][1], t[f][2]);
  return makeMesh(positionsOf(m), t);
}

// A unit box whose top is fanned from a point in the middle of its edge
// along y = 0, which the side below does not have: a T-junction.
inline Mesh boxWithTJunction() {
  std::vector<Point3> p = positionsOf(box());
  std::vector<Triangle> t;
  for (const Triangle& f : trianglesOf(box()))
    if (!(p[f[0]][2] == 1 && p[f[1]][2] == 1 && p[f[2]][2] == 1)) t.push_back(f);
  p.emplace_back(0.5, 0, 1);  // 8
  t.push_back({4, 8, 6});
  t.push_back({8, 7, 6});
  t.push_back({8, 5, 7});
  return makeMesh(p, t);
}

// A wall 4 x 4 x 1 with a 2 x 2 hole through it (closed, genus 1); with
// `openSide`, the faces lining one side of the hole are left out.
inline Mesh wallWithHole(bool openSide = false) {
  std::vector<Point3> p;
  std::vector<Triangle> t;
  auto quad = [&](Point3 a, Point3 b, Point3 c, Point3 d) {
    const int n = int(p.size());
    p.insert(p.end(), {a, b, c, d});
    t.push_back({n, n + 1, n + 2});
    t.push_back({n, n + 2, n + 3});
  };
  const double outer[4][2] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
  const double inner[4][2] = {{1, 1}, {3, 1}, {3, 3}, {1, 3}};
  for (int k = 0; k < 4; ++k) {
    const int l = (k + 1) % 4;
    // bottom (z = 0, facing down) and top (z = 1, facing up) rings
    quad({outer[k][0], outer[k][1], 0}, {inner[k][0], inner[k][1], 0},
         {inner[l][0], inner[l][1], 0}, {outer[l][0], outer[l][1], 0});
    quad({outer[k][0], outer[k][1], 1}, {outer[l][0], outer[l][1], 1},
         {inner[l][0], inner[l][1], 1}, {inner[k][0], inner[k][1], 1});
    quad({outer[k][0], outer[k][1], 0}, {outer[l][0], outer[l][1], 0},
         {outer[l][0], outer[l][1], 1}, {outer[k][0], outer[k][1], 1});
    if (openSide && k == 0) continue;
    quad({inner[l][0], inner[l][1], 0}, {inner[k][0], inner[k][1], 0},
         {inner[k][0], inner[k][1], 1}, {inner[l][0], inner[l][1], 1});
  }
  return welded(makeMesh(p, t));
}

// A closed cylinder of `n` sides along axis z (centred at c), outward.
inline Mesh cylinderAt(Point3 c, double radius, double height, int n = 12) {
  return moved(cappedCylinder(n, 1, radius, radius, -height / 2, height), c);
}

// Boxes and cylinders on a coarse grid, overlapping each other and sharing
// face planes, in one mesh without any boolean: an OpenSCAD-like union
// exported naively. Each part closed and outward.
inline Mesh openscadExport(int parts = 24, unsigned seed = 7) {
  std::mt19937 random(seed);
  auto cell = [&](int n) { return double(std::uniform_int_distribution<int>(0, n - 1)(random)); };
  std::vector<Mesh> meshes;
  for (int k = 0; k < parts; ++k) {
    const Point3 lo(cell(6), cell(6), cell(6));
    if (k % 3 == 2)
      meshes.push_back(cylinderAt(lo + Point3(1, 1, 1), 0.5 * (1 + cell(2)), 2 + cell(3)));
    else
      meshes.push_back(boxAt(lo, lo + Point3(1 + cell(3), 1 + cell(3), 1 + cell(3))));
  }
  return combined(meshes);
}

// Two boxes stacked (touching in a plane) and a third overlapping the
// lower one with coplanar sides.
inline Mesh coplanarParts() {
  return combined({boxAt({0, 0, 0}, {2, 2, 1}), boxAt({0.5, 0.5, 1}, {1.5, 1.5, 2}),
                   boxAt({0.5, 0, 0}, {2.5, 1, 1})});
}

// Two boxes sharing one edge (four faces on it once welded), and a fin: a
// triangle hanging from an edge of a third box.
inline Mesh nonManifoldExport() {
  Mesh boxes = combined(
      {boxAt({0, 0, 0}, {1, 1, 1}), boxAt({1, 1, 0}, {2, 2, 1}), boxAt({3, 0, 0}, {4, 1, 1})});
  std::vector<Point3> p = positionsOf(boxes);
  std::vector<Triangle> t = trianglesOf(boxes);
  p.emplace_back(3.5, -1, 0.5);
  t.push_back({16, 17, int(p.size()) - 1});  // on edge (3,0,0)-(4,0,0) of the third box
  return welded(makeMesh(p, t));
}

// Every class by name, small enough for unit tests.
inline std::vector<std::pair<std::string, Mesh>> robustnessClasses() {
  const Mesh t = torusOf(1.0, 0.4, 32, 16);
  return {
      {"tiny_1e-30", scaledBy(t, 1e-30)},
      {"huge_1e37", scaledBy(t, 1e37)},
      {"part_in_flt_max_box",
       combined({t, boxAt({-0.99 * FLT_MAX, -0.99 * FLT_MAX, -0.99 * FLT_MAX},
                          {0.99 * FLT_MAX, 0.99 * FLT_MAX, 0.99 * FLT_MAX})})},
      {"coplanar_parts", coplanarParts()},
      {"non_manifold_export", nonManifoldExport()},
      {"inconsistently_oriented", withFlippedFaces(box(), {0, 5})},
      {"stl_soup_t_junctions", soupOf(boxWithTJunction())},
      {"wall_with_hole", wallWithHole()},
      {"wall_with_open_hole", wallWithHole(true)},
      {"spindle_torus", torusOf(0.3, 1.0, 64, 32)},
      {"horn_torus", torusOf(1.0, 1.0, 48, 24)},
      {"touching_torus", squeezedTorus(1.0, 0.5, 0.5)},
      {"squeezed_torus", squeezedTorus(1.0, 0.4, 0.5)},
      {"openscad_export", openscadExport()},
  };
}

}  // namespace meshmend::testing
