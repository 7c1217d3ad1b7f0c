// SPDX-License-Identifier: MIT
// Oriented boxes as node volumes (volume/obb.h; paper, Section 3.2): geometry, queries, fits.
//
// Conventions shared by every test here:
//  * closed sets: touching counts as overlapping;
//  * conservative: rounding may make a test report a contact that is short of touching by a few
//    hundred ulps of the magnitudes involved, never miss a true one (the query layer's exact
//    leaf tests then decide). Invalid query shapes (NaN, negative radius or half extent) never
//    overlap anything: every comparison is written so that NaN means "no".
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "boxtree/detail/fit.h"
#include "boxtree/error.h"
#include "boxtree/geometry.h"
#include "boxtree/volume/obb.h"
#include "internal.h"

namespace boxtree {
namespace {

constexpr Real kEpsilon = std::numeric_limits<Real>::epsilon();
// Slack of the point and shape tests, relative to the magnitudes involved: covers the rounding of
// the change to the box frame (a 3-term dot product, plus the axes' own orthonormality error).
constexpr Real kContainSlack = 16 * kEpsilon;
constexpr Real kShapeSlack = 256 * kEpsilon;
// Ray test: margin around the box in its frame, relative to |origin - center|_1 + |h|_1 (see
// intersect_ray), and relative padding of each slab's t like the AABB test.
constexpr Real kRayMargin = 64 * kEpsilon;
constexpr Real kRayPad = 4 * kEpsilon;
// A box whose smallest half extent is below this fraction of its largest is "flat" for the
// nearly-coplanar refinement of the box/box test (see overlaps_in_frame).
constexpr Real kFlat = 1e-3;

// Coordinates of p in the box frame. The fits compute the half extents from exactly this
// expression, so a fitted box contains its input points by contains() with no tolerance at all.
Vec3 to_local(const Obb& box, const Vec3& p) { return box.axes.transpose() * (p - box.center); }

bool is_flat(const Vec3& half_extents) { return half_extents.minCoeff() <= kFlat * half_extents.maxCoeff(); }

// Box/box in world (or any common) frame. When both boxes are flat and the 15 axes say
// "overlap", the generic test adds the in-plane axes of nearly coplanar pairs, where Gottschalk's
// padding would otherwise leave a band of false contacts (see polytope.cpp).
bool obb_obb(const Obb& a, const Obb& b) {
  const Vec3 t = a.axes.transpose() * (b.center - a.center);
  const Mat3 r = a.axes.transpose() * b.axes;
  if (!detail::boxes_overlap(a.half_extents, t, r, b.half_extents)) return false;
  if (is_flat(a.half_extents) && is_flat(b.half_extents)) return sat_overlap(polytope_of(a), polytope_of(b));
  return true;
}

// The box with the given axes that encloses `points` most tightly: its center is the middle of
// the points' projections on the axes (not their centroid, which would not give the smallest
// enclosing box), and its half extents are the largest |to_local| of the points, plus a padding:
//  * leaves (exact input points): two ulps of the points' spread;
//  * parents (the children's rounded corners): 128 ulps of the spread (kParentPad) plus 8 ulps
//    of the coordinates' magnitude (kCornerPad). The children's corners are within an ulp of the
//    coordinates of the exact children, and contains() accepts points up to kContainSlack of
//    |p - center|_1 beyond a box (at most 96 ulps of the spread for points near a child); the
//    padding covers both, so that every point a child contains its parent contains too (what
//    a stabbing query needs to find all the nodes that contain a point).
constexpr Real kParentPad = 128 * kEpsilon;
constexpr Real kCornerPad = 8 * kEpsilon;
enum class Padding { leaf, parent };
Obb fit_box(const Mat3& axes, const Vec3* points, std::size_t count, const Vec3& reference, Padding padding) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<Real>::infinity());
  Vec3 hi = -lo;
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 x = axes.transpose() * (points[k] - reference);
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  Obb box{reference + axes * ((lo + hi) * Real(0.5)), axes, Vec3::Zero()};
  Real spread = 0, magnitude = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 x = to_local(box, points[k]).cwiseAbs();
    box.half_extents = box.half_extents.cwiseMax(x);
    spread = std::max(spread, x.maxCoeff());
    magnitude = std::max(magnitude, points[k].cwiseAbs().maxCoeff());
  }
  box.half_extents.array() +=
      padding == Padding::leaf ? 2 * kEpsilon * spread : kParentPad * spread + kCornerPad * magnitude;
  return box;
}

// Right-handed frame whose third axis is `normal` (unit) and whose first two axes are the
// rectangle's axes (given in the in-plane basis u, v).
Mat3 frame_from_rectangle(const Vec3& u, const Vec3& v, const detail::Rectangle2& rect) {
  const Vec2 ru = rect.axis_u;
  const Vec2 rv = rect.axis_v();
  Mat3 axes;
  axes.col(0) = (u * ru.x() + v * ru.y()).normalized();
  axes.col(1) = (u * rv.x() + v * rv.y()).normalized();
  axes.col(2) = axes.col(0).cross(axes.col(1));
  return axes;
}

}  // namespace

void detail::orthonormal_completion(const Vec3& n, Vec3& b1, Vec3& b2) {
  const Real sign = std::copysign(Real(1), n.z());
  const Real a = -1 / (sign + n.z());
  const Real b = n.x() * n.y() * a;
  b1 = Vec3(1 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
  b2 = Vec3(b, sign + n.y() * n.y() * a, -n.y());
}

// An orthonormal frame (u, v, normal) with u, v spanning the facet's plane, by Gram-Schmidt on
// its corners: u along the longest edge, v along the rest of the opposite corner. Unlike the
// normalized cross product of two edges, whose direction is only known to ~eps L^2 / |n| (an
// O(1) error for a needle or a collinear facet), this frame contains the three corners to
// within rounding whatever the facet's shape, so the fitted volumes are as flat as the facet.
// Returns false for a point (then the frame is arbitrary); a collinear facet (to within 16 ulps
// of its size) gets a valid frame with u along it.
bool detail::facet_frame(const Vec3& a, const Vec3& b, const Vec3& c, Vec3& u, Vec3& v, Vec3& normal) {
  const Vec3 p[3] = {a, b, c};
  int longest = 0;
  Real best = -1;
  for (int k = 0; k < 3; ++k) {
    const Real len = (p[(k + 1) % 3] - p[k]).squaredNorm();
    if (len > best) {
      best = len;
      longest = k;
    }
  }
  const Vec3& origin = p[longest];
  const Vec3 edge = p[(longest + 1) % 3] - origin;
  const Real length = edge.norm();
  if (!(length > 0) || !std::isfinite(length)) {
    u = Vec3::UnitX();
    v = Vec3::UnitY();
    normal = Vec3::UnitZ();
    return false;
  }
  u = edge / length;
  const Vec3 r = p[(longest + 2) % 3] - origin;
  const Vec3 w = r - u.dot(r) * u;
  const Real w_length = w.norm();
  // Below a few ulps of |r| the residual is rounding noise (a collinear facet): any v normal to u.
  if (w_length > 16 * kEpsilon * r.norm() && std::isfinite(w_length)) {
    v = w / w_length;
    v = (v - u.dot(v) * u).normalized();  // one more pass: u . v to rounding
  } else {
    detail::orthonormal_completion(u, v, normal);
  }
  normal = u.cross(v);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Geometry

std::array<Vec3, 8> corners(const Obb& box) {
  std::array<Vec3, 8> c;
  for (int mask = 0; mask < 8; ++mask) {
    Vec3 s;
    for (int k = 0; k < 3; ++k) s[k] = (mask >> k & 1) ? box.half_extents[k] : -box.half_extents[k];
    c[mask] = box.center + box.axes * s;
  }
  return c;
}

ConvexPolytope polytope_of(const Obb& box) {
  ConvexPolytope p;
  const auto c = corners(box);
  std::copy(c.begin(), c.end(), p.vertices.begin());
  p.vertex_count = 8;
  for (int k = 0; k < 3; ++k) {
    p.face_normals[k] = box.axes.col(k);
    p.edge_directions[k] = box.axes.col(k);
  }
  p.face_count = 3;
  p.edge_count = 3;
  return p;
}

ConvexPolytope polytope_of(const Aabb& box) {
  ConvexPolytope p;
  if (box.is_empty()) return p;  // no vertices: overlaps nothing
  for (int mask = 0; mask < 8; ++mask) {
    p.vertices[mask] = Vec3((mask & 1) ? box.max.x() : box.min.x(), (mask & 2) ? box.max.y() : box.min.y(),
                            (mask & 4) ? box.max.z() : box.min.z());
  }
  p.vertex_count = 8;
  for (int k = 0; k < 3; ++k) {
    p.face_normals[k] = Vec3::Unit(k);
    p.edge_directions[k] = Vec3::Unit(k);
  }
  p.face_count = 3;
  p.edge_count = 3;
  return p;
}

Real surface_area(const Obb& box) {
  const Vec3& h = box.half_extents;
  return 8 * (h.x() * h.y() + h.y() * h.z() + h.z() * h.x());
}

Real volume(const Obb& box) { return 8 * box.half_extents.prod(); }

Real mean_width(const Obb& box) { return box.half_extents.sum(); }

Aabb bounding_aabb(const Obb& box) {
  // The corners' bounds, center +- |axes| h, rounded outward so that the result encloses every
  // point contains() accepts (the box plus kContainSlack |p - c|_1 <= 48 ulps of the reach) and
  // the rounding of center and reach: the upper levels of hybrid trees are these boxes, and a
  // point in a child must be in its parent.
  const Vec3 reach = box.axes.cwiseAbs() * box.half_extents;
  const Vec3 pad = 4 * kEpsilon * box.center.cwiseAbs() + Vec3::Constant(64 * kEpsilon * reach.maxCoeff());
  return {box.center - reach - pad, box.center + reach + pad};
}

// ---------------------------------------------------------------------------------------------
// Queries

bool contains(const Obb& box, const Vec3& p, Real tolerance) {
  // Per box axis, absolute `tolerance` (as the AABB's per coordinate), plus the rounding slack.
  const Vec3 x = to_local(box, p);
  const Real slack = kContainSlack * (p - box.center).cwiseAbs().sum();
  return (x.cwiseAbs().array() <= box.half_extents.array() + (tolerance + slack)).all();
}

bool contains(const Obb& outer, const Obb& inner, Real tolerance) {
  for (const Vec3& c : corners(inner)) {
    if (!contains(outer, c, tolerance)) return false;
  }
  return true;
}

bool overlaps(const Obb& box, const Aabb& query) {
  if (!is_valid(query)) return false;
  // Infinite sides (half-spaces, shapes.h) clipped to the box's bounds, which hold the box: the
  // same answer, in finite arithmetic.
  Aabb clipped = query;
  if ((!query.min.allFinite() || !query.max.allFinite()) && !clip_infinite_sides(clipped, bounding_aabb(box)))
    return false;
  const Obb as_box{clipped.center(), Mat3::Identity(), (clipped.max - clipped.min) * Real(0.5)};
  return obb_obb(as_box, box);
}

bool overlaps(const Obb& box, const Obb& query) {
  if (!is_valid(query)) return false;
  return obb_obb(box, query);
}

bool overlaps(const Obb& box, const Sphere& query) {
  if (!is_valid(query)) return false;
  // Clamp in the box frame (Ericson 5.1.4): the closest point of the box to the center.
  const Vec3 x = to_local(box, query.center);
  const Vec3 closest = x.cwiseMax(-box.half_extents).cwiseMin(box.half_extents);
  const Real r = query.radius +
                 kShapeSlack * ((query.center - box.center).cwiseAbs().sum() + box.half_extents.sum() + query.radius);
  return (x - closest).squaredNorm() <= r * r;
}

bool overlaps(const Obb& box, const Capsule& query) {
  if (!is_valid(query)) return false;
  // In the box frame the box is an AABB; the AABB/capsule test is exact up to its own slack
  // (256 ulps of the magnitudes, far above the rounding of this change of frame).
  const Aabb local{-box.half_extents, box.half_extents};
  return overlaps(local, Capsule{to_local(box, query.p0), to_local(box, query.p1), query.radius});
}

bool overlaps(const Obb& box, const Plane& plane) {
  if (!plane.normal.allFinite() || !std::isfinite(plane.offset)) return false;
  // The plane function is linear: over the box it ranges over d +- sum_i h_i |n . a_i|.
  const Real d = plane.normal.dot(box.center) - plane.offset;
  const Real r = (box.axes.transpose() * plane.normal).cwiseAbs().dot(box.half_extents);
  const Real slack =
      kShapeSlack * (plane.normal.cwiseAbs().sum() * (box.center.cwiseAbs().maxCoeff() + box.half_extents.sum()) +
                     std::abs(plane.offset));
  return std::abs(d) <= r + slack;
}

bool overlaps(const Obb& a, const Obb& b, const RigidTransform& a_from_b) {
  const Obb b_in_a{a_from_b.apply(b.center), a_from_b.rotation * b.axes, b.half_extents};
  return obb_obb(a, b_in_a);
}

bool intersect_ray(const Obb& box, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter) {
  // The slab test in the box frame. The change of frame rounds the ray's origin and direction;
  // any point of the box is within |h| of its center, so a ray can only touch it at t with
  // t |d| <= |o - c| + |h|, and there the rounded ray is off by at most a few ulps of
  // |o - c|_1 + |h|_1. Growing the slabs by kRayMargin times that covers it; kRayPad covers the
  // rounding of each t (as in the AABB test). A flat box (h_i = 0) is a slab of width
  // 2 * margin, so a ray lying in its plane touches it.
  const Vec3 relative = ray.origin - box.center;
  const Vec3 o = box.axes.transpose() * relative;
  const Vec3 d = box.axes.transpose() * ray.direction;
  if (!o.allFinite() || !d.allFinite()) return false;  // invalid rays (or boxes) hit nothing
  const Real margin = kRayMargin * (relative.cwiseAbs().sum() + box.half_extents.sum());
  Real t_near = t_min;
  Real t_far = t_max;
  for (int i = 0; i < 3; ++i) {
    const Real h = box.half_extents[i] + margin;
    if (d[i] == 0) {
      if (!(std::abs(o[i]) <= h)) return false;
      continue;
    }
    Real t0 = (-h - o[i]) / d[i];
    Real t1 = (h - o[i]) / d[i];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0 - std::abs(t0) * kRayPad);
    t_far = std::min(t_far, t1 + std::abs(t1) * kRayPad);
    if (!(t_near <= t_far)) return false;
  }
  if (t_enter) *t_enter = t_near;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Fits

Obb obb_from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Paper, Section 3.2: the minimum-area rectangle enclosing the facet in its plane, as a box of
  // zero thickness (up to two ulps, see fit_box).
  const Vec3 points[3] = {a, b, c};
  const Vec3 centroid = (a + b + c) / 3;
  Vec3 u, v, normal;
  if (detail::facet_frame(a, b, c, u, v, normal)) {
    std::vector<Vec2> planar(3);
    for (int k = 0; k < 3; ++k) planar[k] = Vec2(u.dot(points[k] - centroid), v.dot(points[k] - centroid));
    // Only the rectangle's orientation is used: a minimum-area rectangle is tight along its axes,
    // so fit_box recovers its extents (and center) from the projections.
    return fit_box(frame_from_rectangle(u, v, detail::min_area_rectangle(planar)), points, 3, centroid, Padding::leaf);
  }
  // A point: any frame.
  Mat3 axes;
  axes.col(0) = u;
  axes.col(1) = v;
  axes.col(2) = normal;
  return fit_box(axes, points, 3, centroid, Padding::leaf);
}

Obb obb_enclosing(const Obb& x, const Obb& y, PrincipalAxis axis) {
  // Paper, Section 3.2: the 16 corners of the children as one population.
  Vec3 points[16];
  const auto cx = corners(x);
  const auto cy = corners(y);
  std::copy(cx.begin(), cx.end(), points);
  std::copy(cy.begin(), cy.end(), points + 8);
  return obb_enclosing_points(points, 16, axis);
}

Obb obb_enclosing_points(const Vec3* points, std::size_t count, PrincipalAxis axis) {
  BOXTREE_ASSERT(count > 0, "obb_enclosing_points: no points");
  Vec3 centroid = Vec3::Zero();
  for (std::size_t k = 0; k < count; ++k) centroid += points[k];
  centroid /= Real(count);
  const Mat3 principal = detail::principal_axes(points, count);
  if (axis == PrincipalAxis::all) return fit_box(principal, points, count, centroid, Padding::parent);

  // max / min: one axis is the largest / smallest principal component; the other two are the
  // axes of the minimum-area rectangle enclosing the points projected on the plane normal to it.
  const int fixed = axis == PrincipalAxis::max ? 0 : 2;
  const Vec3 u = principal.col(fixed == 0 ? 1 : 0);
  const Vec3 v = principal.col(fixed == 0 ? 2 : 1);
  std::vector<Vec2> planar(count);
  for (std::size_t k = 0; k < count; ++k) planar[k] = Vec2(u.dot(points[k] - centroid), v.dot(points[k] - centroid));
  return fit_box(frame_from_rectangle(u, v, detail::min_area_rectangle(planar)), points, count, centroid,
                 Padding::parent);
}

}  // namespace boxtree
