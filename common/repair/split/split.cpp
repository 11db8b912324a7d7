#include "common/repair/split/split.h"
#include "common/base/timing.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/exact/box_tree.h"
#include "common/exact/exact_point.h"
#include "common/exact/predicates.h"
#include "common/exact/retriangulate.h"
#include "common/repair/split/mesh_splitter.h"

namespace meshmend {

using namespace split_detail;

namespace {

// Does the split snap curve points (quality snapping, or within float steps)?
bool snaps(const SplitOptions& o) {
  return o.snap_tolerance > 0 || o.snap_host_steps > 0;
}

}  // namespace

TriplePoints mostTriplePoints(const std::vector<IntersectingPair>& pairs,
                              const std::vector<std::size_t>& faces, std::size_t bound) {
  std::vector<std::size_t> first(faces.size() + 1, 0);  // each mesh's first global face
  for (std::size_t m = 0; m < faces.size(); ++m) first[m + 1] = first[m] + faces[m];
  auto global = [&](const FaceRef& f) { return first[f.mesh] + f.face; };
  std::vector<std::vector<std::size_t>> crossing(first.back());
  for (const IntersectingPair& p : pairs) {
    crossing[global(p.a)].push_back(global(p.b));
    crossing[global(p.b)].push_back(global(p.a));
  }
  for (auto& list : crossing) std::sort(list.begin(), list.end());
  auto cross = [&](std::size_t g, std::size_t h) {
    return std::binary_search(crossing[g].begin(), crossing[g].end(), h);
  };
  std::size_t most = 0, at = 0;
  for (std::size_t f = 0; f < crossing.size() && most <= bound; ++f) {
    const auto& list = crossing[f];
    std::size_t triples = 0;
    for (std::size_t i = 0; i < list.size() && triples <= bound; ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) triples += cross(list[i], list[j]);
    if (triples > most) most = triples, at = f;
  }
  TriplePoints r;
  r.count = most;
  const std::size_t mesh = std::upper_bound(first.begin(), first.end(), at) - first.begin() - 1;
  r.face = {std::uint32_t(mesh), std::uint32_t(at - first[mesh])};
  return r;
}

namespace {

// The inputs as arrays, with their seams closed when asked; each keeps the
// input index of its vertices and faces. Meshes side by side; an error
// names the first mesh at fault.
bool hasFaceWithArea(const MeshArrays& mesh) {
  const std::vector<Point3>& P = mesh.points;
  for (const Triangle& t : mesh.triangles)
    if (P[t[0]] != P[t[1]] && P[t[1]] != P[t[2]] && P[t[2]] != P[t[0]]) return true;
  return false;
}

std::vector<WeldedArrays> prepareInputs(const std::vector<const Mesh*>& meshes,
                                        const SplitOptions& options, SplitResult& r) {
  std::vector<WeldedArrays> inputs(meshes.size());
  std::vector<std::size_t> duplicateFaces(meshes.size(), 0);
  parallelChunks(
      meshes.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t m = begin; m < end; ++m) {
          requireFacesAndFiniteCoordinates(*meshes[m], "mesh " + std::to_string(m));
          WeldedArrays& in = inputs[m];
          if (options.weld_duplicates) {
            in = weldCoincident(arraysOf(*meshes[m]));
          } else {
            in.mesh = arraysOf(*meshes[m]);
            in.vertex_origin.resize(in.mesh.points.size());
            std::iota(in.vertex_origin.begin(), in.vertex_origin.end(), 0);
            in.face_origin.resize(in.mesh.triangles.size());
            std::iota(in.face_origin.begin(), in.face_origin.end(), 0);
          }
          if (options.remove_duplicate_faces) duplicateFaces[m] = removeDuplicateFaces(in);
        }
      },
      1);
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    // Faces with two corners at one position have no area, and the merged
    // output welds them away: a mesh of only such faces would come out empty.
    if (!hasFaceWithArea(inputs[m].mesh))
      throw InvalidInputError(
          "mesh " + std::to_string(m) +
          " has no face with three corners at distinct positions: every face has two corners "
          "at one position (as where coordinates are very large for the mesh's size, stored "
          "in float), so nothing of it would be left; move the mesh near the origin first, or "
          "check the file");
    r.vertices_welded += inputs[m].vertices_merged;
    r.duplicate_faces_removed += duplicateFaces[m];
  }
  return inputs;
}

// The crossing pairs with their contacts, within the work bound on the
// triple points of one face.
FindIntersectionsResult findCrossings(const std::vector<WeldedArrays>& inputs,
                                      const SplitOptions& options, SplitResult& r) {
  std::vector<const MeshArrays*> arrays;
  for (const WeldedArrays& in : inputs) arrays.push_back(&in.mesh);
  FindIntersectionsOptions find;
  find.self = options.self;
  find.cross = options.between_meshes;
  find.contacts = true;
  find.same_vertices = false;
  find.keep_trees = options.self && options.merged_output;
  find.progress = [&](int percent, const char* stage) {
    return !options.progress || options.progress(percent * 4 / 10, stage);
  };
  FindIntersectionsResult found = findIntersectionsInArrays(arrays, find);
  r.intersecting_pairs = found.pairs.size();
  if (options.pairs_found) options.pairs_found(found.pairs);
  const std::size_t bound = options.max_triple_points_per_face;
  if (bound == 0) return found;
  std::vector<std::size_t> faces;
  for (const MeshArrays* a : arrays) faces.push_back(a->triangles.size());
  const TriplePoints most = mostTriplePoints(found.pairs, faces, bound);
  if (most.count > bound)
    throw WorkLimitError(
        "in face " + std::to_string(most.face.face) + " of mesh " + std::to_string(most.face.mesh) +
        " more than " + std::to_string(bound) +
        " pairs of the faces crossing it cross each other too (max_triple_points_per_face): "
        "the surfaces pass many times through nearly one point there, as the meridians of a "
        "spindle torus do near its axis, and cutting it would take the exact arithmetic "
        "minutes. Nothing was changed. Remove the faces around that point (select them, "
        "Filters > Selection > Delete Selected Faces) and close the hole with MeshMend: Fill "
        "Holes, then split again");
  return found;
}

// Every pair's contact as curve point ids of one table, handed to the faces
// of both meshes; the contacts' exact points move into the table.
void distributeContacts(FindIntersectionsResult& found, std::vector<MeshSplitter>& splitters,
                        CurvePoints& table) {
  std::vector<const std::vector<Triangle>*> triangles;
  for (const MeshSplitter& s : splitters) triangles.push_back(&s.triangles());
  // Each pair's contact as curve point ids, all pairs in one array, and
  // per point the face of the pair it is known to lie strictly inside
  // (FaceWork::kInside: bit 0 the pair's first face, bit 1 its second).
  std::vector<int> contactIds;
  std::vector<std::uint8_t> contactInside;
  std::vector<std::size_t> contactStart(found.pairs.size() + 1, 0);
  contactIds.reserve(2 * found.pairs.size());
  contactInside.reserve(2 * found.pairs.size());
  for (std::size_t i = 0; i < found.pairs.size(); ++i) {
    const FaceRef faces[2] = {found.pairs[i].a, found.pairs[i].b};
    const TriangleContact& c = found.contacts[i];
    if (c.points.size() > 6) throw std::logic_error("a contact of more than six points");
    for (std::size_t k = 0; k < c.points.size(); ++k) {
      contactIds.push_back(table.add(c.points[k], c.exact[k], faces, triangles));
      const ContactPoint& p = c.points[k];
      contactInside.push_back(p.inside_other ? std::uint8_t(1 << (1 - p.triangle)) : 0);
    }
    contactStart[i + 1] = contactIds.size();
  }
  // The contacts' exact points are in the table now: their memory (a third
  // of a small split's) goes back before the outputs are made.
  std::vector<TriangleContact>().swap(found.contacts);
  table.mergeCoincident();
  for (int& id : contactIds) id = table.representative(id);
  // Each mesh's faces receive their contacts on their own thread, in the
  // pairs' order.
  parallelChunks(
      splitters.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t m = begin; m < end; ++m)
          for (std::size_t i = 0; i < found.pairs.size(); ++i) {
            const int* ids = contactIds.data() + contactStart[i];
            const std::uint8_t* inside = contactInside.data() + contactStart[i];
            const std::size_t n = contactStart[i + 1] - contactStart[i];
            const IntersectingPair& pair = found.pairs[i];
            if (pair.a.mesh == m) splitters[m].addContact(pair.a.face, ids, inside, 1, n);
            if (pair.b.mesh == m) splitters[m].addContact(pair.b.face, ids, inside, 2, n);
          }
      },
      1);
}

// What re-triangulating the meshes made: each input's output, as arrays or
// (`direct`: when each input's mesh is all that is asked for, no merged
// output, no snapping) written into the result's meshes, and its new
// vertices' exact points.
struct SplitMeshes {
  bool direct = false;
  std::vector<OutputArrays> outputs;
  std::vector<std::vector<ExactPoint>> exactNew;
};

// Each mesh's split reads only the finished curve point table (and copies
// the points it asks exact questions of), so meshes can be split side by
// side: a second thread takes meshes from the same counter as this one,
// and each mesh's faces are re-triangulated on its thread alone (both
// cores are busy already). Only when the work (points and segments
// received, not faces: a coarse mesh's faces receive many each) is shared
// fairly evenly (as between two meshes that cross, where every curve
// segment goes into both) and there is enough of it to be worth sharing
// (a few dozen faces); otherwise one mesh after the other, each on every
// core. With more than two cores, each mesh still re-triangulates on several.
SplitMeshes splitEachMesh(std::vector<MeshSplitter>& splitters, const CurvePoints& table,
                          const SplitOptions& options, SplitResult& r) {
  const std::size_t n = splitters.size();
  SplitMeshes out;
  out.direct = options.separate_meshes && !options.merged_output && !snaps(options);
  out.outputs.resize(n);
  out.exactNew.resize(n);
  r.curve_edges.resize(n);
  if (out.direct) r.meshes.resize(n);
  std::atomic<std::size_t> nextMesh{0};
  std::vector<std::size_t> facesAdded(n, 0);
  bool sideBySide = false;
  auto splitMeshes = [&] {
    for (std::size_t m; (m = nextMesh++) < n;) {
      MeshSplitter& s = splitters[m];
      s.shareEdgePoints(table);
      s.retriangulateFaces(table, !sideBySide || workerCount() > 2);
      if (out.direct)
        s.build(table, MeshOutput(r.meshes[m]), r.curve_edges[m], out.exactNew[m], facesAdded[m]);
      else
        s.build(table, ArraysOutput(out.outputs[m]), r.curve_edges[m], out.exactNew[m],
                facesAdded[m]);
      s.releaseWorkingMemory();
    }
  };
  std::size_t facesWithPoints = 0, work = 0, mostWork = 0;
  for (const MeshSplitter& s : splitters) {
    facesWithPoints += s.facesWithPoints();
    work += s.pointsAndSegments();
    mostWork = std::max(mostWork, s.pointsAndSegments());
  }
  if (facesWithPoints >= 32 && 3 * mostWork <= 2 * work) {
    sideBySide = true;
    std::exception_ptr asideError;
    TaskAlongside aside([&] {
      try {
        splitMeshes();
      } catch (...) {
        asideError = std::current_exception();
        nextMesh = n;  // the other thread takes no more
      }
    });
    try {
      splitMeshes();
    } catch (...) {
      nextMesh = n;
      throw;
    }
    aside.wait();
    if (asideError) std::rethrow_exception(asideError);
  } else {
    splitMeshes();
  }
  for (std::size_t m = 0; m < n; ++m) {
    r.faces_added += facesAdded[m];
    r.faces_split += splitters[m].facesSplit();
    r.degenerate_faces_kept += splitters[m].degenerateKept();
    r.new_vertices += out.exactNew[m].size();
    if (splitters[m].facesSplit() > 0)
      r.smallest_new_angle_deg =
          std::min(r.smallest_new_angle_deg, splitters[m].smallestAngle() * 180 / M_PI);
  }
  return out;
}

// The separate meshes, when they come from arrays and snapping does not
// rebuild them: their vcglib meshes built in parts (MeshBuilder: vertices,
// faces and their origins, new memory whose page faults cost more than the
// copy) that a second thread takes one after the other, the largest first,
// while this one merges or counts the curves, then takes the parts left.
// Only once there are enough faces to be worth handing to a helper (a few
// thousand faces take a few hundred microseconds). The helper is waited
// for also when the merged output throws.
class SeparateMeshes {
 public:
  SeparateMeshes(SplitMeshes& split, const SplitOptions& options, SplitResult& r)
      : split_(split), options_(options), r_(r) {
    std::size_t outputFaces = 0;
    for (const OutputArrays& out : split.outputs) outputFaces += out.triangles.size();
    if (split.direct || !options.separate_meshes || snaps(options) || outputFaces < 4096) return;
    const std::size_t n = split.outputs.size();
    r.meshes.resize(n);
    builders_.reserve(n);
    for (std::size_t m = 0; m < n; ++m) {
      const OutputArrays& out = split.outputs[m];
      builders_.emplace_back(r.meshes[m], out.positions, out.triangles, out.vertex_origin,
                             out.face_origin);
      const std::size_t nv = out.positions.size(), nf = out.triangles.size();
      parts_.push_back({m, MeshBuilder::kVertices, nv * sizeof(Vertex)});
      parts_.push_back({m, MeshBuilder::kVertexOrigins, nv * sizeof(VertexOrigin)});
      parts_.push_back({m, MeshBuilder::kFaces, nf * sizeof(Face)});
      parts_.push_back({m, MeshBuilder::kFaceOrigins, nf * sizeof(FaceOrigin)});
    }
    std::sort(parts_.begin(), parts_.end(),
              [](const Part& a, const Part& b) { return a.bytes > b.bytes; });
    helper_.emplace([this] { buildSomeParts(); });
  }
  SeparateMeshes(const SeparateMeshes&) = delete;
  SeparateMeshes& operator=(const SeparateMeshes&) = delete;

  // The parts no helper took, then their faces' corners; or every mesh
  // here, from the arrays as snapping left them.
  void finish() {
    if (helper_) {
      buildSomeParts();
      helper_->wait();
      for (MeshBuilder& b : builders_) b.link();
    } else if (options_.separate_meshes && !split_.direct) {
      r_.meshes.resize(split_.outputs.size());
      for (std::size_t m = 0; m < split_.outputs.size(); ++m)
        split_.outputs[m].toMesh(r_.meshes[m]);
    }
  }

 private:
  struct Part {
    std::size_t mesh;
    MeshBuilder::Part part;
    std::size_t bytes;  // what it writes
  };
  void buildSomeParts() {
    for (std::size_t k; (k = next_++) < parts_.size();)
      builders_[parts_[k].mesh].build(parts_[k].part);
  }

  SplitMeshes& split_;
  const SplitOptions& options_;
  SplitResult& r_;
  std::vector<MeshBuilder> builders_;
  std::vector<Part> parts_;
  std::atomic<std::size_t> next_{0};
  std::optional<TaskAlongside> helper_;  // last: destroyed (waited for) first
};

// The curve vertices of every output as exact points, by reference (each
// copied would cost more than the rest of this stage): one per curve point
// id used, then the others (an input vertex on a curve without an id is
// kept in `inputPoints`), and those at one exact position welded: at one
// curve point by its id, the others (crossings of two curves inside a
// face) by comparing exactly.
struct CurveWelding {
  std::vector<const ExactPoint*> points;
  std::deque<ExactPoint> inputPoints;
  std::vector<std::vector<int>> index;  // per mesh vertex: into points, or -1
  std::vector<int> weldedTo;            // per point: its representative
};

void weldCurvePoints(const CurvePoints& table, const std::vector<MeshSplitter>& splitters,
                     const SplitMeshes& split, const SplitResult& r, CurveWelding& w) {
  std::vector<int> pointOfId(table.size(), -1);
  std::size_t notAtCurvePoints = 0;  // curve vertices without an id: crossings made in a face
  w.index.resize(splitters.size());
  for (std::size_t m = 0; m < splitters.size(); ++m) {
    std::vector<int>& index = w.index[m];
    index.assign(split.direct ? r.meshes[m].vert.size() : split.outputs[m].positions.size(), -1);
    const auto& pointOfVertex = splitters[m].pointOfVertex();
    auto mark = [&](int v) {
      if (index[v] >= 0) return;
      const int id = pointOfVertex[v];
      if (id >= 0) {
        int& point = pointOfId[id];
        if (point < 0) {
          point = int(w.points.size());
          w.points.push_back(&table.point(id));
        }
        index[v] = point;
        return;
      }
      ++notAtCurvePoints;
      index[v] = int(w.points.size());
      const std::size_t inputVertices = splitters[m].points().size();
      if (std::size_t(v) < inputVertices) {
        w.inputPoints.emplace_back(split.direct ? r.meshes[m].vert[v].cP()
                                                : split.outputs[m].positions[v]);
        w.points.push_back(&w.inputPoints.back());
      } else {
        w.points.push_back(&split.exactNew[m][v - inputVertices]);
      }
    };
    for (const auto& e : r.curve_edges[m]) mark(e[0]), mark(e[1]);
    for (int v : splitters[m].contactVertices()) mark(v);
  }
  // Distinct curve points never coincide (the table merged those): only
  // points made inside a face can coincide with another.
  w.weldedTo.resize(w.points.size());
  if (notAtCurvePoints > 0)
    w.weldedTo = coincidentGroups(w.points);
  else
    std::iota(w.weldedTo.begin(), w.weldedTo.end(), 0);
}

// Without a merged output: only what it would tell, its slivers (the new
// faces of each mesh, counted as each was built) and its curves, a graph on
// the welded curve points.
void countWithoutMerging(const CurveWelding& w, const std::vector<MeshSplitter>& splitters,
                         SplitResult& r) {
  std::size_t slivers = 0;
  for (const MeshSplitter& s : splitters) slivers += s.slivers();
  r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = slivers;
  std::vector<std::array<int, 2>> curves;
  std::size_t curveEdges = 0;
  for (const auto& edges : r.curve_edges) curveEdges += edges.size();
  curves.reserve(curveEdges);
  for (std::size_t m = 0; m < splitters.size(); ++m)
    for (const auto& e : r.curve_edges[m]) {
      const int a = w.weldedTo[w.index[m][e[0]]], b = w.weldedTo[w.index[m][e[1]]];
      curves.push_back({std::min(a, b), std::max(a, b)});
    }
  sortUnique(curves, w.points.size());
  r.curve_edges_welded = curves.size();
  countCurves(w.points.size(), curves, r.curve_loops, r.open_curves);
}

// All meshes in one, the welded curve points once: the merged arrays, and
// in the result where each mesh's vertices went (merged_vertex), which
// faces are new and the curve edges (sorted, each once). `onCurve` marks
// the merged curve vertices.
OutputArrays mergeOutputs(const CurveWelding& w, const SplitMeshes& split,
                          const std::vector<MeshSplitter>& splitters, SplitResult& r,
                          std::vector<char>& onCurve) {
  std::vector<int> mergedOfPoint(w.points.size(), -1);
  OutputArrays merged;
  std::vector<Point3>& positions = merged.positions;
  std::size_t vertices = 0, faces = 0;
  for (const OutputArrays& mesh : split.outputs)
    vertices += mesh.positions.size(), faces += mesh.triangles.size();
  reserveInHugePages(positions, vertices);
  reserveInHugePages(merged.vertex_origin, vertices);
  reserveInHugePages(merged.triangles, faces);
  reserveInHugePages(merged.face_origin, faces);
  r.merged_new_face.reserve(faces);
  std::vector<std::array<int, 2>>& curves = r.merged_curve_edges;
  for (std::size_t m = 0; m < split.outputs.size(); ++m) {
    const OutputArrays& mesh = split.outputs[m];
    std::vector<int>& global = r.merged_vertex.emplace_back(mesh.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const int c = w.index[m][v];
      if (c >= 0) {
        int& target = mergedOfPoint[w.weldedTo[c]];
        if (target >= 0) {
          global[v] = target;
          continue;
        }
        target = int(positions.size());
      }
      global[v] = int(positions.size());
      positions.push_back(mesh.positions[v]);
      merged.vertex_origin.push_back(mesh.vertex_origin[v]);
      onCurve.push_back(c >= 0);
    }
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      const Triangle& t = mesh.triangles[f];
      const Triangle g = {global[t[0]], global[t[1]], global[t[2]]};
      // Two corners welded into one (they lie at one exact position, as
      // rounded output split again can have them): no area left.
      if (g[0] == g[1] || g[1] == g[2] || g[2] == g[0]) {
        ++r.collapsed_faces_removed;
        continue;
      }
      merged.triangles.push_back(g);
      merged.face_origin.push_back(mesh.face_origin[f]);
      r.merged_new_face.push_back(f >= splitters[m].keptFaces());
    }
    for (const auto& e : r.curve_edges[m])
      if (global[e[0]] != global[e[1]])
        curves.push_back(
            {std::min(global[e[0]], global[e[1]]), std::max(global[e[0]], global[e[1]])});
  }
  sortUnique(curves, positions.size());
  return merged;
}

// The new faces of `merged` with an angle under 1°.
std::size_t newSlivers(const OutputArrays& merged, const std::vector<char>& newFace) {
  std::size_t n = 0;
  for (std::size_t f = 0; f < merged.triangles.size(); ++f) {
    const Triangle& t = merged.triangles[f];
    n += newFace[f] &&
         isSliver(merged.positions[t[0]], merged.positions[t[1]], merged.positions[t[2]]);
  }
  return n;
}

// The merged output: coincident faces kept once, quality snapping, the
// curves counted; the merged mesh built when asked for.
void mergeAndSnap(const CurveWelding& w, SplitMeshes& split,
                  const std::vector<MeshSplitter>& splitters, const SplitOptions& options,
                  SplitResult& r) {
  std::vector<char> onCurve;  // per merged vertex
  OutputArrays merged = mergeOutputs(w, split, splitters, r, onCurve);
  std::vector<std::array<int, 2>>& curves = r.merged_curve_edges;
  r.coincident_faces =
      keepOverlapsOnce(merged, r.merged_new_face, onCurve, curves, options.overlaps_once);
  if (options.overlaps_once) r.coincident_faces_removed = r.coincident_faces;
  r.new_faces_below_1deg = r.new_faces_below_1deg_unsnapped = newSlivers(merged, r.merged_new_face);
  if (snaps(options) && r.faces_split > 0) {
    reportProgress(options.progress, 95, "Snapping curve points");
    snapCurves(merged, curves, split.outputs, options, r);
    r.new_faces_below_1deg = newSlivers(merged, r.merged_new_face);
  }
  r.curve_edges_welded = curves.size();
  countCurves(merged.positions.size(), curves, r.curve_loops, r.open_curves);
  if (!options.merged_output) return;
  merged.toMesh(r.merged);
  r.merged_points = std::move(merged.positions);
  r.merged_triangles = std::move(merged.triangles);
  r.merged_face_origin = std::move(merged.face_origin);
}

}  // namespace

SplitResult splitAlongIntersections(const std::vector<const Mesh*>& meshes,
                                    const SplitOptions& options) {
  const auto start = Clock::now();
  if (!options.separate_meshes && !options.merged_output)
    throw InvalidInputError(
        "nothing to output: ask for the separate meshes, the merged mesh or both");
  SplitResult r;
  std::vector<WeldedArrays> inputs = prepareInputs(meshes, options, r);
  FindIntersectionsResult found = findCrossings(inputs, options, r);
  r.complete = options.self && (options.between_meshes || meshes.size() == 1);
  r.input_face_trees = std::move(found.face_trees);
  if (!r.input_face_trees.empty())
    for (const WeldedArrays& in : inputs) r.input_face_of_box.push_back(in.face_origin);

  reportProgress(options.progress, 40, "Collecting curve points");
  std::vector<MeshSplitter> splitters;
  splitters.reserve(meshes.size());
  for (std::size_t m = 0; m < meshes.size(); ++m)
    splitters.emplace_back(std::move(inputs[m]), std::uint32_t(m));
  CurvePoints table(2 * found.pairs.size());
  distributeContacts(found, splitters, table);

  reportProgress(options.progress, 55, "Re-triangulating crossed faces");
  SplitMeshes split = splitEachMesh(splitters, table, options, r);

  reportProgress(options.progress, 90, "Welding along the curves");
  SeparateMeshes separate(split, options, r);
  CurveWelding welding;
  weldCurvePoints(table, splitters, split, r, welding);
  r.smallest_new_angle_deg_unsnapped = r.smallest_new_angle_deg;
  // Snapping works on the merged arrays (and rebuilds each input's output
  // from them), so it needs them even when the merged mesh is not asked for.
  const bool mergedArrays = options.merged_output || (snaps(options) && r.faces_split > 0);
  if (mergedArrays)
    mergeAndSnap(welding, split, splitters, options, r);
  else
    countWithoutMerging(welding, splitters, r);
  separate.finish();
  if (!options.separate_meshes) r.curve_edges.assign(meshes.size(), {});  // they go with `meshes`
  if (!options.merged_output) {                                           // made for snapping only
    r.merged_curve_edges.clear();
    r.merged_vertex.clear();
    r.merged_new_face.clear();
    r.merged_snapped_face.clear();
  }
  reportProgress(options.progress, 100, "Done");
  r.time_ms = msSince(start);
  return r;
}

std::vector<std::uint8_t> curveEdgeFlags(const Mesh& mesh,
                                         const std::vector<std::array<int, 2>>& curveEdges) {
  std::set<std::array<int, 2>> curves;
  for (auto e : curveEdges) {
    if (e[0] > e[1]) std::swap(e[0], e[1]);
    curves.insert(e);
  }
  const std::vector<Triangle> triangles = trianglesOf(mesh);
  std::vector<std::uint8_t> flags(triangles.size(), 0);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (int i = 0; i < 3; ++i) {
      std::array<int, 2> e{triangles[f][i], triangles[f][(i + 1) % 3]};
      if (e[0] > e[1]) std::swap(e[0], e[1]);
      if (curves.count(e)) flags[f] |= std::uint8_t(1 << i);
    }
  return flags;
}

JsonObject toJson(const SplitResult& r) {
  JsonObject j;
  j.set("intersecting_pairs", r.intersecting_pairs)
      .set("curve_edges", r.curve_edges_welded)
      .set("curve_loops", r.curve_loops)
      .set("open_curves", r.open_curves)
      .set("faces_split", r.faces_split)
      .set("faces_added", r.faces_added)
      .set("new_vertices", r.new_vertices)
      .set("degenerate_faces_kept", r.degenerate_faces_kept)
      .set("vertices_welded", r.vertices_welded)
      .set("duplicate_faces_removed", r.duplicate_faces_removed)
      .set("coincident_faces", r.coincident_faces)
      .set("coincident_faces_removed", r.coincident_faces_removed)
      .set("pairs_split_after_rounding", r.pairs_split_after_rounding)
      .set("collapsed_faces_removed", r.collapsed_faces_removed)
      .set("smallest_new_angle_deg", r.faces_split ? r.smallest_new_angle_deg : 0.0)
      .set("smallest_new_angle_deg_unsnapped",
           r.faces_split ? r.smallest_new_angle_deg_unsnapped : 0.0)
      .set("new_faces_below_1deg", r.new_faces_below_1deg)
      .set("new_faces_below_1deg_unsnapped", r.new_faces_below_1deg_unsnapped)
      .set("vertices_snapped", r.vertices_snapped)
      .set("edges_snapped", r.edges_snapped)
      .set("time_ms", r.time_ms);
  return j;
}

}  // namespace meshmend
