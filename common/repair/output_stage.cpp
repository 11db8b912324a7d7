#include "common/repair/output_stage.h"
#include "common/base/timing.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "common/exact/intersections.h"
#include "common/exact/predicates.h"
#include "common/repair/split/detail.h"

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
  std::vector<std::size_t> found(workerCount(), 0);
  parallelChunks(result.merged.face.size(),
                 [&](std::size_t begin, std::size_t end, unsigned worker) {
                   std::size_t n = 0;
                   for (std::size_t f = begin; f < end; ++f) {
                     if (!result.merged_new_face[f]) continue;
                     const Face& face = result.merged.face[f];
                     n += face.cV(0) == face.cV(1) || face.cV(1) == face.cV(2) ||
                          face.cV(2) == face.cV(0) || collinear(face.cP(0), face.cP(1), face.cP(2));
                   }
                   found[worker] = n;
                 });
  return std::accumulate(found.begin(), found.end(), std::size_t(0));
}

namespace {
void separateFromMerged(SplitResult& r);
}  // namespace

std::size_t mendCollinearNewFaces(SplitResult& r) {
  requireMergedOutput(r, "mending collinear faces");
  Mesh& m = r.merged;
  r.merged_points.clear();  // they no longer describe `merged`
  r.merged_triangles.clear();
  r.merged_face_origin.clear();
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

namespace {

// The stored values of `scalar` around x: the largest at most x and the
// smallest at least x (the same when x is stored exactly, always so for a
// double), and the neighbour of a stored value towards +-infinity.
double storedBelow(double x, Scalar scalar) {
  if (scalar == Scalar::kDouble) return x;
  const float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}
double storedAbove(double x, Scalar scalar) {
  if (scalar == Scalar::kDouble) return x;
  const float f = float(x);
  return double(f) < x ? std::nextafter(f, INFINITY) : f;
}
double storedNext(double v, double towards, Scalar scalar) {
  return scalar == Scalar::kDouble ? std::nextafter(v, towards)
                                   : double(std::nextafter(float(v), float(towards)));
}

// How many stored values away from its unrounded value roundForHost may put
// a coordinate of a new vertex (the nearest below or above is one away).
// The choices grow as its cube; what two values each way cannot keep apart
// is for snapping and splitStoredAgain.
constexpr int kFarthestRounding = 2;

constexpr std::size_t kNoLimit = std::numeric_limits<std::size_t>::max();

// The values a coordinate x may take at `reach`, nearest first: those
// below and above x (one each at reach 1, then the next out), and x itself
// when it is a stored value.
std::vector<double> roundingChoices(double x, int reach, Scalar scalar) {
  double lo = storedBelow(x, scalar), hi = storedAbove(x, scalar);
  std::vector<double> out;
  if (lo == hi) {
    out.push_back(x);
  } else {
    out.push_back(lo);
    out.push_back(hi);
    --reach;
  }
  for (int j = 0; j < reach; ++j) {
    lo = storedNext(lo, -INFINITY, scalar);
    hi = storedNext(hi, INFINITY, scalar);
    if (std::isfinite(lo)) out.push_back(lo);
    if (std::isfinite(hi)) out.push_back(hi);
  }
  return out;
}

// Step 1 on arrays: `P` (the unrounded positions: input vertices exactly,
// curve points within their error; the stored ones on return), `newFace`
// and `movable` (vertices that may be re-rounded: the new ones) given.
// Every face with a movable corner is a new face (the split's new vertices
// lie only on faces it made; storeNewPoints' callers mark them so).
// Rounds in place: the unrounded position is kept only for the vertices
// that may leave it (one array of every position less).
// Returns the crossing pairs left.
class Rounder {
 public:
  // `near` (optional) finds the unchanged faces near the changed ones.
  Rounder(std::vector<Point3>& P, const std::vector<Triangle>& T, const std::vector<char>& newFace,
          const std::vector<char>& movable, Scalar scalar, NearFaceFinder near = {})
      : T_(T),
        newFace_(newFace),
        movable_(movable),
        scalar_(scalar),
        near_(std::move(near)),
        P_(P) {
    double largest = 0;
    for (const Point3& p : P)
      largest = std::max({largest, std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
    floor_ = std::ldexp(largest, -int(kMaxCoordinateBinades));
    resizeInHugePages(moved_, P.size());
    std::vector<std::vector<std::pair<int, Point3>>> kept(workerCount());
    std::vector<std::size_t> movedCount(workerCount(), 0);
    parallelChunks(P_.size(), [&](std::size_t begin, std::size_t end, unsigned worker) {
      for (std::size_t v = begin; v < end; ++v) {
        const bool isMovable = v < movable_.size() && movable_[v];
        moved_[v] = 0;
        if (scalar == Scalar::kDouble && !isMovable) continue;  // stored as it is
        const Point3 r = P_[v];
        Point3 p = storedAs(r, scalar);
        if (isMovable) p = Point3(withinSpan(p[0]), withinSpan(p[1]), withinSpan(p[2]));
        moved_[v] = char((p[0] != r[0]) | (p[1] != r[1]) | (p[2] != r[2]));
        if (!moved_[v] && !isMovable) continue;  // (most: stored as they are, nothing to write)
        movedCount[worker] += std::size_t(!isMovable);
        kept[worker].emplace_back(int(v), r);
        P_[v] = p;
      }
    });
    fixedMoved_ = std::accumulate(movedCount.begin(), movedCount.end(), std::size_t(0)) > 0;
    reference_ = joined(kept);
    std::sort(reference_.begin(), reference_.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
  }

  // Whether vertex v may be stored off its reference position: only those
  // need writing back.
  bool moved(std::size_t v) const { return moved_[v]; }
  // New faces whose corners, as stored, are collinear (degenerateNewFaces).
  std::size_t degenerateNewFaces() const {
    std::size_t n = 0;
    for (std::uint32_t f : changed_) n += degenerate_[f] && f < newFace_.size() && newFace_[f];
    return n;
  }

  // Re-rounds while defects are left, at most `passes` passes per reach and
  // `budget` exact pair tests in all (bounded: the budget stopped it).
  // Gives up at once, leaving the nearest rounding, where that has more
  // than `giveUpAbove` defects.
  std::size_t run(int passes, std::size_t budget, std::size_t giveUpAbove, const Progress& progress,
                  std::size_t& rerounded, bool& bounded) {
    markChanged();
    findCandidates();
    if (changed_.empty()) return 0;
    crossing_ = intersectingOf(P_, T_, *search_, degenerate_, false);
    budget_ = budget;
    if (crossing_.size() > giveUpAbove) return crossing_.size();
    if (crossing_.empty() && collapsedFaces().empty()) return 0;
    rows_.assign(changed_.size(), {});  // only re-rounding needs these
    hasRow_.assign(changed_.size(), 0);
    std::vector<char> moved(P_.size(), 0);  // re-rounded in the last pass
    // Each coordinate goes to one of the `reach` values below its unrounded
    // value or the `reach` above. One each way first (the two nearest);
    // where faces meet at a very small angle, neither may keep them apart,
    // and the next value out may.
    int reach = 1, passesAtReach = 0;
    std::size_t before = std::numeric_limits<std::size_t>::max();  // defects before the last pass
    for (int pass = 0;; ++pass) {
      if (pass > 0) recheck(moved);
      const std::vector<std::uint32_t> flat = collapsedFaces();
      const std::size_t defects = crossing_.size() + flat.size();
      if (defects == 0 || tests_ >= budget_) break;
      if (passesAtReach == passes || defects >= before) {  // this reach has done what it can
        if (reach == kFarthestRounding) break;
        ++reach;
        passesAtReach = 0;
      }
      before = defects;
      ++passesAtReach;
      reportProgress(progress, 96, "Rounding again where faces cross");
      std::set<int> candidates;
      auto addCorners = [&](std::uint32_t f) {
        for (int v : T_[f])
          if (movable_[v]) candidates.insert(v);
      };
      for (const auto& p : crossing_)
        for (std::uint32_t f : p) addCorners(f);
      for (std::uint32_t f : flat) addCorners(f);
      gatherAround(candidates);
      addRows(candidates);
      for (int v : candidates) {
        if (tests_ >= budget_) break;  // the bound holds within a pass too
        moved[v] = reround(v, reach);
      }
    }
    bounded = tests_ >= budget_ && !crossing_.empty();
    rerounded = 0;
    for (const auto& [v, nearest] : nearest_) rerounded += P_[v] != nearest;
    return crossing_.size();
  }

 private:
  // Marks the faces that are new or that rounding moved: only those can
  // cross anything they did not cross before (every other face is an input
  // face, exactly as it was).
  void markChanged() {
    if (!fixedMoved_) {  // the new faces hold every movable vertex
      isChanged_.assign(T_.size(), 0);
      std::copy_n(newFace_.begin(), std::min(newFace_.size(), T_.size()), isChanged_.begin());
      return;
    }
    isChanged_.resize(T_.size());
    parallelChunks(T_.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t f = begin; f < end; ++f) {
        const Triangle& t = T_[f];
        isChanged_[f] =
            (f < newFace_.size() && newFace_[f]) | moved_[t[0]] | moved_[t[1]] | moved_[t[2]];
      }
    });
  }

  // Candidates: boxes widened by more steps than re-rounding moves a vertex
  // (at most kFarthestRounding from its unrounded position; the boxes are
  // float, so a float step covers double steps too).
  void findCandidates() {
    search_ = std::make_unique<ChangedFaceSearch>(P_, T_, isChanged_, kFarthestRounding + 2, near_);
    changed_.assign(search_->faces().begin(),
                    search_->faces().begin() + std::ptrdiff_t(search_->changedCount()));
    // Whether each face that may be in a pair is degenerate as stored,
    // tested once.
    degenerate_.assign(T_.size(), 0);
    const std::vector<std::uint32_t>& faces = search_->faces();
    parallelChunks(faces.size(), [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t i = begin; i < end; ++i) degenerate_[faces[i]] = isFlat(faces[i]);
    });
  }

  // The changed faces around each of `vertices` that has none yet, as
  // positions in changed_: one pass over the changed faces per pass of
  // re-rounding, which asks for a few vertices (rows for every vertex of a
  // large mesh cost about as much as the re-rounding they served).
  void gatherAround(const std::set<int>& vertices) {
    if (wanted_.empty()) wanted_.assign(P_.size(), 0);
    bool any = false;
    for (int v : vertices)
      if (around_.emplace(v, std::vector<std::uint32_t>()).second) {
        wanted_[std::size_t(v)] = 1;
        any = true;
      }
    if (!any) return;
    for (std::size_t i = 0; i < changed_.size(); ++i)
      for (int v : T_[changed_[i]])
        if (wanted_[std::size_t(v)]) around_[v].push_back(std::uint32_t(i));
    for (int v : vertices) wanted_[std::size_t(v)] = 0;
  }
  const std::vector<std::uint32_t>& around(int v) const { return around_.at(v); }

  // The candidates of each changed face around `vertices` that has none
  // yet (re-rounding touches a few vertices: all faces' rows at once cost
  // more than the rest of it). Faces with the same three vertices (a planar
  // overlap kept in each part) coincide however their vertices are
  // rounded: never a crossing, never a candidate.
  void addRows(const std::set<int>& vertices) {
    std::vector<std::uint32_t> faces, at;  // faces without rows, and their positions
    for (int v : vertices)
      for (std::uint32_t i : around(v))
        if (!hasRow_[i]) {
          hasRow_[i] = 1;
          faces.push_back(changed_[i]);
          at.push_back(i);
        }
    if (faces.empty()) return;
    std::vector<std::vector<std::uint32_t>> found = search_->candidatesOf(faces);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      std::vector<std::uint32_t>& row = found[i];
      row.erase(std::remove_if(row.begin(), row.end(),
                               [&](std::uint32_t g) { return sameVertices(T_[faces[i]], T_[g]); }),
                row.end());
      rows_[at[i]] = std::move(row);
    }
  }

  bool isFlat(std::uint32_t f) const {
    const Triangle& t = T_[f];
    return collinear(P_[t[0]], P_[t[1]], P_[t[2]]);
  }

  // Only pairs with a face at a vertex that moved can have changed: the
  // others keep what the last check found.
  void recheck(std::vector<char>& moved) {
    auto touches = [&](std::uint32_t f) {
      return moved[T_[f][0]] | moved[T_[f][1]] | moved[T_[f][2]];
    };
    // Pairs with a moved corner: a changed face's around a vertex the last
    // pass moved (their rows are there: it asked for them), each once.
    std::vector<std::array<std::uint32_t, 2>> again, still;
    for (std::size_t i = 0; i < changed_.size(); ++i) {
      const std::uint32_t f = changed_[i];
      if (touches(f))
        for (std::uint32_t g : rows_[i])
          again.push_back(isChanged_[g]
                              ? std::array<std::uint32_t, 2>{std::min(f, g), std::max(f, g)}
                              : std::array<std::uint32_t, 2>{f, g});
    }
    std::sort(again.begin(), again.end());
    again.erase(std::unique(again.begin(), again.end()), again.end());
    for (const auto& p : crossing_)
      if (!touches(p[0]) && !touches(p[1])) still.push_back(p);
    for (const auto& [v, faces] : around_)  // every vertex a pass moved was asked for
      if (moved[std::size_t(v)])
        for (std::uint32_t i : faces) degenerate_[changed_[i]] = isFlat(changed_[i]);
    crossing_ = intersectingOf(P_, T_, again, degenerate_, false);
    crossing_.insert(crossing_.end(), still.begin(), still.end());
    std::fill(moved.begin(), moved.end(), 0);
  }

  // A changed face whose corners rounding made collinear is worse than a
  // crossing: it has no normal, a checker takes it for a hole in the
  // surface, and a crossing elsewhere is still split again. New faces are
  // never collinear exactly; an input face only when it was already.
  bool collapsed(std::uint32_t f) const {
    const Triangle& t = T_[f];
    return isFlat(f) &&
           ((f < newFace_.size() && newFace_[f]) || !collinear(ref(t[0]), ref(t[1]), ref(t[2])));
  }
  // The same from the degeneracy kept per face (degenerate_).
  std::vector<std::uint32_t> collapsedFaces() const {
    std::vector<std::uint32_t> flat;
    for (std::uint32_t f : changed_) {
      const Triangle& t = T_[f];
      if (degenerate_[f] &&
          ((f < newFace_.size() && newFace_[f]) || !collinear(ref(t[0]), ref(t[1]), ref(t[2]))))
        flat.push_back(f);
    }
    return flat;
  }

  // How many crossings (and collapsed faces, as two each) the changed faces
  // around v take part in, counted up to `enough` (a position is only worth
  // knowing while it beats the best).
  std::size_t localCrossings(int v, std::size_t enough) {
    std::size_t n = 0;
    for (std::uint32_t i : around(v)) {
      const std::uint32_t f = changed_[i];
      if ((n += 2 * collapsed(f)) >= enough) return n;
      for (std::uint32_t g : rows_[i]) {
        ++tests_;
        if ((n += facesIntersect(P_, T_, f, g)) >= enough) return n;
      }
    }
    return n;
  }

  // Moves new vertex v to the rounding choice under which the faces around
  // it take part in the fewest crossings, trying the choices nearest its
  // unrounded position first; true when it moved.
  bool reround(int v, int reach) {
    const Point3 start = P_[v];
    nearest_.emplace(v, start);  // the first time: the nearest rounding
    moved_[std::size_t(v)] = 1;
    std::array<std::vector<double>, 3> choices;
    for (int k = 0; k < 3; ++k) {
      choices[k] = roundingChoices(ref(v)[k], reach, scalar_);
      for (double& c : choices[k]) c = withinSpan(c);
    }
    std::vector<std::array<std::uint8_t, 3>> order;
    for (std::size_t i = 0; i < choices[0].size(); ++i)
      for (std::size_t j = 0; j < choices[1].size(); ++j)
        for (std::size_t k = 0; k < choices[2].size(); ++k)
          order.push_back({std::uint8_t(i), std::uint8_t(j), std::uint8_t(k)});
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
      return a[0] + a[1] + a[2] < b[0] + b[1] + b[2];
    });
    Point3 best = start;
    std::size_t bestCount = localCrossings(v, std::numeric_limits<std::size_t>::max());
    for (const auto& [i, j, k] : order) {
      if (bestCount == 0 || tests_ >= budget_) break;
      P_[v] = Point3(choices[0][i], choices[1][j], choices[2][k]);
      if (P_[v] == start) continue;
      const std::size_t count = localCrossings(v, bestCount);
      if (count < bestCount) best = P_[v], bestCount = count;
    }
    P_[v] = best;
    return best != start;
  }

  // A new vertex's coordinate below floor_ (the largest magnitude over
  // 2^kMaxCoordinateBinades) is stored as zero: a curve point a hair from a
  // coordinate plane can round to 1e-320 beside inputs at 1, and the stored
  // mesh must stay within the span that exact operations take (mesh.h).
  double withinSpan(double x) const { return std::fabs(x) < floor_ ? 0.0 : x; }

  // Vertex v's unrounded position: kept where rounding or re-rounding may
  // have moved it, else where it is stored.
  Point3 ref(int v) const {
    const auto at = std::lower_bound(reference_.begin(), reference_.end(), v,
                                     [](const auto& kept, int u) { return kept.first < u; });
    return at != reference_.end() && at->first == v ? at->second : P_[std::size_t(v)];
  }

  const std::vector<Triangle>& T_;
  const std::vector<char>& newFace_;
  const std::vector<char>& movable_;
  const Scalar scalar_;
  const NearFaceFinder near_;
  std::vector<Point3>& P_;
  std::vector<std::pair<int, Point3>> reference_;  // ascending: see ref()
  std::vector<char> moved_;  // rounded off the reference position, or re-rounded
  bool fixedMoved_ = false;  // a vertex that is not movable moved (rounded to a float host)
  std::vector<char> isChanged_, degenerate_;
  std::vector<std::vector<std::uint32_t>> rows_;  // per changed face: its candidates (addRows)
  std::vector<char> hasRow_;
  std::vector<std::uint32_t> changed_;         // the changed faces, ascending (findCandidates)
  std::unique_ptr<ChangedFaceSearch> search_;  // candidate pairs (findCandidates)
  std::vector<std::array<std::uint32_t, 2>> crossing_;
  std::unordered_map<int, Point3> nearest_;  // re-rounded vertices' nearest rounding
  // Per vertex asked for: the changed faces around it, as positions in
  // changed_ (gatherAround); wanted_ marks those a pass gathers.
  std::unordered_map<int, std::vector<std::uint32_t>> around_;
  std::vector<char> wanted_;
  std::size_t tests_ = 0, budget_ = 0;  // exact pair tests made, and the most allowed
  double floor_ = 0;

 public:
  std::size_t tests() const { return tests_; }
};

// The split's arrays of the merged output (`kept`, emptied) when they
// hold its `count` elements, else made from it.
template <class T, class Make>
std::vector<T> takeOr(std::vector<T>& kept, std::size_t count, Make make, const Mesh& merged) {
  std::vector<T> taken = std::move(kept);
  kept.clear();
  return taken.size() == count ? taken : make(merged);
}

// At most this many boxes of changed faces per query of markNear: on
// bunny + dragon the stage took 654 M instructions with 32, 677 M with a
// leaf each (8) and 657 M with 64.
constexpr std::uint32_t kNearFaceGroup = 32;

// Marks in `taken` the boxes of `tree` that overlap a box of `changed`.
// The tree is asked once per group of changed boxes that lie together
// (their hull: they overlap the same faces many times over), and a box it
// holds is taken at its first overlap with a box of the group.
void markNear(const BoxTree& tree, const BoxTree& changed, std::atomic<std::uint8_t>* taken) {
  std::vector<BoxTree::Leaf> leaves;
  std::vector<BoxTree::Group> groups;
  changed.groups(kNearFaceGroup, leaves, groups);
  auto overlapsGroup = [&](const Box& b, const BoxTree::Group& group) {
    for (std::uint32_t l = group.firstLeaf; l < group.firstLeaf + group.leafCount; ++l) {
      const BoxTree::Leaf& leaf = leaves[l];
      if (!overlap(b, leaf.box)) continue;
      for (std::uint32_t i = 0; i < leaf.count; ++i)
        if (overlap(b, changed.box(leaf.first[i]))) return true;
    }
    return false;
  };
  parallelChunks(
      groups.size(),
      [&](std::size_t begin, std::size_t end, unsigned worker) {
        for (std::size_t g = begin; g < end; ++g)
          tree.query(groups[g].box, worker, [&](std::uint32_t j, unsigned) {
            if (!taken[j].load(std::memory_order_relaxed) && overlapsGroup(tree.box(j), groups[g]))
              taken[j].store(1, std::memory_order_relaxed);
          });
      },
      16);
}

// Per input mesh, per face of the input: the face of the merged output it
// stayed as (a face left as it was is there once; those cut from it are
// new), or -1.
std::vector<std::vector<std::int32_t>> mergedFaceOfInputFace(
    const std::vector<FaceOrigin>& origin, const std::vector<char>& newFace,
    const std::vector<std::vector<int>>& inputFace) {
  std::vector<std::vector<std::int32_t>> out(inputFace.size());
  for (std::size_t m = 0; m < inputFace.size(); ++m) {
    const std::vector<int>& in = inputFace[m];
    out[m].assign(in.empty() ? 0 : std::size_t(*std::max_element(in.begin(), in.end())) + 1, -1);
  }
  for (std::size_t f = 0; f < origin.size(); ++f) {
    const FaceOrigin& o = origin[f];
    if (newFace[f] || o.layer < 0 || std::size_t(o.layer) >= out.size()) continue;
    std::vector<std::int32_t>& of = out[std::size_t(o.layer)];
    if (o.face >= 0 && std::size_t(o.face) < of.size()) of[std::size_t(o.face)] = std::int32_t(f);
  }
  return out;
}

}  // namespace

NearFaceFinder keptFacesNear(SplitResult& r, std::size_t faces) {
  std::vector<std::shared_ptr<const BoxTree>> trees = std::move(r.input_face_trees);
  auto inputFace = std::make_shared<std::vector<std::vector<int>>>(std::move(r.input_face_of_box));
  const std::vector<FaceOrigin> origin = std::move(r.merged_face_origin);
  r.input_face_trees.clear();
  r.input_face_of_box.clear();
  r.merged_face_origin.clear();
  if (trees.empty() || trees.size() != inputFace->size() || origin.size() != faces ||
      r.merged_new_face.size() != faces)
    return {};
  auto mergedFace = std::make_shared<std::vector<std::vector<std::int32_t>>>(
      mergedFaceOfInputFace(origin, r.merged_new_face, *inputFace));
  return [trees, inputFace, mergedFace](const BoxTree& boxes, const std::vector<char>& changed) {
    std::vector<std::uint32_t> near;
    for (std::size_t m = 0; m < trees.size(); ++m) {
      std::unique_ptr<std::atomic<std::uint8_t>[]> taken(
          new std::atomic<std::uint8_t>[trees[m]->size()]());
      markNear(*trees[m], boxes, taken.get());
      for (std::size_t j = 0; j < trees[m]->size(); ++j) {
        if (!taken[j].load(std::memory_order_relaxed)) continue;
        const std::int32_t f = (*mergedFace)[m][std::size_t((*inputFace)[m][j])];
        if (f >= 0 && !changed[std::size_t(f)]) near.push_back(std::uint32_t(f));
      }
    }
    // Ascending already where the merged output keeps the inputs' order.
    if (!std::is_sorted(near.begin(), near.end())) std::sort(near.begin(), near.end());
    return near;
  };
}

std::size_t roundForHost(SplitResult& r, const OutputStageOptions& stage, StoredOutput* out,
                         std::size_t giveUpAbove) {
  requireMergedOutput(r, "rounding for the host");
  Mesh& merged = r.merged;
  if (merged.fn == 0) return 0;
  std::vector<Point3> P = takeOr(r.merged_points, merged.vert.size(), positionsOf, merged);
  const std::vector<Triangle> T =
      takeOr(r.merged_triangles, merged.face.size(), trianglesOf, merged);
  VertexOriginHandle vo = vertexOrigins(merged);
  std::vector<char> movable(P.size(), 0);  // new vertices: inputs stay as they are
  parallelChunks(P.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t v = begin; v < end; ++v) movable[v] = vo[v].vertex < 0;
  });
  std::size_t moved = 0;
  bool bounded = false;
  const std::size_t used = out ? out->rounding_tests : 0;
  Rounder rounder(P, T, r.merged_new_face, movable, stage.scalar, keptFacesNear(r, T.size()));
  const std::size_t remaining = rounder.run(
      stage.rounding_passes, stage.max_rounding_tests > used ? stage.max_rounding_tests - used : 0,
      giveUpAbove, stage.progress, moved, bounded);
  if (out) {
    out->vertices_rerounded += moved;
    out->bounded |= bounded;
    out->rounding_tests += rounder.tests();
    out->degenerate_new_faces = rounder.degenerateNewFaces();
  }
  // The stored positions, to the merged output (where they moved) and to
  // each mesh.
  parallelChunks(P.size(), [&](std::size_t begin, std::size_t end, unsigned) {
    for (std::size_t v = begin; v < end; ++v)
      if (rounder.moved(v)) merged.vert[v].P() = P[v];
  });
  for (std::size_t m = 0; m < r.meshes.size(); ++m)
    for (std::size_t v = 0; v < r.merged_vertex[m].size(); ++v)
      r.meshes[m].vert[v].P() = P[r.merged_vertex[m][v]];
  return remaining;
}

StoredOutput storeNewPoints(std::vector<Point3>& points, const std::vector<Triangle>& triangles,
                            const std::vector<char>& movable, const std::vector<char>& changed,
                            const OutputStageOptions& stage) {
  const auto start = Clock::now();
  StoredOutput out;
  out.scalar = stage.scalar;
  Rounder rounder(points, triangles, changed, movable, stage.scalar);
  out.crossing = rounder.run(stage.rounding_passes, stage.max_rounding_tests, kNoLimit,
                             stage.progress, out.vertices_rerounded, out.bounded);
  out.rounding_tests = rounder.tests();
  for (std::size_t f = 0; f < triangles.size() && f < changed.size(); ++f) {
    const Triangle& t = triangles[f];
    out.degenerate_new_faces += changed[f] && collinear(points[t[0]], points[t[1]], points[t[2]]);
  }
  out.time_ms = msSince(start);
  return out;
}

std::size_t crossingsLeft(const SplitResult& result, Scalar scalar) {
  requireMergedOutput(result, "counting the crossings left");
  return result.merged.fn == 0 ? 0 : selfIntersectingPairs(result.merged, scalar, false);
}

std::size_t storedIntersectingPairs(const Mesh& mesh, Scalar scalar) {
  return mesh.fn == 0 ? 0 : selfIntersectingPairs(mesh, scalar, true);
}

namespace {

// Pairs of non-degenerate faces of `mesh` with the same three vertices.
// Faces are bucketed by their smallest vertex (a counting sort: linear in
// the faces), and only faces in a group of equal ones are tested for
// degeneracy.
std::size_t sameVertexPairs(const Mesh& mesh) {
  const std::vector<Triangle> T = trianglesOf(mesh);
  std::vector<std::uint32_t> start(mesh.vert.size() + 1, 0);
  auto sorted = [&](std::size_t f) {
    Triangle t = T[f];
    std::sort(t.begin(), t.end());
    return t;
  };
  for (const Triangle& t : T) ++start[*std::min_element(t.begin(), t.end()) + 1];
  for (std::size_t v = 0; v < mesh.vert.size(); ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> byVertex(T.size());
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < T.size(); ++f)
      byVertex[next[*std::min_element(T[f].begin(), T[f].end())]++] = std::uint32_t(f);
  }
  std::size_t pairs = 0;
  std::vector<std::pair<Triangle, std::uint32_t>> bucket;
  for (std::size_t v = 0; v < mesh.vert.size(); ++v) {
    if (start[v + 1] - start[v] < 2) continue;
    bucket.clear();
    for (std::uint32_t k = start[v]; k < start[v + 1]; ++k)
      bucket.push_back({sorted(byVertex[k]), byVertex[k]});
    std::sort(bucket.begin(), bucket.end());
    for (std::size_t i = 0, j; i < bucket.size(); i = j) {
      std::size_t flat = 0;
      for (j = i + 1; j < bucket.size() && bucket[j].first == bucket[i].first;) ++j;
      if (j - i < 2) continue;
      for (std::size_t k = i; k < j; ++k) {
        const Face& f = mesh.face[bucket[k].second];
        flat += collinear(f.cP(0), f.cP(1), f.cP(2));
      }
      const std::size_t n = j - i - flat;
      pairs += n * (n - 1) / 2;
    }
  }
  return pairs;
}

}  // namespace

std::size_t storedIntersectingPairs(const SplitResult& r, const StoredOutput& stored,
                                    bool separate) {
  const bool complete = r.complete || stored.rounds_split_again > 0;
  if (!separate) {
    if (!complete || r.merged.fn == 0) return storedIntersectingPairs(r.merged, stored.scalar);
    return stored.crossing + sameVertexPairs(r.merged);
  }
  std::size_t n = 0;
  for (const Mesh& m : r.meshes)
    n += complete && stored.crossing == 0 ? sameVertexPairs(m)
                                          : storedIntersectingPairs(m, stored.scalar);
  return n;
}

std::size_t storedIntersectingPairs(MeshArrays mesh, Scalar scalar) {
  if (mesh.triangles.empty()) return 0;
  for (Point3& p : mesh.points) p = storedAs(p, scalar);
  FindIntersectionsOptions o;
  o.cross = false;
  o.same_vertices = true;
  return findIntersectionsInArrays({&mesh}, o).self_pairs[0];
}

namespace {

// The curve edge a-b of a merged output split again, in the new output:
// the edge itself, or the path the split put on it (the shortest through
// vertices that split made and that lie on the segment, within a step or so
// of `scalar`: they were rounded).
void carryCurveEdge(int a, int b, const Mesh& mesh, Scalar scalar,
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
           (av - ab * t).Norm() <= 1e-5 * ab.Norm() + 4 * scalarStep(mesh.vert[v].cP(), scalar);
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

std::size_t splitStoredAgain(SplitResult& r, const std::vector<const Mesh*>& inputs,
                             const SplitOptions& split, const OutputStageOptions& stage,
                             StoredOutput& out) {
  requireMergedOutput(r, "splitting the stored output again");
  const std::size_t splitBefore = r.pairs_split_after_rounding;
  std::size_t left = out.crossing;  // as the rounding before left them
  std::size_t fewest = left;        // the fewest crossings a round has left
  for (int round = 0; round < stage.split_rounds && left > 0 && r.merged.fn > 0; ++round) {
    // The next round splits at least the pairs left: past the bound, the
    // stage stops here with them.
    if (out.pairs_split_again + left > stage.max_pairs_split_again) {
      out.bounded = true;
      break;
    }
    reportProgress(stage.progress, 97, "Splitting the stored result where it crosses");
    const auto start = Clock::now();
    Mesh& old = r.merged;
    SplitOptions again;
    again.between_meshes = false;
    again.self = true;
    again.separate_meshes = false;
    again.snap_host_steps = split.snap_host_steps;
    again.host = stage.scalar;
    again.overlaps_once = split.overlaps_once;
    again.progress = progressWithin(stage.progress, 97, 97);
    SplitResult next = splitAlongIntersections({&old}, again);
    if (next.intersecting_pairs == 0) {
      left = 0;
      break;
    }
    ++out.rounds_split_again;
    out.pairs_split_again += next.intersecting_pairs;
    // Rounds may leave a few more crossings than the round before and still
    // end at none; where surfaces nearly coincide over a region they can
    // also run away, each round's new slivers crossing more (99, 12, 16,
    // 36, 169, 1,547, ... pairs): a round that leaves more than twice the
    // fewest so far is not taken, and the rounds end. Re-rounding removes
    // some three crossings in four: a round that rounded to nearest leaves
    // more than eight times the fewest is not re-rounded either.
    const std::size_t stillCrossing =
        roundForHost(next, stage, &out, round > 0 ? 8 * fewest : kNoLimit);
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
      carryCurveEdge(moved[e[0]], moved[e[1]], next.merged, stage.scalar, changed, isNew, curves);
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
    r.time_ms += msSince(start);
    left = stillCrossing;
  }
  // (Where planar overlaps were kept once, the merged output no longer
  // holds each input whole: the separate outputs stay as they were.)
  if (r.pairs_split_after_rounding > splitBefore && !r.meshes.empty() &&
      r.coincident_faces_removed == 0)
    separateFromMerged(r);
  return left;
}

namespace {

// Defects of a stored result: crossings (as counted) and collapsed new faces.
std::size_t defectsOf(const SplitResult& r, std::size_t crossing) {
  return crossing + degenerateNewFaces(r);
}

// Steps 3 and 4 on `r` as rounded (crossing: what the rounding left).
void splitAgainAndMend(SplitResult& r, const std::vector<const Mesh*>& inputs,
                       const SplitOptions& split, const OutputStageOptions& stage,
                       StoredOutput& out) {
  if (out.crossing > 0) out.crossing = splitStoredAgain(r, inputs, split, stage, out);
  if (degenerateNewFaces(r) > 0) {
    reportProgress(stage.progress, 98, "Mending flat faces");
    out.collinear_faces_mended += mendCollinearNewFaces(r);
  }
}

// The split of `inputs` with `split`, through steps 1, 3 and 4: a
// candidate for steps 2 and 5.
SplitResult splitAndStore(const std::vector<const Mesh*>& inputs, const SplitOptions& split,
                          const OutputStageOptions& stage, StoredOutput& out) {
  SplitResult again = splitAlongIntersections(inputs, split);
  out.crossing = roundForHost(again, stage, &out);
  splitAgainAndMend(again, inputs, split, stage, out);
  return again;
}

// Keeps `candidate` (and what the stage did to make it) in place of `r`
// when it leaves fewer defects.
bool keepIfBetter(SplitResult& r, StoredOutput& out, SplitResult& candidate,
                  const StoredOutput& made) {
  if (defectsOf(candidate, made.crossing) >= defectsOf(r, out.crossing)) {
    out.rounding_tests = made.rounding_tests;  // the work was done all the same
    out.bounded |= made.bounded;
    return false;
  }
  candidate.time_ms += r.time_ms;
  r = std::move(candidate);
  const StoredOutput before = out;
  out = made;
  out.snapped_for_host = true;
  out.quality_snapped_for_host = before.quality_snapped_for_host || made.quality_snapped_for_host;
  return true;
}

// Steps 2 to 5, for `r` as step 1 left it with defects.
void repairStored(SplitResult& r, const std::vector<const Mesh*>& inputs,
                  const SplitOptions& options, const OutputStageOptions& stage, StoredOutput& out) {
  SplitOptions used = options;
  used.host = stage.scalar;
  // Step 2: where curve points lie a few steps from each other or from an
  // edge, no rounding keeps every face apart (or whole): split again with
  // such points merged as quality snapping merges them.
  if (stage.resplit_with_snapping && options.snap_host_steps <= 0) {
    reportProgress(stage.progress, 96, "Splitting again, merging points a step apart");
    SplitOptions second = used;
    second.snap_host_steps = kHostSnapSteps;
    second.progress = progressWithin(stage.progress, 96, 96);
    StoredOutput made;
    made.scalar = stage.scalar;
    made.rounding_tests = out.rounding_tests;
    SplitResult candidate = splitAlongIntersections(inputs, second);
    made.crossing = roundForHost(candidate, stage, &made);
    if (keepIfBetter(r, out, candidate, made)) used = second;
  }
  // Steps 3 and 4: what is left crosses as stored; split again along those
  // crossings on the stored values, rounded again; flat faces mended.
  splitAgainAndMend(r, inputs, used, stage, out);
  // Step 5: where surfaces nearly coincide over a region (a part and a copy
  // a few steps away), curve points crowd within steps of each other
  // everywhere and neither of the above keeps the stored result apart:
  // quality snapping removes the slivers that hold them. Tried only when
  // none was asked for; kept if it leaves fewer defects.
  if (stage.resplit_with_snapping && options.snap_tolerance <= 0 &&
      defectsOf(r, out.crossing) > 0) {
    reportProgress(stage.progress, 98, "Splitting again with quality snapping");
    SplitOptions snapping = used;
    snapping.snap_tolerance = kQualitySnapTolerance;
    snapping.snap_host_steps = kHostSnapSteps;
    snapping.progress = progressWithin(stage.progress, 98, 98);
    StoredOutput made;
    made.scalar = stage.scalar;
    made.quality_snapped_for_host = true;
    made.rounding_tests = out.rounding_tests;
    SplitResult candidate = splitAndStore(inputs, snapping, stage, made);
    keepIfBetter(r, out, candidate, made);
  }
  out.degenerate_new_faces = degenerateNewFaces(r);
}

}  // namespace

StoredOutput storeForHost(SplitResult& r, const std::vector<const Mesh*>& inputs,
                          const SplitOptions& options, const OutputStageOptions& stage) {
  requireMergedOutput(r, "storing for the host");
  const auto start = Clock::now();
  StoredOutput out;
  out.scalar = stage.scalar;
  reportProgress(
      stage.progress, 95,
      stage.scalar == Scalar::kFloat ? "Rounding to float" : "Checking the double result");
  out.crossing = roundForHost(r, stage, &out);
  if (out.crossing + out.degenerate_new_faces > 0) repairStored(r, inputs, options, stage, out);
  out.time_ms = msSince(start);
  return out;
}

std::string StoredOutput::explanation() const {
  if (crossing == 0 && degenerate_new_faces == 0) return {};
  std::string why = std::to_string(crossing) + " pairs of faces cross and " +
                    std::to_string(degenerate_new_faces) + " new faces are flat once stored in " +
                    toString(scalar) + ": ";
  if (bounded)
    return why + "splitting the stored result again stopped at its work bound (" +
           std::to_string(pairs_split_again) + " pairs split in " +
           std::to_string(rounds_split_again) + " rounds)";
  return why + "curve points lie a few " + toString(scalar) +
         " steps apart where surfaces meet at a very small angle, and no rounding, snapping of "
         "points within " +
         std::to_string(kHostSnapSteps) + " steps or splitting again (" +
         std::to_string(rounds_split_again) + " rounds) kept them apart" +
         (scalar == Scalar::kFloat ? "; a double host (pymeshlab, MeshLab's double build, the "
                                     "Python module) has room for them"
                                   : "");
}

void addToReport(const StoredOutput& stored, JsonObject& report) {
  report.set("host_scalar", toString(stored.scalar))
      .set("crossings_left", stored.crossing)
      .set("degenerate_new_faces", stored.degenerate_new_faces)
      .set("vertices_rerounded", stored.vertices_rerounded)
      .set("snapped_for_host", stored.snapped_for_host)
      .set("quality_snapped_for_host", stored.quality_snapped_for_host)
      .set("collinear_faces_mended", stored.collinear_faces_mended)
      .set("rounds_split_again", std::size_t(stored.rounds_split_again))
      .set("output_stage_bounded", stored.bounded)
      .set("output_stage_ms", stored.time_ms);
}

}  // namespace meshmend
