// SPDX-License-Identifier: MIT
#pragma once
// Reference answers by exhaustive search: every facet, every node, every facet pair. The geometry
// of one triangle against one shape is the library's exact per-triangle test (geometry.h; those
// are checked against independent references in tests/test_geometry.cpp), so that answers agree
// bit for bit where rounding decides a touching contact. Everything else is decided here, not
// by the code under test: which shapes are valid (shapes.h's rule, written out again below
// rather than calling boxtree::is_valid) and how an infinite box side is read.
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/geometry.h"
#include "boxtree/query.h"

namespace boxtree::test {

inline std::vector<RayHit> brute_ray_all_hits(const TriangleMesh& mesh, const Ray& ray) {
  std::vector<RayHit> hits;
  for (FacetId f = 0; f < mesh.facet_count(); ++f) {
    TriangleHit h;
    if (intersect_ray_triangle(ray, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), h))
      hits.push_back({f, h.t, h.u, h.v});
  }
  std::sort(hits.begin(), hits.end(),
            [](const RayHit& a, const RayHit& b) { return a.t != b.t ? a.t < b.t : a.facet < b.facet; });
  return hits;
}

inline std::optional<RayHit> brute_ray_closest_hit(const TriangleMesh& mesh, const Ray& ray) {
  const std::vector<RayHit> hits = brute_ray_all_hits(mesh, ray);
  if (hits.empty()) return std::nullopt;
  return hits.front();
}

// The reference's own reading of shapes.h: an invalid shape matches nothing. A negative radius
// is invalid even where its magnitude would reach the mesh.
inline bool reference_valid(const Sphere& s) {
  return s.center.allFinite() && !std::isnan(s.radius) && !(s.radius < 0);
}
inline bool reference_valid(const Capsule& c) {
  return c.p0.allFinite() && c.p1.allFinite() && !std::isnan(c.radius) && !(c.radius < 0);
}
inline bool reference_valid(const Obb& b) {
  return b.center.allFinite() && b.axes.allFinite() && b.half_extents.allFinite() && b.half_extents.minCoeff() >= 0;
}
inline bool reference_valid(const Aabb& b) {  // infinite sides allowed, NaN and min > max not
  for (int i = 0; i < 3; ++i)
    if (!(b.min[i] <= b.max[i])) return false;
  return true;
}
inline bool reference_valid(const Plane& p) {
  return p.normal.allFinite() && p.normal != Vec3::Zero() && std::isfinite(p.offset);
}

template <class Shape>
bool triangle_overlaps_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Shape& s) {
  if (!reference_valid(s)) return false;
  if constexpr (std::is_same_v<Shape, Aabb>) {
    // A box with infinite sides meets the triangle iff its part within the triangle's bounds
    // does; that part is finite. (Finite boxes are passed as they are: the same rounding.)
    if (s.min.allFinite() && s.max.allFinite()) return triangle_overlaps_aabb(a, b, c, s);
    const Aabb bounds = Aabb::from_triangle(a, b, c);
    const Aabb clipped{s.min.cwiseMax(bounds.min), s.max.cwiseMin(bounds.max)};
    return reference_valid(clipped) && triangle_overlaps_aabb(a, b, c, clipped);
  }
  if constexpr (std::is_same_v<Shape, Obb>) return triangle_overlaps_obb(a, b, c, s);
  if constexpr (std::is_same_v<Shape, Sphere>) return triangle_overlaps_sphere(a, b, c, s);
  if constexpr (std::is_same_v<Shape, Capsule>) return triangle_overlaps_capsule(a, b, c, s);
}

template <class Shape>
std::vector<FacetId> brute_overlap(const TriangleMesh& mesh, const Shape& shape) {
  std::vector<FacetId> out;
  for (FacetId f = 0; f < mesh.facet_count(); ++f)
    if (triangle_overlaps_shape(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), shape)) out.push_back(f);
  return out;
}

// Facets touching the plane or with corners on both sides of it.
inline std::vector<FacetId> brute_plane(const TriangleMesh& mesh, const Plane& plane) {
  std::vector<FacetId> out;
  if (!reference_valid(plane)) return out;
  for (FacetId f = 0; f < mesh.facet_count(); ++f) {
    Real lo = 0, hi = 0;
    for (int k = 0; k < 3; ++k) {
      const Real d = plane.normal.dot(mesh.corner(f, k)) - plane.offset;
      lo = k == 0 ? d : std::min(lo, d);
      hi = k == 0 ? d : std::max(hi, d);
    }
    if (lo <= 0 && hi >= 0) out.push_back(f);
  }
  return out;
}

inline std::vector<FacetPair> brute_collide(const TriangleMesh& a, const TriangleMesh& b,
                                            const RigidTransform& a_from_b) {
  std::vector<Vec3> moved(b.vertices.size());
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = a_from_b.apply(b.vertices[i]);
  std::vector<FacetPair> out;
  for (FacetId fb = 0; fb < b.facet_count(); ++fb) {
    const Vec3& q0 = moved[b.triangles[fb][0]];
    const Vec3& q1 = moved[b.triangles[fb][1]];
    const Vec3& q2 = moved[b.triangles[fb][2]];
    const Aabb box_b = Aabb::from_triangle(q0, q1, q2);
    for (FacetId fa = 0; fa < a.facet_count(); ++fa) {
      // The box pre-check is exact (disjoint boxes => disjoint triangles) and keeps this fast.
      if (!overlaps(Aabb::from_triangle(a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2)), box_b)) continue;
      if (triangles_intersect(a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2), q0, q1, q2)) out.push_back({fa, fb});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace boxtree::test
