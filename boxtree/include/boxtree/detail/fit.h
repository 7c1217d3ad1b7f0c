// SPDX-License-Identifier: MIT
#pragma once
// Fitting primitives behind the oriented volumes' leaf and parent rules (paper, Sections
// 3.2-3.3): principal axes of a point set, 2D convex hulls, and minimum-area enclosing
// rectangles and triangles. Internal to the library (used by volume/obb.h and
// volume/pie_slice.h), declared here so the tests can check them against brute force.
//
// Every enclosing shape returned here really encloses its input points, even after rounding:
// each routine checks its result point by point and pushes sides outward until every point
// passes, with a padding of a few ulps of the largest input coordinate, so callers may rely on
// containment (up to the last rounding of their own transforms). Inputs must be finite
// (asserted); products of coordinates must not overflow or underflow.
// Algorithms, proofs of optimality and measured costs: src/fit.cpp.
#include <array>
#include <vector>

#include "boxtree/mesh.h"

namespace boxtree::detail {

// Eigenvectors of the covariance matrix of `points` (about their centroid), as the columns of a
// rotation matrix ordered by decreasing eigenvalue: col(0) = max principal component, col(2) =
// min. Deterministic: the largest-magnitude component of col(0) and of col(1) is positive (the
// first one on ties) and col(2) = col(0) x col(1), so the determinant is +1. Degenerate sets give
// a valid orthonormal frame whose trailing axes span the degenerate directions (a segment:
// col(0) is its direction; coplanar points: col(2) is the plane's normal); no points or
// coincident points give the identity. Never NaN.
Mat3 principal_axes(const Vec3* points, std::size_t count);

// Convex hull, counter-clockwise from the lexicographically smallest point, without collinear or
// duplicate points; exact (orientation tests are exact), so its vertices are exactly the extreme
// points of the input. 0, 1 or 2 points for degenerate input (2: the extremes of a collinear set).
std::vector<Vec2> convex_hull_2d(std::vector<Vec2> points);

// Rectangle {center + s*axis_u + t*axis_v : |s| <= half_u, |t| <= half_v}, axis_v = perp(axis_u).
struct Rectangle2 {
  Vec2 center = Vec2::Zero();
  Vec2 axis_u = Vec2::UnitX();  // unit length
  Real half_u = 0;
  Real half_v = 0;
  Vec2 axis_v() const { return Vec2(-axis_u.y(), axis_u.x()); }
  Real area() const { return 4 * half_u * half_v; }
};

// Minimum-area enclosing rectangle (rotating calipers over the hull: an optimal rectangle has a
// side flush with a hull edge; Freeman & Shapira 1975, Toussaint 1983). Degenerate input gives a
// rectangle of zero width (a segment) or zero size (a point), up to the padding. Containment:
// |(p - center).dot(axis_u)| <= half_u and likewise for axis_v(), evaluated in double as written
// (and by a padding margin of 4 ulps of the largest coordinate in any other way).
Rectangle2 min_area_rectangle(const std::vector<Vec2>& points);

struct Triangle2 {
  std::array<Vec2, 3> corners;  // counter-clockwise (or degenerate)
  Real area() const;            // absolute
};

// The enclosing triangles below:
//  * contain every input point in the closed triangle of the stored corners, with a margin: the
//    plain double orientation test of a point against each side is positive by more than twice
//    its rounding error bound;
//  * are exact minima up to rounding (the optimizers ignore hull vertices whose turn is lost in
//    rounding noise; containment still covers them), except for hulls so thin (a segment up to
//    ~1e-8 relative) that the optimum has an angle below ~1e-8 rad: corners cannot represent
//    such a needle, so the angles are clamped there (the area stays tiny);
//  * for a hull of 1 or 2 points are degenerate and exact: (p, p, p), or the segment's two ends
//    and its midpoint.

// Minimum-area enclosing triangle, exact (the characterization of O'Rourke, Aggarwal, Maddila,
// Baldwin, "An optimal algorithm for finding minimal enclosing triangles", J. Algorithms 1986,
// enumerated in O(h^3) for h hull points rather than their O(h) walk; see src/fit.cpp).
Triangle2 min_area_triangle(const std::vector<Vec2>& points);

// Minimum-area enclosing isosceles triangle (the paper's pie-slice rule, Section 3.3), exact
// (some optimum has a side flush with a hull edge; each edge as base or leg leaves a
// one-parameter family minimized in closed form, see src/fit.cpp). corners[2] is the apex:
// |c2 - c0| = |c2 - c1| up to the rounding of the corners.
Triangle2 min_area_isosceles_triangle(const std::vector<Vec2>& points);

}  // namespace boxtree::detail
