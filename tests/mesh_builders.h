// Small meshes built in code for the unit tests.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "common/base/mesh.h"

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

// Icosahedron subdivided `levels` times, projected onto the sphere of radius
// r around c: near-uniform triangles (20 * 4^levels), closed, outward normals.
inline Mesh icosphere(int levels, double r = 1, Point3 c = {0, 0, 0}) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Point3> p{{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                        {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Triangle> f{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                          {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                          {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                          {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Point3& q : p) q.Normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      Point3 m = (p[a] + p[b]) / 2;
      m.Normalize();
      p.push_back(m);
      return middle[key] = int(p.size()) - 1;
    };
    std::vector<Triangle> next;
    for (const Triangle& q : f) {
      const int ab = mid(q[0], q[1]), bc = mid(q[1], q[2]), ca = mid(q[2], q[0]);
      next.push_back({q[0], ab, ca});
      next.push_back({q[1], bc, ab});
      next.push_back({q[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  for (Point3& q : p) q = c + q * r;
  return makeMesh(p, f);
}

// Grid of nx x ny squares of side `cell` in the xy plane from the origin,
// each cut into two triangles (normals +z), lifted to z = height(x, y);
// `keep(x, y)` (the square's centre) decides which squares are kept.
template <class Height, class Keep>
Mesh heightGrid(int nx, int ny, double cell, Height&& height, Keep&& keep) {
  std::vector<Point3> p;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) p.emplace_back(i * cell, j * cell, height(i * cell, j * cell));
  auto at = [&](int i, int j) { return j * (nx + 1) + i; };
  std::vector<Triangle> t;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (!keep((i + 0.5) * cell, (j + 0.5) * cell)) continue;
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return makeMesh(p, t);
}

// The cube [0,s]^3 with each side an n x n grid of squares cut into two
// triangles; closed, welded, outward normals.
inline Mesh gridCube(int n, double s = 1) {
  std::vector<Point3> p;
  std::vector<Triangle> t;
  std::map<std::array<long, 3>, int> index;  // grid coordinates -> vertex
  auto vertex = [&](const std::array<int, 3>& g) {
    const std::array<long, 3> key{g[0], g[1], g[2]};
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    p.emplace_back(s * g[0] / n, s * g[1] / n, s * g[2] / n);
    return index[key] = int(p.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          auto at = [&](int a, int b) {
            std::array<int, 3> g{};
            g[axis] = side * n;
            g[(axis + 1) % 3] = a;
            g[(axis + 2) % 3] = b;
            return vertex(g);
          };
          const int v00 = at(i, j), v10 = at(i + 1, j), v11 = at(i + 1, j + 1), v01 = at(i, j + 1);
          if (side == 1) {
            t.push_back({v00, v10, v11});
            t.push_back({v00, v11, v01});
          } else {
            t.push_back({v00, v11, v10});
            t.push_back({v00, v01, v11});
          }
        }
  return makeMesh(p, t);
}

// An open tube (no caps) of radius r around the z axis from z = 0 to h:
// `around` vertices per ring (alternate rings turned by half a step),
// `along` bands; outward normals.
inline Mesh openTube(int around, int along, double r, double h) {
  std::vector<Point3> p;
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const double a = 2 * M_PI * (i + 0.5 * (j % 2)) / around;
      p.emplace_back(r * std::cos(a), r * std::sin(a), h * j / along);
    }
  auto at = [&](int i, int j) { return j * around + (i % around); };
  std::vector<Triangle> t;
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      if (j % 2 == 0) {
        t.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        t.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      } else {
        t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      }
    }
  return makeMesh(p, t);
}

// A closed cylinder around the z axis from z = z0 to z0 + h with an
// elliptic section (radii rx, ry): `around` vertices per ring, `along`
// bands, each cap a fan around a centre vertex; outward normals.
inline Mesh cappedCylinder(int around, int along, double rx, double ry, double z0, double h) {
  std::vector<Point3> p;
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const double a = 2 * M_PI * i / around;
      p.emplace_back(rx * std::cos(a), ry * std::sin(a), z0 + h * j / along);
    }
  const int bottom = int(p.size());
  p.emplace_back(0, 0, z0);
  p.emplace_back(0, 0, z0 + h);
  auto at = [&](int i, int j) { return j * around + (i % around); };
  std::vector<Triangle> t;
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int i = 0; i < around; ++i) {
    t.push_back({bottom, at(i + 1, 0), at(i, 0)});
    t.push_back({bottom + 1, at(i, along), at(i + 1, along)});
  }
  return makeMesh(p, t);
}

// `m` with every face turned over (normals reversed), e.g. the inner skin
// of a hollow part.
inline Mesh flipped(const Mesh& m) {
  std::vector<Triangle> t = trianglesOf(m);
  for (Triangle& f : t) std::swap(f[1], f[2]);
  return makeMesh(positionsOf(m), t);
}

// `m` with its coordinates rounded to a grid of spacing `step`, as a lossy
// codec's quantisation does.
inline Mesh quantized(const Mesh& m, double step) {
  std::vector<Point3> p = positionsOf(m);
  for (Point3& q : p)
    for (int k = 0; k < 3; ++k) q[k] = std::round(q[k] / step) * step;
  return makeMesh(p, trianglesOf(m));
}

// `mesh` without the faces whose centroid `cut` accepts (a hole).
template <class Cut>
Mesh withHole(const Mesh& mesh, Cut&& cut) {
  std::vector<Triangle> kept;
  const std::vector<Point3> P = positionsOf(mesh);
  for (const Triangle& t : trianglesOf(mesh))
    if (!cut((P[t[0]] + P[t[1]] + P[t[2]]) / 3.0)) kept.push_back(t);
  return makeMesh(P, kept);
}

// Signed volume enclosed by a closed, consistently oriented mesh.
inline double volumeOf(const Mesh& m) {
  const std::vector<Point3> P = positionsOf(m);
  double v = 0;
  for (const Triangle& t : trianglesOf(m)) v += P[t[0]] * (P[t[1]] ^ P[t[2]]);
  return v / 6;
}

// Edge counts by use: border (one face), non-manifold (three or more),
// inconsistent (two faces running the edge the same way).
struct EdgeStats {
  std::size_t border = 0, nonManifold = 0, inconsistent = 0;
};
inline EdgeStats edgeStats(const Mesh& mesh) {
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<EdgeUse> uses = edgeUses(T);
  EdgeStats s;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 1) ++s.border;
    if (j - i > 2) ++s.nonManifold;
    if (j - i == 2 && T[uses[i].face][uses[i].corner] == T[uses[i + 1].face][uses[i + 1].corner])
      ++s.inconsistent;
    i = j;
  }
  return s;
}

}  // namespace meshmend::testing
