#include "common/repair/patches/patches.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>
#include <unordered_map>

#include "common/base/errors.h"
#include "common/base/parallel.h"

namespace meshmend {

namespace {

int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

Point3 normalOf(const Point3& a, const Point3& b, const Point3& c) {
  return (b - a) ^ (c - a);
}

// Generalized winding number of one part's faces (Jacobson et al. 2013:
// the sum of their signed solid angles over 4π), evaluated through a
// hierarchy: a cluster far from the query point counts as its dipole
// (area-weighted normal at its area centroid), as in Barill et al. 2018.
class WindingTree {
 public:
  WindingTree(const std::vector<Point3>& points, const std::vector<Triangle>& triangles,
              std::vector<int> faces)
      : P_(points), T_(triangles), faces_(std::move(faces)) {
    if (!faces_.empty()) build(0, int(faces_.size()));
  }

  // At point p on face `onFace` (whose own solid angle there is 0), or -1.
  double at(const Point3& p, int onFace) const {
    if (nodes_.empty()) return 0;
    double omega = 0;
    visit(0, p, onFace, omega);
    return omega / (4 * M_PI);
  }

 private:
  struct Node {
    Point3 centre{0, 0, 0}, dipole{0, 0, 0};  // area centroid; Σ area × unit normal
    double radius = 0;                        // of a ball around centre holding all its faces
    int begin = 0, end = 0, left = -1, right = -1;
  };
  static constexpr int kLeafSize = 8;
  static constexpr double kFar =
      4;  // far: beyond kFar radii (dipole error ~ 1/kFar², a few thousandths)

  int build(int begin, int end) {
    const int index = int(nodes_.size());
    nodes_.emplace_back();
    Node node;
    node.begin = begin, node.end = end;
    double area = 0;
    Point3 lo(HUGE_VAL, HUGE_VAL, HUGE_VAL), hi = -lo, weighted(0, 0, 0);
    for (int i = begin; i < end; ++i) {
      const Triangle& t = T_[faces_[i]];
      const Point3 n = normalOf(P_[t[0]], P_[t[1]], P_[t[2]]) * 0.5;
      const double a = n.Norm();
      const Point3 c = (P_[t[0]] + P_[t[1]] + P_[t[2]]) / 3.0;
      node.dipole += n;
      weighted += c * a;
      area += a;
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], c[k]);
        hi[k] = std::max(hi[k], c[k]);
      }
    }
    node.centre = area > 0 ? weighted / area : (lo + hi) / 2.0;
    for (int i = begin; i < end; ++i)
      for (int v : T_[faces_[i]]) node.radius = std::max(node.radius, Distance(P_[v], node.centre));
    if (end - begin > kLeafSize) {
      int axis = 0;
      for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
      const int middle = (begin + end) / 2;
      auto centre = [&](int f) {
        const Triangle& t = T_[f];
        return P_[t[0]][axis] + P_[t[1]][axis] + P_[t[2]][axis];
      };
      std::nth_element(faces_.begin() + begin, faces_.begin() + middle, faces_.begin() + end,
                       [&](int x, int y) { return centre(x) < centre(y); });
      node.left = build(begin, middle);
      node.right = build(middle, end);
    }
    nodes_[index] = node;
    return index;
  }

  void visit(int n, const Point3& p, int onFace, double& omega) const {
    const Node& node = nodes_[n];
    const Point3 d = node.centre - p;
    const double distance = d.Norm();
    if (distance > kFar * node.radius) {
      omega += (node.dipole * d) / (distance * distance * distance);
      return;
    }
    if (node.left < 0) {
      for (int i = node.begin; i < node.end; ++i)
        if (faces_[i] != onFace) omega += solidAngle(T_[faces_[i]], p);
      return;
    }
    visit(node.left, p, onFace, omega);
    visit(node.right, p, onFace, omega);
  }

  // Van Oosterom and Strackee's formula.
  double solidAngle(const Triangle& t, const Point3& p) const {
    const Point3 a = P_[t[0]] - p, b = P_[t[1]] - p, c = P_[t[2]] - p;
    const double la = a.Norm(), lb = b.Norm(), lc = c.Norm();
    const double numerator = a * (b ^ c);
    // In the triangle's plane (a coplanar neighbour of the query face): no
    // solid angle, whatever the sign of the denominator.
    if (numerator == 0) return 0;
    const double denominator = la * lb * lc + (a * b) * lc + (b * c) * la + (c * a) * lb;
    return 2 * std::atan2(numerator, denominator);
  }

  const std::vector<Point3>& P_;
  const std::vector<Triangle>& T_;
  std::vector<int> faces_;
  std::vector<Node> nodes_;
};

}  // namespace

Patches paintPatches(const Mesh& mesh, const FaceLabels& labels, const PaintOptions& options) {
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<Point3> P = positionsOf(mesh);
  auto sized = [&](std::size_t n) { return n == 0 || n == T.size(); };
  if (!sized(labels.part.size()) || !sized(labels.curve_edges.size()) ||
      !sized(labels.colour.size()))
    throw InvalidInputError("the per-face labels do not match the mesh's " +
                            std::to_string(T.size()) + " faces");
  Patches result;
  for (int p : labels.part) {
    if (p < 0) throw InvalidInputError("a face has a negative part number");
    result.parts = std::max(result.parts, p + 1);
  }
  const double creaseCos = std::cos(options.crease_angle_deg * M_PI / 180);
  std::vector<int> parent(T.size());
  std::iota(parent.begin(), parent.end(), 0);
  const std::vector<EdgeUse> uses = edgeUses(T);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    const std::size_t count = j - i;
    bool bounds = (count == 1 && options.at_borders) || (count > 2 && options.at_non_manifold);
    if (options.at_curves && !labels.curve_edges.empty())
      for (std::size_t k = i; k < j; ++k)
        bounds |= (labels.curve_edges[uses[k].face] >> uses[k].corner) & 1;
    if (count == 2 && !bounds) {
      const int f = uses[i].face, g = uses[i + 1].face;
      if (!labels.part.empty() && labels.part[f] != labels.part[g]) bounds = true;
      if (options.at_colour_changes && !labels.colour.empty() &&
          labels.colour[f] != labels.colour[g])
        bounds = true;
      if (options.crease_angle_deg > 0) {
        const Point3 nf = normalOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]);
        const Point3 ng = normalOf(P[T[g][0]], P[T[g][1]], P[T[g][2]]);
        const double norms = nf.Norm() * ng.Norm();
        // Faces that traverse the edge the same way are inconsistently
        // oriented: compare their normals turned to agree.
        const bool sameWay = T[f][uses[i].corner] == T[g][uses[i + 1].corner];
        const double cosine = norms > 0 ? (sameWay ? -1 : 1) * (nf * ng) / norms : 1;
        if (cosine < creaseCos) bounds = true;
      }
    }
    if (bounds) {
      ++result.boundary_edges;
    } else {
      for (std::size_t k = i + 1; k < j; ++k) {
        const int a = find(parent, uses[i].face), b = find(parent, uses[k].face);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
    i = j;
  }
  result.patch_of_face.assign(T.size(), -1);
  std::vector<int> idOfRoot(T.size(), -1);
  for (std::size_t f = 0; f < T.size(); ++f) {
    const int root = find(parent, int(f));
    if (idOfRoot[root] < 0) {
      idOfRoot[root] = int(result.patches.size());
      Patch patch;
      patch.part = labels.part.empty() ? 0 : labels.part[f];
      patch.first_face = int(f);
      result.patches.push_back(patch);
    }
    const int id = idOfRoot[root];
    result.patch_of_face[f] = id;
    Patch& patch = result.patches[id];
    ++patch.faces;
    patch.area += normalOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]).Norm() / 2;
  }
  return result;
}

Patches patchesFromIds(const Mesh& mesh, const FaceLabels& labels, const std::vector<int>& ids) {
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<Point3> P = positionsOf(mesh);
  if (ids.size() != T.size() || (!labels.part.empty() && labels.part.size() != T.size()))
    throw InvalidInputError("the stored patch ids do not match the mesh's " +
                            std::to_string(T.size()) + " faces: paint the patches again");
  Patches result;
  for (int p : labels.part) result.parts = std::max(result.parts, p + 1);
  std::unordered_map<int, int> idOf;
  result.patch_of_face.resize(T.size());
  for (std::size_t f = 0; f < T.size(); ++f) {
    if (ids[f] < 0) throw InvalidInputError("a face has no patch id: paint the patches again");
    const auto [it, added] = idOf.emplace(ids[f], int(result.patches.size()));
    if (added) {
      Patch patch;
      patch.part = labels.part.empty() ? 0 : labels.part[f];
      patch.first_face = int(f);
      result.patches.push_back(patch);
    }
    result.patch_of_face[f] = it->second;
    Patch& patch = result.patches[it->second];
    ++patch.faces;
    patch.area += normalOf(P[T[f][0]], P[T[f][1]], P[T[f][2]]).Norm() / 2;
  }
  return result;
}

namespace {

// A face's twins in other parts (faces with the same three corners).
struct FaceTwins {
  struct Twin {
    int face = -1;   // in that part, or -1
    int facing = 0;  // +1 the same way, -1 the other way, 0 no twin
  };
  std::vector<std::pair<int, Twin>> twins;  // (part, twin)
  Twin in(int part) const {
    for (const auto& [p, twin] : twins)
      if (p == part) return twin;
    return {};
  }
};

// The twins of the sample faces (those that have any), by face.
template <class PartOf>
std::unordered_map<int, FaceTwins> twinsOf(const std::vector<Point3>& P,
                                           const std::vector<Triangle>& T,
                                           const std::vector<std::vector<int>>& samples,
                                           PartOf partOf, int parts) {
  std::unordered_map<int, FaceTwins> result;
  if (parts < 2) return result;
  using Key = std::array<double, 9>;  // the corners' coordinates, corners in lexicographic order
  auto keyOf = [&](int f) {
    std::array<Point3, 3> c = {P[T[f][0]], P[T[f][1]], P[T[f][2]]};
    std::sort(c.begin(), c.end());
    return Key{c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2]};
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::size_t h = 0;
      for (double x : k) h = h * 1000003u ^ std::hash<double>()(x);
      return h;
    }
  };
  std::unordered_map<Key, std::vector<int>, KeyHash> sampleFaces;
  for (const std::vector<int>& faces : samples)
    for (int f : faces) sampleFaces[keyOf(f)].push_back(f);
  for (std::size_t g = 0; g < T.size(); ++g) {
    const auto it = sampleFaces.find(keyOf(int(g)));
    if (it == sampleFaces.end()) continue;
    for (int f : it->second) {
      const int part = partOf(g);
      if (part == partOf(f)) continue;
      const auto known = result.find(f);
      if (known != result.end() && known->second.in(part).face >= 0) continue;
      // The same way round when g's corner after f's first corner is f's second.
      int k = 0;
      while (k < 3 && !(P[T[g][k]] == P[T[f][0]])) ++k;
      const bool same = k < 3 && P[T[g][(k + 1) % 3]] == P[T[f][1]];
      result[f].twins.push_back({part, {int(g), same ? 1 : -1}});
    }
  }
  return result;
}

// What the stages of classifyPatches share: the mesh as arrays, each face's
// part, the parts' winding number trees.
struct Classification {
  const FaceLabels& labels;
  Patches& patches;
  std::vector<Triangle> T;
  std::vector<Point3> P;
  std::vector<EdgeUse> uses;
  std::vector<WindingTree> trees;  // per part

  int partOf(std::size_t f) const { return labels.part.empty() ? 0 : labels.part[f]; }
  Point3 centroid(int f) const { return (P[T[f][0]] + P[T[f][1]] + P[T[f][2]]) / 3.0; }
};

// A part is closed when none of its edges has a single face of the part.
void findClosedParts(Classification& c) {
  Patches& patches = c.patches;
  patches.part_closed.assign(patches.parts, true);
  const std::vector<EdgeUse>& uses = c.uses;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    std::vector<int> count(patches.parts, 0);
    for (std::size_t k = i; k < j; ++k) ++count[c.partOf(uses[k].face)];
    for (int p = 0; p < patches.parts; ++p)
      if (count[p] == 1) patches.part_closed[p] = false;
    i = j;
  }
}

// Sample faces: the few largest of each patch, away from its edges where
// the winding number of a nearby surface changes fastest.
std::vector<std::vector<int>> sampleFaces(const Classification& c) {
  constexpr std::size_t kSamples = 3;
  const Patches& patches = c.patches;
  std::vector<std::vector<int>> samples(patches.patches.size());
  std::vector<std::vector<std::pair<double, int>>> largest(patches.patches.size());
  for (std::size_t f = 0; f < c.T.size(); ++f) {
    auto& l = largest[patches.patch_of_face[f]];
    const double area = normalOf(c.P[c.T[f][0]], c.P[c.T[f][1]], c.P[c.T[f][2]]).Norm();
    if (!(area > 0)) continue;
    l.push_back({area, int(f)});
    if (l.size() > 4 * kSamples) {
      std::nth_element(l.begin(), l.begin() + kSamples, l.end(), std::greater<>());
      l.resize(kSamples);
    }
  }
  for (std::size_t id = 0; id < largest.size(); ++id) {
    auto& l = largest[id];
    std::sort(l.begin(), l.end(), std::greater<>());
    for (std::size_t k = 0; k < l.size() && k < kSamples; ++k) samples[id].push_back(l[k].second);
    if (samples[id].empty()) samples[id].push_back(patches.patches[id].first_face);
  }
  return samples;
}

// Each patch's winding number in every part: the median over its samples
// (one odd sample is outvoted). Where parts overlap in a plane, each keeps
// its copy of the overlap: a sample face's twin in another part (the same
// corners) is that part's surface at the sample, whose own solid angle
// there is left out like the sample's, and whose orientation tells on which
// side that part lies (the samples' majority).
void windingsAtSamples(Classification& c, const std::vector<std::vector<int>>& samples) {
  Patches& patches = c.patches;
  const std::unordered_map<int, FaceTwins> twins = twinsOf(
      c.P, c.T, samples, [&](std::size_t f) { return c.partOf(f); }, patches.parts);
  parallelChunks(
      patches.patches.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t id = begin; id < end; ++id) {
          Patch& patch = patches.patches[id];
          patch.winding.assign(patches.parts, 0);
          patch.coincident.assign(patches.parts, 0);
          patch.coincident[patch.part] = 1;
          for (int p = 0; p < patches.parts; ++p) {
            std::vector<double> values;
            int facing[3] = {0, 0, 0};  // samples with a twin facing the other way, none, the same
            for (int f : samples[id]) {
              const auto it = twins.find(f);
              const FaceTwins::Twin twin = it == twins.end() ? FaceTwins::Twin{} : it->second.in(p);
              values.push_back(c.trees[p].at(c.centroid(f), twin.face >= 0 ? twin.face : f));
              if (p != patch.part) ++facing[twin.facing + 1];
            }
            std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
            patch.winding[p] = values[values.size() / 2];
            if (p != patch.part)
              patch.coincident[p] = std::int8_t(std::max_element(facing, facing + 3) - facing - 1);
          }
          patch.setSideWindings();
        }
      },
      4);
}

// A closed part whose faces point inward has winding number -1 inside:
// taken turned, its winding numbers and the sides its surface faces change
// sign.
void turnInsideOutParts(Classification& c) {
  Patches& patches = c.patches;
  patches.part_inside_out.assign(patches.parts, false);
  std::vector<double> volume(patches.parts, 0);
  for (std::size_t f = 0; f < c.T.size(); ++f)
    volume[c.partOf(f)] += c.P[c.T[f][0]].dot(c.P[c.T[f][1]] ^ c.P[c.T[f][2]]);
  for (int p = 0; p < patches.parts; ++p) {
    if (!patches.part_closed[p] || !(volume[p] < 0)) continue;
    patches.part_inside_out[p] = true;
    for (Patch& patch : patches.patches) {
      patch.winding[p] = -patch.winding[p];
      patch.coincident[p] = std::int8_t(-patch.coincident[p]);
      patch.setSideWindings();
    }
  }
}

// Per part: inside it in front of the patch and behind it (on a part's
// surface, one side only), and whether the patch is on the union's surface.
std::vector<std::uint8_t> statusOf(const std::vector<double>& winding, const Patch& patch,
                                   int parts) {
  Patch at = patch;
  at.winding = winding;
  at.setSideWindings();
  std::vector<std::uint8_t> status(parts + 1, 0);
  for (int p = 0; p < parts; ++p)
    status[p] = std::uint8_t((at.windingInFront(p) > 0.5) | (at.windingBehind(p) > 0.5) << 1);
  status[parts] = at.onUnionSurface();
  return status;
}

// A face's winding numbers: its patch's for the closed parts, its own for
// the open ones (on an open part's surface, a planar overlap, the face's
// own twin left out, as for the samples).
class FaceWindings {
 public:
  FaceWindings(const Classification& c, const std::vector<std::vector<int>>& facesOfPatch) : c_(c) {
    const Patches& patches = c.patches;
    std::vector<std::vector<int>> onOtherParts(1);
    for (std::size_t id = 0; id < patches.patches.size(); ++id) {
      const Patch& patch = patches.patches[id];
      for (int p = 0; p < patches.parts; ++p)
        if (p != patch.part && patch.coincident[p] != 0 && !patches.part_closed[p]) {
          onOtherParts[0].insert(onOtherParts[0].end(), facesOfPatch[id].begin(),
                                 facesOfPatch[id].end());
          break;
        }
    }
    if (!onOtherParts[0].empty())
      twins_ = twinsOf(
          c.P, c.T, onOtherParts, [&](std::size_t f) { return c.partOf(f); }, patches.parts);
  }

  std::vector<double> at(int f) const {
    const Patches& patches = c_.patches;
    std::vector<double> w = patches.patches[patches.patch_of_face[f]].winding;
    const auto twins = twins_.find(f);
    for (int p = 0; p < patches.parts; ++p) {
      if (patches.part_closed[p]) continue;
      const int twin = twins == twins_.end() ? -1 : twins->second.in(p).face;
      w[p] = c_.trees[p].at(c_.centroid(f), twin >= 0 ? twin : f);
    }
    return w;
  }

 private:
  const Classification& c_;
  std::unordered_map<int, FaceTwins> twins_;
};

// Patches whose faces do not all share their status: probed at a few faces
// spread over each.
std::vector<char> mixedPatches(const Classification& c, const FaceWindings& windings,
                               const std::vector<std::vector<int>>& facesOfPatch) {
  constexpr std::size_t kProbes = 32;
  const Patches& patches = c.patches;
  std::vector<char> mixed(patches.patches.size(), 0);
  parallelChunks(
      patches.patches.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t id = begin; id < end; ++id) {
          const std::vector<int>& faces = facesOfPatch[id];
          const Patch& patch = patches.patches[id];
          const std::vector<std::uint8_t> status = statusOf(patch.winding, patch, patches.parts);
          const std::size_t step = std::max<std::size_t>(1, faces.size() / kProbes);
          for (std::size_t k = step / 2; k < faces.size() && !mixed[id]; k += step)
            mixed[id] = statusOf(windings.at(faces[k]), patch, patches.parts) != status;
        }
      },
      1);
  return mixed;
}

// The faces of the mixed patches classified one by one and joined into
// pieces of one status; each piece becomes a patch (the piece with the
// patch's first face keeps its id), with the mean winding numbers of its
// faces.
void splitMixed(Classification& c, const FaceWindings& windings, const std::vector<char>& mixed,
                const std::vector<int>& refine) {
  Patches& patches = c.patches;
  const std::size_t nf = c.T.size();
  std::vector<std::vector<double>> faceWinding(nf);
  std::vector<std::vector<std::uint8_t>> faceStatus(nf);
  parallelChunks(
      refine.size(),
      [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) {
          const int f = refine[i];
          faceWinding[f] = windings.at(f);
          faceStatus[f] =
              statusOf(faceWinding[f], patches.patches[patches.patch_of_face[f]], patches.parts);
        }
      },
      256);
  std::vector<int> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  const std::vector<EdgeUse>& uses = c.uses;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].u == uses[i].u && uses[j].v == uses[i].v) ++j;
    if (j - i == 2) {
      const int f = uses[i].face, g = uses[i + 1].face;
      const int id = patches.patch_of_face[f];
      if (id == patches.patch_of_face[g] && mixed[id] && faceStatus[f] == faceStatus[g]) {
        const int a = find(parent, f), b = find(parent, g);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
    i = j;
  }
  std::unordered_map<int, int> idOfRoot;
  for (int f : refine) {
    const int root = find(parent, f);
    auto [it, added] = idOfRoot.emplace(root, -1);
    if (added) {
      const int old = patches.patch_of_face[f];
      if (patches.patches[old].first_face == root) {
        it->second = old;
      } else {
        it->second = int(patches.patches.size());
        patches.patches.push_back(patches.patches[old]);
        patches.patches.back().first_face = root;
      }
      Patch& fresh = patches.patches[it->second];
      fresh.faces = 0;
      fresh.area = 0;
      fresh.winding.assign(patches.parts, 0);
    }
    Patch& patch = patches.patches[it->second];
    patches.patch_of_face[f] = it->second;
    ++patch.faces;
    patch.area += normalOf(c.P[c.T[f][0]], c.P[c.T[f][1]], c.P[c.T[f][2]]).Norm() / 2;
    for (int p = 0; p < patches.parts; ++p) patch.winding[p] += faceWinding[f][p];
  }
  for (const auto& [root, id] : idOfRoot) {
    Patch& patch = patches.patches[id];
    for (double& w : patch.winding) w /= double(patch.faces);
    patch.setSideWindings();
  }
}

// A patch can lie on both sides of another part where that part is open:
// a curve that ends at the other part's border does not separate the patch
// (a closed mesh passing through a scan's hole). Faces spread over each
// patch reveal it; such a patch is split by classifying every face, along
// the level set where the other part's winding number crosses ½. A closed
// part's winding number is the same all over a patch that does not cross
// it: only the open parts' change from face to face.
void splitAtOpenParts(Classification& c) {
  Patches& patches = c.patches;
  if (std::all_of(patches.part_closed.begin(), patches.part_closed.end(), [](bool x) { return x; }))
    return;
  std::vector<std::vector<int>> facesOfPatch(patches.patches.size());
  for (std::size_t f = 0; f < c.T.size(); ++f)
    facesOfPatch[patches.patch_of_face[f]].push_back(int(f));
  const FaceWindings windings(c, facesOfPatch);
  const std::vector<char> mixed = mixedPatches(c, windings, facesOfPatch);
  std::vector<int> refine;  // faces of mixed patches
  for (std::size_t id = 0; id < mixed.size(); ++id)
    if (mixed[id]) refine.insert(refine.end(), facesOfPatch[id].begin(), facesOfPatch[id].end());
  if (refine.empty()) return;
  splitMixed(c, windings, mixed, refine);
  patches.patches_split_at_open_parts = std::count(mixed.begin(), mixed.end(), 1);
}

}  // namespace

void classifyPatches(const Mesh& mesh, const FaceLabels& labels, Patches& patches) {
  Classification c{labels, patches, trianglesOf(mesh), positionsOf(mesh), {}, {}};
  if (patches.patch_of_face.size() != c.T.size())
    throw InvalidInputError("the patches were painted on another mesh");
  c.uses = edgeUses(c.T);
  findClosedParts(c);
  std::vector<std::vector<int>> facesOfPart(patches.parts);
  for (std::size_t f = 0; f < c.T.size(); ++f) facesOfPart[c.partOf(f)].push_back(int(f));
  for (int p = 0; p < patches.parts; ++p) c.trees.emplace_back(c.P, c.T, facesOfPart[p]);
  windingsAtSamples(c, sampleFaces(c));
  turnInsideOutParts(c);
  splitAtOpenParts(c);
}

const char* toString(BooleanOperation op) {
  switch (op) {
    case BooleanOperation::kUnion:
      return "union (outer surface)";
    case BooleanOperation::kIntersection:
      return "intersection (common interior)";
    case BooleanOperation::kDifference:
      return "difference (first minus the others)";
  }
  return "";
}

PatchChoice choosePatches(const Patches& patches, BooleanOperation op) {
  PatchChoice choice;
  const std::size_t n = patches.patches.size();
  choice.keep.assign(n, 0);
  choice.flip.assign(n, 0);
  for (std::size_t id = 0; id < n; ++id) {
    const Patch& patch = patches.patches[id];
    if (patch.winding.size() != std::size_t(patches.parts) ||
        patch.coincident.size() != std::size_t(patches.parts))
      throw InvalidInputError("the patches are not classified yet");
    // Is the result's region just in front of the patch (along its normal),
    // or just behind it? The patch bounds the result where they differ, and
    // faces the result's outside: turned over when the region is in front.
    auto inResult = [&](bool front) {
      auto insidePart = [&](int p) {
        return (front ? patch.windingInFront(p) : patch.windingBehind(p)) > 0.5;
      };
      switch (op) {
        case BooleanOperation::kUnion:  // inside all parts together (an open part: fractions add
                                        // up)
          return (front ? patch.winding_outside : patch.winding_inside) > 0.5;
        case BooleanOperation::kIntersection:
          for (int p = 0; p < patches.parts; ++p)
            if (!insidePart(p)) return false;
          return true;
        case BooleanOperation::kDifference:
          if (!insidePart(0)) return false;
          for (int p = 1; p < patches.parts; ++p)
            if (insidePart(p)) return false;
          return true;
      }
      return false;
    };
    const bool behind = inResult(false), inFront = inResult(true);
    // A planar overlap bounds the result once: by the copy of its first part.
    bool copyOfEarlierPart = false;
    for (int p = 0; p < patch.part; ++p) copyOfEarlierPart |= patch.coincident[p] != 0;
    choice.keep[id] = behind != inFront && !copyOfEarlierPart;
    choice.flip[id] = choice.keep[id] && inFront;
  }
  return choice;
}

Mesh extractPatches(const Mesh& mesh, const Patches& patches, const std::vector<char>& keep,
                    const std::vector<char>& flip) {
  const std::vector<Triangle> T = trianglesOf(mesh);
  const std::vector<Point3> P = positionsOf(mesh);
  if (patches.patch_of_face.size() != T.size() || keep.size() != patches.patches.size())
    throw InvalidInputError("the patches were painted on another mesh");
  Mesh& source = const_cast<Mesh&>(mesh);  // (vcglib's attribute lookup is not const)
  const bool hasOrigins = vcg::tri::Allocator<Mesh>::IsValidHandle(
      source,
      vcg::tri::Allocator<Mesh>::FindPerFaceAttribute<FaceOrigin>(source, kFaceOriginAttribute));
  std::vector<int> vertexIndex(P.size(), -1);
  std::vector<Point3> points;
  std::vector<Triangle> triangles;
  std::vector<int> birthVertex, birthFace;
  for (std::size_t f = 0; f < T.size(); ++f) {
    const int id = patches.patch_of_face[f];
    if (!keep[id]) continue;
    Triangle t = T[f];
    if (!flip.empty() && flip[id]) std::swap(t[1], t[2]);
    for (int& v : t) {
      if (vertexIndex[v] < 0) {
        vertexIndex[v] = int(points.size());
        points.push_back(P[v]);
        birthVertex.push_back(v);
      }
      v = vertexIndex[v];
    }
    triangles.push_back(t);
    birthFace.push_back(int(f));
  }
  // Coincident vertices (layers that met along a curve) become one.
  const WeldedArrays welded = weldCoincident({points, triangles});
  Mesh out = makeMesh(welded.mesh.points, welded.mesh.triangles);
  VertexOriginHandle vo = vertexOrigins(out);
  FaceOriginHandle fo = faceOrigins(out);
  VertexOriginHandle inVertex = vertexOrigins(source);
  FaceOriginHandle inFace = faceOrigins(source);
  for (std::size_t v = 0; v < out.vert.size(); ++v) {
    const int input = birthVertex[welded.vertex_origin[v]];
    vo[v] = hasOrigins ? inVertex[input] : VertexOrigin{0, input, -1, {0, 0, 0}};
  }
  for (std::size_t f = 0; f < out.face.size(); ++f) {
    const int input = birthFace[welded.face_origin[f]];
    fo[f] = hasOrigins ? inFace[input] : FaceOrigin{0, input};
  }
  return out;
}

std::array<std::uint8_t, 3> patchColour(int id) {
  const double h = std::fmod(id * 0.6180339887, 1.0) * 6, s = id % 2 ? 0.55 : 0.75, v = 0.95;
  const int sector = int(h);
  const double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double rgb[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
  const double* c = rgb[sector % 6];
  return {std::uint8_t(c[0] * 255), std::uint8_t(c[1] * 255), std::uint8_t(c[2] * 255)};
}

std::string statusOf(const Patch& patch, int parts) {
  if (patch.winding.empty()) return "not classified";
  std::string inside, on;
  for (int p = 0; p < parts; ++p) {
    if (p == patch.part) continue;
    if (patch.inside(p)) inside += (inside.empty() ? "" : ",") + std::to_string(p);
    if (patch.coincident[p] != 0) on += (on.empty() ? "" : ",") + std::to_string(p);
  }
  std::string status = patch.onUnionSurface() ? "outer surface" : "interior";
  if (parts > 1) status += inside.empty() ? "; outside the other parts" : "; inside part " + inside;
  if (!on.empty()) status += "; on the surface of part " + on;
  return status;
}

JsonObject toJson(const Patches& patches) {
  std::vector<JsonObject> list;
  for (std::size_t id = 0; id < patches.patches.size(); ++id) {
    const Patch& p = patches.patches[id];
    JsonObject j;
    j.set("id", std::int64_t(id))
        .set("part", p.part)
        .set("faces", p.faces)
        .set("area", p.area)
        .set("status", statusOf(p, patches.parts));
    if (!p.winding.empty())
      j.set("winding", p.winding)
          .set("winding_outside", p.winding_outside)
          .set("winding_inside", p.winding_inside)
          .set("coincident", std::vector<double>(p.coincident.begin(), p.coincident.end()));
    list.push_back(j);
  }
  JsonObject j;
  j.set("patches", patches.patches.size())
      .set("parts", patches.parts)
      .set("boundary_edges", patches.boundary_edges)
      .set("patches_split_at_open_parts", patches.patches_split_at_open_parts);
  std::vector<double> insideOut;  // the parts classified as turned
  for (std::size_t p = 0; p < patches.part_inside_out.size(); ++p)
    if (patches.part_inside_out[p]) insideOut.push_back(double(p));
  j.set("parts_inside_out", insideOut).set("patch_list", list);
  return j;
}

}  // namespace meshmend
