// SPDX-License-Identifier: MIT
#pragma once
// Pie slices as node volumes (paper, Section 3.3): a triangle swept along a segment normal to
// it, i.e. a right triangular prism. Parent rule: the max or min principal component of the 12
// child corners is the sweep axis; the corners projected along it get a minimum-area enclosing
// triangle: isosceles (the paper's rule) or general (O'Rourke et al.). Leaf: the facet itself,
// zero thickness.
#include "boxtree/volume/obb.h"

namespace boxtree {

// {p + s * axis : p in triangle(base), s in [0, height]}; `axis` is unit length and normal to
// the base triangle's plane. The base may be degenerate (a segment or a point).
struct Prism {
  std::array<Vec3, 3> base = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 axis = Vec3::UnitZ();
  Real height = 0;
};

enum class TriangleRule { isosceles, general };

// ---- Prism geometry (src/volume_prism.cpp) ----
std::array<Vec3, 6> corners(const Prism& prism);
ConvexPolytope polytope_of(const Prism& prism);
Real surface_area(const Prism& prism);  // 2 * base area + perimeter * height
Real volume(const Prism& prism);
Real mean_width(const Prism& prism);  // height / 2 + perimeter / 4
Vec3 center(const Prism& prism);
Aabb bounding_aabb(const Prism& prism);
bool contains(const Prism& prism, const Vec3& p, Real tolerance = 0);
bool contains(const Prism& outer, const Prism& inner, Real tolerance = 0);  // all 6 corners
bool overlaps(const Prism& prism, const Aabb& query);
bool overlaps(const Prism& prism, const Obb& query);
bool overlaps(const Prism& prism, const Sphere& query);   // exact: triangle x segment distance
bool overlaps(const Prism& prism, const Capsule& query);  // may be conservative, never misses
bool overlaps(const Prism& prism, const Plane& plane);
bool overlaps(const Prism& a, const Prism& b, const RigidTransform& a_from_b);
bool intersect_ray(const Prism& prism, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter = nullptr);

Prism prism_from_triangle(const Vec3& a, const Vec3& b, const Vec3& c);
Prism prism_enclosing(const Prism& x, const Prism& y, PrincipalAxis axis, TriangleRule rule);
// The same parent rule applied to any point set (count >= 1). The triangle fits cost O(h^3) on
// a projected hull of h points (the general rule, src/fit.cpp): nullopt when h > max_hull.
std::optional<Prism> prism_enclosing_points(const Vec3* points, std::size_t count, PrincipalAxis axis,
                                            TriangleRule rule, std::size_t max_hull);

template <PrincipalAxis kAxis, TriangleRule kRule>
struct PieSlice {
  Prism prism;

  static constexpr const char* kind_name = kAxis == PrincipalAxis::max
                                               ? (kRule == TriangleRule::isosceles ? "pie-max" : "pie-max-general")
                                               : (kRule == TriangleRule::isosceles ? "pie-min" : "pie-min-general");
  static PieSlice from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) { return {prism_from_triangle(a, b, c)}; }
  static PieSlice enclosing(const PieSlice& x, const PieSlice& y) {
    return {prism_enclosing(x.prism, y.prism, kAxis, kRule)};
  }
  // The parent rule applied to the facet vertices below a node (BuildSettings::parent_fit);
  // nullopt when their projected hull is too large for the triangle fit (the build then keeps
  // the children's rule for that node).
  static constexpr std::size_t kMaxFittedHull = 64;
  static std::optional<PieSlice> fitted(const Vec3* points, std::size_t count) {
    auto prism = prism_enclosing_points(points, count, kAxis, kRule, kMaxFittedHull);
    if (!prism) return std::nullopt;
    return PieSlice{*prism};
  }
};

using PieMax = PieSlice<PrincipalAxis::max, TriangleRule::isosceles>;
using PieMin = PieSlice<PrincipalAxis::min, TriangleRule::isosceles>;
using PieMaxGeneral = PieSlice<PrincipalAxis::max, TriangleRule::general>;
using PieMinGeneral = PieSlice<PrincipalAxis::min, TriangleRule::general>;

template <PrincipalAxis K, TriangleRule R>
Real surface_area(const PieSlice<K, R>& v) {
  return surface_area(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
Real volume(const PieSlice<K, R>& v) {
  return volume(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
Real mean_width(const PieSlice<K, R>& v) {
  return mean_width(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
Vec3 center(const PieSlice<K, R>& v) {
  return center(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
Aabb bounding_aabb(const PieSlice<K, R>& v) {
  return bounding_aabb(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
ConvexPolytope polytope_of(const PieSlice<K, R>& v) {
  return polytope_of(v.prism);
}
template <PrincipalAxis K, TriangleRule R>
bool contains(const PieSlice<K, R>& v, const Vec3& p, Real tol = 0) {
  return contains(v.prism, p, tol);
}
template <PrincipalAxis K, TriangleRule R>
bool contains(const PieSlice<K, R>& o, const PieSlice<K, R>& i, Real tol = 0) {
  return contains(o.prism, i.prism, tol);
}
template <PrincipalAxis K, TriangleRule R, class Shape>
bool overlaps(const PieSlice<K, R>& v, const Shape& s) {
  return overlaps(v.prism, s);
}
template <PrincipalAxis K, TriangleRule R>
bool overlaps(const PieSlice<K, R>& a, const PieSlice<K, R>& b, const RigidTransform& t) {
  return overlaps(a.prism, b.prism, t);
}
template <PrincipalAxis K, TriangleRule R>
bool intersect_ray(const PieSlice<K, R>& v, const RayPrecomputed& ray, Real t_min, Real t_max,
                   Real* t_enter = nullptr) {
  return intersect_ray(v.prism, ray, t_min, t_max, t_enter);
}

}  // namespace boxtree
