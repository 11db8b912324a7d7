#include "common/exact/intersections.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/base/timing.h"
#include "common/exact/box_tree.h"
#include "common/exact/predicates.h"
#include "common/exact/vertex_fans.h"

namespace meshmend {

namespace {

// A mesh flattened for the inner loops (the caller's arrays, not a copy).
struct Soup {
  const std::vector<Point3>& points;
  const std::vector<Triangle>& triangles;
  // Per face: collinear. With `withTree` known for every face; otherwise
  // only for those the search between meshes looks at (facesTouching()),
  // the rest stay 0: most of a mesh lies far from the others, and asking
  // each of its faces cost as much as the search.
  std::vector<char> degenerate;
  bool degenerateKnown = false;
  Box bounds{{1, 1, 1}, {0, 0, 0}};  // of every point, rounded outward to float
  // Only for the search within the mesh (`withTree`): every face's box
  // (moved into the mesh's tree).
  std::vector<Box> boxes;
  // Per vertex: no two of its faces intersect (fansApartInProjection). Most
  // candidate pairs of a mesh are neighbours around a vertex.
  std::vector<char> fanApart;

  explicit Soup(const MeshArrays& mesh) : points(mesh.points), triangles(mesh.triangles) {}
  // The bounds, and with `withTree` the degenerate faces, boxes and fans.
  void prepare(bool withTree) {
    Point3 lo = points.empty() ? Point3(0, 0, 0) : points[0], hi = lo;
    for (const Point3& p : points)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
    if (!points.empty()) bounds = boxOf(lo, hi, hi);
    resizeInHugePages(degenerate, triangles.size());
    degenerateKnown = withTree;
    if (!withTree) return;
    // Each point rounded to float once (about six faces share it), then
    // each face's box from its corners'.
    std::vector<Box> pointBoxes;
    resizeInHugePages(pointBoxes, points.size());
    parallelChunks(points.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t v = begin; v < end; ++v) pointBoxes[v] = boxOf(points[v]);
    });
    resizeInHugePages(boxes, triangles.size());
    parallelChunks(triangles.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f) {
        const Triangle& t = triangles[f];
        const Point3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
        boxes[f] = hull(pointBoxes[t[0]], pointBoxes[t[1]], pointBoxes[t[2]]);
        degenerate[f] = collinear(a, b, c);
      }
    });
    fanApart = fansApartInProjection(points, triangles);
  }
  const Point3& corner(std::uint32_t f, int i) const { return points[triangles[f][i]]; }
  // The exact sides of points against face f's plane. Made for a pair, not
  // kept per face: the fans settle most pairs without one, and a filter per
  // face took twice the memory of the boxes.
  PlaneSide plane(std::uint32_t f) const {
    return PlaneSide(corner(f, 0), corner(f, 1), corner(f, 2));
  }
  TrianglePoints at(std::uint32_t f) const {
    const Triangle& t = triangles[f];
    return {points[t[0]], points[t[1]], points[t[2]]};
  }
};

// The faces of a mesh that may meet another mesh: not degenerate, their box
// overlapping the other's bounds. Only these enter the search between the
// two; on small pairs that meet along a curve they are a small part of each.
struct Candidates {
  std::vector<std::uint32_t> faces;
  std::vector<Box> boxes;  // parallel to faces
};

Candidates facesTouching(Soup& s, const Box& other) {
  // A face whose corners all lie beyond the float next to a side of `other`
  // has its box (rounded outward, never past that float) beyond the side:
  // turned away in double, by one bit per corner and side, its box is never
  // made. The rest are decided on their boxes, as the search sees them.
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::nextafter(other.lo[k], -INFINITY);
    hi[k] = std::nextafter(other.hi[k], INFINITY);
  }
  std::vector<std::uint8_t> beyond(s.points.size());
  // In chunks, each keeping its own candidates, then joined in order.
  std::vector<Candidates> parts(workerCount());
  parallelChunks(
      s.points.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t v = begin; v < end; ++v) {
          const Point3& p = s.points[v];
          beyond[v] = std::uint8_t((p[0] < lo[0]) | (p[0] > hi[0]) << 1 | (p[1] < lo[1]) << 2 |
                                   (p[1] > hi[1]) << 3 | (p[2] < lo[2]) << 4 | (p[2] > hi[2]) << 5);
        }
      },
      4096);
  parallelChunks(
      s.triangles.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        // A large mesh's chunk makes room for every face at once (the first
        // chunk's for all, as the others join it): mapped memory, of which
        // only what is written becomes pages, where growing copied each
        // array a few times into new memory. A small mesh's (under a few
        // hundred KiB) grow as they fill: room for all its faces, most of it
        // unused, would take the heap's top, which a fresh process hands
        // back to the system after every run.
        Candidates& c = parts[worker];
        const std::size_t room = worker == 0 ? s.triangles.size() : end - begin;
        if (room * sizeof(Box) >= (std::size_t(256) << 10)) {
          reserveInHugePages(c.faces, room);
          reserveInHugePages(c.boxes, room);
        }
        for (std::size_t f = begin; f < end; ++f) {
          const Triangle& t = s.triangles[f];
          if (beyond[t[0]] & beyond[t[1]] & beyond[t[2]]) continue;
          const Point3 &p = s.points[t[0]], &q = s.points[t[1]], &r = s.points[t[2]];
          const Box box = boxOf(p, q, r);
          if (!overlap(box, other)) continue;
          if (!s.degenerateKnown) s.degenerate[f] = collinear(p, q, r);
          if (s.degenerate[f]) continue;
          c.faces.push_back(std::uint32_t(f));
          c.boxes.push_back(box);
        }
      },
      1024);
  for (std::size_t w = 1; w < parts.size(); ++w) {
    parts[0].faces.insert(parts[0].faces.end(), parts[w].faces.begin(), parts[w].faces.end());
    parts[0].boxes.insert(parts[0].boxes.end(), parts[w].boxes.begin(), parts[w].boxes.end());
  }
  return std::move(parts[0]);
}

// Exact: can the segment from corner i to corner j of face g meet face f?
// False when both ends lie strictly on one side of f's plane.
bool edgeMayMeet(const Soup& s, std::uint32_t g, int i, int j, std::uint32_t f) {
  const PlaneSide side = s.plane(f);
  return side(s.corner(g, i)) * side(s.corner(g, j)) <= 0;
}

// Faces f and g that share no corner: their plane sides, each triangle's
// against the other's plane, as trianglesIntersect takes them; false as
// soon as one triangle lies strictly on one side (no contact).
bool mayTouch(const Soup& s, std::uint32_t f, std::uint32_t g, PlaneSides& side) {
  auto against = [&](std::uint32_t plane, std::uint32_t face, int* out) {
    const PlaneSide sideOf = s.plane(plane);
    for (int i = 0; i < 3; ++i) out[i] = sideOf(s.corner(face, i));
    return !(out[0] != 0 && out[1] == out[0] && out[2] == out[0]);
  };
  return against(f, g, side[1]) && against(g, f, side[0]);
}

// The self-intersection rule for two faces of one mesh that share the
// corners `c` (fewer than three), not apart around them. Cheap exact plane
// tests settle almost every such pair; the rest get the full test.
bool selfIntersect(const Soup& s, std::uint32_t f, std::uint32_t g, const SharedCorners& c) {
  switch (c.count) {
    case 0: {
      PlaneSides side;
      return mayTouch(s, f, g, side) && trianglesIntersect(s.at(f), s.at(g), side);
    }
    case 1:
      // When either face's edge opposite the shared corner lies strictly on
      // one side of the other's plane, that face meets the plane only at the
      // shared corner: nothing beyond it. Both edges must reach the plane.
      if (!edgeMayMeet(s, f, (c.ia + 1) % 3, (c.ia + 2) % 3, g) ||
          !edgeMayMeet(s, g, (c.ib + 1) % 3, (c.ib + 2) % 3, f))
        return false;
      break;
    default:  // folded faces are coplanar: the other's apex must lie in the plane
      if (s.plane(f)(s.corner(g, c.ib)) != 0) return false;
  }
  return intersectBeyondShared(s.at(f), s.at(g), c.count, c.ia, c.ib);
}

}  // namespace

FindIntersectionsResult findIntersections(const std::vector<const Mesh*>& meshes,
                                          const FindIntersectionsOptions& options) {
  std::vector<MeshArrays> arrays;
  for (const Mesh* mesh : meshes) arrays.push_back(arraysOf(*mesh));
  std::vector<const MeshArrays*> pointers;
  for (const MeshArrays& a : arrays) pointers.push_back(&a);
  try {
    return findIntersectionsInArrays(pointers, options);  // checks the arrays first
  } catch (const InvalidInputError&) {
    // The meshes' own checks where the arrays' fail: the same tests, with a
    // message that names the vertex and the faces that use it (run only
    // then: on a large mesh they took 2 % of the search).
    for (std::size_t m = 0; m < meshes.size(); ++m)
      requireFacesAndFiniteCoordinates(*meshes[m], "mesh " + std::to_string(m));
    throw;
  }
}

std::size_t selfIntersectingPairs(const Mesh& mesh, bool asFloat, bool sameVertices) {
  return selfIntersectingPairs(mesh, asFloat ? Scalar::kFloat : Scalar::kDouble, sameVertices);
}

std::size_t selfIntersectingPairs(const Mesh& mesh, Scalar scalar, bool sameVertices) {
  MeshArrays arrays = arraysOf(mesh);
  if (scalar != Scalar::kDouble)
    for (Point3& p : arrays.points) p = storedAs(p, scalar);
  FindIntersectionsOptions o;
  o.cross = false;
  o.same_vertices = sameVertices;
  return findIntersectionsInArrays({&arrays}, o).self_pairs[0];
}

namespace {

// A pair found between meshes keeps the plane sides its test computed: the
// contact classification needs the same ones.
struct Found {
  IntersectingPair pair;
  std::int8_t side[2][3];  // as PlaneSides, for (pair.a, pair.b)
  bool sidesKnown;
};

// Per-worker results, each on its own cache line (no false sharing).
struct alignas(64) WorkerFindings {
  std::vector<Found> pairs;
  std::size_t candidates = 0;
};

// The meshes' coordinates together: crossings between them are decided on
// both (requireCoordinateSpan).
void requireFacesAndFinite(const std::vector<const MeshArrays*>& meshes) {
  CoordinateMagnitudes all;
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m]->triangles.empty())
      throw InvalidInputError("mesh " + std::to_string(m) + " has no faces");
    for (const Point3& p : meshes[m]->points)
      if (!isFinite(p))
        throw InvalidInputError("mesh " + std::to_string(m) + " has a non-finite coordinate");
    all.add(magnitudesOf(meshes[m]->points, meshes[m]->triangles));
  }
  requireCoordinateSpan(all, meshes.size() == 1 ? "the mesh" : "the meshes together");
}

// A mesh's faces in its tree's order, for the visit of its candidate pairs
// (those of two leaves side by side, where the faces' own arrays are read
// scattered): each face's corners, a corner v as ~v (negative) where v's
// fan is apart in projection, which keeps corners equal where they were;
// and whether the face is degenerate.
struct PlacedFaces {
  std::vector<Triangle> corners;
  std::vector<char> degenerate;

  PlacedFaces(const Soup& s, const BoxTree& tree) {
    resizeInHugePages(corners, tree.size());
    resizeInHugePages(degenerate, tree.size());
    parallelChunks(tree.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t x = begin; x < end; ++x) {
        const std::uint32_t f = tree.primitive(std::uint32_t(x));
        for (int i = 0; i < 3; ++i) {
          const int v = s.triangles[f][i];
          corners[x][i] = s.fanApart[std::size_t(v)] ? ~v : v;
        }
        degenerate[x] = s.degenerate[f];
      }
    });
  }
  // Do the faces at x and y, sharing the corners `c` (fewer than three),
  // share a corner whose fan is apart, or an edge with such an end? They do
  // not intersect by the rule then (most pairs of a mesh).
  bool apartAroundShared(std::uint32_t x, const SharedCorners& c) const {
    const Triangle& t = corners[x];
    if (c.count == 1) return t[c.ia] < 0;
    return c.count == 2 && ((t[(c.ia + 1) % 3] | t[(c.ia + 2) % 3]) < 0);
  }
};

// Out of line: the visit of each candidate pair stays small enough to be
// inlined into the traversal's loops (a call per pair cost more than the
// fans' test), and few pairs are found.
[[gnu::noinline]] void recordSelfPair(WorkerFindings& found, std::uint32_t m, std::uint32_t f,
                                      std::uint32_t g) {
  found.pairs.push_back({{{m, f}, {m, g}}, {{0, 0, 0}, {0, 0, 0}}, false});
}

// Each mesh's own pairs, from a tree of its faces' boxes; returns the
// milliseconds spent building the trees.
double searchSelf(std::vector<Soup>& soups, const FindIntersectionsOptions& options,
                  std::vector<WorkerFindings>& found, FindIntersectionsResult& r) {
  const std::size_t n = soups.size();
  const auto buildStart = Clock::now();
  std::vector<std::shared_ptr<const BoxTree>> trees;
  trees.reserve(n);
  for (std::size_t m = 0; m < n; ++m)
    trees.push_back(std::make_shared<const BoxTree>(
        std::move(soups[m].boxes),
        options.layout == 1 ? BoxTree::Layout::kMedianSplit : BoxTree::Layout::kMorton));
  r.build_ms = msSince(buildStart);
  for (std::size_t m = 0; m < n; ++m) {
    reportProgress(options.progress, int(10 + 40 * m / n), "Self-intersections");
    const Soup& s = soups[m];
    const BoxTree& tree = *trees[m];
    const PlacedFaces placed(s, tree);
    // Inlined into the traversal's leaf loops: as a call (GCC's choice), the
    // visit of 6.7 M candidate pairs on bunny + dragon took 4 % more
    // instructions.
    tree.selfPairsByPlace([&](std::uint32_t x, std::uint32_t y,
                              unsigned worker) __attribute__((always_inline)) {
      if (placed.degenerate[x] | placed.degenerate[y]) return;
      ++found[worker].candidates;
      SharedCorners c = sharedCorners(placed.corners[x], placed.corners[y]);
      if (c.count < 3 && placed.apartAroundShared(x, c)) return;
      std::uint32_t f = tree.primitive(x), g = tree.primitive(y);
      if (f > g) std::swap(f, g), std::swap(c.ia, c.ib);  // c as sharedCorners(f, g)
      if (c.count == 3 ? options.same_vertices : selfIntersect(s, f, g, c))
        recordSelfPair(found[worker], std::uint32_t(m), f, g);
    });
  }
  if (options.keep_trees) r.face_trees = std::move(trees);
  return r.build_ms;
}

// The pairs between meshes m and k: a tree (or a hashed grid) over the
// smaller set of the faces near the other mesh, queried by the other's.
void searchBetween(std::vector<Soup>& soups, std::size_t m, std::size_t k,
                   const FindIntersectionsOptions& options, std::vector<WorkerFindings>& found,
                   FindIntersectionsResult& r) {
  if (!overlap(soups[m].bounds, soups[k].bounds)) return;
  // One mesh after the other, each on every thread: side by side, the
  // smaller one's thread idled while the larger one's did most of the work.
  const Candidates near[2] = {facesTouching(soups[m], soups[k].bounds),
                              facesTouching(soups[k], soups[m].bounds)};
  const bool swap = near[0].faces.size() > near[1].faces.size();
  const Candidates &sc = near[swap ? 1 : 0], &lc = near[swap ? 0 : 1];
  const std::uint32_t small = std::uint32_t(swap ? k : m), large = std::uint32_t(swap ? m : k);
  if (sc.faces.empty()) return;
  const Soup &s = soups[small], &l = soups[large];
  const auto treeStart = Clock::now();
  // Many faces of a large mesh lie inside the smaller one's bounds but far
  // from its faces: a coarse grid of those turns them away before a tree
  // descent (for a small mesh, its set-up would cost more).
  std::unique_ptr<BoxGrid> nearSmall;
  if (lc.faces.size() >= 65536) nearSmall = std::make_unique<BoxGrid>(sc.boxes);
  // The candidates near a curve are faces of similar sizes: a hashed grid
  // finds their overlaps in less time than a tree (about as many
  // instructions, but no median selections, whose comparisons are as good
  // as random, to build it). A tree where the sizes differ too much for a grid.
  std::optional<HashedBoxGrid> grid;
  std::optional<BoxTree> tree;
  std::vector<PlaneSide> planes(sc.faces.size());
  {
    // The planes on a second thread while this one builds.
    TaskAlongside planesAside([&] {
      for (std::size_t i = 0; i < sc.faces.size(); ++i) {
        const TrianglePoints t = s.at(sc.faces[i]);
        planes[i] = PlaneSide(t[0], t[1], t[2]);
      }
    });
    if (options.layout == 0) grid.emplace(sc.boxes);
    if (!grid || !grid->suits(lc.boxes)) {
      grid.reset();
      tree.emplace(sc.boxes, BoxTree::Layout::kMedianSplit);
    }
    planesAside.wait();
  }
  r.build_ms += msSince(treeStart);
  // A query face costs about a microsecond (a descent and its candidates'
  // tests): a second thread from a few hundred each.
  parallelChunks(
      lc.faces.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t i = begin; i < end; ++i) {
          if (nearSmall && !nearSmall->touches(lc.boxes[i])) continue;
          const std::uint32_t g = lc.faces[i];
          const TrianglePoints tg = l.at(g);
          PlaneSide planeOfG;  // made when a face first reaches g's plane
          bool planeOfGMade = false;
          auto candidate = [&](std::uint32_t j, unsigned w) {
            ++found[w].candidates;
            // side[0]: f's corners against g's plane; side[1]: g's against f's.
            PlaneSides side;
            for (int c = 0; c < 3; ++c) side[1][c] = planes[j](tg[c]);
            if (side[1][0] != 0 && side[1][1] == side[1][0] && side[1][2] == side[1][0]) return;
            if (!planeOfGMade) {
              planeOfG = PlaneSide(tg[0], tg[1], tg[2]);
              planeOfGMade = true;
            }
            const std::uint32_t f = sc.faces[j];
            const TrianglePoints tf = s.at(f);
            for (int c = 0; c < 3; ++c) side[0][c] = planeOfG(tf[c]);
            if (!trianglesIntersect(tf, tg, side)) return;
            Found x{{{small, f}, {large, g}}, {}, true};
            const bool flip = x.pair.b < x.pair.a;
            if (flip) std::swap(x.pair.a, x.pair.b);
            for (int t = 0; t < 2; ++t)
              for (int c = 0; c < 3; ++c) x.side[t][c] = std::int8_t(side[flip ? 1 - t : t][c]);
            found[w].pairs.push_back(x);
          };
          if (grid)
            grid->query(lc.boxes[i], [&](std::uint32_t j) { candidate(j, worker); });
          else
            tree->query(lc.boxes[i], worker, candidate);
        }
      },
      256);
}

// The workers' pairs in one sorted list, into the result.
std::vector<Found> gatherPairs(std::vector<WorkerFindings>& found, FindIntersectionsResult& r) {
  std::vector<Found> all;
  for (std::size_t w = 0; w < found.size(); ++w) {
    all.insert(all.end(), found[w].pairs.begin(), found[w].pairs.end());
    r.candidate_pairs += found[w].candidates;
  }
  std::sort(all.begin(), all.end(), [](const Found& x, const Found& y) {
    return x.pair.a < y.pair.a || (x.pair.a == y.pair.a && x.pair.b < y.pair.b);
  });
  r.pairs.reserve(all.size());
  for (const Found& x : all) r.pairs.push_back(x.pair);
  return all;
}

// Pairs and distinct faces per mesh, within and between meshes. Distinct
// faces are counted as they are first met (counting the bits afterwards
// walked every face of every mesh).
void countFaces(const std::vector<Soup>& soups, FindIntersectionsResult& r) {
  const std::size_t n = soups.size();
  r.self_pairs.assign(n, 0);
  r.self_faces.assign(n, 0);
  r.cross_faces.assign(n, 0);
  r.face_involved.resize(n);
  std::vector<std::vector<bool>> inSelf(n), inCross(n);
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t faces = soups[m].triangles.size();
    r.face_involved[m].assign(faces, false);
    inSelf[m].assign(faces, false);
    inCross[m].assign(faces, false);
    r.degenerate_faces.push_back(
        std::size_t(std::count(soups[m].degenerate.begin(), soups[m].degenerate.end(), true)));
  }
  for (const IntersectingPair& p : r.pairs) {
    const bool self = p.a.mesh == p.b.mesh;
    auto& flags = self ? inSelf : inCross;
    auto& distinct = self ? r.self_faces : r.cross_faces;
    if (self)
      ++r.self_pairs[p.a.mesh];
    else
      ++r.cross_pairs;
    for (const FaceRef& f : {p.a, p.b}) {
      if (!flags[f.mesh][f.face]) {
        flags[f.mesh][f.face] = true;
        ++distinct[f.mesh];
      }
      r.face_involved[f.mesh][f.face] = true;
    }
  }
}

// Each pair's contact, with the plane sides its test computed where known.
// A pair takes some ten thousand instructions (a few microseconds): a
// second thread, which takes tens of microseconds to start, pays for itself
// from a few dozen pairs each on.
void classifyContacts(const std::vector<Found>& all, const std::vector<Soup>& soups,
                      FindIntersectionsResult& r) {
  r.contacts.resize(all.size());
  parallelChunks(
      all.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) {
          const Found& x = all[i];
          const TrianglePoints a = soups[x.pair.a.mesh].at(x.pair.a.face);
          const TrianglePoints b = soups[x.pair.b.mesh].at(x.pair.b.face);
          if (!x.sidesKnown) {
            r.contacts[i] = classifyContact(a, b);
            continue;
          }
          PlaneSides side;
          for (int t = 0; t < 2; ++t)
            for (int c = 0; c < 3; ++c) side[t][c] = x.side[t][c];
          r.contacts[i] = classifyContact(a, b, side);
        }
      },
      48);
}

}  // namespace

FindIntersectionsResult findIntersectionsInArrays(const std::vector<const MeshArrays*>& meshes,
                                                  const FindIntersectionsOptions& options) {
  const auto start = Clock::now();
  FindIntersectionsResult r;
  const std::size_t n = meshes.size();
  requireFacesAndFinite(meshes);
  reportProgress(options.progress, 0, "Preparing boxes");
  // Each mesh gets a tree (and every face's box and plane) only for its
  // self-intersections; the search between meshes builds its own over the
  // faces near the other mesh. Each mesh on its own, side by side (a large
  // mesh's own stages take the threads a small one leaves).
  std::vector<Soup> soups;
  soups.reserve(n);
  for (std::size_t m = 0; m < n; ++m) soups.emplace_back(*meshes[m]);
  parallelChunks(
      n,
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t m = begin; m < end; ++m) soups[m].prepare(options.self);
      },
      1);
  std::vector<WorkerFindings> found(workerCount());
  const auto searchStart = Clock::now();
  const double selfBuild = options.self ? searchSelf(soups, options, found, r) : 0;
  if (options.cross)
    for (std::size_t m = 0; m < n; ++m)
      for (std::size_t k = m + 1; k < n; ++k) {
        reportProgress(options.progress, 50, "Intersections between meshes");
        searchBetween(soups, m, k, options, found, r);
      }
  r.search_ms = msSince(searchStart) - selfBuild;
  const std::vector<Found> all = gatherPairs(found, r);
  countFaces(soups, r);
  if (options.contacts) {
    reportProgress(options.progress, 80, "Intersection segments");
    classifyContacts(all, soups, r);
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

namespace {

// Exact and sufficient for "faces f and g meet at most in the corners they
// share": in the projection dropping the axis of f's largest normal
// component, the line through an edge of one face has the other face
// strictly beyond it, but for shared corners on the line. Neighbours in a
// smooth surface (most box-overlapping pairs of a mesh) are settled by these
// 2-D tests, coplanar ones included.
bool separatedInProjection(const Triangle& ta, const TrianglePoints& a, const Triangle& tb,
                           const TrianglePoints& b) {
  const int axis = projectionAxis(a[0], a[1], a[2]);
  for (int pass = 0; pass < 2; ++pass) {
    const Triangle& t = pass == 0 ? ta : tb;
    const TrianglePoints& p = pass == 0 ? a : b;
    const Triangle& other = pass == 0 ? tb : ta;
    const TrianglePoints& q = pass == 0 ? b : a;
    // The side of each edge's line the face is on: the same for all three
    // (a cyclic turn of the corners keeps the sign).
    const int inside = orient2dDropping(p[0], p[1], p[2], axis);
    if (inside == 0) continue;
    for (int e = 0; e < 3; ++e) {
      const int u = e, w = (e + 1) % 3;
      bool separated = true;
      for (int k = 0; k < 3 && separated; ++k) {
        if (other[k] == t[u] || other[k] == t[w]) continue;
        separated = orient2dDropping(p[u], p[w], q[k], axis) == -inside;
      }
      if (separated) return true;
    }
  }
  return false;
}

// Exact and sufficient for the same, by the planes' floating-point filters
// alone (`pa`, `pb`: those of a and b): sharing an edge, the fourth corner
// off the other face's plane (a face crosses that plane only along the
// edge); sharing one corner, the other two corners of one face strictly on
// one side of the other's plane (it meets that plane only at the corner);
// sharing none, all three corners of one face strictly on one side. Most
// neighbours in a curved surface; flat ones, which the filters cannot tell,
// go to the projection.
bool apartByPlanes(const SharedCorners& c, const TrianglePoints& a, const PlaneFilter& pa,
                   const TrianglePoints& b, const PlaneFilter& pb) {
  // The corners `from`, `from` + 1, ... (count of them, modulo 3) of `face`
  // strictly on one side of the plane of `filter` through `origin`. (Every
  // corner is tested, with no branch on a side: those are as good as
  // random.)
  auto oneSide = [](const PlaneFilter& filter, const Point3& origin, const TrianglePoints& face,
                    int from, int count) {
    const int side = filter.filteredSide(origin, face[std::size_t(from % 3)]);
    bool same = side != 0;
    for (int k = 1; k < count; ++k)
      same &= filter.filteredSide(origin, face[std::size_t((from + k) % 3)]) == side;
    return same;
  };
  switch (c.count) {
    case 2:
      return oneSide(pa, a[0], b, c.ib, 1);
    case 1:
      return oneSide(pb, b[0], a, c.ia + 1, 2) || oneSide(pa, a[0], b, c.ib + 1, 2);
    case 0:
      return oneSide(pa, a[0], b, 0, 3) || oneSide(pb, b[0], a, 0, 3);
    default:
      return false;
  }
}

}  // namespace

namespace {

// Exact: some axis along which the faces' corners do not overlap (boxes
// that overlap only through their outward rounding or widening).
bool apartAlongAnAxis(const TrianglePoints& a, const TrianglePoints& b) {
  for (int k = 0; k < 3; ++k)
    if (std::max({a[0][k], a[1][k], a[2][k]}) < std::min({b[0][k], b[1][k], b[2][k]}) ||
        std::max({b[0][k], b[1][k], b[2][k]}) < std::min({a[0][k], a[1][k], a[2][k]}))
      return true;
  return false;
}

// facesMeet after its test along the axes, with the faces' plane filters.
// The pairs of a search around changed faces come here directly: the axis
// test turned away one in two thousand of them.
bool meetBeyondAxes(const Triangle& ta, const TrianglePoints& a, const PlaneFilter& pa,
                    const Triangle& tb, const TrianglePoints& b, const PlaneFilter& pb,
                    int knownFlat, bool sameVertices) {
  if (knownFlat < 0 && (collinear(a[0], a[1], a[2]) || collinear(b[0], b[1], b[2]))) return false;
  const SharedCorners c = sharedCorners(ta, tb);
  if (c.count == 3 && !sameVertices) return false;
  if (c.count < 3 && (apartByPlanes(c, a, pa, b, pb) || separatedInProjection(ta, a, tb, b)))
    return false;
  return intersectBeyondShared(a, b, c.count, c.ia, c.ib);
}

// facesIntersect with the degeneracy of the two faces known (`knownFlat`:
// -1 not known, 0 neither is degenerate); faces with the same three
// vertices meet unless `sameVertices` is false.
bool facesMeet(const Triangle& ta, const TrianglePoints& a, const Triangle& tb,
               const TrianglePoints& b, int knownFlat, bool sameVertices = true) {
  if (apartAlongAnAxis(a, b)) return false;
  return meetBeyondAxes(ta, a, PlaneFilter(a[0], a[1], a[2]), tb, b, PlaneFilter(b[0], b[1], b[2]),
                        knownFlat, sameVertices);
}

// The same for faces f and g of a mesh.
bool facesMeet(const std::vector<Point3>& P, const std::vector<Triangle>& T, std::uint32_t f,
               std::uint32_t g, int knownFlat, bool sameVertices = true) {
  const TrianglePoints a{P[T[f][0]], P[T[f][1]], P[T[f][2]]};
  const TrianglePoints b{P[T[g][0]], P[T[g][1]], P[T[g][2]]};
  return facesMeet(T[f], a, T[g], b, knownFlat, sameVertices);
}

}  // namespace

bool facesIntersect(const std::vector<Point3>& P, const std::vector<Triangle>& T, std::uint32_t f,
                    std::uint32_t g) {
  return facesMeet(P, T, f, g, -1);
}

bool facesIntersect(const Triangle& ta, const TrianglePoints& a, const Triangle& tb,
                    const TrianglePoints& b) {
  return facesMeet(ta, a, tb, b, -1);
}

std::vector<std::array<std::uint32_t, 2>> intersectingOf(
    const std::vector<Point3>& P, const std::vector<Triangle>& T,
    const std::vector<std::array<std::uint32_t, 2>>& pairs) {
  std::vector<std::vector<std::array<std::uint32_t, 2>>> hits(workerCount());
  parallelChunks(
      pairs.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t i = begin; i < end; ++i)
          if (facesIntersect(P, T, pairs[i][0], pairs[i][1])) hits[worker].push_back(pairs[i]);
      },
      1024);
  return joined(hits);
}

std::vector<std::array<std::uint32_t, 2>> intersectingOf(
    const std::vector<Point3>& P, const std::vector<Triangle>& T,
    const std::vector<std::array<std::uint32_t, 2>>& pairs, const std::vector<char>& degenerate,
    bool sameVertices) {
  std::vector<std::vector<std::array<std::uint32_t, 2>>> hits(workerCount());
  parallelChunks(
      pairs.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t i = begin; i < end; ++i) {
          const auto [f, g] = pairs[i];
          if (!degenerate[f] && !degenerate[g] && facesMeet(P, T, f, g, 0, sameVertices))
            hits[worker].push_back(pairs[i]);
        }
      },
      1024);
  return joined(hits);
}

std::vector<std::array<std::uint32_t, 2>> intersectingOf(const std::vector<Point3>& P,
                                                         const std::vector<Triangle>& T,
                                                         const ChangedFaceSearch& search,
                                                         const std::vector<char>& degenerate,
                                                         bool sameVertices) {
  // What the tests read of each face, in one record, side by side in the
  // search's order (each face is in some ten pairs, and its corners' points
  // lie anywhere in P). The plane filters too: each made once, not once or
  // twice per pair.
  struct FaceRecord {
    TrianglePoints points;
    PlaneFilter plane;
    Triangle corners;
    bool flat;
  };
  const std::vector<std::uint32_t>& faces = search.faces();
  std::vector<FaceRecord, DefaultInitAllocator<FaceRecord>> records;  // each written below
  resizeInHugePages(records, faces.size());
  parallelChunks(faces.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t i = begin; i < end; ++i) {
      FaceRecord& r = records[i];
      const Triangle& t = r.corners = T[faces[i]];
      r.points = {P[t[0]], P[t[1]], P[t[2]]};
      r.plane = PlaneFilter(r.points[0], r.points[1], r.points[2]);
      r.flat = degenerate[faces[i]];
    }
  });
  std::vector<std::vector<std::array<std::uint32_t, 2>>> hits(workerCount());
  search.forEachPair([&](std::uint32_t a, std::uint32_t b, unsigned worker) {
    const FaceRecord &ra = records[a], &rb = records[b];
    if (!ra.flat && !rb.flat &&
        meetBeyondAxes(ra.corners, ra.points, ra.plane, rb.corners, rb.points, rb.plane, 0,
                       sameVertices))
      hits[worker].push_back({faces[a], faces[b]});
  });
  return joined(hits);
}

SegmentSoup contactSegments(const FindIntersectionsResult& result) {
  SegmentSoup soup;
  std::map<std::array<double, 3>, int> index;
  auto at = [&](const Point3& p) {
    const auto [it, added] =
        index.emplace(std::array<double, 3>{p[0], p[1], p[2]}, int(soup.points.size()));
    if (added) soup.points.push_back(p);
    return it->second;
  };
  std::set<std::array<int, 2>> seen;
  auto add = [&](const Point3& p, const Point3& q) {
    std::array<int, 2> e{at(p), at(q)};
    if (e[0] == e[1]) return;
    if (e[0] > e[1]) std::swap(e[0], e[1]);
    if (seen.insert(e).second) soup.edges.push_back(e);
  };
  for (const TriangleContact& c : result.contacts) {
    const std::size_t n = c.points.size();
    if (n == 2) add(c.points[0].position, c.points[1].position);
    if (n > 2)
      for (std::size_t i = 0; i < n; ++i) add(c.points[i].position, c.points[(i + 1) % n].position);
  }
  return soup;
}

JsonObject toJson(const FindIntersectionsResult& r) {
  std::size_t selfPairs = 0, selfFaces = 0, crossFaces = 0;
  std::vector<double> perMeshPairs, perMeshFaces, perMeshCross, degenerate;
  for (std::size_t m = 0; m < r.self_pairs.size(); ++m) {
    selfPairs += r.self_pairs[m];
    selfFaces += r.self_faces[m];
    crossFaces += r.cross_faces[m];
    perMeshPairs.push_back(double(r.self_pairs[m]));
    perMeshFaces.push_back(double(r.self_faces[m]));
    perMeshCross.push_back(double(r.cross_faces[m]));
    degenerate.push_back(double(r.degenerate_faces[m]));
  }
  JsonObject j;
  j.set("self_intersecting_pairs", selfPairs)
      .set("self_intersecting_faces", selfFaces)
      .set("cross_intersecting_pairs", r.cross_pairs)
      .set("cross_intersecting_faces", crossFaces)
      .set("self_intersecting_pairs_per_layer", perMeshPairs)
      .set("self_intersecting_faces_per_layer", perMeshFaces)
      .set("cross_intersecting_faces_per_layer", perMeshCross)
      .set("degenerate_faces_skipped_per_layer", degenerate)
      .set("candidate_pairs", r.candidate_pairs)
      .set("build_ms", r.build_ms)
      .set("search_ms", r.search_ms)
      .set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
