// fillHoles: finds the border loops from the border edges alone, collects
// the faces around the holes to fill in one pass, fills each hole
// (holes/fill.h) and writes what was added into the mesh once.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/base/border_loops.h"
#include "common/base/errors.h"
#include "common/base/timing.h"
#include "common/exact/intersections.h"
#include "common/repair/holes/fill.h"
#include "common/repair/holes/holes.h"
#include "common/repair/holes/neighbourhood.h"
#include "common/repair/holes/surface.h"
#include "common/repair/output_stage.h"

namespace meshmend {

const char* toString(HoleFairing fairing) {
  switch (fairing) {
    case HoleFairing::Flat:
      return "flat";
    case HoleFairing::Harmonic:
      return "harmonic";
    case HoleFairing::Biharmonic:
      return "biharmonic";
    case HoleFairing::LaplacianRegression:
      return "laplacian_regression";
  }
  return "unknown";
}

namespace {

using holes::Bounds;
using holes::Surface;

void validateCompactnessAndOptions(const Mesh& mesh, const HoleFillOptions& o) {
  if (std::size_t(mesh.vn) != mesh.vert.size() || std::size_t(mesh.fn) != mesh.face.size())
    throw InvalidInputError(
        "the mesh has deleted vertices or faces; compact it first (MeshLab does when saving, or "
        "run \"Remove Unreferenced Vertices\")");
  auto bad = [](const std::string& what) { throw InvalidInputError("fill holes: " + what); };
  if (!(o.max_diameter >= 0)) bad("max_diameter must be 0 (no limit) or positive");
  if (!(o.long_edge_factor == 0 || o.long_edge_factor > 1))
    bad("long_edge_factor must be 0 (off) or greater than 1");
  if (!(o.size_growth >= 1 && o.size_growth <= 4)) bad("size_growth must be between 1 and 4");
  if (!(o.max_size_factor >= 1)) bad("max_size_factor must be at least 1");
  if (!(o.merge_distance > 0 && o.merge_distance < 1)) bad("merge_distance must be in (0, 1)");
  if (o.regression_rings < 1) bad("regression_rings must be at least 1");
  if (!(o.regression_gamma > 0)) bad("regression_gamma must be positive");
  if (o.regression_max_samples < 8) bad("regression_max_samples must be at least 8");
  if (!o.selected_vertices.empty() && o.selected_vertices.size() != mesh.vert.size())
    bad("selected_vertices has " + std::to_string(o.selected_vertices.size()) +
        " flags but the mesh has " + std::to_string(mesh.vert.size()) + " vertices");
  for (int v : o.selected_vertex_indices)
    if (v < 0 || std::size_t(v) >= mesh.vert.size())
      bad("selected vertex " + std::to_string(v) + " is not a vertex of the mesh");
}

// The largest distance between two points of the loop (within a few
// percent above 512 of them: repeated farthest-point sweeps give a lower
// bound, close for the round and long shapes of holes).
double loopDiameter(const Mesh& mesh, const std::vector<int>& loop) {
  auto at = [&](int v) -> const Point3& { return holes::positionOf(mesh.vert[std::size_t(v)]); };
  double best = 0;
  if (loop.size() <= 512) {
    for (std::size_t i = 0; i < loop.size(); ++i)
      for (std::size_t j = i + 1; j < loop.size(); ++j)
        best = std::max(best, (at(loop[i]) - at(loop[j])).SquaredNorm());
    return std::sqrt(best);
  }
  int from = loop[0];
  for (int sweep = 0; sweep < 4; ++sweep) {
    int far = from;
    for (int v : loop) {
      const double d = (at(v) - at(from)).SquaredNorm();
      if (d > best) best = d, far = v;
    }
    from = far;
  }
  return std::sqrt(best);
}

// The mesh's bounding box diagonal; throws (naming the vertex) when a
// coordinate is not finite.
double diagonalOf(const Mesh& mesh) {
  Bounds box;
  double notFinite = 0;  // x - x is 0 for a finite x, NaN otherwise
  for (const Vertex& v : mesh.vert) {
    const Point3& p = v.cP();
    notFinite += (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]);
    box.add(p);
  }
  if (notFinite != 0) requireFacesAndFiniteCoordinates(mesh, "the mesh");
  return (box.hi - box.lo).Norm();
}

// §3.1 pre-treatment: halves the border edges longer than `factor` x the
// loop's mean edge length (the mean taken again after each pass) together
// with the face each borders, until none is. `loop` (mesh direction) gets
// the new vertices, `sizes` (one per loop edge) the length of the input
// edge each edge is part of: the size the patch takes there; `touched` the
// faces split and added.
std::size_t splitLongEdges(Surface& s, std::vector<int>& loop, std::vector<double>& sizes,
                           double factor, std::vector<int>& touched) {
  sizes.resize(loop.size());
  for (std::size_t i = 0; i < loop.size(); ++i)
    sizes[i] = (s.point(loop[(i + 1) % loop.size()]) - s.point(loop[i])).Norm();
  if (factor <= 0) return 0;
  std::size_t splits = 0;
  for (int pass = 0; pass < 64; ++pass) {
    double total = 0;
    for (std::size_t i = 0; i < loop.size(); ++i)
      total += (s.point(loop[(i + 1) % loop.size()]) - s.point(loop[i])).Norm();
    const double limit = factor * total / double(loop.size());
    std::vector<int> out;
    std::vector<double> outSizes;
    bool any = false;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      out.push_back(a);
      outSizes.push_back(sizes[i]);
      if (!((s.point(b) - s.point(a)).Norm() > limit)) continue;
      const int face = s.borderFace(a, b);
      const int m = s.splitBorderEdge(a, b);
      if (m < 0) continue;
      touched.push_back(face);
      touched.push_back(s.borderFace(m, b));
      out.push_back(m);
      outSizes.push_back(sizes[i]);
      any = true;
      ++splits;
    }
    loop = std::move(out);
    sizes = std::move(outSizes);
    if (!any) break;
  }
  return splits;
}

// The faces around the holes to fill: gathered from the input once for
// every hole's region (its border's box grown by a quarter of its diameter
// and two border edges: room for the patch's bulge and the rings around
// it), and from what was added since; a box beyond the region is gathered
// afresh.
class Neighbourhoods {
 public:
  Neighbourhoods(const Mesh& mesh, const Surface& s, std::vector<Bounds> regions)
      : mesh_(mesh), s_(s), regions_(std::move(regions)) {
    bool finite = true;
    faces_ = holes::inputFacesNear(mesh, regions_, finite);
    if (!finite) requireFacesAndFiniteCoordinates(mesh, "the mesh");  // throws, naming it
  }

  std::vector<int> near(std::size_t hole, const Bounds& bounds) const {
    std::vector<int> out;
    if (regions_[hole].contains(bounds)) {
      out = faces_[hole];
    } else {
      bool finite = true;
      out = holes::inputFacesNear(mesh_, {bounds.grown(1e-9 * (bounds.hi - bounds.lo).Norm())},
                                  finite)[0];
    }
    for (std::size_t f = s_.inputFaces(); f < s_.faceCount(); ++f)
      if (s_.boundsOf(int(f)).overlaps(bounds)) out.push_back(int(f));
    return out;
  }

 private:
  const Mesh& mesh_;
  const Surface& s_;
  std::vector<Bounds> regions_;
  std::vector<std::vector<int>> faces_;
};

// Why a hole is left open (empty: it is to be filled): its border, its
// size against the limits, the selection.
std::string reasonToSkip(const BorderLoop& loop, const HoleReport& report,
                         const HoleFillOptions& options, double diagonal,
                         const std::vector<int>& selected) {
  const bool bySelection =
      !options.selected_vertices.empty() || !options.selected_vertex_indices.empty();
  auto isSelected = [&](int v) { return std::binary_search(selected.begin(), selected.end(), v); };
  if (!loop.closed)
    return "its border is not a closed loop: at vertex " + std::to_string(loop.broken_at) +
           " the faces are non-manifold or inconsistently oriented (repair them first)";
  if (loop.vertices.size() < 3)
    return "a border of two edges (a slit between two faces): weld or stitch it instead";
  if (options.max_boundary_edges > 0 && report.boundary_edges > options.max_boundary_edges)
    return "larger than the limit: " + std::to_string(report.boundary_edges) + " > " +
           std::to_string(options.max_boundary_edges) + " boundary edges";
  if (options.max_diameter > 0 && report.diameter > options.max_diameter * diagonal)
    return "wider than the limit: diameter " + std::to_string(report.diameter / diagonal) + " > " +
           std::to_string(options.max_diameter) + " of the bounding box diagonal";
  if (bySelection && std::none_of(loop.vertices.begin(), loop.vertices.end(), isSelected))
    return "not selected (no selected vertex on its border)";
  return "";
}

// A report per hole found; returns the holes to fill, with the region
// around each whose faces its patch is checked against.
std::vector<std::size_t> chooseHoles(const Mesh& mesh, const Surface& s, const BorderLoops& found,
                                     const HoleFillOptions& options, HoleFillResult& result,
                                     std::vector<Bounds>& regions) {
  // The bounding box and the selection only when a limit needs them.
  const double diagonal = options.max_diameter > 0 ? diagonalOf(mesh) : 0;
  std::vector<int> selected = options.selected_vertex_indices;
  for (std::size_t v = 0; v < options.selected_vertices.size(); ++v)
    if (options.selected_vertices[v]) selected.push_back(int(v));
  std::sort(selected.begin(), selected.end());
  std::vector<std::size_t> toFill;
  for (const BorderLoop& loop : found.loops) {
    HoleReport report;
    report.boundary = loop.vertices;
    report.boundary_edges = loop.closed ? loop.vertices.size() : loop.vertices.size() - 1;
    report.diameter = loopDiameter(mesh, loop.vertices);
    report.reason = reasonToSkip(loop, report, options, diagonal, selected);
    if (report.reason.empty()) {
      toFill.push_back(result.holes.size());
      Bounds box;
      double length = 0;
      for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
        const Point3& p = s.point(loop.vertices[i]);
        box.add(p);
        length += (s.point(loop.vertices[(i + 1) % loop.vertices.size()]) - p).Norm();
      }
      regions.push_back(
          box.grown(0.25 * report.diameter + 2 * length / double(loop.vertices.size())));
    }
    result.holes.push_back(std::move(report));
  }
  return toFill;
}

// The output stage (output_stage.h) on the stored values: the pairs with a
// new or split face counted exactly (new_intersecting_pairs, the patches'
// checks confirmed), new vertices re-rounded where rounding made such a
// pair cross (only where the checks were off), and every intersecting pair
// of the result by the checker's rule (remaining_intersecting_pairs).
void verifyStored(Surface& s, const HoleFillOptions& options, Scalar scalar,
                  HoleFillResult& result) {
  const auto verifyStart = Clock::now();
  std::vector<Point3> points(s.vertexCount());
  std::vector<Triangle> triangles(s.faceCount());
  for (std::size_t v = 0; v < points.size(); ++v) points[v] = s.point(int(v));
  for (std::size_t f = 0; f < triangles.size(); ++f) triangles[f] = s.corners(int(f));
  std::vector<char> movable(points.size(), 0), changed(triangles.size(), 0);
  for (std::size_t v = s.inputVertices(); v < points.size(); ++v) movable[v] = 1;
  for (std::size_t f = s.inputFaces(); f < triangles.size(); ++f) changed[f] = 1;
  for (int f : s.changedInputFaces()) changed[std::size_t(f)] = 1;
  OutputStageOptions stage;
  stage.scalar = scalar;
  stage.progress = progressWithin(options.progress, 92, 96);
  result.stored = storeNewPoints(points, triangles, movable, changed, stage);
  for (std::size_t v = s.inputVertices(); v < points.size(); ++v) s.setNewPoint(int(v), points[v]);
  result.new_intersecting_pairs = result.stored.crossing;
  result.remaining_intersecting_pairs =
      storedIntersectingPairs(MeshArrays{points, triangles}, scalar);
  result.remaining_counted = true;
  result.verified = true;
  result.stage_ms.verify = msSince(verifyStart);
}

}  // namespace

HoleFillResult fillHoles(Mesh& mesh, const HoleFillOptions& options) {
  const auto start = Clock::now();
  // A mesh without faces or with deleted elements is refused before
  // anything is read from its faces.
  if (mesh.fn == 0) requireFacesAndFiniteCoordinates(mesh, "the mesh");
  validateCompactnessAndOptions(mesh, options);
  HoleFillResult result;
  reportProgress(options.progress, 0, "Finding holes");

  const BorderEdges edges = findBorderEdges(mesh);
  const BorderLoops found =
      findBorderLoops(edges, [&mesh](int v) { return mesh.vert[std::size_t(v)].cP(); });
  result.holes_found = found.loops.size();
  const Scalar scalar = options.round_to_float ? Scalar::kFloat : Scalar::kDouble;
  if (found.loops.empty()) {
    result.verified = true;  // nothing new
    if (options.verify) {
      result.remaining_intersecting_pairs = storedIntersectingPairs(mesh, scalar);
      result.remaining_counted = true;
    }
    reportProgress(options.progress, 100, "Done");
    result.time_ms = msSince(start);
    return result;
  }
  Surface s(mesh, options.round_to_float);
  for (const BorderLoop& loop : found.loops)
    for (std::size_t i = 0; i < loop.faces.size(); ++i)
      s.setBorderFace(loop.vertices[i], loop.vertices[(i + 1) % loop.vertices.size()],
                      loop.faces[i]);
  std::vector<Bounds> regions;
  const std::vector<std::size_t> toFill = chooseHoles(mesh, s, found, options, result, regions);
  if (toFill.empty()) {
    for (const HoleReport& r : result.holes) result.holes_skipped += !r.filled;
    reportProgress(options.progress, 100, "Done");
    result.time_ms = msSince(start);
    return result;
  }
  const Neighbourhoods neighbourhoods(mesh, s, std::move(regions));
  result.stage_ms.find = msSince(start);

  for (std::size_t i = 0; i < toFill.size(); ++i) {
    reportProgress(options.progress, int(5 + 85 * i / toFill.size()), "Filling holes");
    const auto holeStart = Clock::now();
    HoleReport& report = result.holes[toFill[i]];
    std::vector<int> loop = report.boundary;
    const Surface::Checkpoint undo = s.checkpoint();
    std::vector<int> splitFaces;
    std::vector<double> sizes;
    const auto splitStart = Clock::now();
    report.edges_split = splitLongEdges(s, loop, sizes, options.long_edge_factor, splitFaces);
    result.stage_ms.split += msSince(splitStart);
    report.vertices_added = report.edges_split;
    holes::HoleContext context{s, options, found.pinched, result.stage_ms,
                               [&](const Bounds& b) { return neighbourhoods.near(i, b); }};
    if (holes::fillHole(context, loop, sizes, splitFaces, report)) {
      report.filled = true;
      if (report.fairing != options.fairing) ++result.fallbacks;
    } else {
      s.restore(undo);
      report.edges_split = 0;
      report.vertices_added = 0;
      report.faces_added = 0;
    }
    report.time_ms = msSince(holeStart);
  }
  for (const HoleReport& r : result.holes) {
    if (r.filled) {
      ++result.holes_filled;
      result.faces_added += r.faces_added;
      result.vertices_added += r.vertices_added;
      result.edges_split += r.edges_split;
    } else {
      ++result.holes_skipped;
    }
  }
  // Every patch kept passed its exact check (none when the check is off),
  // on its new vertices as the host stores them (Surface rounds them to
  // float for a float host): no pair with a new or split face crosses.
  result.verified = options.check_intersections;
  if (options.verify) {
    reportProgress(options.progress, 92, "Checking the stored result");
    verifyStored(s, options, scalar, result);
  }
  reportProgress(options.progress, 97, "Writing");
  const auto writeStart = Clock::now();
  s.writeInto(mesh, result);
  result.stage_ms.write = msSince(writeStart);
  reportProgress(options.progress, 100, "Done");
  result.time_ms = msSince(start);
  return result;
}

JsonObject toJson(const HoleFillResult& r) {
  std::vector<JsonObject> skipped, holes;
  for (std::size_t i = 0; i < r.holes.size(); ++i) {
    const HoleReport& h = r.holes[i];
    JsonObject j;
    j.set("hole", i)
        .set("boundary_vertices", h.boundary.size())
        .set("boundary_edges", h.boundary_edges)
        .set("diameter", h.diameter)
        .set("filled", h.filled);
    if (h.filled)
      j.set("edges_split", h.edges_split)
          .set("faces_added", h.faces_added)
          .set("vertices_added", h.vertices_added)
          .set("fairing", toString(h.fairing))
          .set("planar_domain", h.planar_domain)
          .set("fairing_residual", h.fairing_residual)
          .set("training_samples", h.training_samples);
    if (!h.reason.empty()) j.set("reason", h.reason);
    j.set("time_ms", h.time_ms);
    holes.push_back(j);
    if (!h.filled)
      skipped.push_back(JsonObject()
                            .set("hole", i)
                            .set("boundary_edges", h.boundary_edges)
                            .set("reason", h.reason));
  }
  JsonObject j;
  j.set("holes_found", r.holes_found)
      .set("holes_filled", r.holes_filled)
      .set("holes_skipped", r.holes_skipped)
      .set("skipped", skipped)
      .set("faces_added", r.faces_added)
      .set("vertices_added", r.vertices_added)
      .set("edges_split", r.edges_split)
      .set("fallbacks", r.fallbacks);
  if (r.verified)
    j.set("new_intersecting_pairs", r.new_intersecting_pairs);
  else
    j.setNull("new_intersecting_pairs");
  if (r.remaining_counted) j.set("remaining_intersecting_pairs", r.remaining_intersecting_pairs);
  const auto& t = r.stage_ms;
  j.set("time_ms", r.time_ms)
      .set("stage_ms", JsonObject()
                           .set("find", t.find)
                           .set("split", t.split)
                           .set("triangulate", t.triangulate)
                           .set("fair", t.fair)
                           .set("check", t.check)
                           .set("verify", t.verify)
                           .set("write", t.write))
      .set("holes", holes);
  return j;
}

}  // namespace meshmend
