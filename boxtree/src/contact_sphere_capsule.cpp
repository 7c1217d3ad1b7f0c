// SPDX-License-Identifier: MIT
// contact_sphere_triangle and contact_capsule_triangle (contact.h).
//  * Sphere: the closest point of the triangle (exact).
//  * Capsule: the closest pair of the core segment and the triangle while they are apart; once the
//    core touches the triangle, the separating axes of a segment against a triangle (the faces of
//    their Minkowski difference: the triangle's normal and the three edge x segment crosses), which
//    give the exact penetration depth of the core, plus the radius.
#include <algorithm>
#include <cmath>
#include <utility>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_internal.h"

namespace boxtree {

using namespace detail;  // the narrowphase's helpers (contact_internal.h)

namespace {

// Closest pair of the segment [p0,p1] and the triangle, given `boundary` =
// closest_segment_triangle_boundary of the same segment and triangle (internal.h). The pair has a
// segment end on one side or a triangle edge on the other unless the segment crosses the triangle,
// so the candidates are the crossing point of the plane, then the boundary's (the first of equally
// close ones).
SegmentTrianglePair closest_segment_triangle(const Vec3& p0, const Vec3& p1, const TriangleFrame& tri,
                                             const SegmentTrianglePair& boundary) {
  SegmentTrianglePair best;
  if (!tri.degenerate) {
    const Real s0 = tri.signed_distance(p0);
    const Real s1 = tri.signed_distance(p1);
    if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
      const Vec3 x = p0 + (s0 / (s0 - s1)) * (p1 - p0);
      const Vec3 y = closest_point_on_triangle(x, tri.v[0], tri.v[1], tri.v[2]);
      const Real d2 = (x - y).squaredNorm();
      if (d2 < best.distance_squared) best = {x, y, d2};
    }
  }
  if (boundary.distance_squared < best.distance_squared) best = boundary;
  return best;
}

SegmentTrianglePair closest_segment_triangle(const Vec3& p0, const Vec3& p1, const TriangleFrame& tri) {
  return closest_segment_triangle(p0, p1, tri, closest_segment_triangle_boundary(p0, p1, tri.v[0], tri.v[1], tri.v[2]));
}

// The parameter range [t0, t1] of the segment p0 + t*(p1-p0), t in [0,1], over the triangle
// (inside its prism). False if empty.
bool clip_segment_to_prism(const Vec3& p0, const Vec3& p1, const TriangleFrame& tri, Real& t0, Real& t1) {
  t0 = 0;
  t1 = 1;
  for (int i = 0; i < 3; ++i) {
    const Vec3 m = inward_wall(tri, i);
    const Real f0 = m.dot(p0 - tri.v[i]);
    const Real f1 = m.dot(p1 - tri.v[i]);
    if (f0 < 0 && f1 < 0) return false;
    if (f0 < 0) t0 = std::max(t0, f0 / (f0 - f1));
    if (f1 < 0) t1 = std::min(t1, f0 / (f0 - f1));
  }
  return t0 <= t1;
}

}  // namespace

int contact_sphere_triangle(const Sphere& sphere, const Vec3& a, const Vec3& b, const Vec3& c,
                            const ContactOptions& options, ContactPoint* out) {
  return detail::contact_sphere_triangle_from(sphere, a, b, c, closest_point_on_triangle(sphere.center, a, b, c),
                                              options, out);
}

int detail::contact_sphere_triangle_from(const Sphere& sphere, const Vec3& a, const Vec3& b, const Vec3& c,
                                         const Vec3& closest, const ContactOptions& options, ContactPoint* out) {
  if (!finite(a, b, c) || !sphere.center.allFinite() || !std::isfinite(sphere.radius)) return 0;
  const TriangleFrame tri(a, b, c);
  const Real r = sphere.radius;
  const Vec3& p = sphere.center;
  const Vec3& q = closest;
  const Vec3 d = p - q;
  const Real distance = d.norm();
  if (!(distance <= r + std::max(options.margin, Real(0)))) return 0;  // also rejects NaN

  if (tri.one_sided(options)) {
    const Real s = tri.signed_distance(p);
    if (s < 0) {
      // Behind: the least lift t along n with |p + t n - q'| >= r for every q' of the triangle.
      // The triangle is planar, so with the in-plane offset l of p from it that is
      // (s + t)^2 + l^2 >= r^2, i.e. t = sqrt(r^2 - l^2) - s, touching at the same q.
      if (distance > r) return 0;
      const Real lateral_squared = std::max(Real(0), distance * distance - s * s);
      const Real depth = std::sqrt(std::max(Real(0), r * r - lateral_squared)) - s;
      out[0] = make_contact(q, tri.normal, depth);
      return 1;
    }
  }
  Vec3 normal;
  if (distance > tolerance(std::max(r, tri.size), std::max(tri.coord, max_abs(p)))) {
    normal = d / distance;
  } else if (!tri.degenerate) {
    // The centre is on the triangle: out through the front face (the side is undecided).
    normal = tri.normal;
  } else {
    const auto [s, e] = extent_of(tri);
    normal = perpendicular_to(e - s);
  }
  out[0] = make_contact(q, normal, r - distance);
  return 1;
}

int contact_capsule_triangle(const Capsule& capsule, const Vec3& a, const Vec3& b, const Vec3& c,
                             const ContactOptions& options, ContactPoint* out) {
  return detail::contact_capsule_triangle_from(
      capsule, a, b, c, closest_segment_triangle_boundary(capsule.p0, capsule.p1, a, b, c), options, out);
}

int detail::contact_capsule_triangle_from(const Capsule& capsule, const Vec3& a, const Vec3& b, const Vec3& c,
                                          const SegmentTrianglePair& boundary, const ContactOptions& options,
                                          ContactPoint* out) {
  if (!finite(a, b, c) || !finite(capsule.p0, capsule.p1, Vec3::Constant(capsule.radius))) return 0;
  const TriangleFrame tri(a, b, c);
  const Real r = capsule.radius;
  const Real margin = std::max(options.margin, Real(0));
  const Vec3& p0 = capsule.p0;
  const Vec3& p1 = capsule.p1;
  const Vec3 d = p1 - p0;
  const Real size = std::max({tri.size, d.norm(), r});
  const Real coord = std::max({tri.coord, max_abs(p0), max_abs(p1)});
  const Real tiny = tolerance(size, coord);

  const SegmentTrianglePair pair = closest_segment_triangle(p0, p1, tri, boundary);
  const Real distance = std::sqrt(pair.distance_squared);
  if (!(distance <= r + margin)) return 0;

  const bool one_sided = tri.one_sided(options);
  const Real center_side = tri.degenerate ? 0 : tri.signed_distance((p0 + p1) / 2);

  ContactPoint primary;
  bool push_out = one_sided && center_side < 0;
  if (!push_out && distance > tiny) {
    // Apart cores: the closest pair gives the exact normal and depth.
    primary = make_contact(pair.on_triangle, (pair.on_segment - pair.on_triangle) / distance, r - distance);
    push_out = one_sided && primary.normal.dot(tri.normal) < -kBehind;
  } else if (!push_out && tri.degenerate) {
    // The core touches a segment or point: their Minkowski difference is flat, the core's
    // penetration is zero, and the normal is across both.
    const auto [s, e] = extent_of(tri);
    Vec3 n = (e - s).cross(d);
    if (!(n.norm() > tiny * size)) n = perpendicular_to((e - s).squaredNorm() > 0 ? Vec3(e - s) : d);
    n.normalize();
    if (n.dot((p0 + p1) / 2 - pair.on_triangle) < 0) n = -n;
    primary = make_contact(pair.on_triangle, n, r);
  } else if (!push_out) {
    // The core touches the triangle: separating axes of the segment against the triangle.
    const auto seg_interval = [&](const Vec3& n) {
      const Real x0 = n.dot(p0);
      const Real x1 = n.dot(p1);
      return Interval{std::min(x0, x1), std::max(x0, x1)};
    };
    Vec3 best_normal = tri.normal;
    Real best_overlap = kInf;
    int best_edge = -1;
    const auto consider = [&](const Vec3& n, int edge) {
      const Real overlap = project(tri, n).hi - seg_interval(n).lo;
      if (overlap < best_overlap) {
        best_overlap = overlap;
        best_normal = n;
        best_edge = edge;
      }
    };
    consider(center_side >= 0 ? tri.normal : Vec3(-tri.normal), -1);
    for (int j = 0; j < 3; ++j) {
      const Vec3 e = tri.v[(j + 1) % 3] - tri.v[j];
      const Vec3 u = e.cross(d);
      const Real len = u.norm();
      if (!(len > 1e-6 * e.norm() * d.norm())) continue;
      consider(u / len, j);
      consider(-u / len, j);
    }
    Vec3 position;
    if (best_edge < 0) {
      // Face: the deepest end of the core, projected on the plane (inside the triangle when the
      // face axis is the least one; the clamp only absorbs rounding).
      const Vec3& deepest = best_normal.dot(p0) <= best_normal.dot(p1) ? p0 : p1;
      position = closest_point_on_triangle(deepest - tri.signed_distance(deepest) * tri.normal, a, b, c);
    } else {
      Vec3 on_segment;
      closest_points_on_segments(p0, p1, tri.v[best_edge], tri.v[(best_edge + 1) % 3], on_segment, position);
    }
    primary = make_contact(position, best_normal, r + best_overlap);
    push_out = one_sided && best_normal.dot(tri.normal) < -kBehind;
  }

  if (push_out) {
    // Behind a one-sided triangle: the least lift t along n that clears it. The distance g(t)
    // from the lifted core to the triangle is convex in t (the distance of two convex sets as one
    // translates), so the lifts that overlap (g < r) form an interval containing 0, and t is its
    // upper end. Newton's method on g - r from a lift that clears stays above t (the tangent of a
    // convex function lies below it) and decreases to it; g'(t) is n . (x - y) / g for the
    // closest pair (x, y). Bisection on the exact overlap test finishes what Newton has not
    // within its steps (a closest pair switching features at t converges only linearly).
    if (distance > r) return 0;
    // A lift that clears: both ends of the core r above the plane.
    const Real clears = r - std::min(tri.signed_distance(p0), tri.signed_distance(p1)) + tiny;
    Real hi = clears;
    bool converged = false;
    for (int iteration = 0; iteration < 16 && !converged; ++iteration) {
      const SegmentTrianglePair at = closest_segment_triangle(p0 + hi * tri.normal, p1 + hi * tri.normal, tri);
      const Real g = std::sqrt(at.distance_squared);
      if (!(g > r + tiny)) {
        converged = g >= r - tiny;  // at the answer to rounding; below it, Newton went past
        break;
      }
      const Real slope = tri.normal.dot(at.on_segment - at.on_triangle) / g;
      if (!(slope > 0)) break;
      const Real step = (g - r) / slope;
      hi -= step;
      converged = step <= tiny;
    }
    if (!converged) {
      const auto overlaps_at = [&](Real t) {
        const Vec3 lift = t * tri.normal;
        return segment_triangle_distance_squared(p0 + lift, p1 + lift, a, b, c) <= r * r;
      };
      Real lo = 0;
      if (!(hi >= 0) || overlaps_at(hi)) hi = clears;
      for (int iteration = 0; iteration < 200 && hi - lo > tiny; ++iteration) {
        const Real mid = (lo + hi) / 2;
        (overlaps_at(mid) ? lo : hi) = mid;
      }
    }
    const Vec3 lift = hi * tri.normal;
    const SegmentTrianglePair touch = closest_segment_triangle(p0 + lift, p1 + lift, tri);
    primary = make_contact(touch.on_triangle, tri.normal, hi);
  }

  // Lying on the face (the normal is the face's): the two ends of the core over the triangle,
  // each at its own depth, so that the capsule rests on a segment rather than a point.
  int count = 0;
  Real t0 = 0;
  Real t1 = 0;
  if (!tri.degenerate && std::abs(primary.normal.dot(tri.normal)) >= 1 - 1e-9 &&
      clip_segment_to_prism(p0, p1, tri, t0, t1) &&
      ((t1 - t0) * (d - tri.normal.dot(d) * tri.normal)).norm() > 1e-6 * size) {
    const Real sigma = primary.normal.dot(tri.normal) > 0 ? 1 : -1;
    ContactPoint ends[2];
    for (int k = 0; k < 2; ++k) {
      const Vec3 x = p0 + (k == 0 ? t0 : t1) * d;
      const Real s = tri.signed_distance(x);
      ends[k] = make_contact(closest_point_on_triangle(x - s * tri.normal, a, b, c), primary.normal, r - sigma * s);
    }
    if (ends[1].depth > ends[0].depth) std::swap(ends[0], ends[1]);
    // The exact deepest point can lie just beyond an end (a rounded cap over an edge when pushed
    // out): then it replaces the shallower end.
    if (primary.depth > ends[0].depth + tiny) {
      ends[1] = ends[0];
      ends[0] = primary;
    }
    for (const ContactPoint& end : ends) {
      if (end.depth >= -margin) out[count++] = end;
    }
  }
  if (count == 0) out[count++] = primary;
  return count;
}

}  // namespace boxtree
