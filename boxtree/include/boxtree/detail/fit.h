#pragma once
// Fitting primitives behind the oriented volumes' leaf and parent rules (paper, Sections
// 3.2-3.3): principal axes of a point set, 2D convex hulls, and minimum-area enclosing
// rectangles and triangles. Internal to the library (used by volume/obb.h and
// volume/pie_slice.h), declared here so the tests can check them against brute force.
//
// Every enclosing shape returned here really encloses its input points, even after rounding:
// each routine checks its result and pushes sides outward by the largest violation, so callers
// may rely on containment (up to the last rounding of their own transforms).
#include <array>
#include <vector>

#include "boxtree/mesh.h"

namespace boxtree::detail {

using Vec2 = Eigen::Matrix<Real, 2, 1>;

// Eigenvectors of the covariance matrix of `points` (about their centroid), as the columns of a
// rotation matrix ordered by decreasing eigenvalue: col(0) = max principal component, col(2) =
// min. Deterministic (fixed sign convention); degenerate sets (a point, a segment, coplanar
// points) give a valid orthonormal frame whose trailing axes span the degenerate directions.
Mat3 principal_axes(const Vec3* points, std::size_t count);

// Convex hull, counter-clockwise, without collinear points; 0, 1 or 2 points for degenerate input.
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
// rectangle of zero width (a segment) or zero size (a point).
Rectangle2 min_area_rectangle(const std::vector<Vec2>& points);

struct Triangle2 {
  std::array<Vec2, 3> corners;  // counter-clockwise (or degenerate)
  Real area() const;
};

// Minimum-area enclosing triangle (O'Rourke, Aggarwal, Maddila, Baldwin, "An optimal algorithm
// for finding minimal enclosing triangles", J. Algorithms 1986: linear time on the hull).
Triangle2 min_area_triangle(const std::vector<Vec2>& points);

// Minimum-area enclosing isosceles triangle (the paper's pie-slice rule, Section 3.3).
Triangle2 min_area_isosceles_triangle(const std::vector<Vec2>& points);

}  // namespace boxtree::detail
