// SPDX-License-Identifier: MIT
#pragma once
// Exact signs of the orientation determinants behind the closed triangle tests of geometry.cpp;
// not public API.
//
// Each sign is first taken from the plain double evaluation, which decides whenever its value is
// farther from zero than a bound on its rounding error (Shewchuk's first-stage bounds: 3 eps and
// 7 eps of the permanent, rounded up to 1e-15 here). Only the rest (touching, coplanar and
// collinear configurations, and values within rounding of them) is recomputed exactly: as a
// floating-point expansion, a sum of non-overlapping doubles whose sign is that of its largest
// term (J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
// Predicates", Discrete Comput. Geom. 18, 1997: Two-Sum, Grow-Expansion with zero elimination;
// the error of a product is exact by FMA). Fixed-size arrays: no heap, no exceptions.
//
// Exact for finite coordinates as long as no product of three coordinate differences overflows
// or underflows (build_tree refuses coordinates beyond 1e50; below about 1e-90 differences of
// distinct points could underflow). NaN gives some sign and never loops or overflows an array.
#include <cmath>

#include "boxtree/math.h"

namespace boxtree::detail {

// A sum of up to N non-overlapping doubles in increasing magnitude, without zeros.
template <int N>
struct Expansion {
  Real term[N];
  int size = 0;

  // Adds b exactly (Shewchuk's GROW-EXPANSION-ZEROELIM). Grows by at most one term.
  void add(Real b) {
    int kept = 0;
    Real q = b;
    for (int i = 0; i < size; ++i) {
      const Real sum = q + term[i];
      const Real b_virtual = sum - q;
      const Real error = (q - (sum - b_virtual)) + (term[i] - b_virtual);  // Two-Sum
      if (error != 0) term[kept++] = error;
      q = sum;
    }
    if (q != 0 || kept == 0) term[kept++] = q;
    size = kept;
  }
  int sign() const { return size == 0 ? 0 : (term[size - 1] > 0) - (term[size - 1] < 0); }
};

// a - b exactly, in at most two terms.
inline Expansion<2> exact_difference(Real a, Real b) {
  Expansion<2> e;
  e.add(a);
  e.add(-b);
  return e;
}

// x * y (times `factor`, +1 or -1) added exactly to `out`: every product of terms is a double
// plus its rounding error, itself a double (FMA). Adds 2 * x.size * y.size terms at most.
template <int N, int X, int Y>
void add_product(Expansion<N>& out, const Expansion<X>& x, const Expansion<Y>& y, Real factor = 1) {
  for (int i = 0; i < x.size; ++i)
    for (int j = 0; j < y.size; ++j) {
      const Real xi = factor * x.term[i];
      const Real p = xi * y.term[j];
      out.add(std::fma(xi, y.term[j], -p));
      out.add(p);
    }
}

// Sign of (b_i - a_i)(c_j - a_j) - (b_j - a_j)(c_i - a_i) on the coordinates i = drop + 1 and
// j = drop + 2 (mod 3): the orientation of abc seen along the axis `drop`, positive when
// counter-clockwise in the (i, j) plane.
inline int orient2d_sign(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const Real l = (b[i] - a[i]) * (c[j] - a[j]), r = (b[j] - a[j]) * (c[i] - a[i]);
  const Real det = l - r, bound = 1e-15 * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  // Both products exactly zero (a difference of doubles is zero only for equal doubles): a
  // triangle of an axis-aligned plane seen along another axis, e.g. every facet of a flat
  // terrain seen along x or y, which would otherwise take the expansion below every time.
  if ((b[i] == a[i] || c[j] == a[j]) && (b[j] == a[j] || c[i] == a[i])) return 0;
  Expansion<16> e;  // 2 products of 2 x 2 terms, 8 terms each
  add_product(e, exact_difference(b[i], a[i]), exact_difference(c[j], a[j]));
  add_product(e, exact_difference(b[j], a[j]), exact_difference(c[i], a[i]), -1);
  return e.sign();
}

// Sign of ((b - a) x (c - a)) . (d - a): positive when d lies on the side of the plane abc that
// the normal (b - a) x (c - a) points to, zero when the four points are coplanar.
inline int orient3d_sign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  Real det = 0, permanent = 0;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const Real l = u[i] * v[j], r = u[j] * v[i];
    det += w[k] * (l - r);
    permanent += std::abs(w[k]) * (std::abs(l) + std::abs(r));
  }
  const Real bound = 1e-15 * permanent;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  // Two equal points (shared corners: the common case here) give exactly zero.
  if (a == b || a == c || a == d || b == c || b == d || c == d) return 0;
  Expansion<192> total;  // 3 x (2 terms times 16): 64 terms each
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    Expansion<16> cross;  // component k of (b - a) x (c - a)
    add_product(cross, exact_difference(b[i], a[i]), exact_difference(c[j], a[j]));
    add_product(cross, exact_difference(b[j], a[j]), exact_difference(c[i], a[i]), -1);
    add_product(total, exact_difference(d[k], a[k]), cross);
  }
  return total.sign();
}

// orient3d_sign(a, b, c, d) for many d against one plane: the normal and the magnitudes of its
// products (for the error bound) are computed once.
// Holds references to the three corners: it lives within the caller's use of them.
// (b - a) x (c - a) as orient3d_sign rounds it, and |l| + |r| per component (the magnitudes of its
// two products, for the error bound of a sign taken with it).
inline void rounded_normal(const Vec3& a, const Vec3& b, const Vec3& c, Vec3& normal, Vec3& magnitude) {
  const Vec3 u = b - a, v = c - a;
  // Component k: l - r with l = u_i v_j, r = u_j v_i (i = k + 1, j = k + 2), as whole vectors.
  const Vec3 l(u.y() * v.z(), u.z() * v.x(), u.x() * v.y());
  const Vec3 r(u.z() * v.y(), u.x() * v.z(), u.y() * v.x());
  normal = l - r;
  magnitude = l.cwiseAbs() + r.cwiseAbs();
}

struct PlaneSide {
  const Vec3& a;
  const Vec3& b;
  const Vec3& c;
  Vec3 normal, magnitude;  // rounded_normal(a, b, c)
  PlaneSide(const Vec3& a_, const Vec3& b_, const Vec3& c_) : a(a_), b(b_), c(c_) {
    rounded_normal(a, b, c, normal, magnitude);
  }
  // An axis along which the triangle abc is certainly seen with non-zero area (a component of
  // the normal beyond its rounding bound, as orient2d_sign decides it), or -1 when none is certain:
  // then the triangle may be degenerate, which only the exact orient2d signs can tell.
  int certain_axis() const {
    for (int k = 0; k < 3; ++k)
      if (std::abs(normal[k]) > 1e-15 * magnitude[k]) return k;
    return -1;
  }
  int operator()(const Vec3& d) const {
    const Vec3 w = d - a;
    const Real det = w.x() * normal.x() + w.y() * normal.y() + w.z() * normal.z();
    const Real bound =
        1e-15 * (std::abs(w.x()) * magnitude.x() + std::abs(w.y()) * magnitude.y() + std::abs(w.z()) * magnitude.z());
    if (det > bound) return 1;
    if (det < -bound) return -1;
    return orient3d_sign(a, b, c, d);
  }
};

}  // namespace boxtree::detail
