// SPDX-License-Identifier: MIT
#pragma once
// The paper's hybrids (Section 4): a method's volumes in the lower levels of the tree and
// axis-aligned boxes from a chosen level up ("pie-min+aabb@L": levels >= L are boxes; level =
// height of the node's subtree, leaves are level 0). Oriented volumes are tightest near the
// leaves, axis-aligned boxes are as tight and far cheaper to test near the root.
//
// A hybrid tree has the topology of the lower method's tree; build_tree<Hybrid<V>> builds that
// tree and replaces the volumes of the upper levels by the smallest boxes enclosing their
// children (BuildSettings::hybrid_level).
#include "boxtree/volume/pie_slice.h"

namespace boxtree {

template <class LowerVolume>
struct Hybrid {
  using Lower = LowerVolume;
  Lower lower;  // valid when !is_box
  Aabb box;     // valid when is_box
  bool is_box = false;

  static constexpr const char* kind_name = "hybrid";
  static Hybrid from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    return {Lower::from_triangle(a, b, c), Aabb(), false};
  }
  // Once a box, always a box: the parent of a box is the box around both children.
  static Hybrid enclosing(const Hybrid& x, const Hybrid& y) {
    if (!x.is_box && !y.is_box) return {Lower::enclosing(x.lower, y.lower), Aabb(), false};
    return {Lower(), Aabb::enclosing(x.bounds(), y.bounds()), true};
  }
  static Hybrid upper(const Aabb& b) { return {Lower(), b, true}; }
  Aabb bounds() const { return is_box ? box : bounding_aabb(lower); }
};

template <class V>
struct is_hybrid : std::false_type {};
template <class L>
struct is_hybrid<Hybrid<L>> : std::true_type {};
template <class V>
inline constexpr bool is_hybrid_v = is_hybrid<V>::value;

// Any two volume kinds, b given in frame B: exact SAT over their polytopes.
template <class A, class B>
bool overlaps_by_polytopes(const A& a, const B& b, const RigidTransform& a_from_b) {
  return sat_overlap(polytope_of(a), polytope_of(b).transformed(a_from_b));
}

template <class L>
Real surface_area(const Hybrid<L>& v) {
  return v.is_box ? surface_area(v.box) : surface_area(v.lower);
}
template <class L>
Real volume(const Hybrid<L>& v) {
  return v.is_box ? volume(v.box) : volume(v.lower);
}
template <class L>
Real mean_width(const Hybrid<L>& v) {
  return v.is_box ? mean_width(v.box) : mean_width(v.lower);
}
template <class L>
Vec3 center(const Hybrid<L>& v) {
  return v.is_box ? v.box.center() : center(v.lower);
}
template <class L>
Aabb bounding_aabb(const Hybrid<L>& v) {
  return v.bounds();
}
template <class L>
ConvexPolytope polytope_of(const Hybrid<L>& v) {
  return v.is_box ? polytope_of(v.box) : polytope_of(v.lower);
}
template <class L>
bool contains(const Hybrid<L>& v, const Vec3& p, Real tol = 0) {
  return v.is_box ? contains(v.box, p, tol) : contains(v.lower, p, tol);
}
// A box contains a convex volume iff it contains the volume's bounding box.
template <class L>
bool contains(const Hybrid<L>& outer, const Hybrid<L>& inner, Real tol = 0) {
  if (outer.is_box) return contains(outer.box, inner.bounds(), tol);
  if (inner.is_box) return false;  // a lower-level volume never holds an upper-level box
  return contains(outer.lower, inner.lower, tol);
}
template <class L, class Shape>
bool overlaps(const Hybrid<L>& v, const Shape& s) {
  return v.is_box ? overlaps(v.box, s) : overlaps(v.lower, s);
}
template <class L>
bool overlaps(const Hybrid<L>& a, const Hybrid<L>& b, const RigidTransform& a_from_b) {
  if (a.is_box && b.is_box) return overlaps(a.box, b.box, a_from_b);
  if (!a.is_box && !b.is_box) return overlaps(a.lower, b.lower, a_from_b);
  if (a.is_box) return overlaps_by_polytopes(a.box, b.lower, a_from_b);
  return overlaps_by_polytopes(a.lower, b.box, a_from_b);
}
template <class L>
bool intersect_ray(const Hybrid<L>& v, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter = nullptr) {
  return v.is_box ? intersect_ray(v.box, ray, t_min, t_max, t_enter)
                  : intersect_ray(v.lower, ray, t_min, t_max, t_enter);
}

}  // namespace boxtree
