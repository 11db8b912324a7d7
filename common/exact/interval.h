#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "common/base/mesh.h"

namespace meshmend {

// Interval arithmetic on doubles with outward rounding: the exact result of
// every operation on exact values inside the operands lies inside the result.
// Used to bound the error of approximations of constructed points; a sign is
// certain when the interval excludes zero.
//
// Each operation rounds to nearest, so its exact result lies within
// |x| 2^-53 (plus half the smallest subnormal) of the computed x; widening
// by |x| 2^-51 plus the smallest subnormal encloses it with room to spare.

constexpr double kRelative = 0x1p-51;
constexpr double kTiny = 0x1p-1074;

inline double down(double x) {
  return x - (std::fabs(x) * kRelative + kTiny);
}
inline double up(double x) {
  return x + (std::fabs(x) * kRelative + kTiny);
}

struct Interval {
  double lo, hi;
  Interval() : lo(0), hi(0) {}
  Interval(double x) : lo(x), hi(x) {}  // NOLINT: doubles are exact intervals
  Interval(double l, double h) : lo(l), hi(h) {}
  bool positive() const { return lo > 0; }
  bool negative() const { return hi < 0; }
};

inline Interval operator+(const Interval& a, const Interval& b) {
  return {down(a.lo + b.lo), up(a.hi + b.hi)};
}
inline Interval operator-(const Interval& a, const Interval& b) {
  return {down(a.lo - b.hi), up(a.hi - b.lo)};
}
inline Interval operator*(const Interval& a, const Interval& b) {
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  return {down(std::min({p[0], p[1], p[2], p[3]})), up(std::max({p[0], p[1], p[2], p[3]}))};
}
inline Interval operator/(const Interval& a, const Interval& b) {
  if (!(b.lo > 0 || b.hi < 0)) return {-INFINITY, INFINITY};
  const double q[4] = {a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi};
  return {down(std::min({q[0], q[1], q[2], q[3]})), up(std::max({q[0], q[1], q[2], q[3]}))};
}
inline Interval intersect(const Interval& a, double lo, double hi) {
  return {std::max(a.lo, lo), std::min(a.hi, hi)};
}

using Interval3 = std::array<Interval, 3>;

inline Interval3 intervalOf(const Point3& p) {
  return {Interval(p[0]), Interval(p[1]), Interval(p[2])};
}

}  // namespace meshmend
