// Placing a hole's patch vertices (Xu, Li, Tan 2013, §2.1, §2.3, §3.4): a
// least-squares Poisson solve over cotangent Laplacians. The smooth shapes
// minimise the squared Laplacians of the new vertices and of the boundary
// vertices, whose outer neighbours stay fixed: that joins the patch to the
// surface with a continuous tangent plane. Biharmonic: target Laplacians 0;
// regression: the paper's targets, learnt from the surface around the hole;
// harmonic: the membrane L x = 0 over the new vertices alone.
//
// Each system's ordering and symbolic factorisation are made once per patch
// (Eigen's sparse LDL^T, AMD ordering); the biharmonic system is factorised
// with the weights of the patch in its domain, then with those of the
// shapes that gives (the cotangent weights of a flat or membrane placement
// leave the shape further from the removed surface, and conjugate
// gradients preconditioned with the first factorisation took 10 to 60
// iterations, each as costly as a factorisation of a small patch); the
// regression's targets are further right-hand sides of the last
// factorisation.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <vector>

#include "common/repair/holes/front.h"

namespace meshmend::holes {

// A hole's patch in its domain: local vertices, the boundary's first.
struct Patch {
  std::size_t n = 0;                // boundary vertices: local 0 .. n-1, front order
  std::vector<Vec2> uv;             // every local vertex in the domain
  std::vector<double> height;       // over the plane (planar domains; else 0)
  std::vector<Triangle> triangles;  // local corners, counter-clockwise in the domain
  TrianglesAround around;           // the triangles at each local vertex
  std::size_t size() const { return uv.size(); }
};

// One vertex's cotangent Laplacian (Eq. 1-3): neighbours (keys) with weights
// omega_ij = cot alpha_ij + cot beta_ij, not normalised, and the vertex's
// mixed Voronoi area (Meyer et al. 2003; A of Eq. 4).
struct LaplacianRow {
  std::vector<std::pair<int, double>> weights;  // key, omega
  double total = 0;
  double area = 0;
  void add(int key, double omega);
  // Sums the weights, raising those below `floor` to it first.
  void finish(double floor = -INFINITY);
};

// The cotangents at the corners of a triangle, and the part of its area
// each corner's Laplacian counts (the Voronoi part in a non-obtuse
// triangle, else half the area to the obtuse corner and a quarter to each
// other one: Meyer et al. 2003).
struct TriangleWeights {
  std::array<double, 3> cot;
  std::array<double, 3> area;
};
TriangleWeights triangleWeights(const Point3& a, const Point3& b, const Point3& c);
// Adds a triangle (keys k[0..2]) to the row of its corner `corner`.
void addTriangleToRow(LaplacianRow& row, const std::array<int, 3>& k, const TriangleWeights& w,
                      int corner);

// The membrane, and the curvature samples of the regression, raise edge
// weights below this to it: obtuse triangles give negative cotangent sums,
// which would make the membrane's matrix indefinite. The least-squares
// systems are positive semi-definite whatever the signs and keep the true
// weights: raising them would bend a flat fan of slivers (CAD meshes),
// where the true weights give it a zero Laplacian.
constexpr double kPositiveWeightFloor = 0.05;

// The surface just outside a hole's boundary, which the fairing keeps fixed.
// Keys name vertices: a local index for the patch's, -(mesh index + 1) for
// the others.
struct Rim {
  // Per boundary vertex: whether it has a Laplacian row (its faces outside
  // form one fan; a vertex where several borders pass has none), and the
  // row's part from those faces.
  std::vector<char> hasRow;
  std::vector<LaplacianRow> outside;
  // Per boundary vertex: the sum of its outside faces' area vectors and a
  // third of their area (the regression's normal and area there).
  std::vector<Point3> outsideNormal;
  std::vector<double> outsideArea;
  std::function<Point3(int)> point;  // a mesh vertex's position
};

// Mean curvature learnt around a hole by least-squares SVM regression
// (Suykens 1999; the paper's §2.2, §3.3) over 3-D position, with Wendland's
// compactly supported C2 kernel (positive definite in 3-D): solves
// [0 1^T; 1 Omega + I/gamma] [b; a] = [0; y] (Eq. 14) and predicts
// f(x) = sum a_i K(x, x_i) + b (Eq. 15), within the 5th to 95th percentile
// of the curvatures it saw, so that noise learnt near the border does not
// extrapolate into a balloon in the middle of a large hole.
class CurvatureModel {
 public:
  // Samples: positions and mean curvatures; `centre` and `scale` normalise
  // the positions (the kernel's support is 2.5 scales).
  bool fit(const std::vector<Point3>& positions, const std::vector<double>& curvatures,
           const Point3& centre, double scale, double gamma);
  double predict(const Point3& p) const;

 private:
  std::vector<Eigen::Vector3d> centres_;
  Eigen::VectorXd alpha_;
  double bias_ = 0, inverseSupport_ = 1, low_ = 0, high_ = 0, scale_ = 1;
  Point3 centre_;
};

// Shapes one patch. Each method takes the positions of every local vertex
// (the boundary's fixed, the new ones where the last shape put them) and
// moves the new ones; the RMS residual of the system is returned as a
// length (sum of |omega| times the position error), 0 where exact.
class Fairing {
 public:
  Fairing(const Patch& patch, const Rim& rim);
  ~Fairing();
  Fairing(const Fairing&) = delete;
  Fairing& operator=(const Fairing&) = delete;

  // Minimal curvature: target Laplacians 0. Solved with the weights of the
  // patch in its domain (or, `fromShape`, where x has it), then twice with
  // those of the shape the last solve gave (kReweightings): one ordering
  // and symbolic analysis, the numbers factorised for each weight set.
  bool biharmonic(std::vector<Point3>& x, double& residual, bool fromShape = false) {
    return firstBiharmonic(x, residual, fromShape) && reweightBiharmonic(x, residual);
  }
  // Its stages: the first solve (the system analysed and factorised), and
  // the solves with the weights of each shape in turn.
  bool firstBiharmonic(std::vector<Point3>& x, double& residual, bool fromShape = false);
  bool reweightBiharmonic(std::vector<Point3>& x, double& residual);
  // The paper's: the Laplacians the model predicts at each row's vertex
  // (-4 A H n), a few rounds (normals and areas from the last shape); the
  // biharmonic shape first, with its system (factorised once for both).
  bool regression(std::vector<Point3>& x, const CurvatureModel& model, double& residual,
                  bool fromShape = false);
  // The membrane L x = 0 over the new vertices, weights from x as given.
  bool harmonic(std::vector<Point3>& x, double& residual);
  // A uniform membrane (every edge weight 1, a Tutte embedding): where the
  // new vertices go when nothing better is known (a disk domain's flat patch).
  bool uniform(std::vector<Point3>& x);

 private:
  struct System;
  struct Membrane;
  bool membrane(std::vector<Point3>& x, bool uniformWeights, double& residual);
  void rowOf(int v, const std::vector<TriangleWeights>& weights, LaplacianRow& row,
             double floor = -INFINITY) const;
  std::vector<TriangleWeights> weightsAt(const std::vector<Point3>& x) const;
  Point3 fixedPosition(int key, const std::vector<Point3>& x) const {
    return key >= 0 ? x[std::size_t(key)] : rim_.point(-key - 1);
  }
  // The system's rows with the given triangle weights (its pattern the
  // first time), fixed positions from x; the normal matrix refilled.
  void assemble(const std::vector<Point3>& x, const std::vector<TriangleWeights>& weights);
  Eigen::MatrixXd rightHandSide(const Eigen::MatrixXd& delta) const;
  // Solves for the new vertices given the target Laplacians delta (rows x
  // 3), starting from x; returns the RMS residual as a length, or -1.
  double solve(const Eigen::MatrixXd& delta, std::vector<Point3>& x) const;
  std::pair<Point3, double> normalAndArea(int v, const std::vector<Point3>& x) const;

  const Patch& patch_;
  const Rim& rim_;
  std::vector<int> rows_;  // the least-squares rows: new vertices, then boundary ones
  // Solves with the weights of the last shape after the first: the
  // discrete Laplacian then measures the shape it describes. One more
  // made the mean distance to the removed surface of the fidelity set
  // smaller on 12 of 22 holes and larger on 7 (docs/BENCHMARKS.md).
  static constexpr int kReweightings = 2;
  std::unique_ptr<System> system_;
};

}  // namespace meshmend::holes
