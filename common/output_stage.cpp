#include "common/output_stage.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include "common/errors.h"
#include "common/intersections.h"
#include "common/predicates.h"
#include "common/split_detail.h"

namespace meshmend {

using namespace split_detail;

namespace {

// Rounding and the check work on the merged output: where the meshes meet
// it holds each curve point once, so all meshes round it alike.
void requireMergedOutput(const SplitResult& result, const char* operation) {
  if (result.merged.fn == 0 && !result.meshes.empty())
    throw InvalidInputError(std::string(operation) +
                            " needs the merged output: split with SplitOptions::merged_output");
}

}  // namespace

std::size_t degenerateNewFaces(const SplitResult& result) {
  requireMergedOutput(result, "counting degenerate faces");
  std::size_t n = 0;
  for (std::size_t f = 0; f < result.merged.face.size(); ++f) {
    if (!result.merged_new_face[f]) continue;
    const Face& face = result.merged.face[f];
    n += face.cV(0) == face.cV(1) || face.cV(1) == face.cV(2) || face.cV(2) == face.cV(0) ||
         collinear(face.cP(0), face.cP(1), face.cP(2));
  }
  return n;
}

namespace {
void separateFromMerged(SplitResult& r);
}  // namespace

std::size_t mendCollinearNewFaces(SplitResult& r) {
  requireMergedOutput(r, "mending collinear faces");
  Mesh& m = r.merged;
  FaceOriginHandle origin = faceOrigins(m);
  std::vector<Triangle> T = trianglesOf(m);
  auto isFlat = [&](std::size_t f) {
    const Triangle& t = T[f];
    const Point3 &p0 = m.vert[t[0]].cP(), &p1 = m.vert[t[1]].cP(), &p2 = m.vert[t[2]].cP();
    return r.merged_new_face[f] && t[0] != t[1] && t[1] != t[2] && t[2] != t[0] && p0 != p1 &&
           p1 != p2 && p2 != p0 && collinear(p0, p1, p2);
  };
  // The faces along each side of a flat face, found in one pass (a pass per
  // flat face would be quadratic where rounding leaves many). A flip below
  // adds its two faces to the sides they take; entries it makes stale are
  // told apart by the faces' current corners.
  auto key = [](int u, int v) { return std::array<int, 2>{std::min(u, v), std::max(u, v)}; };
  std::map<std::array<int, 2>, std::vector<int>> along;
  for (std::size_t f = 0; f < T.size(); ++f)
    if (isFlat(f))
      for (int i = 0; i < 3; ++i) along[key(T[f][i], T[f][(i + 1) % 3])];
  if (along.empty()) return 0;
  auto link = [&](int h) {
    for (int i = 0; i < 3; ++i) {
      const auto side = along.find(key(T[h][i], T[h][(i + 1) % 3]));
      if (side != along.end() &&
          std::find(side->second.begin(), side->second.end(), h) == side->second.end())
        side->second.push_back(h);
    }
  };
  for (std::size_t h = 0; h < T.size(); ++h) link(int(h));
  std::set<std::array<int, 2>> curves;
  for (const auto& e : r.merged_curve_edges) curves.insert(key(e[0], e[1]));
  std::size_t mended = 0;
  std::vector<char> removed(T.size(), 0);
  std::vector<int> near;
  for (std::size_t f = 0; f < T.size(); ++f) {
    if (!isFlat(f)) continue;
    const Triangle t = T[f];
    // The corner strictly between the other two: the one opposite the
    // longest side (distinct collinear points; compared along an axis on
    // which they differ, exactly).
    int k = 0;
    const Point3 &p0 = m.vert[t[0]].cP(), &p1 = m.vert[t[1]].cP();
    const int axis = p0[0] != p1[0] ? 0 : p0[1] != p1[1] ? 1 : 2;
    for (int i = 0; i < 3; ++i) {
      const double x = m.vert[t[i]].cP()[axis], y = m.vert[t[(i + 1) % 3]].cP()[axis],
                   z = m.vert[t[(i + 2) % 3]].cP()[axis];
      if ((y < x && x < z) || (z < x && x < y)) k = i;
    }
    const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    // Per side of the flat face, the other faces along it running the same
    // way and the other way (a closed surface has as many of each, curves
    // included); g: the face running c to b beyond the long side.
    int g = -1, d = -1, same[3] = {0, 0, 0}, reverse[3] = {0, 0, 0};
    const int side[3][2] = {{a, b}, {b, c}, {c, a}};
    near.clear();
    for (const auto& s : side) {
      const std::vector<int>& faces = along.at(key(s[0], s[1]));
      near.insert(near.end(), faces.begin(), faces.end());
    }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    for (int h : near) {
      if (h == int(f) || removed[h]) continue;
      for (int i = 0; i < 3; ++i) {
        const int u = T[h][i], v = T[h][(i + 1) % 3];
        for (int e = 0; e < 3; ++e) {
          same[e] += u == side[e][0] && v == side[e][1];
          reverse[e] += u == side[e][1] && v == side[e][0];
        }
        if (u == c && v == b) g = h, d = T[h][(i + 2) % 3];
      }
    }
    const int others = same[1] + reverse[1];
    // Nothing beyond the long side: the flat face only fills a gap of no
    // area between faces that already meet along the short sides (a split
    // there put a on that side). It goes where that leaves its sides
    // closer to closed.
    if (others == 0) {
      int before = 0, after = 0;
      for (int e = 0; e < 3; ++e) {
        before += std::abs(1 + same[e] - reverse[e]);
        after += std::abs(same[e] - reverse[e]);
      }
      if (after < before) {
        removed[f] = 1;
        ++mended;
      }
      continue;
    }
    if (others != 1 || g < 0 || d == a) continue;
    const Point3& pd = m.vert[d].cP();
    if (collinear(m.vert[a].cP(), m.vert[b].cP(), pd) ||
        collinear(m.vert[a].cP(), pd, m.vert[c].cP()))
      continue;
    T[f] = {a, b, d};
    T[g] = {a, d, c};
    for (int i = 0; i < 3; ++i) {
      m.face[f].V(i) = &m.vert[T[f][i]];
      m.face[g].V(i) = &m.vert[T[g][i]];
    }
    origin[f] = origin[g];
    r.merged_new_face[g] = 1;
    if (!r.merged_snapped_face.empty()) r.merged_snapped_face[f] = r.merged_snapped_face[g];
    if (curves.erase(key(b, c)))  // the curve now runs through a
      curves.insert(key(a, b)), curves.insert(key(a, c));
    link(int(f));
    link(g);
    ++mended;
  }
  if (std::find(removed.begin(), removed.end(), 1) != removed.end()) {
    std::size_t kept = 0;
    for (std::size_t f = 0; f < T.size(); ++f) {
      if (removed[f]) {
        vcg::tri::Allocator<Mesh>::DeleteFace(m, m.face[f]);
        continue;
      }
      r.merged_new_face[kept] = r.merged_new_face[f];
      if (!r.merged_snapped_face.empty()) r.merged_snapped_face[kept] = r.merged_snapped_face[f];
      ++kept;
    }
    vcg::tri::Allocator<Mesh>::CompactFaceVector(m);  // in order; attributes follow
    r.merged_new_face.resize(kept);
    if (!r.merged_snapped_face.empty()) r.merged_snapped_face.resize(kept);
    r.collapsed_faces_removed += T.size() - kept;
  }
  if (mended) {
    r.merged_curve_edges.assign(curves.begin(), curves.end());
    if (!r.meshes.empty() && r.coincident_faces_removed == 0) separateFromMerged(r);
  }
  return mended;
}

FloatOutput roundForFloatHost(SplitResult& r, const std::vector<const Mesh*>& inputs,
                              const SplitOptions& options) {
  FloatOutput out;
  out.crossing = roundToFloat(r);
  SplitOptions used = options;
  // Where curve points lie a few float steps from each other or from an
  // edge, no rounding keeps every face apart (or whole): split again with
  // such points merged as quality snapping merges them.
  if (options.snap_float_steps <= 0 && (out.crossing > 0 || degenerateNewFaces(r) > 0)) {
    reportProgress(options.progress, 96, "Splitting again, merging points a float apart");
    used.snap_float_steps = kFloatSnapSteps;
    SplitResult second = splitAlongIntersections(inputs, used);
    const std::size_t left = roundToFloat(second);
    if (left + degenerateNewFaces(second) < out.crossing + degenerateNewFaces(r)) {
      second.time_ms += r.time_ms;
      r = std::move(second);
      out.crossing = left;
      out.snapped_for_float = true;
    } else {
      used.snap_float_steps = options.snap_float_steps;
    }
  }
  // What is left crosses as rounded: the merged output is split again along
  // those crossings, on its float values, and rounded again (the separate
  // outputs follow).
  if (out.crossing > 0) {
    reportProgress(options.progress, 97, "Splitting the rounded result where it crosses");
    out.crossing = splitRoundedAgain(r, inputs, used);
  }
  if (degenerateNewFaces(r) > 0) out.collinear_faces_mended = mendCollinearNewFaces(r);
  // Where surfaces nearly coincide over a region (a part and a copy a few
  // float steps away), curve points crowd within float steps of each other
  // everywhere and neither of the above keeps the float result apart:
  // quality snapping removes the slivers that hold them. Tried only when
  // none was asked for and crossings or collapsed faces are left; kept if
  // it leaves fewer.
  if (options.snap_tolerance <= 0 && out.crossing + degenerateNewFaces(r) > 0) {
    reportProgress(options.progress, 98, "Splitting again with quality snapping");
    SplitOptions snapping = options;
    snapping.snap_tolerance = kFloatQualitySnapTolerance;
    snapping.snap_float_steps = kFloatSnapSteps;
    SplitResult third = splitAlongIntersections(inputs, snapping);
    std::size_t left = roundToFloat(third);
    if (left > 0) left = splitRoundedAgain(third, inputs, snapping);
    const std::size_t mended = degenerateNewFaces(third) > 0 ? mendCollinearNewFaces(third) : 0;
    if (left + degenerateNewFaces(third) < out.crossing + degenerateNewFaces(r)) {
      third.time_ms += r.time_ms;
      r = std::move(third);
      out.crossing = left;
      out.snapped_for_float = true;
      out.quality_snapped_for_float = true;
      out.collinear_faces_mended = mended;
    }
  }
  return out;
}

std::size_t remainingIntersections(const SplitResult& result, bool asFloat) {
  requireMergedOutput(result, "counting the intersections left");
  return result.merged.fn == 0 ? 0 : selfIntersectingPairs(result.merged, asFloat, false);
}

namespace {

float below(double x) {
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float above(double x) {
  float f = float(x);
  return double(f) < x ? std::nextafter(f, INFINITY) : f;
}

}  // namespace

// How many floats away from its exact value roundToFloat may put a
// coordinate of a new vertex (the nearest below or above is one away). The
// choices grow as its cube; what two floats each way cannot keep apart is
// for snapping and splitRoundedAgain.
constexpr int kFarthestRounding = 2;

std::size_t roundToFloat(SplitResult& r, int passes) {
  requireMergedOutput(r, "rounding to float");
  Mesh& merged = r.merged;
  if (merged.fn == 0) return 0;
  const std::vector<Point3> exact = positionsOf(merged);
  std::vector<Point3> P = exact;
  for (Point3& p : P) p = roundedToFloat(p);
  const std::vector<Triangle> T = trianglesOf(merged);
  VertexOriginHandle vo = vertexOrigins(merged);

  // Only faces that are new or that rounding moves can cross anything they
  // did not cross before: every other face is an input face, exactly as it was.
  std::vector<char> isChanged(T.size(), 0);
  std::vector<int> changedIndex(T.size(), -1);
  std::vector<std::uint32_t> changed;
  for (std::size_t f = 0; f < T.size(); ++f) {
    isChanged[f] = f < r.merged_new_face.size() && r.merged_new_face[f];
    for (int v : T[f]) isChanged[f] |= P[v] != exact[v];
    if (isChanged[f]) {
      changedIndex[f] = int(changed.size());
      changed.push_back(std::uint32_t(f));
    }
  }
  if (changed.empty()) return 0;
  // Candidates: boxes widened by more float steps than re-rounding moves a
  // vertex (at most kFarthestRounding from its exact position).
  // Faces with the same three vertices (a planar overlap kept in each part)
  // coincide however their vertices are rounded: never a crossing here.
  std::vector<std::array<std::uint32_t, 2>> pairs =
      pairsWithChangedFaces(P, T, isChanged, kFarthestRounding + 2);
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const auto& p) { return sameVertices(T[p[0]], T[p[1]]); }),
              pairs.end());
  // Candidates of each changed face, both ways (compressed rows).
  std::vector<std::uint32_t> offsets(changed.size() + 1, 0), others;
  for (const auto& [f, g] : pairs) {
    ++offsets[changedIndex[f] + 1];
    if (changedIndex[g] >= 0) ++offsets[changedIndex[g] + 1];
  }
  for (std::size_t i = 0; i < changed.size(); ++i) offsets[i + 1] += offsets[i];
  others.resize(offsets.back());
  {
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (const auto& [f, g] : pairs) {
      others[next[changedIndex[f]]++] = g;
      if (changedIndex[g] >= 0) others[next[changedIndex[g]]++] = f;
    }
  }
  // Changed faces around each vertex.
  std::vector<std::uint32_t> aroundOffsets(P.size() + 1, 0), around;
  for (std::uint32_t f : changed)
    for (int v : T[f]) ++aroundOffsets[v + 1];
  for (std::size_t v = 0; v < P.size(); ++v) aroundOffsets[v + 1] += aroundOffsets[v];
  around.resize(aroundOffsets.back());
  {
    std::vector<std::uint32_t> next(aroundOffsets.begin(), aroundOffsets.end() - 1);
    for (std::uint32_t f : changed)
      for (int v : T[f]) around[next[v]++] = f;
  }

  auto crosses = [&](std::uint32_t f, std::uint32_t g) { return facesIntersect(P, T, f, g); };
  // A changed face whose corners rounding made collinear (a face that was
  // not) is worse than a crossing: it has no normal, a checker takes it for
  // a hole in the surface, and a crossing elsewhere is still split again
  // (splitRoundedAgain). It counts as two.
  auto collapsed = [&](std::uint32_t f) {
    return collinear(P[T[f][0]], P[T[f][1]], P[T[f][2]]) &&
           !collinear(exact[T[f][0]], exact[T[f][1]], exact[T[f][2]]);
  };
  // How many crossings (and collapsed faces) the changed faces around v
  // take part in, counted up to `enough` (a position is only worth knowing
  // while it beats the best).
  auto localCrossings = [&](int v, std::size_t enough) {
    std::size_t n = 0;
    for (std::uint32_t k = aroundOffsets[v]; k < aroundOffsets[v + 1]; ++k) {
      const std::uint32_t f = around[k];
      if ((n += 2 * collapsed(f)) >= enough) return n;
      const int i = changedIndex[f];
      for (std::uint32_t j = offsets[i]; j < offsets[i + 1]; ++j)
        if ((n += crosses(f, others[j])) >= enough) return n;
    }
    return n;
  };

  std::size_t remaining = 0;
  std::vector<std::array<std::uint32_t, 2>> crossing = intersectingOf(P, T, pairs);
  std::vector<char> moved(P.size(), 0);  // re-rounded in the last pass
  // Each coordinate goes to one of the `reach` floats below its exact value
  // or the `reach` above. One each way first (the two nearest); where faces
  // meet at a very small angle, neither may keep them apart, and the next
  // float out may.
  int reach = 1, passesAtReach = 0;
  std::size_t before = std::numeric_limits<std::size_t>::max();  // defects before the last pass
  for (int pass = 0;; ++pass) {
    if (pass > 0) {
      // Only pairs with a face at a vertex that moved can have changed: the
      // others keep what the last check found.
      auto touches = [&](std::uint32_t f) {
        return moved[T[f][0]] | moved[T[f][1]] | moved[T[f][2]];
      };
      std::vector<std::array<std::uint32_t, 2>> recheck, still;
      for (const auto& p : pairs)
        if (touches(p[0]) || touches(p[1])) recheck.push_back(p);
      for (const auto& p : crossing)
        if (!touches(p[0]) && !touches(p[1])) still.push_back(p);
      crossing = intersectingOf(P, T, recheck);
      crossing.insert(crossing.end(), still.begin(), still.end());
      std::fill(moved.begin(), moved.end(), 0);
    }
    remaining = crossing.size();
    std::vector<std::uint32_t> flat;
    for (std::uint32_t f : changed)
      if (collapsed(f)) flat.push_back(f);
    const std::size_t defects = remaining + flat.size();
    if (defects == 0) break;
    if (passesAtReach == passes || defects >= before) {  // this reach has done what it can
      if (reach == kFarthestRounding) break;
      ++reach;
      passesAtReach = 0;
    }
    before = defects;
    ++passesAtReach;
    std::set<int> candidates;
    auto addCorners = [&](std::uint32_t f) {
      for (int v : T[f])
        if (vo[v].vertex < 0) candidates.insert(v);  // new vertices only: inputs stay as they are
    };
    for (const auto& p : crossing)
      for (std::uint32_t f : p) addCorners(f);
    for (std::uint32_t f : flat) addCorners(f);
    for (int v : candidates) {
      const Point3 e = exact[v], start = P[v];
      // Per coordinate, the floats nearest first: below, above, then the
      // next ones out.
      std::array<std::array<float, 2 * kFarthestRounding>, 3> options;
      for (int k = 0; k < 3; ++k) {
        float lo = below(e[k]), hi = above(e[k]);
        for (int j = 0; j < reach; ++j) {
          options[k][2 * j] = lo;
          options[k][2 * j + 1] = hi;
          lo = std::nextafter(lo, -INFINITY);
          hi = std::nextafter(hi, INFINITY);
        }
      }
      Point3 best = start;
      std::size_t bestCount = localCrossings(v, std::numeric_limits<std::size_t>::max());
      const int n = 2 * reach;
      for (int choice = 0; choice < n * n * n && bestCount > 0; ++choice) {
        P[v] = Point3(options[0][choice % n], options[1][choice / n % n],
                      options[2][choice / (n * n)]);
        if (P[v] == start) continue;
        const std::size_t count = localCrossings(v, bestCount);
        if (count < bestCount) best = P[v], bestCount = count;
      }
      moved[v] = best != start;
      P[v] = best;
    }
  }
  // Write the float positions back, to the merged output and to each mesh.
  for (std::size_t v = 0; v < P.size(); ++v) merged.vert[v].P() = P[v];
  for (std::size_t m = 0; m < r.meshes.size(); ++m)
    for (std::size_t v = 0; v < r.merged_vertex[m].size(); ++v)
      r.meshes[m].vert[v].P() = P[r.merged_vertex[m][v]];
  return remaining;
}

namespace {

// The curve edge a-b of a merged output split again, in the new output:
// the edge itself, or the path the split put on it (the shortest through
// vertices that split made and that lie on the segment, within a float step
// or so: they were rounded).
void carryCurveEdge(int a, int b, const Mesh& mesh,
                    const std::unordered_map<int, std::vector<int>>& changed,
                    const std::vector<char>& isNew, std::vector<std::array<int, 2>>& curves) {
  const auto around = changed.find(a);
  if (around == changed.end() || changed.find(b) == changed.end() ||
      std::find(around->second.begin(), around->second.end(), b) != around->second.end()) {
    curves.push_back({std::min(a, b), std::max(a, b)});  // untouched, or still an edge
    return;
  }
  const Point3 &pa = mesh.vert[a].cP(), &pb = mesh.vert[b].cP(), ab = pb - pa;
  auto onSegment = [&](int v) {
    const Point3 av = mesh.vert[v].cP() - pa;
    const double t = (av * ab) / ab.SquaredNorm();
    return t > 0 && t < 1 &&
           (av - ab * t).Norm() <= 1e-5 * ab.Norm() + 4 * floatStep(mesh.vert[v].cP());
  };
  std::unordered_map<int, int> from{{a, -1}};
  std::vector<int> layer{a};
  for (int depth = 0; depth < 8 && !layer.empty() && !from.count(b); ++depth) {
    std::vector<int> next;
    for (int v : layer) {
      const auto n = changed.find(v);
      if (n == changed.end()) continue;
      for (int w : n->second)
        if ((w == b || (isNew[w] && onSegment(w))) && from.emplace(w, v).second) next.push_back(w);
    }
    layer = std::move(next);
  }
  if (!from.count(b)) return;  // gone (points merged by snapping)
  for (int v = b; from.at(v) >= 0; v = from.at(v))
    curves.push_back({std::min(v, from.at(v)), std::max(v, from.at(v))});
}

}  // namespace

namespace {

// Each input's own output again from the merged output (after
// splitRoundedAgain changed it): its vertices in their order, each at its
// merged vertex (of two that became one, the first is used by the faces),
// then the new vertices its faces use; its faces as the merged output has them; its curve edges,
// those of the merged output along its faces.
void separateFromMerged(SplitResult& r) {
  Mesh& merged = r.merged;
  FaceOriginHandle mergedFace = faceOrigins(merged);
  VertexOriginHandle mergedVertex = vertexOrigins(merged);
  std::set<std::array<int, 2>> curves(r.merged_curve_edges.begin(), r.merged_curve_edges.end());
  for (std::size_t m = 0; m < r.meshes.size(); ++m) {
    VertexOriginHandle oldVertex = vertexOrigins(r.meshes[m]);
    const std::vector<int>& globalOf = r.merged_vertex[m];
    OutputArrays out;
    std::vector<int> newGlobalOf;
    std::unordered_map<int, int> localOf;                // merged vertex -> its vertex here
    for (std::size_t u = 0; u < globalOf.size(); ++u) {  // each in its place, also two that met
      const int g = globalOf[u];
      if (g >= 0) localOf.emplace(g, int(u));  // the first of them takes the faces
      out.positions.push_back(g >= 0 ? merged.vert[g].cP() : r.meshes[m].vert[u].cP());
      out.vertex_origin.push_back(oldVertex[u]);
      newGlobalOf.push_back(g);
    }
    std::set<std::array<int, 2>> meshCurves;
    for (std::size_t f = 0; f < merged.face.size(); ++f) {
      if (mergedFace[f].layer != int(m)) continue;
      Triangle global, local;
      for (int k = 0; k < 3; ++k) {
        global[k] = int(vcg::tri::Index(merged, merged.face[f].cV(k)));
        auto [it, added] = localOf.emplace(global[k], int(out.positions.size()));
        if (added) {
          out.positions.push_back(merged.vert[global[k]].cP());
          out.vertex_origin.push_back(mergedVertex[global[k]]);
          newGlobalOf.push_back(global[k]);
        }
        local[k] = it->second;
      }
      out.triangles.push_back(local);
      out.face_origin.push_back(mergedFace[f]);
      for (int k = 0; k < 3; ++k) {
        const int a = global[k], b = global[(k + 1) % 3];
        if (curves.count({std::min(a, b), std::max(a, b)}))
          meshCurves.insert(
              {std::min(local[k], local[(k + 1) % 3]), std::max(local[k], local[(k + 1) % 3])});
      }
    }
    out.toMesh(r.meshes[m]);
    r.merged_vertex[m] = std::move(newGlobalOf);
    r.curve_edges[m].assign(meshCurves.begin(), meshCurves.end());
  }
}

}  // namespace

std::size_t splitRoundedAgain(SplitResult& r, const std::vector<const Mesh*>& inputs,
                              const SplitOptions& options, int rounds) {
  requireMergedOutput(r, "splitting the rounded output again");
  const std::size_t splitBefore = r.pairs_split_after_rounding;
  std::size_t left = std::numeric_limits<std::size_t>::max();  // not counted yet
  std::size_t fewest = left;  // the fewest crossings a round has left (none yet)
  for (int round = 0; round < rounds && left > 0 && r.merged.fn > 0; ++round) {
    const auto start = std::chrono::steady_clock::now();
    Mesh& old = r.merged;
    SplitOptions again;
    again.between_meshes = false;
    again.self = true;
    again.separate_meshes = false;
    again.snap_float_steps = options.snap_float_steps;
    again.overlaps_once = options.overlaps_once;
    again.progress = options.progress;
    SplitResult next = splitAlongIntersections({&old}, again);
    if (next.intersecting_pairs == 0) {
      left = 0;
      break;
    }
    const std::size_t stillCrossing = roundToFloat(next);
    // Rounds may leave a few more crossings than the round before and still
    // end at none; where surfaces nearly coincide over a region they can
    // also run away, each round's new slivers crossing more (99, 12, 16,
    // 36, 169, 1,547, ... pairs): a round that leaves more than twice the
    // fewest so far is not taken, and the rounds end.
    if (round > 0 && stillCrossing > 2 * fewest) break;
    fewest = std::min(fewest, stillCrossing);
    // Provenance through the old output to the inputs.
    FaceOriginHandle oldFace = faceOrigins(old), newFace = faceOrigins(next.merged);
    VertexOriginHandle oldVertex = vertexOrigins(old), newVertex = vertexOrigins(next.merged);
    std::vector<char> isNew(next.merged.vert.size(), 0);
    for (std::size_t v = 0; v < next.merged.vert.size(); ++v) {
      const VertexOrigin o = newVertex[v];
      if (o.vertex >= 0) {
        newVertex[v] = oldVertex[o.vertex];
        continue;
      }
      isNew[v] = 1;
      const FaceOrigin birth = oldFace[o.face];
      VertexOrigin carried{birth.layer, -1, birth.face, Point3(1, 0, 0)};
      if (birth.layer >= 0 && std::size_t(birth.layer) < inputs.size() && birth.face >= 0 &&
          std::size_t(birth.face) < inputs[birth.layer]->face.size()) {
        const Face& f = inputs[birth.layer]->face[birth.face];
        carried.barycentric = barycentric(next.merged.vert[v].cP(), f.cP(0), f.cP(1), f.cP(2));
      }
      newVertex[v] = carried;
    }
    std::vector<char> newFaces(next.merged.face.size()), snapped;
    const bool anySnapped = !r.merged_snapped_face.empty() || !next.merged_snapped_face.empty();
    if (anySnapped) snapped.resize(next.merged.face.size());
    for (std::size_t f = 0; f < next.merged.face.size(); ++f) {
      const int before = newFace[f].face;
      newFaces[f] = next.merged_new_face[f] || r.merged_new_face[before];
      if (anySnapped)
        snapped[f] = (!r.merged_snapped_face.empty() && r.merged_snapped_face[before]) ||
                     (!next.merged_snapped_face.empty() && next.merged_snapped_face[f]);
      newFace[f] = oldFace[before];
    }
    // The curves: the old ones where they went, and the new ones.
    const std::vector<int>& moved = next.merged_vertex[0];  // old vertex -> new
    // Around each vertex of a new face, its neighbours (over every face).
    std::unordered_map<int, std::vector<int>> changed;
    auto corner = [&](const Face& face, int i) {
      return int(vcg::tri::Index(next.merged, face.cV(i)));
    };
    for (std::size_t f = 0; f < next.merged.face.size(); ++f)
      if (next.merged_new_face[f])
        for (int i = 0; i < 3; ++i) changed[corner(next.merged.face[f], i)];
    for (const Face& face : next.merged.face)
      for (int i = 0; i < 3; ++i) {
        const int a = corner(face, i), b = corner(face, (i + 1) % 3);
        if (const auto n = changed.find(a); n != changed.end()) n->second.push_back(b);
        if (const auto n = changed.find(b); n != changed.end()) n->second.push_back(a);
      }
    std::vector<std::array<int, 2>> curves = next.merged_curve_edges;
    for (const auto& e : r.merged_curve_edges)
      carryCurveEdge(moved[e[0]], moved[e[1]], next.merged, changed, isNew, curves);
    // Only edges of the mesh (a face that collapsed takes its edges along).
    curves.erase(std::remove_if(curves.begin(), curves.end(),
                                [&](const std::array<int, 2>& e) {
                                  const auto a = changed.find(e[0]);
                                  return a != changed.end() &&
                                         std::find(a->second.begin(), a->second.end(), e[1]) ==
                                             a->second.end();
                                }),
                 curves.end());
    sortUnique(curves, next.merged.vert.size());
    for (std::vector<int>& global : r.merged_vertex)
      for (int& g : global) g = moved[g];
    r.merged_curve_edges = std::move(curves);
    r.merged_new_face = std::move(newFaces);
    r.merged_snapped_face = std::move(snapped);
    r.faces_added += next.merged.face.size() - old.face.size();
    r.new_vertices += next.new_vertices;
    r.vertices_snapped += next.vertices_snapped;
    r.edges_snapped += next.edges_snapped;
    r.new_faces_below_1deg += next.new_faces_below_1deg;
    r.smallest_new_angle_deg = std::min(r.smallest_new_angle_deg, next.smallest_new_angle_deg);
    r.pairs_split_after_rounding += next.intersecting_pairs;
    r.collapsed_faces_removed += next.collapsed_faces_removed;
    r.merged = next.merged;
    r.curve_edges_welded = r.merged_curve_edges.size();
    countCurves(r.merged.vert.size(), r.merged_curve_edges, r.curve_loops, r.open_curves);
    r.time_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    left = stillCrossing;
  }
  // (Where planar overlaps were kept once, the merged output no longer
  // holds each input whole: the separate outputs stay as they were.)
  if (r.pairs_split_after_rounding > splitBefore && !r.meshes.empty() &&
      r.coincident_faces_removed == 0)
    separateFromMerged(r);
  return left == std::numeric_limits<std::size_t>::max() ? remainingIntersections(r, true) : left;
}

}  // namespace meshmend
