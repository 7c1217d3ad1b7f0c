// SPDX-License-Identifier: MIT
#pragma once
// Independent triangle tests for the brute-force oracle (brute_force.h): nothing here calls the
// library's geometry (geometry.h, volume/), so a bug there cannot hide in the expected answers.
//
// The algorithms differ on purpose from the library's (Guigue-Devillers triangle pairs,
// Akenine-Moller box SAT, Ericson's Voronoi-region closest points). Everything is built from two
// primitives:
//  * a closed segment/triangle intersection decided by signs of 3x3 determinants (orient3d), and
//  * distances as minima over the pieces where a minimum can be attained (corners, edges, the
//    interior through the plane), never by case analysis of regions.
// The intersection tests are exact: signs of determinants, evaluated in double and, within its
// error bound of zero, again in exact expansion arithmetic. The distances are rounded; touching
// spheres and capsules agree with the library's where their coordinates are short dyadics.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "boxtree/shapes.h"

namespace boxtree::test::reference {

inline int sign(Real x) { return (x > 0) - (x < 0); }

// Exact signs of polynomials in the coordinates (Shewchuk, "Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates", 1997): a value is an expansion, a sum of
// doubles that do not overlap, kept in increasing magnitude, so its sign is that of its last
// non-zero term. Used only where the plain double value is within its error bound of zero.
using Expansion = std::vector<Real>;

inline void two_sum(Real a, Real b, Real& sum, Real& error) {
  sum = a + b;
  const Real b_virtual = sum - a;
  error = (a - (sum - b_virtual)) + (b - b_virtual);
}

// Adds one double exactly (Shewchuk's GROW-EXPANSION).
inline void grow(Expansion& e, Real b) {
  Real q = b;
  for (Real& term : e) {
    Real sum, error;
    two_sum(q, term, sum, error);
    term = error;
    q = sum;
  }
  e.push_back(q);
}

inline Expansion difference(Real a, Real b) {
  Expansion e;
  grow(e, a);
  grow(e, -b);
  return e;
}

inline Expansion product(const Expansion& x, const Expansion& y) {
  Expansion e;
  for (const Real a : x)
    for (const Real b : y) {
      const Real p = a * b;
      grow(e, std::fma(a, b, -p));  // exact: the rounding error of a product is a double
      grow(e, p);
    }
  return e;
}

inline Expansion sum(Expansion x, const Expansion& y, Real y_sign = 1) {
  for (const Real b : y) grow(x, y_sign * b);
  return x;
}

inline int sign(const Expansion& e) {
  for (auto it = e.rbegin(); it != e.rend(); ++it)
    if (*it != 0) return sign(*it);
  return 0;
}

// Sign of det[b - a, c - a, d - a]: positive when d lies on the side of plane abc that
// (b - a) x (c - a) points to. Exact.
inline int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const Real det = u.dot(v.cross(w));
  // Each of the six products of the determinant is rounded, and so are the differences: far
  // less than 1e-14 of the sum of their magnitudes (Shewchuk's bound is 7.8e-16 of it).
  Real permanent = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    permanent += std::abs(u[i]) * (std::abs(v[j] * w[k]) + std::abs(v[k] * w[j]));
  }
  if (std::abs(det) > 1e-14 * permanent) return sign(det);
  // Two equal points make the determinant exactly zero (shared corners of adjacent facets: the
  // common undecided case, and the expansions below are slow).
  if (a == b || a == c || a == d || b == c || b == d || c == d) return 0;
  std::array<Expansion, 3> eu, ev, ew;
  for (int i = 0; i < 3; ++i) {
    eu[i] = difference(b[i], a[i]);
    ev[i] = difference(c[i], a[i]);
    ew[i] = difference(d[i], a[i]);
  }
  Expansion total;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Expansion cross_i = sum(product(ev[j], ew[k]), product(ev[k], ew[j]), -1);
    total = sum(std::move(total), product(eu[i], cross_i));
  }
  return sign(total);
}

// Sign of the 2-D cross product of (b - a, c - a) after dropping coordinate `drop`. Exact.
inline int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const Real l = (b[i] - a[i]) * (c[j] - a[j]), r = (b[j] - a[j]) * (c[i] - a[i]);
  if (std::abs(l - r) > 1e-14 * (std::abs(l) + std::abs(r))) return sign(l - r);
  return sign(sum(product(difference(b[i], a[i]), difference(c[j], a[j])),
                  product(difference(b[j], a[j]), difference(c[i], a[i])), -1));
}

// Closed 2-D segment intersection in the coordinate plane without `drop`.
inline bool segments_meet_2d(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int drop) {
  const int o1 = orient2d(p, q, r, drop), o2 = orient2d(p, q, s, drop);
  const int o3 = orient2d(r, s, p, drop), o4 = orient2d(r, s, q, drop);
  if (o1 * o2 > 0 || o3 * o4 > 0) return false;
  if (o1 != 0 || o2 != 0 || o3 != 0 || o4 != 0) return true;
  // All four on one line: the intervals must overlap on both remaining coordinates.
  for (int k = 0; k < 3; ++k) {
    if (k == drop) continue;
    if (std::max(p[k], q[k]) < std::min(r[k], s[k]) || std::max(r[k], s[k]) < std::min(p[k], q[k])) return false;
  }
  return true;
}

// Closed 3-D segment intersection. Two segments in a common plane meet iff their shadows meet on
// all three coordinate planes: one of those shadows is one-to-one on the plane.
inline bool segments_meet(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  if (orient3d(p, q, r, s) != 0) return false;
  for (int drop = 0; drop < 3; ++drop)
    if (!segments_meet_2d(p, q, r, s, drop)) return false;
  return true;
}

// The coordinate whose dropping keeps the triangle abc one-to-one, or -1 if its corners are on
// one line (exactly).
inline int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient2d(a, b, c, drop) != 0) return drop;
  return -1;
}

// Closed: does the point p in the plane of the proper triangle abc lie in it? `drop` from
// projection_axis.
inline bool coplanar_point_in_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  const int s0 = orient2d(a, b, p, drop), s1 = orient2d(b, c, p, drop), s2 = orient2d(c, a, p, drop);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

// Closed segment [p, q] against the closed triangle abc, which may be degenerate (then it is
// the union of its edges).
inline bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int drop = projection_axis(a, b, c);
  if (drop < 0) return segments_meet(p, q, a, b) || segments_meet(p, q, b, c) || segments_meet(p, q, c, a);
  const int sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
  if (sp * sq > 0) return false;
  if (sp == 0 && sq == 0) {  // in the plane
    return coplanar_point_in_triangle(p, a, b, c, drop) || segments_meet(p, q, a, b) || segments_meet(p, q, b, c) ||
           segments_meet(p, q, c, a);
  }
  // The segment reaches the plane at one point; it is in the triangle iff the line pq passes on
  // the same side of (or through) all three edges.
  const int e0 = orient3d(p, q, a, b), e1 = orient3d(p, q, b, c), e2 = orient3d(p, q, c, a);
  return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

// Two closed triangles meet iff an edge of one meets the other: a point of their intersection
// that is extreme lies on an edge of one of them.
inline bool triangles_meet(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
  for (int i = 0; i < 3; ++i) {
    if (segment_meets_triangle(s[i], s[(i + 1) % 3], t[0], t[1], t[2])) return true;
    if (segment_meets_triangle(t[i], t[(i + 1) % 3], s[0], s[1], s[2])) return true;
  }
  return false;
}

// A box as its 8 corners (corner k has bit i of k set for the high side of axis i), with the
// test "is a point inside".
struct BoxCorners {
  std::array<Vec3, 8> corner;
};

// The 12 edges and 12 face triangles of a box, by corner index.
inline constexpr int kBoxEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                         {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
inline constexpr int kBoxFaceTriangles[12][3] = {{0, 2, 6}, {0, 6, 4}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                                                 {2, 3, 7}, {2, 7, 6}, {0, 1, 3}, {0, 3, 2}, {4, 5, 7}, {4, 7, 6}};

// A triangle meets a closed box iff a corner of the triangle is in the box, an edge of the
// triangle meets a face of the box, or an edge of the box meets the triangle.
template <class Inside>
bool triangle_meets_box(const Vec3& a, const Vec3& b, const Vec3& c, const BoxCorners& box, Inside&& inside) {
  if (inside(a) || inside(b) || inside(c)) return true;
  const std::array<Vec3, 3> t = {a, b, c};
  for (const auto& f : kBoxFaceTriangles)
    for (int i = 0; i < 3; ++i)
      if (segment_meets_triangle(t[i], t[(i + 1) % 3], box.corner[f[0]], box.corner[f[1]], box.corner[f[2]]))
        return true;
  for (const auto& e : kBoxEdges)
    if (segment_meets_triangle(box.corner[e[0]], box.corner[e[1]], a, b, c)) return true;
  return false;
}

// Finite, valid box.
inline bool triangle_meets_aabb(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& lo, const Vec3& hi) {
  for (int i = 0; i < 3; ++i)  // separated along a coordinate axis
    if (std::max({a[i], b[i], c[i]}) < lo[i] || std::min({a[i], b[i], c[i]}) > hi[i]) return false;
  BoxCorners box;
  for (int k = 0; k < 8; ++k)
    box.corner[k] = Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
  const auto inside = [&](const Vec3& p) { return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all(); };
  return triangle_meets_box(a, b, c, box, inside);
}

// Valid oriented box: centre, axes (columns), half extents.
inline bool triangle_meets_obb(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& center, const Mat3& axes,
                               const Vec3& half) {
  // Far apart along a box axis (by more than 1e-9 of the sizes involved, far above the rounding of
  // these projections): no need for the exact test. Only for speed.
  for (int i = 0; i < 3; ++i) {
    const Real pa = axes.col(i).dot(a - center), pb = axes.col(i).dot(b - center), pc = axes.col(i).dot(c - center);
    const Real margin = 1e-9 * (half[i] + std::max({std::abs(pa), std::abs(pb), std::abs(pc)}));
    if (std::min({pa, pb, pc}) > half[i] + margin || std::max({pa, pb, pc}) < -half[i] - margin) return false;
  }
  BoxCorners box;
  for (int k = 0; k < 8; ++k) {
    Vec3 p = center;
    for (int i = 0; i < 3; ++i) p += ((k >> i) & 1 ? half[i] : -half[i]) * axes.col(i);
    box.corner[k] = p;
  }
  const auto inside = [&](const Vec3& p) {
    for (int i = 0; i < 3; ++i)
      if (std::abs(axes.col(i).dot(p - center)) > half[i]) return false;
    return true;
  };
  return triangle_meets_box(a, b, c, box, inside);
}

// Squared distance from p to the segment [a, b] (a point if a == b).
inline Real point_segment_distance2(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const Real along = (p - a).dot(d), length2 = d.squaredNorm();
  if (along <= 0 || length2 == 0) return (p - a).squaredNorm();
  if (along >= length2) return (p - b).squaredNorm();
  return (p - (a + (along / length2) * d)).squaredNorm();
}

// Squared distance from p to the closed triangle: the nearest point is on an edge or is p's foot
// on the plane, when that foot is in the triangle.
inline Real point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Real best =
      std::min({point_segment_distance2(p, a, b), point_segment_distance2(p, b, c), point_segment_distance2(p, c, a)});
  const Vec3 n = (b - a).cross(c - a);
  const Real n2 = n.squaredNorm();
  if (n2 > 0) {
    const Real height = n.dot(p - a);
    const Vec3 foot = p - (height / n2) * n;
    // The foot is rounded off the plane; the inside test only needs its shadow on a coordinate
    // plane where the triangle is not flat (rounding decides only feet on an edge, where the
    // edge distance above is as small).
    const Vec3 m = n.cwiseAbs();
    const int drop = m.x() >= m.y() && m.x() >= m.z() ? 0 : (m.y() >= m.z() ? 1 : 2);
    const int s0 = orient2d(a, b, foot, drop), s1 = orient2d(b, c, foot, drop), s2 = orient2d(c, a, foot, drop);
    if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0)) best = std::min(best, height * height / n2);
  }
  return best;
}

// Squared distance between the segments [p, q] and [r, s]: attained at an endpoint of one of
// them or, for non-parallel segments, at the interior points where the common perpendicular of
// the two lines meets both.
inline Real segment_segment_distance2(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  Real best = std::min({point_segment_distance2(p, r, s), point_segment_distance2(q, r, s),
                        point_segment_distance2(r, p, q), point_segment_distance2(s, p, q)});
  const Vec3 d1 = q - p, d2 = s - r, w = p - r;
  const Real a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const Real det = a * c - b * b;
  if (det > 0) {
    const Real t1 = (b * e - c * d) / det, t2 = (a * e - b * d) / det;
    if (t1 > 0 && t1 < 1 && t2 > 0 && t2 < 1) best = std::min(best, ((p + t1 * d1) - (r + t2 * d2)).squaredNorm());
  }
  return best;
}

// Squared distance between the segment [p, q] and the closed triangle (0 when they meet).
inline Real segment_triangle_distance2(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  if (segment_meets_triangle(p, q, a, b, c)) return 0;
  return std::min({point_triangle_distance2(p, a, b, c), point_triangle_distance2(q, a, b, c),
                   segment_segment_distance2(p, q, a, b), segment_segment_distance2(p, q, b, c),
                   segment_segment_distance2(p, q, c, a)});
}

// How deep two closed triangles interpenetrate: the least distance one must move to come apart,
// 0 if they are apart or merely touch, and 0 for coplanar ones (flat sets part along their common
// normal). By the separating-axis theorem, the least overlap of their shadows on the face normals
// of their Minkowski difference: the triangles' normals and the cross products of an edge of each.
// Rounded, and an axis from two edges (or a normal from a corner's two edges) within 1e-8 rad of
// parallel is left out, its direction being rounding noise: the result can be off by about 1e-8 of
// the triangles' size, so callers compare it with a margin above that.
inline Real penetration_depth(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
  constexpr Real kParallel = 1e-8;
  std::array<Vec3, 3> es, et;
  for (int i = 0; i < 3; ++i) {
    es[i] = s[(i + 1) % 3] - s[i];
    et[i] = t[(i + 1) % 3] - t[i];
  }
  Real depth = std::numeric_limits<Real>::infinity();
  bool any_axis = false;
  const auto try_axis = [&](const Vec3& x, const Vec3& y) {
    const Vec3 axis = x.cross(y);
    const Real length = axis.norm();
    if (!(length > kParallel * x.norm() * y.norm())) return;
    Real s_lo = axis.dot(s[0]), s_hi = s_lo, t_lo = axis.dot(t[0]), t_hi = t_lo;
    for (int i = 1; i < 3; ++i) {
      s_lo = std::min(s_lo, axis.dot(s[i]));
      s_hi = std::max(s_hi, axis.dot(s[i]));
      t_lo = std::min(t_lo, axis.dot(t[i]));
      t_hi = std::max(t_hi, axis.dot(t[i]));
    }
    depth = std::min(depth, std::min(s_hi - t_lo, t_hi - s_lo) / length);
    any_axis = true;
  };
  try_axis(es[0], es[1]);
  try_axis(et[0], et[1]);
  for (const Vec3& x : es)
    for (const Vec3& y : et) try_axis(x, y);
  return any_axis ? std::max(depth, Real(0)) : Real(0);
}

// Squared distance between two closed triangles (0 when they meet): when they do not, a closest
// pair has a point on an edge of one of them (two interior points could only be closest across
// parallel planes, where sliding reaches an edge).
inline Real triangle_triangle_distance2(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
  Real best = std::numeric_limits<Real>::infinity();
  for (int i = 0; i < 3; ++i) {
    best = std::min(best, segment_triangle_distance2(s[i], s[(i + 1) % 3], t[0], t[1], t[2]));
    best = std::min(best, segment_triangle_distance2(t[i], t[(i + 1) % 3], s[0], s[1], s[2]));
  }
  return best;
}

}  // namespace boxtree::test::reference
