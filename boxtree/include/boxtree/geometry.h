// SPDX-License-Identifier: MIT
#pragma once
// Exact-as-practical tests between one triangle and a query shape. These are the leaf tests of
// every query; all are closed sets (touching counts as overlapping). An invalid query shape
// (shapes.h: a negative or NaN radius, an inverted box, ...) overlaps nothing; infinite sides of
// an Aabb are handled exactly. Triangles may be degenerate (zero area); no test divides by zero
// or returns NaN for them.
#include "boxtree/shapes.h"
#include "boxtree/volume/aabb.h"

namespace boxtree {

// Barycentric hit: point = (1-u-v)*a + u*b + v*c = ray.origin + t*ray.direction.
struct TriangleHit {
  Real t = 0;
  Real u = 0;
  Real v = 0;
};

// Watertight, two-sided ray/triangle test (Woop, Benthin, Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2013): a ray through a shared edge or vertex of a closed mesh hits at
// least one of the facets around it. Hits with t in [ray.t_min, ray.t_max] only; edges and
// corners are inclusive. Degenerate triangles are never hit. On a hit fills `hit`.
bool intersect_ray_triangle(const Ray& ray, const Vec3& a, const Vec3& b, const Vec3& c, TriangleHit& hit);

// The part of that test that depends on the ray's direction only (the axis permutation and the
// shear that turn the ray into +z), computed once for the many triangles of a tree walk. The
// overload below gives bit for bit the answer of the one above.
struct RayShear {
  int kx = 0, ky = 1, kz = 2;
  Real shear_x = 0, shear_y = 0, shear_z = 0;
  bool valid = false;  // false for a zero or NaN direction: nothing is hit
};
RayShear ray_shear(const Vec3& direction);
bool intersect_ray_triangle(const Ray& ray, const RayShear& shear, const Vec3& a, const Vec3& b, const Vec3& c,
                            TriangleHit& hit);

// Triangle/triangle intersection (closed: touching at a point counts). Handles coplanar and
// degenerate triangles (Guigue & Devillers 2003, with coplanar and degenerate fallbacks). Exact on
// the coordinates given, whatever they are (finite, within the 1e50 build_tree accepts): every
// orientation sign is exact, so two facets sharing a corner or an edge always intersect, and a
// pair reported is a pair that meets. A triangle with its corners on one line is the segment
// between its extreme corners.
bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2);

// Separating-axis test of a triangle against a closed box (Akenine-Moller 2001, 13 axes).
bool triangle_overlaps_aabb(const Vec3& a, const Vec3& b, const Vec3& c, const Aabb& box);
bool triangle_overlaps_obb(const Vec3& a, const Vec3& b, const Vec3& c, const Obb& box);
bool triangle_overlaps_sphere(const Vec3& a, const Vec3& b, const Vec3& c, const Sphere& sphere);
bool triangle_overlaps_capsule(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& capsule);
// The four above by overload, for code generic over the query shape.
inline bool triangle_overlaps(const Vec3& a, const Vec3& b, const Vec3& c, const Aabb& s) {
  return triangle_overlaps_aabb(a, b, c, s);
}
inline bool triangle_overlaps(const Vec3& a, const Vec3& b, const Vec3& c, const Obb& s) {
  return triangle_overlaps_obb(a, b, c, s);
}
inline bool triangle_overlaps(const Vec3& a, const Vec3& b, const Vec3& c, const Sphere& s) {
  return triangle_overlaps_sphere(a, b, c, s);
}
inline bool triangle_overlaps(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& s) {
  return triangle_overlaps_capsule(a, b, c, s);
}
// True if the triangle touches the plane or has corners on both sides of it.
bool triangle_crosses_plane(const Vec3& a, const Vec3& b, const Vec3& c, const Plane& plane);

// An oriented box enclosing the axis-aligned box of half extents `half` swept from centre `from`
// to centre `to`: its first axis is along the motion, so it is far tighter than the axis-aligned
// box of the sweep for long diagonal motions (convex casts). `from == to` gives the box itself.
Obb swept_box(const Vec3& from, const Vec3& to, const Vec3& half);

// Closest point of the (possibly degenerate) triangle to p (Ericson, Real-Time Collision
// Detection, 5.1.5).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);
// Closest points of the segments [p0,p1] and [q0,q1] (Ericson 5.1.9), stable for nearly parallel
// and zero-length segments.
void closest_points_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3& on_p, Vec3& on_q);
// Squared distance between segments [p0,p1] and [q0,q1] (Ericson 5.1.9), robust for zero-length segments.
Real segment_segment_distance_squared(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1);
// Squared distance between a segment and a triangle (0 if they intersect).
Real segment_triangle_distance_squared(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace boxtree
