// SPDX-License-Identifier: MIT
// Tests of the fitting primitives (detail/fit.h) against independent references:
//  * principal axes: point sets whose scatter matrix is known exactly (symmetric stars along a
//    rotated frame), and degenerate sets (a point, a segment, a plane);
//  * convex hull: a brute-force extreme-point test in exact integer arithmetic (__int128), on
//    small integer grids full of duplicates and collinear points and on Fibonacci-like points
//    whose orientation is +-1 against products near 2^80, where plain doubles get it wrong;
//  * minimum-area rectangle: the best rectangle over every direction defined by two input points
//    (a superset of the hull-edge directions) and over 10,000 random directions;
//  * minimum-area triangles: a numerical optimizer over the three side-normal angles (each side
//    the support line of the hull with that normal; random sampling, then pattern search), and
//    for the isosceles triangle a dense grid over (axis angle, base angle) refined the same way.
//    A sampled optimum is an upper bound on the true minimum, so the fit must not exceed it; for
//    the general triangle the optimizer also converges, so the two must agree. Known values:
//    a triangle is its own minimum, parallelograms need twice their area, the regular hexagon
//    3/2 of its area;
//  * clusters of near-duplicates, as the volume fits produce them (a box or prism seen along its
//    own axis): the face (base triangle) must come back, and brute force must agree;
//  * rounding: offsets of 1e6-1e8, spreads of 1e-9, nearly collinear sets.
// Containment is checked in long double: the fits pad their shapes by a few ulps, more than
// the rounding of a long double orientation test.
// BOXTREE_TEST_SCALE (a positive factor, default 1) scales the number of random cases.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "boxtree/detail/fit.h"
#include "support/random.h"

namespace boxtree::detail {
namespace {

using test::Random;
using test::scaled;

constexpr Real kPi = 3.14159265358979323846;
constexpr Real kInf = std::numeric_limits<Real>::infinity();

std::string str(const Vec2& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.17g, %.17g)", p.x(), p.y());
  return text;
}

std::string str(const std::vector<Vec2>& points) {
  std::string s = "{";
  for (const Vec2& p : points) s += str(p) + " ";
  return s + "}";
}

// A Vec2 of two draws, y first: the order gcc gave the former Vec2(draw(), draw()) (see
// tests/support/random.h).
template <class Draw>
Vec2 vec2_y_first(Draw&& draw) {
  const Real y = draw();
  const Real x = draw();
  return {x, y};
}

Real cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// ------------------------------------------------------------------------------------------
// Random point sets

enum class Cloud { square, thin, circle, grid, clustered };

std::vector<Vec2> random_cloud(Random& r, Cloud kind, int count) {
  std::vector<Vec2> points;
  const Real angle = r.uniform(0, 2 * kPi);
  const Eigen::Rotation2D<Real> rotation(angle);
  for (int i = 0; i < count; ++i) {
    switch (kind) {
      case Cloud::square: {
        const Real y = r.uniform(-1, 1);  // y first: see tests/support/random.h
        const Real x = r.uniform(-1, 1);
        points.emplace_back(x, y);
        break;
      }
      case Cloud::thin: {
        const Real y = r.uniform(-0.02, 0.02);
        const Real x = r.uniform(-1, 1);
        points.push_back(rotation * Vec2(x, y));
        break;
      }
      case Cloud::circle: {
        const Real a = r.uniform(0, 2 * kPi);
        points.emplace_back(std::cos(a), 0.5 * std::sin(a));
        break;
      }
      case Cloud::grid: {
        const int y = r.integer(0, 4);
        const int x = r.integer(0, 4);
        points.emplace_back(x, y);
        break;
      }
      case Cloud::clustered: {
        const Real y = 3 * r.normal();
        const Real x = r.normal();
        points.push_back(Vec2(x, y));
        break;
      }
    }
  }
  return points;
}

// ------------------------------------------------------------------------------------------
// Containment checks (long double, independent of the library's predicates)

long double orient(const Vec2& a, const Vec2& b, const Vec2& p) {
  const long double ax = a.x(), ay = a.y(), bx = b.x(), by = b.y(), px = p.x(), py = p.y();
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// For a non-degenerate triangle: counter-clockwise and every point on the inner side of every
// side. For a degenerate one (the fits return those only for exactly collinear input, as the
// segment and its rounded midpoint): every point on the closed segment spanned by the corners.
::testing::AssertionResult triangle_encloses(const Triangle2& t, const std::vector<Vec2>& points) {
  const auto& c = t.corners;
  if (!(c[0].allFinite() && c[1].allFinite() && c[2].allFinite()))
    return ::testing::AssertionFailure() << "non-finite corner";
  const Real size = std::max({(c[1] - c[0]).norm(), (c[2] - c[1]).norm(), (c[0] - c[2]).norm()});
  const bool degenerate = std::abs(orient(c[0], c[1], c[2])) <= 1e-14 * size * size;
  if (!degenerate && orient(c[0], c[1], c[2]) > 0) {
    for (const Vec2& p : points)
      for (int k = 0; k < 3; ++k)
        if (orient(c[k], c[(k + 1) % 3], p) < 0)
          return ::testing::AssertionFailure()
                 << "point " << str(p) << " outside side " << k << " of " << str(std::vector<Vec2>(c.begin(), c.end()));
    return ::testing::AssertionSuccess();
  }
  if (!degenerate) return ::testing::AssertionFailure() << "clockwise triangle";
  // Degenerate: the two corners farthest apart span the segment.
  Vec2 a = c[0], b = c[1];
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if ((c[j] - c[i]).squaredNorm() > (b - a).squaredNorm()) a = c[i], b = c[j];
  for (const Vec2& p : points) {
    if (orient(a, b, p) != 0)
      return ::testing::AssertionFailure() << "point " << str(p) << " off the degenerate triangle";
    if ((p - a).dot(b - a) < 0 || (p - b).dot(a - b) < 0)
      return ::testing::AssertionFailure() << "point " << str(p) << " beyond its ends";
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult rectangle_encloses(const Rectangle2& r, const std::vector<Vec2>& points) {
  if (std::abs(r.axis_u.norm() - 1) > 1e-15) return ::testing::AssertionFailure() << "axis_u not unit";
  if (!(r.half_u >= 0 && r.half_v >= 0)) return ::testing::AssertionFailure() << "negative extent";
  const Vec2 v = r.axis_v();
  for (const Vec2& p : points) {
    // The evaluation a caller would write, in double ...
    if (std::abs((p - r.center).dot(r.axis_u)) > r.half_u || std::abs((p - r.center).dot(v)) > r.half_v)
      return ::testing::AssertionFailure() << "point " << str(p) << " outside (double)";
    // ... and a more accurate one.
    const long double dx = static_cast<long double>(p.x()) - r.center.x(),
                      dy = static_cast<long double>(p.y()) - r.center.y();
    if (std::abs(dx * r.axis_u.x() + dy * r.axis_u.y()) > r.half_u || std::abs(dx * v.x() + dy * v.y()) > r.half_v)
      return ::testing::AssertionFailure() << "point " << str(p) << " outside (long double)";
  }
  return ::testing::AssertionSuccess();
}

Real side_length(const Triangle2& t, int k) { return (t.corners[(k + 1) % 3] - t.corners[k]).norm(); }

// Two sides of equal length, up to 1e-9 of the longest side plus what rounding the corners to
// doubles can do: a corner moved by delta changes a side by delta, and where two sides meet at
// a small angle their intersection moves by (side shift) / sin(angle). Far from the origin
// (1e6 with sides of 1e-8) or for needle-thin triangles this is all the precision there is.
::testing::AssertionResult is_isosceles(const Triangle2& t) {
  const Real a = side_length(t, 0), b = side_length(t, 1), c = side_length(t, 2);
  const Real longest = std::max({a, b, c});
  const Real best = std::min({std::abs(a - b), std::abs(b - c), std::abs(c - a)});
  Real magnitude = 0;
  for (const Vec2& corner : t.corners) magnitude = std::max(magnitude, corner.cwiseAbs().maxCoeff());
  const Real second = a + b + c - longest - std::min({a, b, c});
  const Real smallest_sine = longest > 0 ? 2 * t.area() / (longest * second) : 1;
  const Real rounding =
      64 * std::numeric_limits<Real>::epsilon() * (magnitude + longest) / std::max(smallest_sine, 1e-300);
  if (best <= 1e-9 * longest + rounding) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "sides " << a << ", " << b << ", " << c << " (rounding allowance " << rounding
                                       << ")";
}

// ------------------------------------------------------------------------------------------
// Brute-force references

// Area of the triangle whose sides are the support lines of `hull` with outward normals at the
// given angles; infinite if they do not bound a triangle.
Real support_triangle_area(const std::vector<Vec2>& hull, std::array<Real, 3> angle) {
  for (Real& a : angle) a = a - 2 * kPi * std::floor(a / (2 * kPi));
  std::sort(angle.begin(), angle.end());
  std::array<Vec2, 3> n;
  std::array<Real, 3> h;
  for (int k = 0; k < 3; ++k) {
    n[k] = Vec2(std::cos(angle[k]), std::sin(angle[k]));
    h[k] = -kInf;
    for (const Vec2& p : hull) h[k] = std::max(h[k], n[k].dot(p));
  }
  // Corners, then the shoelace formula.
  std::array<Vec2, 3> c;
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    const Real det = cross(n[k], n[j]);
    if (!(det > 1e-12)) return kInf;
    c[k] = Vec2((h[k] * n[j].y() - h[j] * n[k].y()) / det, (n[k].x() * h[j] - n[j].x() * h[k]) / det);
  }
  const Real doubled = cross(c[1] - c[0], c[2] - c[0]);
  return doubled > 0 ? doubled / 2 : kInf;
}

// Pattern search: from `start`, try steps along every direction in `directions`, halving the
// step when none improves. Works on the piecewise-smooth area functions well enough for an
// upper bound that, started from a dense sample, lands on the optimum.
template <int N, class F>
Real pattern_search(F f, std::array<Real, N> x, const std::vector<std::array<Real, N>>& directions, Real step) {
  Real best = f(x);
  while (step > 1e-13) {
    bool improved = false;
    for (const auto& d : directions) {
      std::array<Real, N> y = x;
      for (int k = 0; k < N; ++k) y[k] += step * d[k];
      const Real value = f(y);
      if (value < best) {
        best = value;
        x = y;
        improved = true;
        break;
      }
    }
    if (!improved) step /= 2;
  }
  return best;
}

template <int N>
std::vector<std::array<Real, N>> search_directions(Random& r, int random_count) {
  std::vector<std::array<Real, N>> directions;
  for (int k = 0; k < N; ++k)
    for (const Real sign : {1.0, -1.0}) {
      std::array<Real, N> d{};
      d[k] = sign;
      directions.push_back(d);
    }
  for (int i = 0; i < random_count; ++i) {
    std::array<Real, N> d;
    for (Real& x : d) x = r.normal();
    directions.push_back(d);
    for (Real& x : d) x = -x;
    directions.push_back(d);
  }
  return directions;
}

Real brute_min_triangle_area(const std::vector<Vec2>& hull, Random& r) {
  auto f = [&](const std::array<Real, 3>& a) { return support_triangle_area(hull, a); };
  std::vector<std::pair<Real, std::array<Real, 3>>> samples;
  for (int i = 0; i < 20000; ++i) {
    const std::array<Real, 3> a = {r.uniform(0, 2 * kPi), r.uniform(0, 2 * kPi), r.uniform(0, 2 * kPi)};
    samples.emplace_back(f(a), a);
  }
  std::partial_sort(samples.begin(), samples.begin() + 8, samples.end(),
                    [](const auto& x, const auto& y) { return x.first < y.first; });
  const auto directions = search_directions<3>(r, 12);
  Real best = kInf;
  for (int i = 0; i < 8; ++i) best = std::min(best, pattern_search<3>(f, samples[i].second, directions, 0.05));
  return best;
}

Real isosceles_area(const std::vector<Vec2>& hull, Real theta, Real beta) {
  if (!(beta > 0 && beta < kPi / 2)) return kInf;
  return support_triangle_area(hull, {theta + kPi, theta - beta, theta + beta});
}

Real brute_min_isosceles_area(const std::vector<Vec2>& hull, Random& r) {
  auto f = [&](const std::array<Real, 2>& x) { return isosceles_area(hull, x[0], x[1]); };
  constexpr int kTheta = 2048, kBeta = 512;
  std::vector<std::pair<Real, std::array<Real, 2>>> samples;
  for (int i = 0; i < kTheta; ++i)
    for (int j = 1; j < kBeta; ++j) {
      const std::array<Real, 2> x = {2 * kPi * i / kTheta, kPi / 2 * j / kBeta};
      samples.emplace_back(f(x), x);
    }
  std::partial_sort(samples.begin(), samples.begin() + 16, samples.end(),
                    [](const auto& x, const auto& y) { return x.first < y.first; });
  const auto directions = search_directions<2>(r, 8);
  Real best = kInf;
  for (int i = 0; i < 16; ++i)
    best = std::min(best, pattern_search<2>(f, samples[i].second, directions, 2 * kPi / kTheta));
  return best;
}

// Hull vertices by brute force, exactly: points are integers (given as doubles) up to 2^52,
// so differences fit in 64 bits and orientation products in 128.
using Int = __int128;
int exact_orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Int abx = static_cast<Int>(static_cast<long long>(b.x()) - static_cast<long long>(a.x()));
  const Int aby = static_cast<Int>(static_cast<long long>(b.y()) - static_cast<long long>(a.y()));
  const Int acx = static_cast<Int>(static_cast<long long>(c.x()) - static_cast<long long>(a.x()));
  const Int acy = static_cast<Int>(static_cast<long long>(c.y()) - static_cast<long long>(a.y()));
  const Int det = abx * acy - aby * acx;
  return det > 0 ? 1 : det < 0 ? -1 : 0;
}

bool on_closed_segment(const Vec2& a, const Vec2& b, const Vec2& p) {
  return exact_orient(a, b, p) == 0 && std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

// p is a vertex of the hull iff it is not in the convex hull of the other (distinct) points,
// i.e. (Caratheodory) not on a segment of two of them and not in a triangle of three.
std::vector<Vec2> brute_hull_vertices(std::vector<Vec2> points) {
  std::sort(points.begin(), points.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::vector<Vec2> vertices;
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& p = points[i];
    bool inside = false;
    for (std::size_t a = 0; a < n && !inside; ++a)
      for (std::size_t b = a + 1; b < n && !inside; ++b) {
        if (a == i || b == i) continue;
        if (on_closed_segment(points[a], points[b], p)) inside = true;
        for (std::size_t c = b + 1; c < n && !inside; ++c) {
          if (c == i) continue;
          const int o = exact_orient(points[a], points[b], points[c]);
          if (o == 0) continue;
          const int s0 = exact_orient(points[a], points[b], p), s1 = exact_orient(points[b], points[c], p),
                    s2 = exact_orient(points[c], points[a], p);
          if (s0 * o >= 0 && s1 * o >= 0 && s2 * o >= 0) inside = true;
        }
      }
    if (!inside) vertices.push_back(p);
  }
  return vertices;
}

// The hull of integer points is exactly right: same vertex set as brute force, strictly convex
// counter-clockwise order, every input point inside.
void expect_exact_hull(const std::vector<Vec2>& points, const std::string& label) {
  const std::vector<Vec2> hull = convex_hull_2d(points);
  std::vector<Vec2> sorted = hull;
  std::sort(sorted.begin(), sorted.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  const std::vector<Vec2> expected = brute_hull_vertices(points);
  ASSERT_EQ(sorted, expected) << label << " input " << str(points) << " hull " << str(hull);
  if (hull.size() >= 3) {
    for (std::size_t k = 0; k < hull.size(); ++k) {
      const Vec2& a = hull[k];
      const Vec2& b = hull[(k + 1) % hull.size()];
      ASSERT_EQ(exact_orient(a, b, hull[(k + 2) % hull.size()]), 1) << label << " not strictly convex: " << str(hull);
      for (const Vec2& p : points) ASSERT_GE(exact_orient(a, b, p), 0) << label << " point outside: " << str(p);
    }
  }
}

// ------------------------------------------------------------------------------------------
// Principal axes

::testing::AssertionResult is_rotation(const Mat3& m) {
  if (!m.allFinite()) return ::testing::AssertionFailure() << "non-finite\n" << m;
  if ((m.transpose() * m - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-12)
    return ::testing::AssertionFailure() << "not orthonormal\n" << m;
  if (std::abs(m.determinant() - 1) > 1e-12) return ::testing::AssertionFailure() << "det " << m.determinant();
  return ::testing::AssertionSuccess();
}

// The documented sign convention: the largest-magnitude component of col(0) and col(1) is
// positive.
bool has_sign_convention(const Mat3& m) {
  for (int c = 0; c < 2; ++c) {
    int largest = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(m(k, c)) > std::abs(m(largest, c))) largest = k;
    if (m(largest, c) < 0) return false;
  }
  return true;
}

// The quaternion's coordinates are drawn z, y, x, w: see tests/support/random.h.
Eigen::Quaternion<Real> random_quaternion(Random& r) {
  const Real z = r.normal();
  const Real y = r.normal();
  const Real x = r.normal();
  const Real w = r.normal();
  return Eigen::Quaternion<Real>(w, x, y, z);
}

Mat3 random_rotation(Random& r) {
  const Eigen::Quaternion<Real> q = random_quaternion(r);
  return q.normalized().toRotationMatrix();
}

TEST(FitPrincipalAxes, RecoversAKnownFrame) {
  Random r(101);
  for (int trial = 0; trial < scaled(200); ++trial) {
    const Mat3 frame = random_rotation(r);
    const Vec3 offset = test::vec3_z_first([&] { return r.uniform(-100, 100); });
    // Distinct spreads, well separated (ratio >= 1.5) so the eigenvectors are well conditioned.
    const Real c = r.uniform(0.1, 1), b = c * r.uniform(1.5, 3), a = b * r.uniform(1.5, 3);
    // A star symmetric about the offset: its scatter is frame * diag(a^2, b^2, c^2) * frame^T
    // times a constant, exactly.
    std::vector<Vec3> points;
    for (const Real s : {1.0, -1.0, 0.5, -0.5}) {
      points.push_back(offset + s * a * frame.col(0));
      points.push_back(offset + s * b * frame.col(1));
      points.push_back(offset + s * c * frame.col(2));
    }
    const Mat3 axes = principal_axes(points.data(), points.size());
    ASSERT_TRUE(is_rotation(axes));
    EXPECT_TRUE(has_sign_convention(axes));
    for (int k = 0; k < 3; ++k)
      EXPECT_GT(std::abs(axes.col(k).dot(frame.col(k))), 1 - 1e-12) << "trial " << trial << " axis " << k;
  }
}

TEST(FitPrincipalAxes, StretchedGaussianCloud) {
  Random r(102);
  for (int trial = 0; trial < scaled(20); ++trial) {
    const Mat3 frame = random_rotation(r);
    std::vector<Vec3> points;
    for (int i = 0; i < 4000; ++i) {
      const Real z = 0.5 * r.normal();  // z first: see tests/support/random.h
      const Real y = 3 * r.normal();
      const Real x = 10 * r.normal();
      points.push_back(frame * Vec3(x, y, z) + Vec3(5, -7, 1e3));
    }
    const Mat3 axes = principal_axes(points.data(), points.size());
    ASSERT_TRUE(is_rotation(axes));
    // Sampling error of the directions is about 1/sqrt(N) relative to the spread ratios.
    for (int k = 0; k < 3; ++k)
      EXPECT_GT(std::abs(axes.col(k).dot(frame.col(k))), 0.995) << "trial " << trial << " axis " << k;
  }
}

TEST(FitPrincipalAxes, DegenerateSets) {
  Random r(103);
  // No points, one point, coincident points: any rotation (identity), never NaN.
  EXPECT_TRUE(principal_axes(nullptr, 0).isIdentity());
  const Vec3 single(1e6, -3, 2);
  EXPECT_TRUE(is_rotation(principal_axes(&single, 1)));
  const std::vector<Vec3> same(7, Vec3(0.1, 0.2, 0.3));
  EXPECT_TRUE(is_rotation(principal_axes(same.data(), same.size())));

  for (int trial = 0; trial < scaled(120); ++trial) {
    const Mat3 frame = random_rotation(r);
    // Offsets and spreads such that rounding the points to doubles moves them off their line or
    // plane by at most ~1e-10 of the spread; the last combination (spread 1e-6 at 1e6, where
    // rounding is 1e-4 of the spread) only has to give a valid frame.
    const int combination = trial % 4;
    const Real magnitude = combination == 0 ? 1e6 : combination == 1 ? 1e-9 : combination == 2 ? 1 : 1e6;
    const Real spread = combination == 0 ? 1 : combination == 1 ? 1e-6 : combination == 2 ? 1e-6 : 1e-6;
    const Real tolerance = combination == 3 ? 2 : 1e-9;  // on 1 - |cos(angle)|
    const Vec3 offset = magnitude * test::vec3_z_first([&] { return r.normal(); });

    // Two points, and many collinear points (the first two at the ends): col(0) is the line.
    std::vector<Vec3> line = {offset + spread * frame.col(0), offset - spread * frame.col(0)};
    for (int i = 0; i < (trial % 3 == 0 ? 0 : 7); ++i)
      line.push_back(offset + spread * r.uniform(-1, 1) * frame.col(0));
    Mat3 axes = principal_axes(line.data(), line.size());
    ASSERT_TRUE(is_rotation(axes)) << "line, trial " << trial;
    EXPECT_TRUE(has_sign_convention(axes));
    EXPECT_GT(std::abs(axes.col(0).dot(frame.col(0))), 1 - tolerance) << "line, trial " << trial;

    // Coplanar points: col(2) is the plane's normal.
    std::vector<Vec3> plane = {offset + spread * frame.col(0), offset - spread * frame.col(0),
                               offset + spread * frame.col(1)};
    for (int i = 0; i < trial % 10; ++i) {
      const Real v = r.uniform(-1, 1);  // v first: see tests/support/random.h
      const Real u = r.uniform(-1, 1);
      plane.push_back(offset + spread * (u * frame.col(0) + v * frame.col(1)));
    }
    axes = principal_axes(plane.data(), plane.size());
    ASSERT_TRUE(is_rotation(axes)) << "plane, trial " << trial;
    EXPECT_TRUE(has_sign_convention(axes));
    EXPECT_GT(std::abs(axes.col(2).dot(frame.col(2))), 1 - tolerance) << "plane, trial " << trial;

    // Isotropic set (cube corners): every frame is principal; still a rotation.
    std::vector<Vec3> cube;
    for (int i = 0; i < 8; ++i)
      cube.push_back(offset + spread * frame * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
    EXPECT_TRUE(is_rotation(principal_axes(cube.data(), cube.size()))) << "cube, trial " << trial;
  }
}

TEST(FitPrincipalAxes, DeterministicAndOrderIndependent) {
  Random r(104);
  for (int trial = 0; trial < scaled(50); ++trial) {
    std::vector<Vec3> points;
    const Mat3 frame = random_rotation(r);
    for (int i = 0; i < 16; ++i) {
      const Real z = r.normal();  // z first: see tests/support/random.h
      const Real y = 2 * r.normal();
      const Real x = 4 * r.normal();
      points.push_back(frame * Vec3(x, y, z));
    }
    const Mat3 first = principal_axes(points.data(), points.size());
    const Mat3 again = principal_axes(points.data(), points.size());
    EXPECT_EQ(first, again);
    r.shuffle(points.begin(), points.end());
    const Mat3 shuffled = principal_axes(points.data(), points.size());
    // Same axes with the same signs (the sign convention, not the input order, picks them).
    EXPECT_LT((first - shuffled).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  }
}

// ------------------------------------------------------------------------------------------
// Convex hull

TEST(FitConvexHull, MatchesBruteForceOnIntegerGrids) {
  Random r(201);
  for (int trial = 0; trial < scaled(400); ++trial) {
    const int size = trial % 3 == 0 ? 2 : trial % 3 == 1 ? 4 : 9;
    const int count = r.integer(1, 40);
    std::vector<Vec2> points;
    for (int i = 0; i < count; ++i) {
      const int y = r.integer(0, size);  // y first: see tests/support/random.h
      const int x = r.integer(0, size);
      points.emplace_back(x, y);
    }
    expect_exact_hull(points, "grid trial " + std::to_string(trial));
    if (HasFatalFailure()) return;
  }
}

TEST(FitConvexHull, OrientationBeyondDoublePrecision) {
  // Consecutive Fibonacci vectors u_k = (F_k, F_{k+1}) satisfy u_k x u_{k+1} = +-1 while the
  // products involved are near 2^80: a plain double orientation test rounds them to zero or
  // the wrong sign. Sets mixing such vectors (and their sums, offsets) must still give the
  // exact hull.
  std::vector<long long> f = {1, 1};
  while (f.back() < (1LL << 44)) f.push_back(f[f.size() - 1] + f[f.size() - 2]);
  const std::size_t k = f.size() - 3;
  const Vec2 u(static_cast<Real>(f[k]), static_cast<Real>(f[k + 1]));
  const Vec2 v(static_cast<Real>(f[k + 1]), static_cast<Real>(f[k + 2]));
  const Vec2 o = Vec2::Zero(), offset(1LL << 46, -(1LL << 45));
  const std::vector<std::vector<Vec2>> sets = {
      {o, u, v},
      {o, v, u},
      {o, u, v, u + v},
      {o, u + v, v, u},
      {o, u, 2 * u, v},
      {o, u, v, 2 * v, u + v},
      {offset, offset + u, offset + v, offset + u + v, offset + 2 * u},
      {o, u, v - u, v},
      {u, v, u + v, 2 * u + v, 2 * v + u},
  };
  for (std::size_t i = 0; i < sets.size(); ++i) {
    expect_exact_hull(sets[i], "Fibonacci set " + std::to_string(i));
    if (HasFatalFailure()) return;
  }
}

TEST(FitConvexHull, DegenerateInputs) {
  EXPECT_TRUE(convex_hull_2d({}).empty());
  EXPECT_EQ(convex_hull_2d({Vec2(1, 2)}), std::vector<Vec2>{Vec2(1, 2)});
  EXPECT_EQ(convex_hull_2d({Vec2(1, 2), Vec2(1, 2), Vec2(1, 2)}), std::vector<Vec2>{Vec2(1, 2)});
  // Collinear sets: the two extreme points, whatever the order and duplicates.
  const std::vector<Vec2> horizontal = {Vec2(3, 1), Vec2(-2, 1), Vec2(0, 1), Vec2(3, 1), Vec2(1, 1)};
  EXPECT_EQ(convex_hull_2d(horizontal), (std::vector<Vec2>{Vec2(-2, 1), Vec2(3, 1)}));
  const std::vector<Vec2> vertical = {Vec2(0, 5), Vec2(0, -1), Vec2(0, 2)};
  EXPECT_EQ(convex_hull_2d(vertical), (std::vector<Vec2>{Vec2(0, -1), Vec2(0, 5)}));
  const std::vector<Vec2> diagonal = {Vec2(0.5, 1.5), Vec2(-1, 0), Vec2(2, 3), Vec2(0.25, 1.25), Vec2(2, 3)};
  EXPECT_EQ(convex_hull_2d(diagonal), (std::vector<Vec2>{Vec2(-1, 0), Vec2(2, 3)}));
  // A square with points on its edges and inside: the four corners, counter-clockwise.
  const std::vector<Vec2> square = {Vec2(0, 0), Vec2(1, 0), Vec2(2, 0), Vec2(2, 1), Vec2(2, 2),
                                    Vec2(1, 2), Vec2(0, 2), Vec2(0, 1), Vec2(1, 1), Vec2(0, 0)};
  EXPECT_EQ(convex_hull_2d(square), (std::vector<Vec2>{Vec2(0, 0), Vec2(2, 0), Vec2(2, 2), Vec2(0, 2)}));
}

// ------------------------------------------------------------------------------------------
// Minimum-area rectangle

// Area of the bounding rectangle of `points` with one side along `direction`.
Real rectangle_area_along(const std::vector<Vec2>& points, Vec2 direction) {
  direction.normalize();
  const Vec2 across(-direction.y(), direction.x());
  Real lo_u = kInf, hi_u = -kInf, lo_v = kInf, hi_v = -kInf;
  for (const Vec2& p : points) {
    lo_u = std::min(lo_u, p.dot(direction));
    hi_u = std::max(hi_u, p.dot(direction));
    lo_v = std::min(lo_v, p.dot(across));
    hi_v = std::max(hi_v, p.dot(across));
  }
  return (hi_u - lo_u) * (hi_v - lo_v);
}

TEST(FitRectangle, MatchesBruteForce) {
  Random r(301);
  const Cloud kinds[] = {Cloud::square, Cloud::thin, Cloud::circle, Cloud::grid, Cloud::clustered};
  for (int trial = 0; trial < scaled(150); ++trial) {
    const std::vector<Vec2> points = random_cloud(r, kinds[trial % 5], r.integer(3, 40));
    const Rectangle2 rect = min_area_rectangle(points);
    ASSERT_TRUE(rectangle_encloses(rect, points)) << "trial " << trial;
    // Every direction through two input points includes every hull-edge direction.
    Real pair_best = kInf;
    for (std::size_t i = 0; i < points.size(); ++i)
      for (std::size_t j = 0; j < points.size(); ++j)
        if (points[i] != points[j])
          pair_best = std::min(pair_best, rectangle_area_along(points, points[j] - points[i]));
    const Real scale = 1e-12 * (1 + pair_best);
    if (pair_best > 1e-12) {
      EXPECT_NEAR(rect.area(), pair_best, scale) << "trial " << trial << " " << str(points);
    } else {
      EXPECT_LT(rect.area(), 1e-12) << "trial " << trial;
    }
    for (int i = 0; i < 10000; ++i) {
      const Real angle = r.uniform(0, kPi);
      EXPECT_LE(rect.area(), rectangle_area_along(points, Vec2(std::cos(angle), std::sin(angle))) + scale)
          << "trial " << trial;
    }
  }
}

TEST(FitRectangle, DegenerateInputs) {
  EXPECT_EQ(min_area_rectangle({}).area(), 0);
  // A point (repeated): zero size up to the few-ulp padding.
  const std::vector<Vec2> point(3, Vec2(5, -2));
  Rectangle2 rect = min_area_rectangle(point);
  EXPECT_TRUE(rectangle_encloses(rect, point));
  EXPECT_LE(rect.half_u, 1e-14);
  EXPECT_LE(rect.half_v, 1e-14);
  EXPECT_LE((rect.center - Vec2(5, -2)).norm(), 1e-14);
  // A segment: zero width, along the segment.
  const std::vector<Vec2> line = {Vec2(0, 0), Vec2(3, 4), Vec2(1.5, 2), Vec2(-3, -4), Vec2(0.75, 1)};
  rect = min_area_rectangle(line);
  EXPECT_TRUE(rectangle_encloses(rect, line));
  EXPECT_NEAR(std::abs(rect.axis_u.dot(Vec2(0.6, 0.8))), 1, 1e-15);
  EXPECT_NEAR(rect.half_u, 5, 1e-13);
  EXPECT_LE(rect.half_v, 1e-14);
  EXPECT_LE(rect.center.norm(), 1e-14);
  // A square: the square itself, area 1.
  const std::vector<Vec2> square = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1), Vec2(0.5, 0.5)};
  rect = min_area_rectangle(square);
  EXPECT_TRUE(rectangle_encloses(rect, square));
  EXPECT_NEAR(rect.area(), 1, 1e-14);
}

// ------------------------------------------------------------------------------------------
// Minimum-area triangles

std::vector<Vec2> regular_polygon(int n, Real radius, Real phase = 0) {
  std::vector<Vec2> points;
  for (int k = 0; k < n; ++k)
    points.emplace_back(radius * std::cos(phase + 2 * kPi * k / n), radius * std::sin(phase + 2 * kPi * k / n));
  return points;
}

// Both fits on one input: enclose, the isosceles one is isosceles, general <= isosceles.
void check_triangle_fits(const std::vector<Vec2>& points, Triangle2& general, Triangle2& isosceles,
                         const std::string& label) {
  general = min_area_triangle(points);
  isosceles = min_area_isosceles_triangle(points);
  EXPECT_TRUE(triangle_encloses(general, points)) << label;
  EXPECT_TRUE(triangle_encloses(isosceles, points)) << label;
  EXPECT_TRUE(is_isosceles(isosceles)) << label;
  EXPECT_LE(general.area(), isosceles.area() * (1 + 1e-9) + 1e-300) << label;
}

TEST(FitTriangle, KnownCases) {
  Triangle2 general, isosceles;
  // A scalene triangle is its own minimum; the isosceles minimum is strictly larger.
  const std::vector<Vec2> scalene = {Vec2(0, 0), Vec2(4, 0), Vec2(1, 2), Vec2(1.5, 0.5)};
  check_triangle_fits(scalene, general, isosceles, "scalene");
  EXPECT_NEAR(general.area(), 4, 1e-12);
  for (int k = 0; k < 3; ++k) {
    Real nearest = kInf;
    for (int j = 0; j < 3; ++j) nearest = std::min(nearest, (general.corners[j] - scalene[k]).norm());
    EXPECT_LT(nearest, 1e-12) << "corner " << k;
  }
  EXPECT_GT(isosceles.area(), 4 * (1 + 1e-3));
  // An isosceles triangle (apex at (1, 3)) is its own minimum for both.
  const std::vector<Vec2> iso = {Vec2(-1, 0), Vec2(3, 0), Vec2(1, 3)};
  check_triangle_fits(iso, general, isosceles, "isosceles");
  EXPECT_NEAR(general.area(), 6, 1e-12);
  EXPECT_NEAR(isosceles.area(), 6, 1e-12);
  EXPECT_LT((isosceles.corners[2] - Vec2(1, 3)).norm(), 1e-12) << "corner 2 is the apex";
  // Parallelograms: the minimum enclosing triangle has twice their area (Gross 1918), and for
  // the square the triangle with base 2 and height 2 is isosceles.
  const std::vector<Vec2> square = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  check_triangle_fits(square, general, isosceles, "square");
  EXPECT_NEAR(general.area(), 2, 1e-12);
  EXPECT_NEAR(isosceles.area(), 2, 1e-12);
  const std::vector<Vec2> parallelogram = {Vec2(0, 0), Vec2(3, 0), Vec2(4, 1), Vec2(1, 1)};
  check_triangle_fits(parallelogram, general, isosceles, "parallelogram");
  EXPECT_NEAR(general.area(), 6, 1e-12);
  // Regular hexagon of side 1: extending alternate sides gives the equilateral triangle of
  // side 3, area 9 sqrt(3) / 4, 3/2 of the hexagon's area; it is minimal (the brute-force
  // tests below agree on random hulls; here the value is pinned).
  const std::vector<Vec2> hexagon = regular_polygon(6, 1, 0.3);
  check_triangle_fits(hexagon, general, isosceles, "hexagon");
  EXPECT_NEAR(general.area(), 9 * std::sqrt(3.0) / 4, 1e-12);
  EXPECT_NEAR(isosceles.area(), 9 * std::sqrt(3.0) / 4, 1e-12);
  // A 64-gon inscribed in the unit circle: between the equilateral triangles around its
  // incircle and around the circle, 3 sqrt(3) r^2 for r = cos(pi / 64) and r = 1.
  const std::vector<Vec2> many = regular_polygon(64, 1, 0.1);
  check_triangle_fits(many, general, isosceles, "64-gon");
  const Real incircle = std::cos(kPi / 64);
  EXPECT_GE(general.area(), 3 * std::sqrt(3.0) * incircle * incircle * (1 - 1e-12));
  EXPECT_LE(isosceles.area(), 3 * std::sqrt(3.0) * (1 + 1e-12));
}

TEST(FitTriangle, MatchesBruteForce) {
  Random r(401);
  const Cloud kinds[] = {Cloud::square, Cloud::circle, Cloud::clustered, Cloud::thin, Cloud::grid};
  int checked = 0;
  for (int trial = 0; checked < scaled(40); ++trial) {
    const std::vector<Vec2> points = random_cloud(r, kinds[trial % 5], r.integer(3, 12));
    const std::vector<Vec2> hull = convex_hull_2d(points);
    if (hull.size() < 3) continue;
    ++checked;
    Triangle2 general, isosceles;
    const std::string label = "trial " + std::to_string(trial) + " " + str(points);
    check_triangle_fits(points, general, isosceles, label);
    const Real brute = brute_min_triangle_area(hull, r);
    EXPECT_LE(general.area(), brute * (1 + 1e-9)) << label;
    // The optimizer converges on these small hulls, so it must also find our value.
    EXPECT_GE(general.area(), brute * (1 - 1e-6)) << label;
  }
}

TEST(FitTriangle, LargeHull) {
  // "Any size": a regular 200-gon mapped by a random affine map. Minimum enclosing triangles
  // commute with affine maps, so the area is det(map) times that of the regular 200-gon, which
  // lies between the equilateral triangles around its incircle and its circumcircle.
  Random r(402);
  constexpr int kCount = 200;
  Eigen::Matrix<Real, 2, 2> map;
  map << r.uniform(0.5, 2), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(0.5, 2);
  const Real offset_y = r.uniform(-10, 10);  // y first: see tests/support/random.h
  const Real offset_x = r.uniform(-10, 10);
  const Vec2 offset(offset_x, offset_y);
  std::vector<Vec2> points;
  for (const Vec2& p : regular_polygon(kCount, 1, 0.2)) points.push_back(map * p + offset);
  Triangle2 general, isosceles;
  check_triangle_fits(points, general, isosceles, "affine 200-gon");
  const Real det = std::abs(map.determinant()), incircle = std::cos(kPi / kCount);
  EXPECT_GE(general.area(), det * 3 * std::sqrt(3.0) * incircle * incircle * (1 - 1e-12));
  EXPECT_LE(general.area(), det * 3 * std::sqrt(3.0) * (1 + 1e-12));
  // Sampling does not converge on 200 sides; its optimum is still an upper bound.
  EXPECT_LE(general.area(), brute_min_triangle_area(convex_hull_2d(points), r) * (1 + 1e-9));
}

TEST(FitIsoscelesTriangle, MatchesBruteForce) {
  Random r(501);
  const Cloud kinds[] = {Cloud::square, Cloud::circle, Cloud::clustered, Cloud::thin, Cloud::grid};
  int checked = 0;
  for (int trial = 0; checked < scaled(24); ++trial) {
    const std::vector<Vec2> points = random_cloud(r, kinds[trial % 5], r.integer(3, 12));
    const std::vector<Vec2> hull = convex_hull_2d(points);
    if (hull.size() < 3) continue;
    ++checked;
    Triangle2 general, isosceles;
    const std::string label = "trial " + std::to_string(trial) + " " + str(points);
    check_triangle_fits(points, general, isosceles, label);
    const Real brute = brute_min_isosceles_area(hull, r);
    EXPECT_LE(isosceles.area(), brute * (1 + 1e-9)) << label;
  }
}

TEST(FitTriangle, DegenerateInputs) {
  for (const auto fit : {&min_area_triangle, &min_area_isosceles_triangle}) {
    EXPECT_EQ(fit({}).area(), 0);
    const std::vector<Vec2> point(4, Vec2(-1, 7));
    Triangle2 t = fit(point);
    EXPECT_TRUE(triangle_encloses(t, point));
    for (const Vec2& c : t.corners) EXPECT_EQ(c, Vec2(-1, 7));
    const std::vector<Vec2> line = {Vec2(1, 1), Vec2(-2, -5), Vec2(0, -1), Vec2(3, 5), Vec2(3, 5)};
    t = fit(line);
    EXPECT_EQ(t.area(), 0);
    EXPECT_TRUE(triangle_encloses(t, line));
    EXPECT_TRUE(is_isosceles(t));
  }
}

// ------------------------------------------------------------------------------------------
// Clusters of near-duplicates: what the volume fits really project. The corners of a box (or of
// a prism) seen along one of its own axes fall in clusters whose members differ by rounding
// only, so the exact hull has tiny edges pointing anywhere. The answer must still be the face
// (the base triangle), and the fits must still match brute force.

Mat3 random_frame(Random& r) {
  const Eigen::Quaternion<Real> q = random_quaternion(r);
  return q.normalized().toRotationMatrix();
}

// Coordinates of `points` in the plane spanned by frame columns 0 and 1 (projected along col 2),
// measured from `reference`: the computation a volume fit performs.
std::vector<Vec2> project(const std::vector<Vec3>& points, const Mat3& frame, const Vec3& reference) {
  std::vector<Vec2> planar;
  for (const Vec3& p : points) planar.emplace_back(frame.col(0).dot(p - reference), frame.col(1).dot(p - reference));
  return planar;
}

TEST(FitClusters, BoxSeenAlongItsAxis) {
  Random r(801);
  for (int trial = 0; trial < scaled(300); ++trial) {
    const Mat3 frame = random_frame(r);
    const Vec3 center = test::vec3_z_first([&] { return r.uniform(-3, 3); });
    const Real a = r.uniform(0.01, 1), b = trial % 3 == 0 ? 0 : r.uniform(0.01, 1), c = trial % 2 ? 0 : r.uniform(0, 1);
    std::vector<Vec3> corners;
    for (int copy = 0; copy < 2; ++copy)  // a box and a copy of itself: 16 corners
      for (int k = 0; k < 8; ++k)
        corners.push_back(center + frame * Vec3(k & 1 ? a : -a, k & 2 ? b : -b, k & 4 ? c : -c));
    Vec3 centroid = Vec3::Zero();
    for (const Vec3& p : corners) centroid += p / 16;
    const std::vector<Vec2> planar = project(corners, frame, centroid);  // along the c axis
    const Rectangle2 rect = min_area_rectangle(planar);
    const std::string label = "trial " + std::to_string(trial) + " " + str(planar);
    ASSERT_TRUE(rectangle_encloses(rect, planar)) << label;
    // The face itself (up to rounding of the corners and the padding).
    EXPECT_NEAR(rect.half_u * rect.half_v, a * b, 1e-12) << label;
    EXPECT_NEAR(std::max(rect.half_u, rect.half_v), std::max(a, b), 1e-12) << label;
    const Triangle2 general = min_area_triangle(planar), isosceles = min_area_isosceles_triangle(planar);
    EXPECT_TRUE(triangle_encloses(general, planar)) << label;
    EXPECT_TRUE(triangle_encloses(isosceles, planar)) << label;
    // Twice the rectangle (parallelograms, Gross 1918), also reached by an isosceles triangle;
    // for a segment (b = 0) a sliver, its angles clamped at ~1e-8 (see fit.h).
    if (b > 0) {
      EXPECT_NEAR(general.area(), 8 * a * b, 1e-9 * a) << label;
      EXPECT_NEAR(isosceles.area(), 8 * a * b, 1e-9 * a) << label;
    } else {
      EXPECT_LE(general.area(), 1e-7 * a * a) << label;
      EXPECT_LE(isosceles.area(), 1e-7 * a * a) << label;
    }
  }
}

TEST(FitClusters, PrismsSeenAlongTheirAxis) {
  Random r(802);
  int checked = 0;
  for (int trial = 0; checked < scaled(30); ++trial) {
    const Mat3 frame = random_frame(r);
    const Vec3 offset = test::vec3_z_first([&] { return r.uniform(-3, 3); });
    std::vector<Vec2> base;
    for (int k = 0; k < 3; ++k) base.push_back(vec2_y_first([&] { return r.uniform(-1, 1); }));
    const Real base_area = std::abs(cross(base[1] - base[0], base[2] - base[0])) / 2;
    if (base_area < 0.05) continue;
    ++checked;
    // Two prisms with the same axis: the first one's 6 corners, a second one's 6 with a
    // different base, all seen along the axis.
    std::vector<Vec3> corners;
    std::vector<Vec2> second;
    for (int k = 0; k < 3; ++k) second.push_back(vec2_y_first([&] { return r.uniform(-1, 1); }));
    for (const auto* tri : {&base, &second})
      for (const Vec2& q : *tri)
        for (const Real h : {0.0, r.uniform(0.1, 2)}) corners.push_back(offset + frame * Vec3(q.x(), q.y(), h));
    const std::vector<Vec2> planar = project(corners, frame, offset);
    const std::vector<Vec2> hull = convex_hull_2d(planar);
    const std::string label = "trial " + std::to_string(trial) + " " + str(planar);
    Triangle2 general, isosceles;
    check_triangle_fits(planar, general, isosceles, label);
    const Real brute = brute_min_triangle_area(hull, r);
    EXPECT_LE(general.area(), brute * (1 + 1e-9)) << label;
    EXPECT_GE(general.area(), brute * (1 - 1e-6)) << label;
    if (checked <= 8) {  // (the grid is slow)
      EXPECT_LE(isosceles.area(), brute_min_isosceles_area(hull, r) * (1 + 1e-9)) << label;
    }
    const Rectangle2 rect = min_area_rectangle(planar);
    EXPECT_TRUE(rectangle_encloses(rect, planar)) << label;
    Real pair_best = kInf;
    for (const Vec2& p : planar)
      for (const Vec2& q : planar)
        if (p != q) pair_best = std::min(pair_best, rectangle_area_along(planar, q - p));
    EXPECT_NEAR(rect.area(), pair_best, 1e-12 * (1 + pair_best)) << label;
    // A single prism: its base triangle is the minimum.
    const std::vector<Vec2> one(planar.begin(), planar.begin() + 6);
    EXPECT_NEAR(min_area_triangle(one).area(), base_area, 1e-12) << label;
    EXPECT_TRUE(triangle_encloses(min_area_triangle(one), one)) << label;
  }
}

// ------------------------------------------------------------------------------------------
// Rounding: large offsets, tiny spreads, nearly collinear sets

TEST(FitEnclosure, NastyInputs) {
  Random r(601);
  for (int trial = 0; trial < scaled(300); ++trial) {
    const int kind = trial % 6;
    std::vector<Vec2> points;
    const int count = r.integer(3, 16);
    const Vec2 offset = kind == 0 || kind == 3 ? Vec2(1e6, -1e6)
                        : kind == 5            ? Vec2(1e8, 3e7)
                                               : vec2_y_first([&] { return r.normal(); });
    const Real spread = kind == 1 || kind == 3 ? 1e-9 : 1;
    const Vec2 direction = vec2_y_first([&] { return r.normal(); }).normalized();
    for (int i = 0; i < count; ++i) {
      if (kind == 2 || kind == 5) {  // nearly collinear: off the line by a few ulps or less
        // The noise first, y first, then the position along the line: see tests/support/random.h.
        const Vec2 noise = vec2_y_first([&] { return r.normal(); });
        const Real along = r.uniform(-1, 1);
        points.push_back(offset + spread * along * direction + noise * 1e-15 * (kind == 5 ? 1e8 : 1));
      } else if (kind == 4) {  // collinear in floating point (not exactly), then one point off
        points.push_back(offset + spread * r.uniform(-1, 1) * direction + (i == 0 ? Vec2(0, 1e-12) : Vec2(0, 0)));
      } else {
        points.push_back(offset + spread * vec2_y_first([&] { return r.uniform(-1, 1); }));
      }
    }
    const std::string label = "trial " + std::to_string(trial) + " " + str(points);
    EXPECT_TRUE(rectangle_encloses(min_area_rectangle(points), points)) << label;
    const Triangle2 general = min_area_triangle(points);
    const Triangle2 isosceles = min_area_isosceles_triangle(points);
    EXPECT_TRUE(triangle_encloses(general, points)) << label;
    EXPECT_TRUE(triangle_encloses(isosceles, points)) << label;
    EXPECT_TRUE(is_isosceles(isosceles)) << label;
  }
}

TEST(FitEnclosure, ScaleAndTranslationInvariance) {
  // Shrinking a set by 1e-9 (a power of two would be exact; this is not) or moving it changes
  // the fits only by rounding.
  Random r(602);
  for (int trial = 0; trial < scaled(30); ++trial) {
    const std::vector<Vec2> points = random_cloud(r, trial % 2 ? Cloud::square : Cloud::clustered, r.integer(4, 12));
    std::vector<Vec2> small, moved;
    for (const Vec2& p : points) {
      small.push_back(p * 1e-9);
      moved.push_back(p + Vec2(1e3, -2e3));
    }
    const Real rect = min_area_rectangle(points).area(), tri = min_area_triangle(points).area(),
               iso = min_area_isosceles_triangle(points).area();
    EXPECT_NEAR(min_area_rectangle(small).area() * 1e18, rect, 1e-9 * rect);
    EXPECT_NEAR(min_area_triangle(small).area() * 1e18, tri, 1e-9 * tri);
    EXPECT_NEAR(min_area_isosceles_triangle(small).area() * 1e18, iso, 1e-9 * iso);
    EXPECT_NEAR(min_area_rectangle(moved).area(), rect, 1e-9 * rect);
    EXPECT_NEAR(min_area_triangle(moved).area(), tri, 1e-9 * tri);
    EXPECT_NEAR(min_area_isosceles_triangle(moved).area(), iso, 1e-9 * iso);
  }
}

// ------------------------------------------------------------------------------------------
// Performance sanity (no assertion): per-call times on 12-point inputs, printed.
// Measured (RelWithDebInfo, GCC 12, x86-64, 2 cores shared with other builds), 12 points all on
// the hull: principal_axes 0.5 us, convex_hull_2d 0.2 us, min_area_rectangle 0.6 us,
// min_area_triangle 3.5-4 us, min_area_isosceles_triangle 12-15 us (callgrind: 4k, 3k, 8k, 47k,
// 123k instructions per call). 12 points of which about 7 are on the hull: min_area_triangle
// 1.2 us (17k), min_area_isosceles_triangle 4.5 us (63k).

TEST(FitPerformance, TwelvePointTimings) {
  Random r(701);
  std::vector<std::vector<Vec2>> inputs;
  for (int i = 0; i < 64; ++i) inputs.push_back(random_cloud(r, Cloud::circle, 12));  // 12 hull points
  std::vector<Vec3> cloud;
  for (int i = 0; i < 12; ++i) cloud.push_back(test::vec3_z_first([&] { return r.normal(); }));
  constexpr int kCalls = 2000;
  Real sink = 0;
  auto time = [&](const char* name, auto call) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < kCalls; ++i) sink += call(i);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count() / kCalls;
    std::printf("[ timing   ] %-28s %8.2f us/call (12 points)\n", name, us);
  };
  time("principal_axes", [&](int) { return principal_axes(cloud.data(), cloud.size())(0, 0); });
  time("convex_hull_2d", [&](int i) { return static_cast<Real>(convex_hull_2d(inputs[i % 64]).size()); });
  time("min_area_rectangle", [&](int i) { return min_area_rectangle(inputs[i % 64]).area(); });
  time("min_area_triangle", [&](int i) { return min_area_triangle(inputs[i % 64]).area(); });
  time("min_area_isosceles_triangle", [&](int i) { return min_area_isosceles_triangle(inputs[i % 64]).area(); });
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace boxtree::detail
