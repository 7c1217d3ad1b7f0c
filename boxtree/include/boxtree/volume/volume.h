// SPDX-License-Identifier: MIT
#pragma once
// The operations every volume kind provides, and a compile-time check of them. The builder,
// the queries and the statistics use nothing else, so a new kind (oriented boxes, pie slices)
// slots in by providing this set and an explicit instantiation in each src/*.cpp.
//
//   V::from_triangle(a, b, c)     leaf rule: a volume enclosing one facet
//   V::enclosing(x, y)            parent rule: a volume enclosing two children
//   surface_area(v), volume(v), mean_width(v), center(v), bounding_aabb(v)
//   contains(v, point, tol), contains(outer, inner, tol)
//   overlaps(v, Aabb | Obb | Sphere | Capsule | Plane)        query shapes
//   overlaps(v, w, a_from_b)                                   two trees, w given in frame b
//   intersect_ray(v, RayPrecomputed, t_min, t_max, &t_enter)   conservative slab-like test
#include <type_traits>

#include "boxtree/volume/aabb.h"

namespace boxtree {

template <class V, class = void>
struct is_volume : std::false_type {};

template <class V>
struct is_volume<V, std::void_t<decltype(V::from_triangle(Vec3(), Vec3(), Vec3())), decltype(V::enclosing(V(), V())),
                                decltype(surface_area(V())), decltype(volume(V())), decltype(mean_width(V())),
                                decltype(center(V())), decltype(bounding_aabb(V())),
                                decltype(contains(V(), Vec3(), Real())), decltype(contains(V(), V(), Real())),
                                decltype(overlaps(V(), Aabb())), decltype(overlaps(V(), Obb())),
                                decltype(overlaps(V(), Sphere())), decltype(overlaps(V(), Capsule())),
                                decltype(overlaps(V(), Plane())), decltype(overlaps(V(), V(), RigidTransform())),
                                decltype(intersect_ray(V(), std::declval<const RayPrecomputed&>(), Real(), Real(),
                                                       static_cast<Real*>(nullptr)))>> : std::true_type {};

template <class V>
inline constexpr bool is_volume_v = is_volume<V>::value;

static_assert(is_volume_v<Aabb>, "Aabb must provide every volume operation");

}  // namespace boxtree
