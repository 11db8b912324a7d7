#include "common/repair/holes/fill.h"
#include "common/base/timing.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "common/repair/holes/check.h"
#include "common/repair/holes/domain.h"
#include "common/repair/holes/fairing.h"
#include "common/repair/holes/front.h"
#include "common/repair/holes/refine.h"

namespace meshmend::holes {

namespace {

// Patch edges that a placement stretches beyond this factor of their length
// in the domain are split (refineStretched): twice the size the front meant.
constexpr double kMaxStretch = 2;
// A first shape of at least this mean shape quality (1 = equilateral
// triangles) over the hole's plane is used without making the disk's. (On
// the fidelity holes of docs/BENCHMARKS.md the disk's shape was the rounder
// one only where the plane's was below 0.7.)
constexpr double kRoundPatchQuality = 0.8;
// A disk whose flat patch covers less than this fraction of its area in
// space (measured on a coarse patch of kCoarse times the sizes) is
// triangulated with triangles that grow inwards by kDiskGrowth per layer,
// up to 1 / sqrt(ratio) times the border's size and at most kMostDiskScale.
// (Not 1 / ratio, which would match the area better: triangles that large
// stretch so far in a bulging shape that the refinement, and the choice
// between the plane and the disk, turn on the last bits of the coordinates,
// and a float host and a double one fill the same hole differently.)
// The dense disk (the last fallback, the border's spacing as split) grows
// so too, up to kMostDenseDiskScale: with the border's spacing throughout,
// the patch over spot's large round hole had 3.6 times the faces cut out
// (2,043 unknowns against the disk's 522) and most of the fill's time.
constexpr double kDenseDisk = 0.75;
constexpr double kDiskGrowth = 1.2;
constexpr double kMostDiskScale = 4;
constexpr double kMostDenseDiskScale = 2;
constexpr double kCoarse = 3;
constexpr const char* kNoMembrane = "the membrane over the disk could not be solved";

const char* where(const Domain& d) {
  return d.planar ? "over its plane: " : "over a disk: ";
}

bool smoothWithTangents(HoleFairing mode) {
  return mode == HoleFairing::Biharmonic || mode == HoleFairing::LaplacianRegression;
}

// The patch over one domain: triangulated, refined, placed flat; the
// fairing of the patch as it stands (its systems made on first use).
struct Candidate {
  Domain domain;
  bool uniform = false;  // a disk whose triangles start at the border's spacing (the dense disk)
  bool graded = false;   // a disk (not the dense one) whose triangles were made larger inside
  bool tried = false;
  std::string problem;  // why there is no patch over this domain (empty: there is)
  Patch patch;
  std::vector<Point3> flat;  // every local vertex: the boundary, then the flat placement
  std::unique_ptr<Fairing> fairing;
  // Shaped in the first mode (made once, then used as it is).
  bool shaped = false, shapedOk = false;
  std::vector<Point3> first;
  double residual = 0;
  HoleFairing shapedAs = HoleFairing::Flat;
  std::string why;
  double quality = -1;  // mean shape quality of the first shape (-1: none)
};

class HoleFiller {
 public:
  HoleFiller(HoleContext& context, const std::vector<int>& loop, const std::vector<double>& sizes,
             const std::vector<int>& splitFaces, HoleReport& report)
      : s_(context.surface),
        options_(context.options),
        context_(context),
        loop_(loop),
        edgeSizes_(sizes),
        splitFaces_(splitFaces),
        report_(report) {}

  bool fill() {
    if (!readBorder()) return false;
    const std::vector<HoleFairing> modes = modesToTry();
    std::vector<Candidate> candidates = domainsToTry();
    Candidate* disk = &candidates.back();
    Candidate* plane = candidates.size() > 1 ? &candidates.front() : nullptr;
    std::string failed;
    // The plane's patch, then the disk's: first the rounder of the two in
    // space (the disk's is made only when the plane's is not round).
    std::vector<Candidate*> order;
    if (plane) {
      order.push_back(plane);
      shapeFirst(*plane, modes[0]);
      if (plane->quality < kRoundPatchQuality) {
        shapeFirst(*disk, modes[0]);
        if (disk->quality > plane->quality) order.insert(order.begin(), disk);
      }
    }
    if (std::find(order.begin(), order.end(), disk) == order.end()) order.push_back(disk);
    // Last, a disk with triangles of the border's spacing (as split),
    // growing inwards to at most twice it, where the disk's are larger:
    // more vertices for the patch to bend around what it met.
    candidates.emplace_back();
    Candidate* dense = &candidates.back();
    dense->domain = disk->domain;
    dense->uniform = true;
    order.push_back(dense);
    // A smoother shape over any domain before a flatter one.
    for (HoleFairing mode : modes)
      for (Candidate* c : order) {
        if (c == dense && !denseDiffers(*disk)) continue;
        if (tryAs(*c, mode, failed)) return done(mode, candidates, failed);
      }
    report_.reason = problems(candidates);
    if (!failed.empty()) report_.reason += (report_.reason.empty() ? "" : "; ") + failed;
    return false;
  }

 private:
  // ---- The border and the surface around it -------------------------------------

  // The front (the border against the faces' direction, so that the patch
  // runs with them), the faces at each border vertex, and the rim the
  // fairing keeps fixed. False when the border has no length.
  bool readBorder() {
    n_ = loop_.size();
    front_.assign(loop_.rbegin(), loop_.rend());
    local_.reserve(2 * n_);
    for (std::size_t k = 0; k < n_; ++k) local_[front_[k]] = int(k);
    Bounds bounds;
    meanEdge_ = 0;
    for (std::size_t k = 0; k < n_; ++k) {
      boundary_.push_back(s_.point(front_[k]));
      bounds.add(boundary_.back());
      meanEdge_ += (s_.point(front_[(k + 1) % n_]) - s_.point(front_[k])).Norm();
    }
    meanEdge_ /= double(n_);
    if (!(meanEdge_ > 0)) {
      report_.reason = "the hole's border has zero length";
      return false;
    }
    fans_.assign(n_, {});
    for (int f : context_.facesNear(bounds)) {
      const Triangle t = s_.corners(f);
      for (int k = 0; k < 3; ++k) {
        const auto it = local_.find(t[k]);
        if (it != local_.end() && (k == 0 || t[k] != t[k - 1]) && (k < 2 || t[2] != t[0]))
          fans_[std::size_t(it->second)].push_back(f);
      }
    }
    for (std::size_t k = 0; k < n_; ++k)
      for (int f : fans_[k])
        for (int c : s_.corners(f)) {
          const auto it = local_.find(c);
          if (it != local_.end() && std::size_t(it->second) > k) {
            existing_.push_back({int(k), it->second});
            chords_.insert(edgeKey(int(k), it->second));
          }
        }
    // Along the border: the faces' mean normal (one of the planes tried).
    for (std::size_t k = 0; k < n_; ++k) {
      const int f = s_.borderFace(front_[(k + 1) % n_], front_[k]);
      if (f < 0) continue;
      faceNormals_ += faceNormal(f);
    }
    readRim();
    return true;
  }

  Point3 faceNormal(int f) const {
    const Triangle t = s_.corners(f);
    const Point3& a = s_.point(t[0]);
    return (s_.point(t[1]) - a) ^ (s_.point(t[2]) - a);
  }

  int keyOf(int global) const {
    const auto it = local_.find(global);
    return it == local_.end() ? -(global + 1) : it->second;
  }

  // The rim: each border vertex's Laplacian row from the faces outside the
  // patch (none where several borders pass: those faces are not one fan).
  void readRim() {
    rim_.hasRow.assign(n_, 0);
    rim_.outside.assign(n_, {});
    rim_.outsideNormal.assign(n_, Point3(0, 0, 0));
    rim_.outsideArea.assign(n_, 0);
    rim_.point = [this](int v) { return s_.point(v); };
    for (std::size_t k = 0; k < n_; ++k) {
      for (int f : fans_[k]) {
        const Triangle t = s_.corners(f);
        int corner = 0;
        while (t[corner] != front_[k]) ++corner;
        const Point3 &a = s_.point(t[0]), &b = s_.point(t[1]), &c = s_.point(t[2]);
        addTriangleToRow(rim_.outside[k], {keyOf(t[0]), keyOf(t[1]), keyOf(t[2])},
                         triangleWeights(a, b, c), corner);
        const Point3 normal = (b - a) ^ (c - a);
        rim_.outsideNormal[k] += normal;
        rim_.outsideArea[k] += normal.Norm() / 6;
      }
      rim_.hasRow[k] =
          !rim_.outside[k].weights.empty() &&
          !std::binary_search(context_.pinched.begin(), context_.pinched.end(), front_[k]);
    }
  }

  // The shapes to try, smoothest first: the one asked for, then each
  // flatter one; asked for the smoothest and none down to flat fits, the
  // regression's, which bends with the curvature around the hole instead,
  // may clear what they hit.
  std::vector<HoleFairing> modesToTry() const {
    std::vector<HoleFairing> modes;
    for (HoleFairing m :
         {options_.fairing, HoleFairing::Biharmonic, HoleFairing::Harmonic, HoleFairing::Flat})
      if (int(m) <= int(options_.fairing) &&
          std::find(modes.begin(), modes.end(), m) == modes.end())
        modes.push_back(m);
    if (options_.fairing == HoleFairing::Biharmonic)
      modes.push_back(HoleFairing::LaplacianRegression);
    return modes;
  }

  // The hole's plane, if the border projects onto one, then the disk, which
  // any border maps to.
  std::vector<Candidate> domainsToTry() const {
    std::vector<Candidate> out;
    out.reserve(3);  // never moved: a candidate's fairing refers to its patch
    out.emplace_back();
    out[0].domain = diskDomain(boundary_);
    Domain plane;
    if (!planeDomain(boundary_, faceNormals_, plane)) return out;
    out.insert(out.begin(), Candidate{});
    out[0].domain = std::move(plane);
    return out;
  }

  // The candidate's patch shaped in the first mode (kept for later).
  void shapeFirst(Candidate& c, HoleFairing mode) {
    if (c.shaped) return;
    c.shaped = true;
    if (!c.tried) triangulate(c);
    if (!c.problem.empty()) return;
    c.first = c.flat;
    c.shapedOk = shape(c, mode, c.first, c.residual, c.shapedAs, c.why);
    if (c.shapedOk) c.quality = meanShapeQuality(c.patch, c.first);
  }

  // Shapes the candidate's patch in `mode` and commits it when it passes
  // the exact check; else says why in `failed`.
  bool tryAs(Candidate& c, HoleFairing mode, std::string& failed) {
    const bool firstMode = mode == modesToTry()[0];
    if (firstMode) shapeFirst(c, mode);
    if (!c.tried) triangulate(c);
    if (!c.problem.empty()) return false;
    std::vector<Point3> x;
    double residual = 0;
    HoleFairing shaped = mode;
    std::string why;
    bool ok;
    if (firstMode) {
      x = c.first;
      residual = c.residual;
      shaped = c.shapedAs;
      why = c.why;
      ok = c.shapedOk;
    } else {
      x = c.flat;
      ok = shape(c, mode, x, residual, shaped, why);
    }
    const std::string name = std::string(where(c.domain)) + toString(mode);
    if (!ok) {
      failed += (failed.empty() ? "" : "; ") + name + ": " + why;
      return false;
    }
    if (check(c, x) > 0) {
      failed += (failed.empty() ? "" : "; ") + name + " patch would intersect itself or the mesh";
      return false;
    }
    commit(c, x, shaped, residual);
    return true;
  }

  // Whether the dense disk would differ from the disk: the disk's
  // triangles grew inside, or the border's edges were split (the disk
  // takes the input edges' sizes).
  bool denseDiffers(Candidate& disk) {
    if (!disk.tried) triangulate(disk);
    return disk.graded || report_.edges_split > 0;
  }

  bool done(HoleFairing mode, const std::vector<Candidate>& candidates, const std::string& failed) {
    explain(mode, candidates, failed);
    return true;
  }

  // ---- Triangulate, place flat, refine -------------------------------------------

  void triangulate(Candidate& c) {
    const auto clock = Clock::now();
    c.tried = true;
    const Domain& d = c.domain;
    // Each border vertex's size in space: the mean of the input edges it
    // is between (loop edge i runs front k = n - 1 - i to k - 1), in the
    // domain as the border's own edges there are.
    std::vector<double> sizes(n_);
    double meanSize = 0;
    for (std::size_t k = 0; k < n_; ++k) {
      const std::size_t before = n_ - 1 - k, after = (2 * n_ - 2 - k) % n_;
      const std::size_t next = (k + 1) % n_, previous = (k + n_ - 1) % n_;
      const double inDomain = norm(d.uv[next] - d.uv[k]) + norm(d.uv[previous] - d.uv[k]);
      const double inSpace =
          (boundary_[next] - boundary_[k]).Norm() + (boundary_[previous] - boundary_[k]).Norm();
      // (The uniform disk keeps the border's spacing as split.)
      const double target = c.uniform ? inSpace / 2 : (edgeSizes_[before] + edgeSizes_[after]) / 2;
      sizes[k] = inSpace > 0 ? target * inDomain / inSpace : target;
      meanSize += sizes[k];
    }
    meanSize /= double(n_);
    // Triangles of the border's size throughout, unless that makes too
    // many: then they grow by size_growth per layer towards the middle.
    FrontSettings settings;
    settings.merge = options_.merge_distance;
    settings.maxTriangles = 10 * options_.uniform_face_limit;
    const double uniformFaces = std::abs(signedArea(d.uv)) / (0.433 * meanSize * meanSize);
    if (!std::isfinite(uniformFaces) || !(meanSize > 0) || !std::isfinite(meanSize)) {
      c.problem =
          "its size overflows double (coordinates near the limits of double): scale the mesh "
          "towards the origin";
      context_.times.triangulate += msSince(clock);
      return;
    }
    if (uniformFaces > double(options_.uniform_face_limit)) {
      settings.growth = options_.size_growth;
      settings.maxSize = options_.max_size_factor * meanSize;
    } else {
      settings.growth = 1;
      settings.maxSize = meanSize * 4;
      // A disk holds more area than the surface its border bounds (all of
      // it where the border is round and flat): its triangles inside grow
      // towards the size that makes up for it.
      const double ratio = d.planar ? 1 : flatAreaRatio(c, sizes, settings);
      if (ratio < kDenseDisk) {
        settings.growth = kDiskGrowth;
        const double most = c.uniform ? kMostDenseDiskScale : kMostDiskScale;
        settings.maxSize = meanSize * std::min(most, 1 / std::sqrt(ratio));
        c.graded = !c.uniform;
      }
    }
    if (cover(c, sizes, settings)) placeFlat(c);
    context_.times.triangulate += msSince(clock);
  }

  // The area in space of a disk's flat patch over the disk's area (both in
  // units of size^2), measured on a coarse patch (kCoarse times the sizes:
  // about a ninth of the vertices to place), so that the patch itself is
  // triangulated once, at its grading; 1 when the coarse front fails.
  double flatAreaRatio(const Candidate& c, const std::vector<double>& sizes,
                       const FrontSettings& settings) {
    Candidate coarse;
    coarse.domain = c.domain;
    std::vector<double> coarseSizes = sizes;
    for (double& size : coarseSizes) size *= kCoarse;
    FrontSettings coarseSettings = settings;
    coarseSettings.maxSize *= kCoarse;
    if (!cover(coarse, coarseSizes, coarseSettings) || !placeFlat(coarse)) return 1;
    double inSpace = 0;
    for (const Triangle& t : coarse.patch.triangles)
      inSpace += ((coarse.flat[std::size_t(t[1])] - coarse.flat[std::size_t(t[0])]) ^
                  (coarse.flat[std::size_t(t[2])] - coarse.flat[std::size_t(t[0])]))
                     .Norm() /
                 2;
    return inSpace / std::abs(signedArea(c.domain.uv));
  }

  // The advancing front over the candidate's domain, its new vertices
  // relaxed; false (the problem said) when it could not cover the hole.
  bool cover(Candidate& c, const std::vector<double>& sizes, const FrontSettings& settings) {
    const Domain& d = c.domain;
    Front front = advanceFront(d.uv, sizes, existing_, settings);
    if (!front.covered) {
      c.problem = "the advancing front could not cover the hole (its border is too tangled)";
      return false;
    }
    Patch& p = c.patch;
    p.n = n_;
    p.uv = std::move(front.uv);
    p.triangles = std::move(front.triangles);
    p.height.assign(p.uv.size(), 0);
    if (d.planar) {
      for (std::size_t k = 0; k < n_; ++k) p.height[k] = d.height[k];
      for (std::size_t v = n_; v < p.uv.size(); ++v) {
        const auto [a, b] = front.parent[v - n_];
        p.height[v] = (p.height[std::size_t(a)] + p.height[std::size_t(b)]) / 2;
      }
    }
    relaxInterior(p.uv, p.height, n_, p.triangles, 3);
    p.around = TrianglesAround(p.triangles, p.uv.size());
    return true;
  }

  // The flat placement: the front's own (heights carried inward from the
  // boundary) over the plane, a uniform membrane over a disk.
  bool placeFlat(Candidate& c) {
    const Patch& p = c.patch;
    c.fairing.reset();
    c.flat.assign(p.size(), Point3(0, 0, 0));
    for (std::size_t k = 0; k < n_; ++k) c.flat[k] = boundary_[k];
    if (c.domain.planar) {
      const Domain& d = c.domain;
      for (std::size_t v = n_; v < p.size(); ++v)
        c.flat[v] = d.origin + d.U * p.uv[v].x + d.V * p.uv[v].y + d.N * p.height[v];
      return true;
    }
    Fairing membrane(p, rim_);
    if (membrane.uniform(c.flat)) return true;
    c.problem = kNoMembrane;
    return false;
  }

  std::function<bool(int, int)> forbidden() const {
    return [this](int a, int b) { return chords_.count(edgeKey(a, b)) > 0; };
  }

  // ---- Fair ------------------------------------------------------------------------

  // Shapes the candidate's patch in `mode` from x (the flat placement);
  // `shaped` says the shape it got (the regression's falls back to the
  // biharmonic one when too little is known around the hole).
  bool shape(Candidate& c, HoleFairing mode, std::vector<Point3>& x, double& residual,
             HoleFairing& shaped, std::string& why) {
    const auto clock = Clock::now();
    shaped = mode;
    // The domain sized the triangles; where the shape in space stretches
    // them far beyond that, the patch is refined there and shaped again,
    // from where it is (the flat placement follows the splits). The
    // biharmonic shape is looked at after its first solve too: a patch that
    // is refined then is not reweighted before.
    auto refine = [&] {
      return refineStretched(c.patch, x, c.flat, meanEdge_, kMaxStretch, forbidden()) > 0;
    };
    bool ok, refined = false;
    if (mode == HoleFairing::Biharmonic) {
      if (!c.fairing) c.fairing = std::make_unique<Fairing>(c.patch, rim_);
      ok = c.fairing->firstBiharmonic(x, residual);
      refined = ok && refine();
      if (ok && !refined) {
        ok = c.fairing->reweightBiharmonic(x, residual);
        refined = ok && refine();
      }
    } else {
      ok = fairOnce(c, mode, x, residual, shaped, false);
      refined = ok && smoothWithTangents(mode) && refine();
    }
    if (refined) {
      c.fairing.reset();
      ok = fairOnce(c, mode, x, residual, shaped, true);
    }
    context_.times.fair += msSince(clock);
    if (!ok) why = "the solver failed";
    if (ok && mode != HoleFairing::Flat && mode != HoleFairing::Harmonic) residual /= meanEdge_;
    return ok;
  }

  bool fairOnce(Candidate& c, HoleFairing mode, std::vector<Point3>& x, double& residual,
                HoleFairing& shaped, bool fromShape) {
    residual = 0;
    if (mode == HoleFairing::Flat) return true;
    if (!c.fairing) c.fairing = std::make_unique<Fairing>(c.patch, rim_);
    switch (mode) {
      case HoleFairing::Harmonic:
        return c.fairing->harmonic(x, residual);
      case HoleFairing::Biharmonic:
        return c.fairing->biharmonic(x, residual, fromShape);
      case HoleFairing::LaplacianRegression:
        if (!learnCurvature()) {
          shaped = HoleFairing::Biharmonic;
          return c.fairing->biharmonic(x, residual, fromShape);
        }
        return c.fairing->regression(x, model_, residual, fromShape);
      case HoleFairing::Flat:
        break;
    }
    return true;
  }

  // Mean curvature from the rings around the hole (§3.3): the samples are
  // H at each ring vertex inside the surface, from its cotangent Laplacian,
  // sum_j omega_ij (x_j - x_i) = -4 A_i H_i n_i (Meyer et al. 2003).
  bool learnCurvature() {
    if (learnt_ >= 0) return learnt_ == 1;
    learnt_ = 0;
    Point3 centre(0, 0, 0);
    for (const Point3& p : boundary_) centre += p;
    centre /= double(n_);
    double scale = 0;
    for (const Point3& p : boundary_) scale += (p - centre).SquaredNorm();
    scale = std::sqrt(scale / double(n_));
    // The faces at each vertex near the hole.
    Bounds bounds;
    for (const Point3& p : boundary_) bounds.add(p);
    std::unordered_map<int, std::vector<int>> facesAt;
    for (int f : context_.facesNear(bounds.grown(2 * options_.regression_rings * meanEdge_)))
      for (int v : s_.corners(f)) facesAt[v].push_back(f);
    std::unordered_set<int> seen(front_.begin(), front_.end());
    std::vector<int> ring(front_.begin(), front_.end()), samples;
    for (int level = 0; level < options_.regression_rings; ++level) {
      std::vector<int> next;
      for (int v : ring)
        for (int f : facesAt[v])
          for (int c : s_.corners(f))
            if (seen.insert(c).second) next.push_back(c);
      samples.insert(samples.end(), next.begin(), next.end());
      ring = std::move(next);
    }
    std::vector<Point3> xs;
    std::vector<double> ys;
    const std::size_t most = std::size_t(options_.regression_max_samples);
    const std::size_t stride = std::max<std::size_t>(1, (samples.size() + most - 1) / most);
    for (std::size_t i = 0; i < samples.size(); i += stride) {
      const int v = samples[i];
      // Only vertices inside the surface (a closed fan: each neighbour on two
      // faces); a vertex whose faces were not all gathered fails this too.
      std::unordered_map<int, int> count;
      LaplacianRow row;
      Point3 normal(0, 0, 0);
      double area = 0;
      for (int f : facesAt[v]) {
        const Triangle t = s_.corners(f);
        int corner = 0;
        while (t[corner] != v) ++corner;
        for (int c : t)
          if (c != v) ++count[c];
        const Point3 &a = s_.point(t[0]), &b = s_.point(t[1]), &c = s_.point(t[2]);
        addTriangleToRow(row, {t[0], t[1], t[2]}, triangleWeights(a, b, c), corner);
        const Point3 fn = (b - a) ^ (c - a);
        normal += fn;
        area += fn.Norm() / 6;
      }
      bool closedFan = !count.empty();
      for (const auto& [c, k] : count) closedFan = closedFan && k == 2;
      if (!closedFan || !(area > 0) || !(normal.Norm() > 0)) continue;
      // Raised weights: one sliver in a scan's ring must not make its
      // vertex's curvature sample an outlier the regression then spreads.
      row.finish(kPositiveWeightFloor);
      Point3 sum(0, 0, 0);
      for (const auto& [c, w] : row.weights) sum += (s_.point(c) - s_.point(v)) * w;
      normal.Normalize();
      const double H = -(sum * normal) / (4 * area);
      if (!std::isfinite(H)) continue;
      xs.push_back(s_.point(v));
      ys.push_back(H);
    }
    report_.training_samples = xs.size();
    if (!model_.fit(xs, ys, centre, scale, options_.regression_gamma)) {
      report_.reason = "too few surface vertices around the hole to learn its curvature from";
      return false;
    }
    learnt_ = 1;
    return true;
  }

  // ---- Check and commit ------------------------------------------------------------

  // The patch's faces in mesh numbering: new vertices follow the surface's.
  std::vector<Triangle> meshTriangles(const Patch& p) const {
    const std::size_t base = s_.vertexCount();
    std::vector<Triangle> out;
    out.reserve(p.triangles.size());
    for (const Triangle& t : p.triangles) {
      Triangle g;
      for (int k = 0; k < 3; ++k)
        g[k] =
            std::size_t(t[k]) < n_ ? front_[std::size_t(t[k])] : int(base + std::size_t(t[k]) - n_);
      out.push_back(g);
    }
    return out;
  }

  // Rounds the new vertices as they will be stored; 1 if the patch would
  // make a pair of faces intersect (the check stops there), else 0 (and 0
  // when the check is off).
  std::size_t check(const Candidate& c, std::vector<Point3>& x) {
    for (std::size_t v = n_; v < x.size(); ++v) x[v] = s_.stored(x[v]);
    if (!options_.check_intersections) return 0;
    const auto clock = Clock::now();
    Bounds bounds;
    for (const Point3& p : x) bounds.add(p);
    for (int f : splitFaces_) bounds.add(s_.boundsOf(f));
    const std::vector<Point3> added(x.begin() + std::ptrdiff_t(n_), x.end());
    const std::size_t pairs = patchIntersections(s_, meshTriangles(c.patch), added, splitFaces_,
                                                 context_.facesNear(bounds), 1);
    context_.times.check += msSince(clock);
    return pairs;
  }

  void commit(const Candidate& c, const std::vector<Point3>& x, HoleFairing shaped,
              double residual) {
    const std::vector<Triangle> faces = meshTriangles(c.patch);
    s_.addPatch(std::vector<Point3>(x.begin() + std::ptrdiff_t(n_), x.end()), faces);
    for (std::size_t k = 0; k < n_; ++k) s_.setBorderFace(front_[(k + 1) % n_], front_[k], -1);
    report_.faces_added = faces.size();
    report_.vertices_added += x.size() - n_;
    report_.fairing = shaped;
    report_.fairing_residual = residual;
    report_.planar_domain = c.domain.planar;
  }

  // Why the hole got another shape, or another domain, than asked for.
  void explain(HoleFairing mode, const std::vector<Candidate>& candidates, std::string failed) {
    const std::string problem = problems(candidates);
    if (!problem.empty()) failed = problem + (failed.empty() ? "" : "; ") + failed;
    if (mode != options_.fairing || !failed.empty())
      report_.reason = "fell back: " + failed;
    else if (report_.fairing != mode)
      report_.reason = "fell back to biharmonic: " + report_.reason;
    else
      report_.reason.clear();
  }

  static std::string problems(const std::vector<Candidate>& candidates) {
    std::string out;
    for (const Candidate& c : candidates)
      if (!c.problem.empty())
        out += (out.empty() ? "" : "; ") + std::string(where(c.domain)) + c.problem;
    return out;
  }

  Surface& s_;
  const HoleFillOptions& options_;
  HoleContext& context_;
  const std::vector<int>& loop_;
  const std::vector<double>& edgeSizes_;  // per loop edge: the size the patch takes there
  const std::vector<int>& splitFaces_;
  HoleReport& report_;
  std::size_t n_ = 0;
  double meanEdge_ = 0;
  std::vector<int> front_;                     // the border, front order (mesh indices)
  std::vector<Point3> boundary_;               // its points
  std::unordered_map<int, int> local_;         // border vertex -> front index
  std::vector<std::vector<int>> fans_;         // the faces at each border vertex
  std::vector<std::pair<int, int>> existing_;  // border vertices joined by a mesh edge
  std::unordered_set<std::uint64_t> chords_;   // the same, as keys
  Point3 faceNormals_{0, 0, 0};
  Rim rim_;
  CurvatureModel model_;
  int learnt_ = -1;  // the curvature model: -1 not tried, 0 failed, 1 learnt
};

}  // namespace

bool fillHole(HoleContext& context, const std::vector<int>& loop, const std::vector<double>& sizes,
              const std::vector<int>& splitFaces, HoleReport& report) {
  return HoleFiller(context, loop, sizes, splitFaces, report).fill();
}

}  // namespace meshmend::holes
