#include "common/repair/holes/domain.h"

#include <Eigen/Dense>

namespace meshmend::holes {

namespace {

bool projectOnPlane(const std::vector<Point3>& pts, Point3 origin, Point3 normal, Domain& d) {
  normal.Normalize();
  auto [u, v] = tangentFrame(normal);
  d.uv.clear();
  d.height.clear();
  for (const Point3& p : pts) {
    const Point3 r = p - origin;
    d.uv.push_back({r * u, r * v});
    d.height.push_back(r * normal);
  }
  if (signedArea(d.uv) < 0) {  // the front must run counter-clockwise
    v = -v;
    normal = -normal;
    for (Vec2& q : d.uv) q.y = -q.y;
    for (double& h : d.height) h = -h;
  }
  if (!isSimplePolygon(d.uv)) return false;
  d.planar = true;
  d.origin = origin;
  d.U = u;
  d.V = v;
  d.N = normal;
  return true;
}

}  // namespace

Domain diskDomain(const std::vector<Point3>& pts) {
  Domain d;
  d.planar = false;
  double perimeter = 0;
  std::vector<double> at;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    at.push_back(perimeter);
    perimeter += (pts[(i + 1) % pts.size()] - pts[i]).Norm();
  }
  const double radius = perimeter / (2 * M_PI);
  for (double s : at) {
    const double phi = 2 * M_PI * s / perimeter;
    d.uv.push_back({radius * std::cos(phi), radius * std::sin(phi)});
  }
  return d;
}

bool planeDomain(const std::vector<Point3>& pts, const Point3& meanFaceNormal, Domain& d) {
  Point3 centroid(0, 0, 0);
  for (const Point3& p : pts) centroid += p;
  centroid /= double(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Point3& p : pts) {
    const Eigen::Vector3d r(p[0] - centroid[0], p[1] - centroid[1], p[2] - centroid[2]);
    cov += r * r.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
  const Eigen::Vector3d e = eigen.eigenvectors().col(0);
  const Point3 fitted(e[0], e[1], e[2]);
  if (projectOnPlane(pts, centroid, fitted, d)) return true;
  if (meanFaceNormal.Norm() > 0 && projectOnPlane(pts, centroid, meanFaceNormal, d)) return true;
  // The boundary's vector area (half the sum of p_i x p_i+1): the direction
  // in which the loop encloses the most area, often simple where the
  // best-fit plane folds the loop over itself.
  Point3 area(0, 0, 0);
  for (std::size_t i = 0; i < pts.size(); ++i)
    area += (pts[i] - centroid) ^ (pts[(i + 1) % pts.size()] - centroid);
  if (area.Norm() > 0 && projectOnPlane(pts, centroid, area, d)) return true;
  // Directions tilted around those by up to 60 degrees.
  for (const Point3& axis : {area, meanFaceNormal, fitted}) {
    if (!(axis.Norm() > 0)) continue;
    const Point3 n = axis / axis.Norm();
    const auto [u, v] = tangentFrame(n);
    for (double tilt : {15.0, 30.0, 45.0, 60.0})
      for (int k = 0; k < 8; ++k) {
        const double t = tilt * M_PI / 180, a = k * M_PI / 4;
        const Point3 dir = n * std::cos(t) + (u * std::cos(a) + v * std::sin(a)) * std::sin(t);
        if (projectOnPlane(pts, centroid, dir, d)) return true;
      }
  }
  return false;
}

}  // namespace meshmend::holes
