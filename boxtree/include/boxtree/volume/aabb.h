// SPDX-License-Identifier: MIT
#pragma once
// Axis-aligned box: the paper's Section 3.1 volume and the first volume kind of the library.
// Every volume kind offers the same set of operations (see volume/volume.h for the list and the
// compile-time check); the builder and the queries use nothing else.
#include <algorithm>
#include <cmath>
#include <limits>

#include "boxtree/shapes.h"

namespace boxtree {

struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<Real>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<Real>::infinity());

  static constexpr const char* kind_name = "aabb";

  static Aabb empty() { return {}; }
  static Aabb from_points(const Vec3& a, const Vec3& b) { return {a.cwiseMin(b), a.cwiseMax(b)}; }
  // Leaf rule: the smallest box around the facet.
  static Aabb from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    return {a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
  }
  // Parent rule (paper 3.1): the smallest box enclosing both children.
  static Aabb enclosing(const Aabb& x, const Aabb& y) { return {x.min.cwiseMin(y.min), x.max.cwiseMax(y.max)}; }

  bool is_empty() const { return (min.array() > max.array()).any(); }
  Vec3 center() const { return (min + max) * Real(0.5); }
  Vec3 extent() const { return max - min; }
  void expand(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
};

inline Real surface_area(const Aabb& box) {
  const Vec3 e = box.extent();
  return 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}
inline Real volume(const Aabb& box) {
  const Vec3 e = box.extent();
  return e.x() * e.y() * e.z();
}
// Mean width (the mean over directions of the box's extent along them): (a + b + c) / 2 for
// edge lengths a, b, c. By Crofton's formula the chance that a random plane meets a convex body
// is proportional to its mean width, as the chance that a random line meets it is proportional
// to its surface area.
inline Real mean_width(const Aabb& box) { return box.extent().sum() / 2; }
inline Vec3 center(const Aabb& box) { return box.center(); }
inline Aabb bounding_aabb(const Aabb& box) { return box; }

// Closed containment, up to `tolerance` (absolute, per coordinate).
inline bool contains(const Aabb& box, const Vec3& p, Real tolerance = 0) {
  return (p.array() >= box.min.array() - tolerance).all() && (p.array() <= box.max.array() + tolerance).all();
}
// `outer` contains `inner` up to `tolerance` (absolute, per coordinate).
inline bool contains(const Aabb& outer, const Aabb& inner, Real tolerance = 0) {
  return (inner.min.array() >= outer.min.array() - tolerance).all() &&
         (inner.max.array() <= outer.max.array() + tolerance).all();
}

// The query shape rule of shapes.h: no NaN, min <= max on every axis (infinite sides allowed).
// Aabb::empty() is not a valid query shape.
inline bool is_valid(const Aabb& box) { return (box.min.array() <= box.max.array()).all(); }

// A valid query box with infinite sides (a half-space, shapes.h) clipped to `bounds`, finite
// bounds that hold the shape it is tested against: the same overlap answer, in finite arithmetic.
// False when the clipped box is empty (no overlap).
inline bool clip_infinite_sides(Aabb& query, const Aabb& bounds) {
  query = {query.min.cwiseMax(bounds.min), query.max.cwiseMin(bounds.max)};
  return is_valid(query) && query.min.allFinite() && query.max.allFinite();
}

inline bool overlaps(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

// False for an invalid sphere (shapes.h).
inline bool overlaps(const Aabb& box, const Sphere& s) {
  if (!is_valid(s)) return false;
  const Vec3 closest = s.center.cwiseMax(box.min).cwiseMin(box.max);
  return (closest - s.center).squaredNorm() <= s.radius * s.radius;
}

bool overlaps(const Aabb& box, const Obb& obb);
bool overlaps(const Aabb& box, const Capsule& capsule);  // false for an invalid capsule (shapes.h)
bool overlaps(const Aabb& box, const Plane& plane);

// Box `b` given in frame B, box `a` in frame A, x_a = a_from_b(x_b): exact separating-axis test
// of the two boxes (15 axes; Gottschalk, Lin, Manocha, "OBBTree", 1996).
bool overlaps(const Aabb& a, const Aabb& b, const RigidTransform& a_from_b);

// Per-ray data computed once per query so that each box test is a few multiplies.
struct RayPrecomputed {
  Vec3 origin;
  Vec3 direction;
  Vec3 inv_direction;  // +-inf where direction is 0
  explicit RayPrecomputed(const Ray& ray)
      : origin(ray.origin), direction(ray.direction), inv_direction(ray.direction.cwiseInverse()) {}
};

// Slab test over [t_min, t_max]; returns false if the ray misses the closed box, else sets
// *t_enter (if given) to where the ray enters it (>= t_min). Conservative:
// t_far is widened by a few ulps (Ize, "Robust BVH Ray Traversal", JCGT 2013) so rounding never
// culls a box that the exact ray touches. Rays lying exactly in a face plane count as touching.
inline bool intersect_ray(const Aabb& box, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter = nullptr) {
  constexpr Real kPad = 4 * std::numeric_limits<Real>::epsilon();  // relative error of each t, with margin
  Real t_near = t_min;
  Real t_far = t_max;
  for (int i = 0; i < 3; ++i) {
    if (ray.direction[i] == 0) {
      if (ray.origin[i] < box.min[i] || ray.origin[i] > box.max[i]) return false;
      continue;
    }
    Real t0 = (box.min[i] - ray.origin[i]) * ray.inv_direction[i];
    Real t1 = (box.max[i] - ray.origin[i]) * ray.inv_direction[i];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0 - std::abs(t0) * kPad);
    t_far = std::min(t_far, t1 + std::abs(t1) * kPad);
    if (t_near > t_far) return false;
  }
  if (t_enter) *t_enter = t_near;
  return true;
}

}  // namespace boxtree
