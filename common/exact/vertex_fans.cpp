#include "common/exact/vertex_fans.h"

#include <cmath>
#include <cstdint>

#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/exact/predicates.h"

namespace meshmend {

namespace {

// Face (v, a, b) seen from its corner v: the edge of v's link it adds.
struct Link {
  int a, b;
};

// Each vertex's link edges, by a counting sort on the faces' corners: those
// of vertex v are links[offsets[v]] .. links[offsets[v + 1] - 1].
struct Links {
  std::vector<std::uint32_t> offsets;
  std::vector<Link> links;
};

Links linksOf(std::size_t vertexCount, const std::vector<Triangle>& triangles) {
  Links in;
  in.offsets.assign(vertexCount + 1, 0);
  for (const Triangle& t : triangles)
    for (int v : t) ++in.offsets[std::size_t(v) + 1];
  for (std::size_t v = 0; v < vertexCount; ++v) in.offsets[v + 1] += in.offsets[v];
  std::vector<std::uint32_t> next(in.offsets.begin(), in.offsets.end() - 1);
  resizeInHugePages(in.links, 3 * triangles.size());
  for (const Triangle& t : triangles) {
    in.links[next[std::size_t(t[0])]++] = {t[1], t[2]};
    in.links[next[std::size_t(t[1])]++] = {t[2], t[0]};
    in.links[next[std::size_t(t[2])]++] = {t[0], t[1]};
  }
  return in;
}

// Is every neighbour of v once the first and once the second corner after
// v in its faces? The fan's link edges then form closed walks, each of
// which turns around v at least once in any projection where every face
// turns the same way; oneToOne's single turn leaves one walk: one closed,
// consistently oriented fan. `seen` holds a mark per vertex, and `mark`
// and `mark` + 1 are used by no other vertex's test.
bool closedFan(const Link* links, int k, std::uint32_t* seen, std::uint32_t mark) {
  for (int i = 0; i < k; ++i) {  // the first corners, each once
    std::uint32_t& m = seen[links[i].a];
    if (m == mark) return false;
    m = mark;
  }
  for (int i = 0; i < k; ++i) {  // the second ones, each a first one, once
    std::uint32_t& m = seen[links[i].b];
    if (m != mark) return false;
    m = mark + 1;
  }
  return true;
}

// The axis along which the normals of two faces across the fan sum largest
// (as rounded, and from two faces only: any axis gives an exact answer, and
// on the dragon this one sets apart all but one in ten thousand of the fans
// that the summed normal of all faces does).
int dominantAxis(const Point3& v, const std::vector<Point3>& P, const Link* links, int k) {
  auto normal = [&](const Link& l) {
    return (P[std::size_t(l.a)] - v) ^ (P[std::size_t(l.b)] - v);
  };
  const Point3 n = normal(links[0]) + normal(links[k / 2]);
  const double x = std::fabs(n[0]), y = std::fabs(n[1]), z = std::fabs(n[2]);
  return x >= y && x >= z ? 0 : y >= z ? 1 : 2;
}

// Is the closed fan one-to-one in the projection dropping `axis`? Every
// face turns the same strict way, and the sectors, each under half a turn,
// wind once around v: the ray from v along +u (after mirroring a clockwise
// fan) is crossed upwards by exactly one sector. With every sector turning
// counter-clockwise, one from y <= 0 to y > 0 crosses the ray on its +u
// side; the signs of y are comparisons of coordinates, exact.
bool oneToOne(const Point3& v, const std::vector<Point3>& P, const Link* links, int k, int axis) {
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  int turn = 0, crossings = 0;
  for (int i = 0; i < k; ++i) {
    const Point3 &p = P[std::size_t(links[i].a)], &q = P[std::size_t(links[i].b)];
    const int s = orient2d(v[u], v[w], p[u], p[w], q[u], q[w]);
    if (s == 0 || (turn != 0 && s != turn)) return false;
    turn = s;
    const bool fromBelow = turn > 0 ? p[w] <= v[w] : p[w] >= v[w];
    const bool toAbove = turn > 0 ? q[w] > v[w] : q[w] < v[w];
    crossings += fromBelow && toAbove;
  }
  return crossings == 1;
}

}  // namespace

std::vector<char> fansApartInProjection(const std::vector<Point3>& points,
                                        const std::vector<Triangle>& triangles) {
  const Links in = linksOf(points.size(), triangles);
  std::vector<char> apart;
  resizeInHugePages(apart, points.size());
  std::vector<std::vector<std::uint32_t>> seen(workerCount());  // closedFan's, per worker
  parallelChunks(points.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
    if (seen[worker].empty()) seen[worker].assign(points.size(), 0);
    for (std::size_t v = begin; v < end; ++v) {
      const Link* links = &in.links[in.offsets[v]];
      const int k = int(in.offsets[v + 1] - in.offsets[v]);
      // Vertex indices are ints: 2v + 2 fits.
      apart[v] = k >= 3 && closedFan(links, k, seen[worker].data(), std::uint32_t(2 * v + 1)) &&
                 oneToOne(points[v], points, links, k, dominantAxis(points[v], points, links, k));
    }
  });
  return apart;
}

}  // namespace meshmend
