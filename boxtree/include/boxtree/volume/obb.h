// SPDX-License-Identifier: MIT
#pragma once
// Oriented boxes as node volumes (paper, Section 3.2). The geometry lives in `Obb` (shapes.h,
// also a query shape); the three parent rules are three volume types, OrientedBox<axis>:
//   all  - the three principal components of the 16 child corners are the axes;
//   max  - the largest principal component is one axis, the other two come from the
//          minimum-area rectangle enclosing the corners projected along it;
//   min  - the same with the smallest principal component.
// Leaf rule (all three): the minimum-area rectangle enclosing the facet, zero thickness.
#include <optional>

#include "boxtree/volume/aabb.h"
#include "boxtree/volume/polytope.h"

namespace boxtree {

enum class PrincipalAxis { all, max, min };

// ---- Obb geometry (src/volume_obb.cpp) ----
std::array<Vec3, 8> corners(const Obb& box);
ConvexPolytope polytope_of(const Obb& box);
ConvexPolytope polytope_of(const Aabb& box);
Real surface_area(const Obb& box);
Real volume(const Obb& box);
Real mean_width(const Obb& box);  // sum of the full edge lengths / 2
inline Vec3 center(const Obb& box) { return box.center; }
Aabb bounding_aabb(const Obb& box);
bool contains(const Obb& box, const Vec3& p, Real tolerance = 0);
bool contains(const Obb& outer, const Obb& inner, Real tolerance = 0);  // all 8 corners
bool overlaps(const Obb& box, const Aabb& query);
bool overlaps(const Obb& box, const Obb& query);
bool overlaps(const Obb& box, const Sphere& query);
bool overlaps(const Obb& box, const Capsule& query);  // may be conservative, never misses
bool overlaps(const Obb& box, const Plane& plane);
bool overlaps(const Obb& a, const Obb& b, const RigidTransform& a_from_b);  // b in frame B
bool intersect_ray(const Obb& box, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter = nullptr);

// The fits (src/volume_obb.cpp).
Obb obb_from_triangle(const Vec3& a, const Vec3& b, const Vec3& c);
Obb obb_enclosing(const Obb& x, const Obb& y, PrincipalAxis axis);
// The same parent rule applied to any point set (count >= 1), e.g. all facet vertices below a node.
Obb obb_enclosing_points(const Vec3* points, std::size_t count, PrincipalAxis axis);

namespace detail {
// The leaf rules' frame of a facet (shared by obb_from_triangle and prism_from_triangle): an
// orthonormal (u, v, normal), u along the longest edge and v by Gram-Schmidt, so the corners lie
// in the (u, v) plane to rounding even for needles. False for a point (an arbitrary frame).
bool facet_frame(const Vec3& a, const Vec3& b, const Vec3& c, Vec3& u, Vec3& v, Vec3& normal);
}  // namespace detail

template <PrincipalAxis kAxis>
struct OrientedBox {
  Obb box;

  static constexpr const char* kind_name = kAxis == PrincipalAxis::all   ? "obb-all"
                                           : kAxis == PrincipalAxis::max ? "obb-max"
                                                                         : "obb-min";
  static OrientedBox from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) { return {obb_from_triangle(a, b, c)}; }
  static OrientedBox enclosing(const OrientedBox& x, const OrientedBox& y) {
    return {obb_enclosing(x.box, y.box, kAxis)};
  }
  // The parent rule applied to the facet vertices below a node (BuildSettings::parent_fit).
  static std::optional<OrientedBox> fitted(const Vec3* points, std::size_t count) {
    return OrientedBox{obb_enclosing_points(points, count, kAxis)};
  }
};

using ObbAll = OrientedBox<PrincipalAxis::all>;
using ObbMax = OrientedBox<PrincipalAxis::max>;
using ObbMin = OrientedBox<PrincipalAxis::min>;

// The volume operations on OrientedBox<K> are those of its Obb.
template <PrincipalAxis K>
Real surface_area(const OrientedBox<K>& v) {
  return surface_area(v.box);
}
template <PrincipalAxis K>
Real volume(const OrientedBox<K>& v) {
  return volume(v.box);
}
template <PrincipalAxis K>
Real mean_width(const OrientedBox<K>& v) {
  return mean_width(v.box);
}
template <PrincipalAxis K>
Vec3 center(const OrientedBox<K>& v) {
  return v.box.center;
}
template <PrincipalAxis K>
Aabb bounding_aabb(const OrientedBox<K>& v) {
  return bounding_aabb(v.box);
}
template <PrincipalAxis K>
ConvexPolytope polytope_of(const OrientedBox<K>& v) {
  return polytope_of(v.box);
}
template <PrincipalAxis K>
bool contains(const OrientedBox<K>& v, const Vec3& p, Real tol = 0) {
  return contains(v.box, p, tol);
}
template <PrincipalAxis K>
bool contains(const OrientedBox<K>& o, const OrientedBox<K>& i, Real tol = 0) {
  return contains(o.box, i.box, tol);
}
template <PrincipalAxis K, class Shape>
bool overlaps(const OrientedBox<K>& v, const Shape& s) {
  return overlaps(v.box, s);
}
template <PrincipalAxis K>
bool overlaps(const OrientedBox<K>& a, const OrientedBox<K>& b, const RigidTransform& t) {
  return overlaps(a.box, b.box, t);
}
template <PrincipalAxis K>
bool intersect_ray(const OrientedBox<K>& v, const RayPrecomputed& ray, Real t_min, Real t_max,
                   Real* t_enter = nullptr) {
  return intersect_ray(v.box, ray, t_min, t_max, t_enter);
}

}  // namespace boxtree
