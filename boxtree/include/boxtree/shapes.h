// SPDX-License-Identifier: MIT
#pragma once
// Query shapes: small value types, no behaviour beyond construction. The tests between them
// and triangles live in geometry.h; the tests between them and node volumes live beside each
// volume type (volume/aabb.h, ...).
#include <cmath>
#include <limits>

#include "boxtree/mesh.h"

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

// x_a = rotation * x_b + translation. Used as `a_from_b` in tree-vs-tree queries.
struct RigidTransform {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();

  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
  RigidTransform inverse() const { return {rotation.transpose(), -(rotation.transpose() * translation)}; }
  static RigidTransform identity() { return {}; }
};

}  // namespace boxtree
