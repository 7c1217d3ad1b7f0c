// SPDX-License-Identifier: MIT
#pragma once
// Reference answers by exhaustive search: every facet, every node, every facet pair. The
// overlap geometry is decided here, not by the code under test: reference_geometry.h's own
// triangle tests (sharing no predicate with geometry.h), shapes.h's validity rule written out
// again below rather than calling boxtree::is_valid, and how an infinite box side is read.
//
// Rays still use the library's watertight ray/triangle test (geometry.h): callers compare hit
// distances and barycentrics bit for bit, which only the same arithmetic gives, and where a ray
// crosses a shared edge which facet is hit is the test's own choice (any one of them, never none).
// That test is checked on its own against an independent linear solve and for watertightness
// in tests/test_geometry.cpp.
//
// Overlap answers come as two sets (Expected): `must`, what the library has to report, and
// `may`, what it is allowed to. They differ only near touching: a facet (or facet pair) within
// the tolerance of touching the shape is in `may` alone, because the library rounds (a sphere's
// distance, a rotated box's corners, b's corners moved into a's frame) and touching, for such
// shapes, is not decided the same way by two roundings. The tolerance is relative: kTolerance
// times the query's scale (1 + the largest coordinate magnitude of the mesh and the shape), far
// above the library's rounding and far below any geometry of the tests. Tolerance 0 asks for
// the exact answer, where the library promises it: tree vs tree at the identity (its triangle
// test is exact on the coordinates it is given), and shapes whose arithmetic is exact in double
// (small dyadic coordinates, geometry.cpp's convention). Check with `violations`.
#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
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

// The default relative tolerance of the overlap answers (see the top of the file).
inline constexpr Real kTolerance = 1e-12;

// What a query must report and what it may: must ⊆ may, both sorted.
template <class T>
struct Expected {
  std::vector<T> must;
  std::vector<T> may;
};

inline std::ostream& operator<<(std::ostream& out, const FacetPair& p) {
  return out << "(" << p.a << ", " << p.b << ")";
}

// "" if must ⊆ got ⊆ may (got sorted), else what breaks it (the first few of each kind), for
// EXPECT_EQ(violations(got, expected), "") and for the fuzz targets.
template <class T>
std::string violations(const std::vector<T>& got, const Expected<T>& expected) {
  std::vector<T> missed, extra;
  std::set_difference(expected.must.begin(), expected.must.end(), got.begin(), got.end(), std::back_inserter(missed));
  std::set_difference(got.begin(), got.end(), expected.may.begin(), expected.may.end(), std::back_inserter(extra));
  if (missed.empty() && extra.empty()) return "";
  std::ostringstream out;
  const auto list = [&](const char* what, const std::vector<T>& items) {
    if (items.empty()) return;
    out << items.size() << " " << what << ":";
    for (std::size_t i = 0; i < items.size() && i < 5; ++i) out << " " << items[i];
    out << (items.size() > 5 ? " ..." : "") << "; ";
  };
  list("missed (in must, not reported)", missed);
  list("extra (reported, not in may)", extra);
  out << "reported " << got.size() << ", must " << expected.must.size() << ", may " << expected.may.size();
  return out.str();
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

// The exact closed test (up to the rounding of distances) of one facet against a valid shape.
template <class Shape>
bool triangle_overlaps_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Shape& s) {
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

// Largest finite coordinate magnitude of a shape (its extent included), of a mesh.
inline Real magnitude(const Vec3& p) {
  Real m = 0;
  for (int i = 0; i < 3; ++i)
    if (std::isfinite(p[i])) m = std::max(m, std::abs(p[i]));
  return m;
}
inline Real magnitude(const Sphere& s) { return magnitude(s.center) + (std::isfinite(s.radius) ? s.radius : 0); }
inline Real magnitude(const Capsule& c) {
  return std::max(magnitude(c.p0), magnitude(c.p1)) + (std::isfinite(c.radius) ? c.radius : 0);
}
inline Real magnitude(const Aabb& b) { return std::max(magnitude(b.min), magnitude(b.max)); }
inline Real magnitude(const Obb& b) { return magnitude(b.center) + b.half_extents.sum(); }
inline Real magnitude(const TriangleMesh& mesh) {
  Real m = 0;
  for (const Vec3& v : mesh.vertices) m = std::max(m, magnitude(v));
  return m;
}

// The valid shape grown (delta > 0) or shrunk (delta < 0) by |delta| all round; a shrunk box
// keeps at least its mid-plane, a shrunk radius below zero makes the shape invalid.
inline Sphere offset_shape(Sphere s, Real delta) {
  s.radius += delta;
  return s;
}
inline Capsule offset_shape(Capsule c, Real delta) {
  c.radius += delta;
  return c;
}
inline Aabb offset_shape(Aabb b, Real delta) {
  for (int i = 0; i < 3; ++i) {
    const Real lo = b.min[i] - delta, hi = b.max[i] + delta;
    if (lo <= hi) {
      b.min[i] = lo;
      b.max[i] = hi;
    } else {
      b.min[i] = b.max[i] = b.min[i] + (b.max[i] - b.min[i]) / 2;
    }
  }
  return b;
}
inline Obb offset_shape(Obb b, Real delta) {
  b.half_extents = (b.half_extents.array() + delta).max(Real(0)).matrix();
  return b;
}

// Facets meeting the shape: `must` those that meet it shrunk by the tolerance, `may` those that
// meet it grown by it.
template <class Shape>
Expected<FacetId> brute_overlap(const TriangleMesh& mesh, const Shape& shape, Real tolerance = kTolerance) {
  Expected<FacetId> out;
  if (!reference_valid(shape)) return out;
  const Real delta = tolerance * (1 + std::max(magnitude(mesh), magnitude(shape)));
  const Shape inner = offset_shape(shape, -delta), outer = offset_shape(shape, delta);
  const bool inner_valid = reference_valid(inner);
  for (FacetId f = 0; f < mesh.facet_count(); ++f) {
    const Vec3 &a = mesh.corner(f, 0), &b = mesh.corner(f, 1), &c = mesh.corner(f, 2);
    if (!triangle_overlaps_shape(a, b, c, outer)) continue;  // then not the inner one either
    out.may.push_back(f);
    if (inner_valid && triangle_overlaps_shape(a, b, c, inner)) out.must.push_back(f);
  }
  return out;
}

// Facets touching the plane or with corners on both sides of it: `must` those reaching the
// tolerance beyond it on both sides, `may` those within the tolerance of it.
inline Expected<FacetId> brute_plane(const TriangleMesh& mesh, const Plane& plane, Real tolerance = kTolerance) {
  Expected<FacetId> out;
  if (!reference_valid(plane)) return out;
  const Real norm = plane.normal.norm();
  const Real delta = tolerance * norm * (1 + std::max(magnitude(mesh), std::abs(plane.offset) / norm));
  for (FacetId f = 0; f < mesh.facet_count(); ++f) {
    Real lo = 0, hi = 0;
    for (int k = 0; k < 3; ++k) {
      const Real d = plane.normal.dot(mesh.corner(f, k)) - plane.offset;
      lo = k == 0 ? d : std::min(lo, d);
      hi = k == 0 ? d : std::max(hi, d);
    }
    if (lo <= -delta && hi >= delta) out.must.push_back(f);
    if (lo <= delta && hi >= -delta) out.may.push_back(f);
  }
  return out;
}

// Facet pairs of a and of b (moved by a_from_b, with RigidTransform::apply as the library moves
// them) that meet. At the identity (moving changes no coordinate) or with tolerance 0, the exact
// answer on those coordinates in both sets, as triangles_intersect promises. Otherwise a pair is
// in `may` if the triangles are within the tolerance of each other, in `must` if they meet and
// interpenetrate deeper than the tolerance plus reference::penetration_depth's own error, 1e-7
// of the pair's size (then no rounding of the motion can part them).
inline Expected<FacetPair> brute_collide(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b,
                                         Real tolerance = kTolerance) {
  std::vector<Vec3> moved(b.vertices.size());
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = a_from_b.apply(b.vertices[i]);
  const bool exact = tolerance == 0 || (a_from_b.rotation == Mat3::Identity() && a_from_b.translation == Vec3::Zero());
  Real scale = 1 + magnitude(a);
  for (const Vec3& v : moved) scale = std::max(scale, 1 + magnitude(v));
  const Real delta = tolerance * scale;
  using Triangle = std::array<Vec3, 3>;
  const auto bounds_apart = [](const Triangle& s, const Triangle& t, Real gap) {
    // Bounding boxes farther apart than `gap` (compared exactly) mean triangles as far apart;
    // this keeps it fast.
    for (int k = 0; k < 3; ++k) {
      if (std::max({s[0][k], s[1][k], s[2][k]}) + gap < std::min({t[0][k], t[1][k], t[2][k]})) return true;
      if (std::max({t[0][k], t[1][k], t[2][k]}) + gap < std::min({s[0][k], s[1][k], s[2][k]})) return true;
    }
    return false;
  };
  Expected<FacetPair> out;
  for (FacetId fb = 0; fb < b.facet_count(); ++fb) {
    const Triangle q = {moved[b.triangles[fb][0]], moved[b.triangles[fb][1]], moved[b.triangles[fb][2]]};
    for (FacetId fa = 0; fa < a.facet_count(); ++fa) {
      const Triangle p = {a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2)};
      if (bounds_apart(p, q, exact ? 0 : delta)) continue;
      const bool meet = reference::triangles_meet(p, q);
      if (exact) {
        if (meet) {
          out.must.push_back({fa, fb});
          out.may.push_back({fa, fb});
        }
        continue;
      }
      if (meet || reference::triangle_triangle_distance2(p, q) <= delta * delta) out.may.push_back({fa, fb});
      if (meet) {
        Real size = 0;
        for (int i = 0; i < 3; ++i)
          size = std::max({size, (p[i] - p[(i + 1) % 3]).norm(), (q[i] - q[(i + 1) % 3]).norm()});
        if (reference::penetration_depth(p, q) > delta + 1e-7 * size) out.must.push_back({fa, fb});
      }
    }
  }
  std::sort(out.must.begin(), out.must.end());
  std::sort(out.may.begin(), out.may.end());
  return out;
}

}  // namespace boxtree::test
