// SPDX-License-Identifier: MIT
#pragma once
// Reference answers by exhaustive search: every facet, every node, every facet pair. The
// overlap geometry is decided here, not by the code under test: reference_geometry.h's own
// triangle tests (sharing no predicate with geometry.h), shapes.h's validity rule written out
// again below rather than calling boxtree::is_valid, and how an infinite box side is read. Rays
// still use the library's watertight ray/triangle test (geometry.h), because the callers compare
// hit distances bit for bit; that test is checked against an independent linear solve in
// tests/test_geometry.cpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/geometry.h"  // intersect_ray_triangle only
#include "boxtree/query.h"
#include "support/reference_geometry.h"

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
    // does; that part is finite.
    const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const Vec3 clipped_lo = s.min.cwiseMax(lo), clipped_hi = s.max.cwiseMin(hi);
    if (!(clipped_lo.array() <= clipped_hi.array()).all()) return false;
    const bool finite = s.min.allFinite() && s.max.allFinite();
    return finite ? reference::triangle_meets_aabb(a, b, c, s.min, s.max)
                  : reference::triangle_meets_aabb(a, b, c, clipped_lo, clipped_hi);
  }
  if constexpr (std::is_same_v<Shape, Obb>)
    return reference::triangle_meets_obb(a, b, c, s.center, s.axes, s.half_extents);
  if constexpr (std::is_same_v<Shape, Sphere>)
    return reference::point_triangle_distance2(s.center, a, b, c) <= s.radius * s.radius;
  if constexpr (std::is_same_v<Shape, Capsule>)
    return reference::segment_triangle_distance2(s.p0, s.p1, a, b, c) <= s.radius * s.radius;
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
  const auto corners = [](const Vec3& p, const Vec3& q, const Vec3& r) { return std::array<Vec3, 3>{p, q, r}; };
  const auto apart = [](const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
    // Disjoint bounding boxes (compared exactly) mean disjoint triangles; this keeps it fast.
    for (int k = 0; k < 3; ++k) {
      if (std::max({s[0][k], s[1][k], s[2][k]}) < std::min({t[0][k], t[1][k], t[2][k]})) return true;
      if (std::max({t[0][k], t[1][k], t[2][k]}) < std::min({s[0][k], s[1][k], s[2][k]})) return true;
    }
    return false;
  };
  std::vector<FacetPair> out;
  for (FacetId fb = 0; fb < b.facet_count(); ++fb) {
    const auto q = corners(moved[b.triangles[fb][0]], moved[b.triangles[fb][1]], moved[b.triangles[fb][2]]);
    for (FacetId fa = 0; fa < a.facet_count(); ++fa) {
      const auto p = corners(a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2));
      if (!apart(p, q) && reference::triangles_meet(p, q)) out.push_back({fa, fb});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace boxtree::test
