// Exact floating-point expansion arithmetic (Shewchuk, "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997): an
// expansion is a sum of non-overlapping doubles, smallest first, and
// represents its value exactly as long as nothing overflows or underflows.
// Used by predicates.cpp as the exact stage after the floating-point filter;
// no allocation, so it is far cheaper than rationals.
#pragma once

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "common/base/mesh.h"

namespace meshmend::expansion {

inline void twoSum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

inline void fastTwoSum(double a, double b, double& x, double& y) {  // needs |a| >= |b|
  x = a + b;
  y = b - (x - a);
}

inline void twoDiff(double a, double b, double& x, double& y) {
  x = a - b;
  const double bv = a - x, av = x + bv;
  y = (a - av) + (bv - b);
}

inline void twoProduct(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

// h = e + f; returns the length of h (zero components dropped). h must not
// alias e or f and must hold elen + flen doubles.
inline int sum(int elen, const double* e, int flen, const double* f, double* h) {
  int ei = 0, fi = 0, hi = 0;
  double q, qn, hh;
  // Start with the smaller-magnitude head.
  if (ei < elen && (fi >= flen || (f[fi] > e[ei]) == (f[fi] > -e[ei]))) {
    q = e[ei++];
  } else {
    q = f[fi++];
  }
  while (ei < elen && fi < flen) {
    if ((f[fi] > e[ei]) == (f[fi] > -e[ei])) {
      twoSum(q, e[ei++], qn, hh);
    } else {
      twoSum(q, f[fi++], qn, hh);
    }
    q = qn;
    if (hh != 0.0) h[hi++] = hh;
  }
  for (; ei < elen; ++ei) {
    twoSum(q, e[ei], qn, hh);
    q = qn;
    if (hh != 0.0) h[hi++] = hh;
  }
  for (; fi < flen; ++fi) {
    twoSum(q, f[fi], qn, hh);
    q = qn;
    if (hh != 0.0) h[hi++] = hh;
  }
  if (q != 0.0 || hi == 0) h[hi++] = q;
  return hi;
}

// h = b * e; returns the length of h (at most 2 * elen).
inline int scale(int elen, const double* e, double b, double* h) {
  double q, hh, p1, p0, s;
  int hi = 0;
  twoProduct(e[0], b, q, hh);
  if (hh != 0.0) h[hi++] = hh;
  for (int i = 1; i < elen; ++i) {
    twoProduct(e[i], b, p1, p0);
    twoSum(q, p0, s, hh);
    if (hh != 0.0) h[hi++] = hh;
    fastTwoSum(p1, s, q, hh);
    if (hh != 0.0) h[hi++] = hh;
  }
  if (q != 0.0 || hi == 0) h[hi++] = q;
  return hi;
}

// h = e * f for short f (at most 2 components); h holds 2 * elen * flen doubles.
inline int product(int elen, const double* e, int flen, const double* f, double* h) {
  if (flen == 1) return scale(elen, e, f[0], h);
  double a[32], b[32];
  const int al = scale(elen, e, f[0], a);
  const int bl = scale(elen, e, f[1], b);
  return sum(al, a, bl, b, h);
}

// a - b as an exact expansion of one or two components.
inline int difference(double a, double b, double* h) {
  double x, y;
  twoDiff(a, b, x, y);
  if (y == 0.0) {
    h[0] = x;
    return 1;
  }
  h[0] = y;
  h[1] = x;
  return 2;
}

inline int signOf(int len, const double* e) {
  const double top = e[len - 1];
  return (top > 0) - (top < 0);
}

// The products stay exact (no underflow or overflow) when every non-zero
// value has a magnitude within [1e-60, 1e60].
inline bool safe(std::initializer_list<double> values) {
  for (double v : values) {
    const double m = std::fabs(v);
    if (m != 0.0 && (m < 1e-60 || m > 1e60)) return false;
  }
  return true;
}

// Exact sign of (ax-cx)(by-cy) - (ay-cy)(bx-cx).
inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  double acx[2], bcy[2], acy[2], bcx[2], left[8], right[8], det[16];
  const int n1 = difference(ax, cx, acx), n2 = difference(by, cy, bcy);
  const int n3 = difference(ay, cy, acy), n4 = difference(bx, cx, bcx);
  const int ll = product(n1, acx, n2, bcy, left);
  const int rl = product(n3, acy, n4, bcx, right);
  for (int i = 0; i < rl; ++i) right[i] = -right[i];
  return signOf(sum(ll, left, rl, right, det), det);
}

// Exact sign of det[b-a, c-a, d-a], expanded along d's row.
inline int orient3d(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  double B[3][2], C[3][2], D[3][2];
  int nb[3], nc[3], nd[3];
  for (int k = 0; k < 3; ++k) {
    nb[k] = difference(b[k], a[k], B[k]);
    nc[k] = difference(c[k], a[k], C[k]);
    nd[k] = difference(d[k], a[k], D[k]);
  }
  double total[192], next[192];
  int tl = 0;
  for (int k = 0; k < 3; ++k) {
    // D[k] * (B[u] C[v] - B[v] C[u]), (u, v) the other two axes in cyclic order
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    double p[8], q[8], minor[16], term[64];
    const int pl = product(nb[u], B[u], nc[v], C[v], p);
    const int ql = product(nb[v], B[v], nc[u], C[u], q);
    for (int i = 0; i < ql; ++i) q[i] = -q[i];
    const int ml = sum(pl, p, ql, q, minor);
    const int l = product(ml, minor, nd[k], D[k], term);
    if (tl == 0) {
      std::copy(term, term + l, total);
      tl = l;
    } else {
      tl = sum(tl, total, l, term, next);
      std::copy(next, next + tl, total);
    }
  }
  return signOf(tl, total);
}

}  // namespace meshmend::expansion
