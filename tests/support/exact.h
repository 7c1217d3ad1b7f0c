// SPDX-License-Identifier: MIT
#pragma once
// Exact references for the geometry tests: rational arithmetic on __int128 and an exact LP
// feasibility oracle ("do the convex hulls of two point sets intersect?"). Exact for the
// short dyadic coordinates the tests use, so touching and coplanar cases are decided exactly.
// Shared by tests/test_geometry.cpp and tests/test_volumes.cpp.
#include <array>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#include "boxtree/mesh.h"

namespace boxtree::test {

// Exact rational arithmetic and an exact LP feasibility oracle

using Int = __int128;

inline Int abs_int(Int x) { return x < 0 ? -x : x; }
inline Int gcd_int(Int a, Int b) {
  a = abs_int(a);
  b = abs_int(b);
  while (b != 0) {
    const Int r = a % b;
    a = b;
    b = r;
  }
  return a;
}
inline Int mul_checked(Int a, Int b) {
  Int r;
  if (__builtin_mul_overflow(a, b, &r)) throw std::overflow_error("rational overflow");
  return r;
}
inline Int add_checked(Int a, Int b) {
  Int r;
  if (__builtin_add_overflow(a, b, &r)) throw std::overflow_error("rational overflow");
  return r;
}

struct Rational {
  Int num = 0;
  Int den = 1;
  Rational() = default;
  Rational(long long n) : num(n) {}  // NOLINT: implicit on purpose, integers are rationals
  static Rational of(Int n, Int d) {
    if (d < 0) {
      n = -n;
      d = -d;
    }
    const Int g = gcd_int(n, d);
    Rational r;
    r.num = g > 1 ? n / g : n;
    r.den = g > 1 ? d / g : d;
    return r;
  }
  int sign() const { return num > 0 ? 1 : (num < 0 ? -1 : 0); }
  double to_double() const { return static_cast<double>(num) / static_cast<double>(den); }
};

inline Rational operator-(const Rational& a) { return Rational::of(-a.num, a.den); }
inline Rational operator+(const Rational& a, const Rational& b) {
  const Int g = gcd_int(a.den, b.den);
  return Rational::of(add_checked(mul_checked(a.num, b.den / g), mul_checked(b.num, a.den / g)),
                      mul_checked(a.den / g, b.den));
}
inline Rational operator-(const Rational& a, const Rational& b) { return a + (-b); }
inline Rational operator*(const Rational& a, const Rational& b) {
  const Int g1 = std::max<Int>(1, gcd_int(a.num, b.den));
  const Int g2 = std::max<Int>(1, gcd_int(b.num, a.den));
  return Rational::of(mul_checked(a.num / g1, b.num / g2), mul_checked(a.den / g2, b.den / g1));
}
inline Rational operator/(const Rational& a, const Rational& b) { return a * Rational::of(b.den, b.num); }
inline bool operator==(const Rational& a, const Rational& b) { return a.num == b.num && a.den == b.den; }
inline bool operator<(const Rational& a, const Rational& b) { return (a - b).sign() < 0; }

// The exact value of a double that is a short dyadic (all test data is).
inline Rational exact(double x) {
  for (int k = 0; k <= 40; ++k) {
    const double s = std::ldexp(x, k);
    if (s == std::floor(s) && std::abs(s) < 9e15) return Rational::of(static_cast<long long>(s), Int(1) << k);
  }
  throw std::invalid_argument("not a short dyadic: " + std::to_string(x));
}

using RPoint = std::array<Rational, 3>;
using RMat = std::array<std::array<Rational, 3>, 3>;

inline RPoint exact(const Vec3& v) { return {exact(v.x()), exact(v.y()), exact(v.z())}; }
inline Vec3 to_double(const RPoint& p) { return {p[0].to_double(), p[1].to_double(), p[2].to_double()}; }
inline Mat3 to_double(const RMat& m) {
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j].to_double();
  }
  return r;
}
inline RMat multiply(const RMat& a, const RMat& b) {
  RMat r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
  }
  return r;
}
inline RPoint rotate(const RMat& m, const RPoint& p) {
  return {m[0][0] * p[0] + m[0][1] * p[1] + m[0][2] * p[2], m[1][0] * p[0] + m[1][1] * p[1] + m[1][2] * p[2],
          m[2][0] * p[0] + m[2][1] * p[1] + m[2][2] * p[2]};
}
inline RPoint plus(const RPoint& a, const RPoint& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }

// Is {x >= 0 : A x = b} non-empty? Phase 1 of the simplex method (minimize the sum of artificial
// variables) with Bland's rule, which cannot cycle; exact, so touching counts.
inline bool lp_feasible(const std::vector<std::vector<Rational>>& a, const std::vector<Rational>& b) {
  const std::size_t m = a.size();
  const std::size_t n = a[0].size();
  const std::size_t cols = n + m;  // original variables, then one artificial per row
  std::vector<std::vector<Rational>> t(m, std::vector<Rational>(cols));
  std::vector<Rational> rhs(m);
  std::vector<std::size_t> basis(m);
  for (std::size_t i = 0; i < m; ++i) {
    const Rational flip = b[i].sign() < 0 ? Rational(-1) : Rational(1);
    for (std::size_t j = 0; j < n; ++j) t[i][j] = a[i][j] * flip;
    t[i][n + i] = 1;
    rhs[i] = b[i] * flip;
    basis[i] = n + i;
  }
  // Objective w = sum of artificials = W + sum_j cost_j x_j over the non-basic x_j; value = -W.
  std::vector<Rational> cost(cols);
  Rational value;
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < n; ++j) cost[j] = cost[j] - t[i][j];
    value = value - rhs[i];
  }
  for (;;) {
    std::size_t enter = cols;
    for (std::size_t j = 0; j < cols && enter == cols; ++j) {
      if (cost[j].sign() < 0) enter = j;
    }
    if (enter == cols) break;
    std::size_t leave = m;
    Rational best;
    for (std::size_t i = 0; i < m; ++i) {
      if (t[i][enter].sign() <= 0) continue;
      const Rational ratio = rhs[i] / t[i][enter];
      if (leave == m || ratio < best || (ratio == best && basis[i] < basis[leave])) {
        leave = i;
        best = ratio;
      }
    }
    if (leave == m) break;  // unbounded: impossible in phase 1
    const Rational pivot = t[leave][enter];
    for (std::size_t j = 0; j < cols; ++j) t[leave][j] = t[leave][j] / pivot;
    rhs[leave] = rhs[leave] / pivot;
    for (std::size_t i = 0; i < m; ++i) {
      const Rational f = t[i][enter];
      if (i == leave || f.sign() == 0) continue;
      for (std::size_t j = 0; j < cols; ++j) t[i][j] = t[i][j] - f * t[leave][j];
      rhs[i] = rhs[i] - f * rhs[leave];
    }
    const Rational f = cost[enter];
    for (std::size_t j = 0; j < cols; ++j) cost[j] = cost[j] - f * t[leave][j];
    value = value - f * rhs[leave];
    basis[leave] = enter;
  }
  return value.sign() == 0;
}

// Exact: do the convex hulls of two finite point sets intersect?
inline bool hulls_intersect(const std::vector<RPoint>& p, const std::vector<RPoint>& q) {
  const std::size_t n = p.size() + q.size();
  std::vector<std::vector<Rational>> a(5, std::vector<Rational>(n));
  std::vector<Rational> b(5);
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int k = 0; k < 3; ++k) a[k][i] = p[i][k];
    a[3][i] = 1;
  }
  for (std::size_t j = 0; j < q.size(); ++j) {
    for (int k = 0; k < 3; ++k) a[k][p.size() + j] = -q[j][k];
    a[4][p.size() + j] = 1;
  }
  b[3] = 1;
  b[4] = 1;
  return lp_feasible(a, b);
}

}  // namespace boxtree::test
