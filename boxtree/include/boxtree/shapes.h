// SPDX-License-Identifier: MIT
#pragma once
// Query shapes: small value types, no behaviour beyond construction. The tests between them
// and triangles live in geometry.h; the tests between them and node volumes live beside each
// volume type (volume/aabb.h, ...).
#include <cmath>
#include <limits>

#include "boxtree/math.h"
#include "boxtree/mesh.h"  // not used here; kept for the files that take FacetId and TriangleMesh from here

namespace boxtree {

// Points o + t*d for t in [t_min, t_max]. `direction` need not be normalized; t is in units of
// |direction|. A segment from p to q is Ray{p, q - p, 0, 1}.
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();
  Real t_min = 0;
  Real t_max = std::numeric_limits<Real>::infinity();
};

// What every ray query accepts: finite origin and direction, and a t range that is not NaN and
// not empty. Queries answer "no hit" for anything else.
inline bool is_valid(const Ray& ray) {
  return ray.origin.allFinite() && ray.direction.allFinite() && !std::isnan(ray.t_min) && !std::isnan(ray.t_max) &&
         ray.t_min <= ray.t_max;
}

struct Sphere {
  Vec3 center = Vec3::Zero();
  Real radius = 0;
};

// All points within `radius` of the segment [p0, p1].
struct Capsule {
  Vec3 p0 = Vec3::Zero();
  Vec3 p1 = Vec3::Zero();
  Real radius = 0;
};

// The plane {x : normal . x == offset}. `normal` need not be unit length.
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  Real offset = 0;
  Real signed_distance_scaled(const Vec3& p) const { return normal.dot(p) - offset; }
};

// Oriented box: center + axes.col(i) * s_i with |s_i| <= half_extents[i]. `axes` is a rotation
// (orthonormal columns). A half extent may be zero (a rectangle or a segment).
struct Obb {
  Vec3 center = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
  Vec3 half_extents = Vec3::Zero();
};

// What every overlap and plane query accepts, as is_valid(Ray) above for rays: an invalid shape
// matches nothing, wherever it lies and whatever its size's magnitude would touch, in every tree
// form (Tree<V> of every volume kind, hybrids included, PackedAabbTree, PackedPrismTree, AnyTree)
// and in both FacetTest modes. The queries check this once, on entry; the triangle tests of
// geometry.h and the volume tests of a sphere or capsule (volume/*.h) answer "no overlap" too.
//  - Sphere: finite centre, radius >= 0 (not NaN; +infinity is all of space). A negative radius
//    is not read as its magnitude: Sphere{c, -1} matches nothing even where Sphere{c, 1} touches
//    the mesh.
//  - Capsule: finite ends, radius as a sphere's (p0 == p1 is a sphere).
//  - Obb: finite centre, axes and half extents, half extents >= 0 (zero: a rectangle or segment).
//  - Aabb (volume/aabb.h): no NaN, min <= max on every axis; infinite sides are allowed (a
//    half-space or all of space).
//  - Plane: finite normal, not zero, and finite offset.
inline bool is_valid(const Sphere& s) { return s.center.allFinite() && s.radius >= 0; }
inline bool is_valid(const Capsule& c) { return c.p0.allFinite() && c.p1.allFinite() && c.radius >= 0; }
inline bool is_valid(const Obb& box) {
  return box.center.allFinite() && box.axes.allFinite() && box.half_extents.allFinite() &&
         (box.half_extents.array() >= 0).all();
}
inline bool is_valid(const Plane& plane) {
  return plane.normal.allFinite() && !plane.normal.isZero(0) && std::isfinite(plane.offset);
}

}  // namespace boxtree
