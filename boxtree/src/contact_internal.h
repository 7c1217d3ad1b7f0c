// SPDX-License-Identifier: MIT
#pragma once
// Helpers shared by the narrowphase's source files; not part of the public API.
//
// The narrowphase (contact.h), one file per way of finding the answer:
//  contact_sphere_capsule.cpp  spheres and capsules (closest points, a segment's separating axes)
//  contact_polytope.h/.cpp     the convex-polytope description of boxes, hulls and triangles
//  contact_sat.cpp             boxes, convex polyhedra and triangle pairs: separating axes
//  contact_convex.cpp          general convex shapes: GJK + EPA (libccd), then a polished normal
//  contact_cylinder.h/.cpp     cylinders: the overlap along known normals, searched where curved
//  contact_faces.cpp           mesh vs mesh along face normals only
//  contact_reduction.cpp       reduce_contacts
//
// One-sided triangles (ContactOptions::two_sided == false) and the "push out through the front
// face" rule, which every routine follows: when the shape's centre is behind the plane of a
// non-degenerate triangle, or when the two-sided answer's normal would point behind it
// (n . normal < -kBehind), the normal becomes the front normal n = (b-a)x(c-a)/|.| and the depth
// the *directional* penetration along n: the least t such that the shape moved by t*n no longer
// overlaps the triangle. Such a shape gets a contact only if it really overlaps the triangle: a
// shape behind a one-sided triangle (or whose nearest direction is behind it) and apart from it
// is not seen, not even within the margin. So one-sided normals always satisfy
// n . normal >= -kBehind and the shape is never pushed further in. Degenerate triangles have no
// front and are always two-sided.
//
// Contact counts: the sphere, convex and edge-edge cases give one point; a capsule lying along
// the face gives the two ends of its core over the triangle; box, polyhedron, cylinder and
// triangle-pair face cases give a patch, reduced to the kMax... bound by reduce_contacts' rule.
// All points of one call share one normal, and the deepest point is first.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "internal.h"

namespace boxtree::detail {

constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kEps = std::numeric_limits<Real>::epsilon();

// A triangle is degenerate (treated as the segment or point it nearly is) when it is narrower
// than 1e-8 of its longest edge: the same threshold as closest_point_on_triangle, so that both
// agree on what the triangle is.
constexpr Real kDegenerateWidth = 1e-8;
// Relative size below which a geometric quantity is taken as zero (a distance, an axis length).
constexpr Real kTiny = 1e-10;
// Normals whose component along the front normal is below this count as pointing behind it.
constexpr Real kBehind = 1e-9;

inline Real max_abs(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }
inline bool finite(const Vec3& a, const Vec3& b, const Vec3& c) {
  return a.allFinite() && b.allFinite() && c.allFinite();
}

// Corners, the unit front normal and sizes of a triangle.
struct TriangleFrame {
  Vec3 v[3];
  Vec3 normal = Vec3::Zero();  // unit (b-a)x(c-a); zero when degenerate
  bool degenerate = true;
  Real size = 0;   // longest edge
  Real coord = 0;  // largest coordinate magnitude (for rounding tolerances)

  TriangleFrame(const Vec3& a, const Vec3& b, const Vec3& c) : v{a, b, c} {
    const Vec3 n = (b - a).cross(c - a);
    const Real longest_squared = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    size = std::sqrt(longest_squared);
    coord = std::max({max_abs(a), max_abs(b), max_abs(c)});
    const Real normal_squared = n.squaredNorm();
    degenerate = !(normal_squared > kDegenerateWidth * kDegenerateWidth * longest_squared * longest_squared);
    if (!degenerate) normal = n / std::sqrt(normal_squared);
  }
  Real signed_distance(const Vec3& p) const { return normal.dot(p - v[0]); }
  bool one_sided(const ContactOptions& options) const { return !options.two_sided && !degenerate; }
};

// Tolerance for "zero" distances and positions: a tiny fraction of the sizes involved plus the
// rounding of coordinates of magnitude `coord`.
inline Real tolerance(Real size, Real coord) { return kTiny * size + 64 * kEps * coord; }

// The two corners of a degenerate triangle that are farthest apart: the segment it is.
inline std::pair<Vec3, Vec3> extent_of(const TriangleFrame& tri) {
  const Real ab = (tri.v[1] - tri.v[0]).squaredNorm();
  const Real bc = (tri.v[2] - tri.v[1]).squaredNorm();
  const Real ca = (tri.v[0] - tri.v[2]).squaredNorm();
  if (ab >= bc && ab >= ca) return {tri.v[0], tri.v[1]};
  if (bc >= ca) return {tri.v[1], tri.v[2]};
  return {tri.v[2], tri.v[0]};
}

// Some unit vector perpendicular to `d` (UnitZ if d is zero): the normal used when the geometry
// leaves it undetermined (a shape's core exactly on a degenerate triangle).
inline Vec3 perpendicular_to(const Vec3& d) {
  const Real len = d.norm();
  if (!(len > 0)) return Vec3::UnitZ();
  Vec3 b1;
  Vec3 b2;
  detail::orthonormal_completion(d / len, b1, b2);
  return b1;
}

// contact_sphere_triangle given `closest`, which must be closest_point_on_triangle(sphere.center,
// a, b, c) (for callers that have it already): the same contacts.
int contact_sphere_triangle_from(const Sphere& sphere, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& closest,
                                 const ContactOptions& options, ContactPoint* out);

// contact_capsule_triangle given `boundary`, which must be closest_segment_triangle_boundary(
// capsule.p0, capsule.p1, a, b, c) (internal.h; for callers that have it already): the same
// contacts.
int contact_capsule_triangle_from(const Capsule& capsule, const Vec3& a, const Vec3& b, const Vec3& c,
                                  const SegmentTrianglePair& boundary, const ContactOptions& options,
                                  ContactPoint* out);

// Inward normals of the triangle's side walls (the prism over it along its normal):
// wall(i) . (x - v[i]) >= 0 for points over the triangle.
inline Vec3 inward_wall(const TriangleFrame& tri, int i) { return tri.normal.cross(tri.v[(i + 1) % 3] - tri.v[i]); }

inline ContactPoint make_contact(const Vec3& position, const Vec3& normal, Real depth) {
  ContactPoint contact;
  contact.position = position;
  contact.normal = normal;
  contact.depth = depth;
  return contact;
}

// The interval of projections of a shape on an axis.
struct Interval {
  Real lo = kInf;
  Real hi = -kInf;
};

// The triangle's projection on u.
[[gnu::always_inline]] inline Interval project(const TriangleFrame& tri, const Vec3& u) {
  const Real x0 = u.dot(tri.v[0]);
  const Real x1 = u.dot(tri.v[1]);
  const Real x2 = u.dot(tri.v[2]);
  return {std::min({x0, x1, x2}), std::max({x0, x1, x2})};
}

// reduce_contacts on an array: returns the new count (and, if asked, how many were merged away).
// Defined in contact_reduction.cpp.
int reduce_in_place(ContactPoint* contacts, int count, int max_count, Real merge_distance, int* merged = nullptr);

// Sutherland-Hodgman clipping of a convex polygon by one half-space (Sutherland, Hodgman,
// "Reentrant polygon clipping", CACM 17(1), 1974): writes the part of in[0..n) where
// signed_distance(x) <= 0 to `out` and returns its corner count, at most n + 1. A crossing edge
// is cut at the linear interpolation of the two distances' zero.
template <class SignedDistance>
int clip_polygon(const Vec3* in, int n, const SignedDistance& signed_distance, Vec3* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3& cur = in[i];
    const Vec3& next = in[(i + 1) % n];
    const Real dc = signed_distance(cur);
    const Real dn = signed_distance(next);
    if (dc <= 0) out[m++] = cur;
    if ((dc < 0 && dn > 0) || (dc > 0 && dn < 0)) out[m++] = cur + (dc / (dc - dn)) * (next - cur);
  }
  return m;
}

// Local minimization of f(u) (the projections' overlap along the unit normal u) from `normal`:
// a pattern search over 8 tangent directions plus the last successful move (which follows a
// valley that is not aligned with the pattern, as along a rounded edge), doubling the step after
// a success and halving it after a failure. A non-zero `front` keeps u.front >= -kBehind.
// Stops at `min_step` rad and `max_evaluations` per start: 1e-7 and 150 by default, far below
// what contacts need, and 3x cheaper than polishing to 1e-12.
// `ridges` (up to 4, may be null): axes r across which f has a crease along the great circles
// u.r = const (a cylinder's |u.axis|, a triangle's corner switch across an edge); moves along
// those circles (+-r x u) are tried too, since a minimum along a crease is otherwise out of the
// pattern's reach.
// `probe`: before the first round the moves are tried at min_step; if none lowers f there by more
// than `noise` (rounding of f on large coordinates), the normal is a local minimum to the search's
// resolution and the search stops at once, returning true (at a kink of f, where a flat face of
// the Minkowski difference is the answer, the search would otherwise repeat its failure down to
// min_step: ~14 rounds of up to 16 moves). `stop_below`: stop as soon as f is below it (the
// caller's "apart" bound).
template <class F>
bool polish_normal(const F& f, const Vec3& front, Vec3& normal, Real& value, Real step = 1e-2, Real min_step = 1e-7,
                   int max_evaluations = 150, const Vec3* ridges = nullptr, int ridge_count = 0, Real noise = 0,
                   bool probe = false, Real stop_below = -kInf) {
  int evaluations = 0;
  Vec3 momentum = Vec3::Zero();
  bool probe_now = probe;
  while (step > min_step && evaluations < max_evaluations && !(value < stop_below)) {
    Vec3 t1;
    Vec3 t2;
    detail::orthonormal_completion(normal, t1, t2);
    const Real r = std::sqrt(Real(0.5));
    Vec3 moves[17] = {momentum, t1, -t1, t2, -t2, r * (t1 + t2), r * (t1 - t2), -r * (t1 + t2), -r * (t1 - t2)};
    for (int k = 9; k < 17; ++k) moves[k].setZero();  // Eigen leaves the rest uninitialized
    for (int k = 0; k < std::min(ridge_count, 4); ++k) {
      const Vec3 along = ridges[k].cross(normal);
      const Real length = along.norm();
      if (!(length > 1e-12)) continue;
      moves[9 + 2 * k] = along / length;
      moves[10 + 2 * k] = -along / length;
    }
    const auto try_moves = [&](Real length, Real threshold) {
      for (const Vec3& move : moves) {
        if (move.squaredNorm() == 0) continue;
        const Vec3 candidate = (normal + length * move).normalized();
        if (candidate.dot(front) < -kBehind) continue;  // never wander behind a one-sided triangle
        const Real candidate_value = f(candidate);
        ++evaluations;
        if (candidate_value < value - threshold) {
          momentum = (candidate - normal).normalized();
          normal = candidate;
          value = candidate_value;
          return true;
        }
      }
      return false;
    };
    if (probe_now) {
      probe_now = false;
      const bool descends = try_moves(min_step, noise);
      momentum.setZero();  // the probe's move is no direction to follow
      if (!descends) return true;
    }
    const bool improved = try_moves(step, 0);
    if (!improved) momentum.setZero();
    step = improved ? step * 2 : step / 2;
  }
  return false;
}

// The contact position for a shape moved out along `normal`: where its deepest point lands
// (`landing`), on the triangle's supporting feature along the normal (a corner, an edge, or the
// face). Defined in contact_convex.cpp.
Vec3 landing_position(const TriangleFrame& tri, const Vec3& normal, const Vec3& landing, Real size);

}  // namespace boxtree::detail
