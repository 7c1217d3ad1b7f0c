// SPDX-License-Identifier: MIT
// Per-facet narrowphase (contact.h): contact points between one triangle and a convex shape, and
// between two triangles.
//
// How each routine finds its answer:
//  * Sphere: the closest point of the triangle (exact).
//  * Capsule: the closest pair of the core segment and the triangle while they are apart; once the
//    core touches the triangle, the separating axes of a segment against a triangle (the faces of
//    their Minkowski difference: the triangle's normal and the three edge x segment crosses), which
//    give the exact penetration depth of the core, plus the radius.
//  * Box, convex polyhedra and triangle pairs: one shared separating-axis routine over a small polytope description
//    (polytope_triangle below): every face normal of the Minkowski difference (the shape's faces,
//    the triangle's normal, edge x edge crosses) is tried, so the least overlap is the exact
//    penetration depth when the shapes overlap and a lower bound of the distance when they are
//    apart. Face axes are preferred unless an edge axis is clearly better (as the box colliders of
//    ODE and Bullet do): face contacts come as a stable patch of points, edge contacts as one.
//  * General convex shapes: GJK + EPA from libccd against the triangle rounded by the margin, then
//    a local polish of the normal on the exact projection overlap (contact_convex_triangle).
//
// One-sided triangles (ContactOptions::two_sided == false) and the "push out through the front
// face" rule: when the shape's centre is behind the plane of a non-degenerate triangle, or when
// the two-sided answer's normal would point behind it (n . normal < -1e-9), the normal becomes
// the front normal n = (b-a)x(c-a)/|.| and the depth the *directional* penetration along n: the
// least t such that the shape moved by t*n no longer overlaps the triangle. Such a shape gets a
// contact only if it really overlaps the triangle: a shape behind a one-sided triangle (or whose
// nearest direction is behind it) and apart from it is not seen, not even within the margin. So
// one-sided normals always satisfy n . normal >= -1e-9 and the shape is never pushed further in.
// Degenerate triangles have no front and are always two-sided.
//
// Contact counts: the sphere, convex and edge-edge cases give one point; a capsule lying along
// the face gives the two ends of its core over the triangle; box and triangle-pair face cases
// give a patch, reduced to the kMax... bound by reduce_contacts' rule. All points of one call
// share one normal, and the deepest point is first.
#include "boxtree/contact.h"

#include "boxtree/geometry.h"
#include "contact_internal.h"
#include "internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <ccd/ccd.h>

namespace boxtree {
namespace {

constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kEps = std::numeric_limits<Real>::epsilon();
static_assert(std::is_same_v<ccd_real_t, Real>, "libccd must be built in double precision (CCD_DOUBLE)");

// A triangle is degenerate (treated as the segment or point it nearly is) when it is narrower
// than 1e-8 of its longest edge: the same threshold as closest_point_on_triangle, so that both
// agree on what the triangle is.
constexpr Real kDegenerateWidth = 1e-8;
// Relative size below which a geometric quantity is taken as zero (a distance, an axis length).
constexpr Real kTiny = 1e-10;
// Face axes win unless an edge axis is better by this fraction of the face overlap: a box resting
// on a face keeps a patch of contacts instead of flickering to a single edge contact.
constexpr Real kFaceBias = 0.05;
// Normals whose component along the front normal is below this count as pointing behind it.
constexpr Real kBehind = 1e-9;

Real max_abs(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }
bool finite(const Vec3& a, const Vec3& b, const Vec3& c) { return a.allFinite() && b.allFinite() && c.allFinite(); }

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
Real tolerance(Real size, Real coord) { return kTiny * size + 64 * kEps * coord; }

// The two corners of a degenerate triangle that are farthest apart: the segment it is.
std::pair<Vec3, Vec3> extent_of(const TriangleFrame& tri) {
  const Real ab = (tri.v[1] - tri.v[0]).squaredNorm();
  const Real bc = (tri.v[2] - tri.v[1]).squaredNorm();
  const Real ca = (tri.v[0] - tri.v[2]).squaredNorm();
  if (ab >= bc && ab >= ca) return {tri.v[0], tri.v[1]};
  if (bc >= ca) return {tri.v[1], tri.v[2]};
  return {tri.v[2], tri.v[0]};
}

// Some unit vector perpendicular to `d` (UnitZ if d is zero): the normal used when the geometry
// leaves it undetermined (a shape's core exactly on a degenerate triangle).
Vec3 perpendicular_to(const Vec3& d) {
  const Real len = d.norm();
  if (!(len > 0)) return Vec3::UnitZ();
  Vec3 b1;
  Vec3 b2;
  detail::orthonormal_completion(d / len, b1, b2);
  return b1;
}

// Closest pair of the segment [p0,p1] and the triangle. The pair has a segment end on one side or
// a triangle edge on the other unless the segment crosses the triangle, so the candidates are the
// two ends, the three edges and the crossing point of the plane.
struct SegmentTrianglePair {
  Vec3 on_segment = Vec3::Zero();
  Vec3 on_triangle = Vec3::Zero();
  Real distance_squared = kInf;
};

SegmentTrianglePair closest_segment_triangle(const Vec3& p0, const Vec3& p1, const TriangleFrame& tri) {
  SegmentTrianglePair best;
  const auto consider = [&](const Vec3& x, const Vec3& y) {
    const Real d2 = (x - y).squaredNorm();
    if (d2 < best.distance_squared) best = {x, y, d2};
  };
  const Vec3& a = tri.v[0];
  const Vec3& b = tri.v[1];
  const Vec3& c = tri.v[2];
  if (!tri.degenerate) {
    const Real s0 = tri.signed_distance(p0);
    const Real s1 = tri.signed_distance(p1);
    if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
      const Vec3 x = p0 + (s0 / (s0 - s1)) * (p1 - p0);
      consider(x, closest_point_on_triangle(x, a, b, c));
    }
  }
  consider(p0, closest_point_on_triangle(p0, a, b, c));
  consider(p1, closest_point_on_triangle(p1, a, b, c));
  for (int i = 0; i < 3; ++i) {
    Vec3 x;
    Vec3 y;
    closest_points_on_segments(p0, p1, tri.v[i], tri.v[(i + 1) % 3], x, y);
    consider(x, y);
  }
  return best;
}

// Inward normals of the triangle's side walls (the prism over it along its normal):
// wall(i) . (x - v[i]) >= 0 for points over the triangle.
Vec3 inward_wall(const TriangleFrame& tri, int i) { return tri.normal.cross(tri.v[(i + 1) % 3] - tri.v[i]); }

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

ContactPoint make_contact(const Vec3& position, const Vec3& normal, Real depth) {
  ContactPoint contact;
  contact.position = position;
  contact.normal = normal;
  contact.depth = depth;
  return contact;
}

// ---------------------------------------------------------------------------------------------
// Contact reduction

// Twice the signed area of the triangle (o, a, b): positive when it turns counter-clockwise.
Real cross_2d(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Twice the area that q adds to the convex polygon `hull` (counter-clockwise, h vertices; a
// segment or a point when h < 3): the triangles from q to the edges that face it.
Real added_area_2d(const Vec2* hull, int h, const Vec2& q) {
  if (h == 1) return 0;
  if (h == 2) return std::abs(cross_2d(hull[0], hull[1], q));
  Real added = 0;
  for (int i = 0; i < h; ++i) {
    const Real c = cross_2d(hull[i], hull[(i + 1) % h], q);
    if (c < 0) added -= c;
  }
  return added;
}

// reduce_contacts on an array; returns the new count (and, if asked, how many were merged away).
int reduce_in_place(ContactPoint* contacts, int count, int max_count, Real merge_distance, int* merged = nullptr) {
  if (merged) *merged = 0;
  if (count <= 0) return 0;
  std::sort(contacts, contacts + count, [](const ContactPoint& x, const ContactPoint& y) { return x.depth > y.depth; });
  // Near-duplicates: same place and normals within ~10 degrees; the deeper one (earlier) stays.
  const Real cos_merge = std::cos(Real(10) * Real(3.14159265358979323846) / 180);
  const Real merge_squared = merge_distance * merge_distance;
  int kept = 0;
  for (int i = 0; i < count; ++i) {
    bool duplicate = false;
    for (int j = 0; j < kept && !duplicate; ++j) {
      duplicate = (contacts[i].position - contacts[j].position).squaredNorm() <= merge_squared &&
                  contacts[i].normal.dot(contacts[j].normal) >= cos_merge;
    }
    if (!duplicate) contacts[kept++] = contacts[i];
  }
  if (merged) *merged = count - kept;
  if (kept <= max_count) return kept;

  // Keep the deepest, then greedily the point that makes the largest hull (in the plane across
  // the deepest contact's normal), ties (collinear sets) broken by the distance to the chosen set.
  // The hull of the chosen set is kept, so a candidate costs the area it adds (its visible edges)
  // and its distance is updated once per choice: O(max_count * n * hull) in all.
  Vec3 u;
  Vec3 w;
  detail::orthonormal_completion(contacts[0].normal.normalized(), u, w);
  const int n = std::min(kept, 64);
  std::array<Vec2, 64> planar;
  planar.fill(Vec2::Zero());  // only [0, n) is read; GCC cannot tell
  std::array<Real, 64> distance;  // squared, to the nearest chosen point
  std::array<bool, 64> chosen{};
  Real extent_squared = 0;
  for (int i = 0; i < n; ++i) {
    planar[i] = Vec2(contacts[i].position.dot(u), contacts[i].position.dot(w));
    distance[i] = (contacts[i].position - contacts[0].position).squaredNorm();
    extent_squared = std::max(extent_squared, distance[i]);
  }
  std::array<int, 64> order{};
  std::array<Vec2, 64> points;
  std::array<Vec2, 128> hull;  // room for 2 x 64 points (convex_hull_2d)
  chosen[0] = true;
  order[0] = 0;
  int selected = 1;
  int h = 1;
  hull[0] = planar[0];
  Real area = 0;  // twice the chosen set's hull area
  while (selected < std::min(max_count, n)) {
    int best = -1;
    Real best_area = -1;
    Real best_distance = -1;
    for (int i = 0; i < n; ++i) {
      if (chosen[i]) continue;
      const Real candidate_area = area + added_area_2d(hull.data(), h, planar[i]);
      // Areas compare with a slack (relative, and to the set's size for collinear sets, whose
      // areas are rounding noise) so that rounding does not beat a real spread.
      const Real slack = 1e-9 * std::max(best_area, Real(0)) + 1e-12 * extent_squared;
      const bool better =
          candidate_area > best_area + slack || (candidate_area >= best_area - slack && distance[i] > best_distance);
      if (better) {
        best = i;
        best_area = candidate_area;
        best_distance = distance[i];
      }
    }
    if (best < 0) break;
    chosen[best] = true;
    order[selected++] = best;
    for (int i = 0; i < n; ++i) {
      distance[i] = std::min(distance[i], (contacts[i].position - contacts[best].position).squaredNorm());
    }
    for (int s = 0; s < selected; ++s) points[s] = planar[order[s]];
    h = detail::convex_hull_2d(points.data(), selected, hull.data());
    area = 0;
    for (int i = 0; h >= 3 && i < h; ++i) area += cross_2d(hull[0], hull[i], hull[(i + 1) % h]);
  }
  std::array<ContactPoint, 64> result;
  for (int s = 0; s < selected; ++s) result[s] = contacts[order[s]];
  std::sort(result.begin(), result.begin() + selected,
            [](const ContactPoint& x, const ContactPoint& y) { return x.depth > y.depth; });
  std::copy(result.begin(), result.begin() + selected, contacts);
  return selected;
}

// ---------------------------------------------------------------------------------------------
// Polytope vs triangle (boxes, convex polyhedra, and triangle a of a triangle pair)

// The half-space {x : normal . x <= offset} (signed_distance_scaled(x) <= 0).
using HalfSpace = Plane;

// One face of a Polytope: its outward unit normal, the plane's offset (outward . x on the face),
// and the half-spaces that cut the face's polygon out of that plane.
struct PolytopeFace {
  Vec3 outward;
  Real offset;
  int side_count;
  const HalfSpace* sides;
};

// A convex polytope as the separating-axis routine (polytope_triangle) reads it: corners, edges
// with their classes of parallel edges, faces, and the half-spaces whose intersection it is.
// The arrays are not owned: they belong to a ConvexPolyhedron (polytope_of_polyhedron) or to a
// PolytopeArrays (polytope_of_box, polytope_of_triangle), which must outlive the description.
struct Polytope {
  enum class Kind { kBox, kTriangle, kPolyhedron };
  Kind kind = Kind::kTriangle;
  int vertex_count = 0;
  const Vec3* vertices = nullptr;
  int edge_count = 0;
  const int* edge_from = nullptr;  // edge e joins vertices[edge_from[e]] and vertices[edge_to[e]]
  const int* edge_to = nullptr;
  const int* edge_direction = nullptr;  // its class: an index into `directions`
  int direction_count = 0;
  const Vec3* directions = nullptr;  // unit, one per class of parallel edges
  // Face f: the plane faces[f] (unit outward normal) and its sides
  // sides[face_begin[f] .. face_begin[f + 1]).
  int face_count = 0;
  const HalfSpace* faces = nullptr;
  const int* face_begin = nullptr;
  const HalfSpace* sides = nullptr;
  int bound_count = 0;
  const HalfSpace* bounds = nullptr;  // the polytope is the intersection of these
  Vec3 center = Vec3::Zero();         // an interior point (the side of a two-sided triangle)
  Real size = 0;                      // a length of the polytope's scale (for tolerances)
  Real coord = 0;                     // largest coordinate magnitude (for rounding tolerances)
  // Whether a face's patch (the triangle clipped to the face's polygon) always holds the
  // polytope's deepest point along the face's normal: true for a box (it is the prism over each
  // of its faces) and a triangle (its faces are all of it), not for a general polyhedron.
  bool patches_hold_depth = true;
  // Boxes (kind kBox): the box's frame, for closest points and projections in closed form.
  Mat3 axes = Mat3::Identity();
  Vec3 half_extents = Vec3::Zero();
  // Polyhedra (kind kPolyhedron), as ConvexPolyhedron documents them; null otherwise. The face
  // widths give the projection along a face's normal, the loops the faces' corners (for closest
  // points), the cones which edge pairs can touch; edges_by_cone: whether the edge axes are
  // tried edge by edge through the cones rather than by parallel class.
  const Real* face_width = nullptr;
  const int* loops = nullptr;
  const Vec3* edge_cone = nullptr;
  bool edges_by_cone = false;

  PolytopeFace face(int f) const {
    return {faces[f].normal, faces[f].offset, face_begin[f + 1] - face_begin[f], sides + face_begin[f]};
  }

  // The closest point of the polytope to a point outside it (of its surface, for a polyhedron:
  // over the faces cut into fans of triangles).
  Vec3 closest_point(const Vec3& x) const {
    if (kind == Kind::kBox) {
      const Vec3 local = axes.transpose() * (x - center);
      return center + axes * local.cwiseMax(-half_extents).cwiseMin(half_extents);
    }
    if (kind == Kind::kTriangle) return closest_point_on_triangle(x, vertices[0], vertices[1], vertices[2]);
    Vec3 best = vertices[0];
    Real best_distance = kInf;
    for (int f = 0; f < face_count; ++f) {
      const Vec3& apex = vertices[loops[face_begin[f]]];
      for (int k = face_begin[f] + 1; k + 1 < face_begin[f + 1]; ++k) {
        const Vec3 y = closest_point_on_triangle(x, apex, vertices[loops[k]], vertices[loops[k + 1]]);
        const Real d = (y - x).squaredNorm();
        if (d < best_distance) {
          best_distance = d;
          best = y;
        }
      }
    }
    return best;
  }
};

// Storage for the polytopes that are not a ConvexPolyhedron: a box (8 corners, 12 edges in 3
// classes, 6 faces of 4 sides) or a triangle (3 corners and edges, 2 faces of 3 sides, 5 bounds).
struct PolytopeArrays {
  Vec3 vertices[8];
  int edge_from[12] = {};
  int edge_to[12] = {};
  int edge_direction[12] = {};
  Vec3 directions[3];
  HalfSpace faces[6];
  int face_begin[7] = {};
  HalfSpace sides[24];
  HalfSpace bounds[6];
};

Polytope polytope_of_box(const Obb& box, PolytopeArrays& arrays) {
  Polytope p;
  p.kind = Polytope::Kind::kBox;
  p.vertices = arrays.vertices;
  p.edge_from = arrays.edge_from;
  p.edge_to = arrays.edge_to;
  p.edge_direction = arrays.edge_direction;
  p.directions = arrays.directions;
  p.faces = arrays.faces;
  p.face_begin = arrays.face_begin;
  p.sides = arrays.sides;
  p.bounds = arrays.faces;  // a box is the intersection of its faces' half-spaces
  const Vec3& c = box.center;
  const Vec3 h = box.half_extents.cwiseAbs();
  p.center = c;
  p.vertex_count = 8;
  for (int i = 0; i < 8; ++i) {
    Vec3 x = c;
    for (int k = 0; k < 3; ++k) x += ((i >> k) & 1 ? h[k] : -h[k]) * box.axes.col(k);
    arrays.vertices[i] = x;
  }
  p.direction_count = 3;
  for (int k = 0; k < 3; ++k) {
    arrays.directions[k] = box.axes.col(k);
    for (int i = 0; i < 8; ++i) {
      if ((i >> k) & 1) continue;
      arrays.edge_from[p.edge_count] = i;
      arrays.edge_to[p.edge_count] = i | (1 << k);
      arrays.edge_direction[p.edge_count] = k;
      ++p.edge_count;
    }
  }
  int side_count = 0;
  for (int k = 0; k < 3; ++k) {
    for (const Real sign : {Real(1), Real(-1)}) {
      const Vec3 n = sign * box.axes.col(k);
      arrays.face_begin[p.face_count] = side_count;
      arrays.faces[p.face_count++] = {n, n.dot(c) + h[k]};
      for (int j = 0; j < 3; ++j) {
        if (j == k) continue;
        const Vec3 m = box.axes.col(j);
        arrays.sides[side_count++] = {m, m.dot(c) + h[j]};
        arrays.sides[side_count++] = {-m, -m.dot(c) + h[j]};
      }
    }
  }
  arrays.face_begin[p.face_count] = side_count;
  p.bound_count = p.face_count;
  p.size = 2 * h.norm();
  p.coord = max_abs(c) + h.sum();
  p.axes = box.axes;
  p.half_extents = h;
  return p;
}

Polytope polytope_of_triangle(const TriangleFrame& tri, PolytopeArrays& arrays) {
  Polytope p;
  p.kind = Polytope::Kind::kTriangle;
  p.vertices = arrays.vertices;
  p.edge_from = arrays.edge_from;
  p.edge_to = arrays.edge_to;
  p.edge_direction = arrays.edge_direction;
  p.directions = arrays.directions;
  p.faces = arrays.faces;
  p.face_begin = arrays.face_begin;
  p.sides = arrays.sides;
  p.bounds = arrays.bounds;
  p.vertex_count = 3;
  for (int i = 0; i < 3; ++i) arrays.vertices[i] = tri.v[i];
  p.center = (tri.v[0] + tri.v[1] + tri.v[2]) / 3;
  for (int i = 0; i < 3; ++i) {
    const Vec3 e = tri.v[(i + 1) % 3] - tri.v[i];
    const Real len = e.norm();
    if (!(len > kTiny * tri.size)) continue;
    arrays.directions[p.direction_count] = e / len;
    arrays.edge_from[p.edge_count] = i;
    arrays.edge_to[p.edge_count] = (i + 1) % 3;
    arrays.edge_direction[p.edge_count] = p.direction_count;
    ++p.edge_count;
    ++p.direction_count;
  }
  if (!tri.degenerate) {
    HalfSpace sides[3];
    for (int i = 0; i < 3; ++i) {
      const Vec3 m = inward_wall(tri, i).normalized();
      sides[i] = {-m, -m.dot(tri.v[i])};
    }
    for (const Real sign : {Real(1), Real(-1)}) {
      const Vec3 outward = sign * tri.normal;
      arrays.face_begin[p.face_count] = 3 * p.face_count;
      arrays.faces[p.face_count] = {outward, outward.dot(tri.v[0])};
      for (int i = 0; i < 3; ++i) arrays.sides[3 * p.face_count + i] = sides[i];
      arrays.bounds[p.bound_count++] = arrays.faces[p.face_count];
      ++p.face_count;
    }
    arrays.face_begin[p.face_count] = 3 * p.face_count;
    for (int i = 0; i < 3; ++i) arrays.bounds[p.bound_count++] = sides[i];
  }
  p.size = tri.size;
  p.coord = tri.coord;
  return p;
}

Polytope polytope_of_polyhedron(const ConvexPolyhedron& polyhedron) {
  Polytope p;
  p.kind = Polytope::Kind::kPolyhedron;
  p.vertex_count = int(polyhedron.vertices.size());
  p.vertices = polyhedron.vertices.data();
  p.edge_count = int(polyhedron.edge_from.size());
  p.edge_from = polyhedron.edge_from.data();
  p.edge_to = polyhedron.edge_to.data();
  p.edge_direction = polyhedron.edge_direction.data();
  p.direction_count = int(polyhedron.directions.size());
  p.directions = polyhedron.directions.data();
  p.face_count = polyhedron.face_count();
  p.faces = polyhedron.faces.data();
  p.face_begin = polyhedron.face_begin.data();
  p.sides = polyhedron.sides.data();
  p.bound_count = polyhedron.face_count();
  p.bounds = polyhedron.faces.data();
  p.center = polyhedron.center;
  p.size = polyhedron.size;
  p.coord = polyhedron.coord;
  p.patches_hold_depth = false;
  p.face_width = polyhedron.face_width.data();
  p.loops = polyhedron.loops.data();
  p.edge_cone = polyhedron.edge_cone.data();
  // Per triangle, the parallel classes cost 2 x 3 x classes projections of all corners,
  // the cones 3 x edges tests of 3 dot products (and their branches) plus a projection
  // per pair that passes. Measured on the drop scene's stretched icosahedra (15 classes,
  // 12 corners, 30 edges): classes 18.7, cones 20.5 us per terrain call; on random hulls
  // without parallel edges (12 to 32 corners) the cones are 1.9-2.5x faster per triangle.
  p.edges_by_cone = p.direction_count * (p.vertex_count + 3) > 8 * p.edge_count;
  return p;
}

struct Interval {
  Real lo = kInf;
  Real hi = -kInf;
};

// The projections are called once or twice per separating axis. GCC kept the two below as calls
// (7.6% of a box-vs-terrain call's samples in their bodies); forced inline, with the corner loop
// for general polytopes out of line, ODE's box calls take 3-5% less time (pair_replay --only box,
// 6.38-6.67 -> 6.15-6.30 us per call in alternating runs).
[[gnu::noinline]] Interval project_points(const Vec3* points, int count, const Vec3& u) {
  Interval r;
  for (int i = 0; i < count; ++i) {
    const Real x = u.dot(points[i]);
    r.lo = std::min(r.lo, x);
    r.hi = std::max(r.hi, x);
  }
  return r;
}

[[gnu::always_inline]] inline Interval project(const Polytope& p, const Vec3& u) {
  if (p.kind == Polytope::Kind::kBox) {
    // Centre and radius: three dot products instead of eight.
    const Real c = u.dot(p.center);
    const Real radius = p.half_extents.dot((p.axes.transpose() * u).cwiseAbs());
    return {c - radius, c + radius};
  }
  return project_points(p.vertices, p.vertex_count, u);
}

[[gnu::always_inline]] inline Interval project(const TriangleFrame& tri, const Vec3& u) {
  const Real x0 = u.dot(tri.v[0]);
  const Real x1 = u.dot(tri.v[1]);
  const Real x2 = u.dot(tri.v[2]);
  return {std::min({x0, x1, x2}), std::max({x0, x1, x2})};
}

enum class AxisKind { kTriangleFace, kShapeFace, kEdges };

// A candidate normal N (from the triangle towards the shape) and the overlap along it: how far the
// shape must move along N for its projection to clear the triangle's.
struct Axis {
  Vec3 normal = Vec3::UnitZ();
  Real overlap = kInf;
  AxisKind kind = AxisKind::kTriangleFace;
  int shape_index = 0;       // face index, or edge direction (a polyhedron's: the edge)
  int triangle_index = 0;    // triangle edge
  bool single_edge = false;  // shape_index is one edge of a polyhedron, not a parallel class
};

constexpr int kScratchContacts = 48;

// Contacts for the triangle's face as the normal N = +-n: the points of the shape over the
// triangle (inside its prism), at their distance below the plane along N. The deepest point of
// the shape over the triangle is a vertex of shape-within-prism, which is a shape vertex inside
// the prism, a shape edge crossing a prism wall, or a prism edge (the line through a triangle
// corner along N) crossing the shape's boundary: all three kinds are generated, so the deepest
// contact is exactly the directional penetration depth along N.
int triangle_face_contacts(const Polytope& shape, const TriangleFrame& tri, const Vec3& normal, Real slack,
                           ContactPoint* out) {
  int count = 0;
  const Real plane = normal.dot(tri.v[0]);
  Vec3 walls[3];
  for (int i = 0; i < 3; ++i) walls[i] = inward_wall(tri, i).normalized();
  const auto inside_prism = [&](const Vec3& x, int skip) {
    for (int i = 0; i < 3; ++i) {
      if (i != skip && walls[i].dot(x - tri.v[i]) < -slack) return false;
    }
    return true;
  };
  const auto add = [&](const Vec3& x) {
    if (count >= kScratchContacts) return;
    const Real depth = plane - normal.dot(x);
    out[count++] = make_contact(x + depth * normal, normal, depth);
  };
  for (int i = 0; i < shape.vertex_count; ++i) {
    if (inside_prism(shape.vertices[i], -1)) add(shape.vertices[i]);
  }
  for (int e = 0; e < shape.edge_count; ++e) {
    const Vec3& p = shape.vertices[shape.edge_from[e]];
    const Vec3& q = shape.vertices[shape.edge_to[e]];
    for (int i = 0; i < 3; ++i) {
      const Real fp = walls[i].dot(p - tri.v[i]);
      const Real fq = walls[i].dot(q - tri.v[i]);
      if (!((fp < 0 && fq > 0) || (fp > 0 && fq < 0))) continue;
      const Vec3 x = p + (fp / (fp - fq)) * (q - p);
      if (inside_prism(x, i)) add(x);
    }
  }
  // Lines v - t*N through the triangle's corners against the shape's bounding half-spaces
  // (Cyrus-Beck): the largest t is the deepest point of the shape under that corner.
  for (int j = 0; j < 3 && shape.bound_count > 0; ++j) {
    Real t_lo = -kInf;
    Real t_hi = kInf;
    for (int k = 0; k < shape.bound_count; ++k) {
      // bound.normal . (v - t N) <= offset  <=>  -t (bound.normal . N) <= offset - bound.normal . v
      const Real rate = -shape.bounds[k].normal.dot(normal);
      const Real room = -shape.bounds[k].signed_distance_scaled(tri.v[j]);
      if (std::abs(rate) <= kEps) {
        if (room < -slack) t_hi = -kInf;
        continue;
      }
      const Real t = room / rate;
      if (rate > 0) {
        t_hi = std::min(t_hi, t);
      } else {
        t_lo = std::max(t_lo, t);
      }
    }
    if (t_lo <= t_hi + slack && std::isfinite(t_hi) && count < kScratchContacts) {
      out[count++] = make_contact(tri.v[j], normal, t_hi);
    }
  }
  return count;
}

// Contacts for a face of the shape (outward f, N = -f): the triangle clipped to the face's
// polygon prism, each point at its depth below the face plane. Clipping a triangle by k sides
// leaves at most 3 + k corners; at most kScratchContacts are written.
int shape_face_contacts(const PolytopeFace& face, const TriangleFrame& tri, ContactPoint* out) {
  constexpr int kBuffer = 3 + kMaxPolyhedronFaceCorners;
  Vec3 buffer_a[kBuffer] = {tri.v[0], tri.v[1], tri.v[2]};
  Vec3 buffer_b[kBuffer];
  Vec3* in = buffer_a;
  Vec3* next = buffer_b;
  int n = 3;
  for (int s = 0; s < face.side_count && n > 0; ++s) {
    n = detail::clip_polygon(
        in, n, [&](const Vec3& x) { return face.sides[s].signed_distance_scaled(x); }, next);
    std::swap(in, next);
  }
  n = std::min(n, kScratchContacts);
  for (int i = 0; i < n; ++i) out[i] = make_contact(in[i], -face.outward, face.offset - face.outward.dot(in[i]));
  return n;
}

// The closest points of the shape's supporting edge along direction k and the triangle's edge j.
int edge_contacts(const Polytope& shape, const TriangleFrame& tri, const Axis& axis, Real slack, ContactPoint* out) {
  int best = -1;
  Real best_height = kInf;
  if (axis.single_edge) {
    best = axis.shape_index;
    best_height = axis.normal.dot(shape.vertices[shape.edge_from[best]] + shape.vertices[shape.edge_to[best]]);
  } else {
    for (int e = 0; e < shape.edge_count; ++e) {
      if (shape.edge_direction[e] != axis.shape_index) continue;
      const Real height = axis.normal.dot(shape.vertices[shape.edge_from[e]] + shape.vertices[shape.edge_to[e]]);
      if (height < best_height) {
        best_height = height;
        best = e;
      }
    }
  }
  if (best < 0) return 0;
  // Both edges must be where the projections meet (the shape's lowest and the triangle's highest
  // along N). A box always has such an edge in each direction class; a general polyhedron need
  // not, and an axis without it is no edge-edge feature pair (it can be the least axis only when
  // the rule "the triangle's normal on the side of the centre" leaves the true least one out).
  const Vec3& j0 = tri.v[axis.triangle_index];
  const Vec3& j1 = tri.v[(axis.triangle_index + 1) % 3];
  if (best_height / 2 > project(shape, axis.normal).lo + slack ||
      std::min(axis.normal.dot(j0), axis.normal.dot(j1)) < project(tri, axis.normal).hi - slack)
    return 0;
  // Where the two edges cross when seen along N: the closest points of their lines (the segment
  // between them is along N). When the edge pair is the least axis both lie on the edges and
  // position - N * depth is exactly on the shape's edge; when they do not (an edge axis that is
  // nearly a face normal, picked by rounding), there is no edge-edge contact and the caller falls
  // back to the face axes.
  const Vec3& p0 = shape.vertices[shape.edge_from[best]];
  const Vec3& q0 = tri.v[axis.triangle_index];
  const Vec3 d1 = shape.vertices[shape.edge_to[best]] - p0;
  const Vec3 d2 = tri.v[(axis.triangle_index + 1) % 3] - q0;
  const Vec3 n = d1.cross(d2);
  const Real nn = n.squaredNorm();
  if (!(nn > 0)) return 0;
  const Real s = (q0 - p0).cross(d2).dot(n) / nn;
  const Real t = (q0 - p0).cross(d1).dot(n) / nn;
  constexpr Real kOnEdge = 1e-9;
  if (!(s >= -kOnEdge && s <= 1 + kOnEdge && t >= -kOnEdge && t <= 1 + kOnEdge)) return 0;
  const Vec3 on_triangle = q0 + std::clamp(t, Real(0), Real(1)) * d2;
  out[0] = make_contact(on_triangle, axis.normal, axis.overlap);
  return 1;
}

// The closest pair of the shape and the triangle when they are apart: it joins a vertex of one to
// the other, or two edges, so those candidates cover it (a face-face or edge-face pair, when
// parallel, always contains such a pair too).
struct PolytopeTrianglePair {
  Vec3 on_shape = Vec3::Zero();
  Vec3 on_triangle = Vec3::Zero();
  Real distance_squared = kInf;
};

PolytopeTrianglePair closest_polytope_triangle(const Polytope& shape, const TriangleFrame& tri) {
  PolytopeTrianglePair best;
  const auto consider = [&](const Vec3& x, const Vec3& y) {
    const Real d2 = (x - y).squaredNorm();
    if (d2 < best.distance_squared) best = {x, y, d2};
  };
  // A feature pair is skipped when a lower bound of its distance (centre distance minus both
  // bounding radii) already reaches the best pair so far: for a box resting on a terrain most of
  // the 36 edge pairs are far from the closest pair, and the cheap candidates (the triangle's
  // corners against the box) usually find it first.
  const auto cannot_beat = [&](const Vec3& c0, Real r0, const Vec3& c1, Real r1) {
    const Real lower = (c0 - c1).norm() - r0 - r1;
    return lower > 0 && lower * lower >= best.distance_squared;
  };
  for (int j = 0; j < 3; ++j) consider(shape.closest_point(tri.v[j]), tri.v[j]);
  const Vec3 tri_center = (tri.v[0] + tri.v[1] + tri.v[2]) / 3;
  const Real tri_radius =
      std::sqrt(std::max({(tri.v[0] - tri_center).squaredNorm(), (tri.v[1] - tri_center).squaredNorm(),
                          (tri.v[2] - tri_center).squaredNorm()}));
  for (int i = 0; i < shape.vertex_count; ++i) {
    if (cannot_beat(shape.vertices[i], 0, tri_center, tri_radius)) continue;
    consider(shape.vertices[i], closest_point_on_triangle(shape.vertices[i], tri.v[0], tri.v[1], tri.v[2]));
  }
  for (int e = 0; e < shape.edge_count; ++e) {
    const Vec3& p0 = shape.vertices[shape.edge_from[e]];
    const Vec3& p1 = shape.vertices[shape.edge_to[e]];
    const Vec3 edge_center = (p0 + p1) / 2;
    const Real edge_radius = (p1 - p0).norm() / 2;
    if (cannot_beat(edge_center, edge_radius, tri_center, tri_radius)) continue;
    for (int j = 0; j < 3; ++j) {
      const Vec3& q0 = tri.v[j];
      const Vec3& q1 = tri.v[(j + 1) % 3];
      if (cannot_beat(edge_center, edge_radius, (q0 + q1) / 2, (q1 - q0).norm() / 2)) continue;
      Vec3 x;
      Vec3 y;
      closest_points_on_segments(p0, p1, q0, q1, x, y);
      consider(x, y);
    }
  }
  return best;
}

// Separating axes of a convex polytope against a triangle. Every axis is tested in both
// directions; `separation` (the largest gap) is > 0 exactly when they are apart, and then it is a
// lower bound of the distance. Overlapping: the least overlap is the penetration depth, its axis
// the normal, and the contacts come from the features of that axis. Apart: the exact closest pair
// decides, and the axis' features are used only when its gap is the distance (a face over a
// vertex, crossing edges), so that a face hovering over a face still gets a patch.
int polytope_triangle(const Polytope& shape, const TriangleFrame& tri, const ContactOptions& options, int max_contacts,
                      ContactPoint* out) {
  const Real size = std::max(shape.size, tri.size);
  const Real slack = tolerance(size, std::max(shape.coord, tri.coord));
  const Real margin = std::max(options.margin, Real(0));
  const bool one_sided = tri.one_sided(options);
  const Real center_side = tri.degenerate ? 0 : tri.signed_distance(shape.center);

  // The overlap of the shape's and triangle's projections when the shape moves along N.
  const auto overlap_along = [&](const Vec3& n) { return project(tri, n).hi - project(shape, n).lo; };
  // Both directions of one axis from one pair of projections (negating the axis negates every
  // dot product exactly, so these equal overlap_along(n) and overlap_along(-n) to the bit).
  const auto overlaps_both_ways = [&](const Vec3& n) {
    const Interval t = project(tri, n);
    const Interval p = project(shape, n);
    return std::pair<Real, Real>{t.hi - p.lo, p.hi - t.lo};
  };

  // Along the shape's own face f (n = -outward): a polyhedron's projection is known from the
  // face's plane and width, three dot products instead of one per corner per face.
  const auto overlaps_both_ways_on_face = [&](int f, const Vec3& n) {
    if (shape.face_width) {
      const Interval t = project(tri, n);
      const Real lo = -shape.faces[f].offset;
      const Real hi = lo + shape.face_width[f];
      return std::pair<Real, Real>{t.hi - lo, hi - t.lo};
    }
    return overlaps_both_ways(n);
  };
  Axis best_face;
  Axis best_tri_face;
  Axis best_edge;
  Real separation = -kInf;
  const auto consider = [](Axis& best, const Axis& axis) {
    if (axis.overlap < best.overlap) best = axis;
  };
  if (!tri.degenerate) {
    const auto [up, down] = overlaps_both_ways(tri.normal);
    separation = std::max(separation, -std::min(up, down));
    // Whichever side the shape's centre is on.
    const Real sigma = center_side >= 0 ? 1 : -1;
    consider(best_tri_face, {sigma * tri.normal, sigma > 0 ? up : down, AxisKind::kTriangleFace, 0, 0});
  }
  // Apart by more than the margin along any axis: no contact, the other axes need not be tried
  // (most candidates of a query volume are apart along the triangle's normal or a face's).
  if (separation > margin) return 0;
  for (int f = 0; f < shape.face_count; ++f) {
    const Vec3 n = -shape.faces[f].normal;
    const auto [ov, reverse] = overlaps_both_ways_on_face(f, n);
    separation = std::max(separation, -std::min(ov, reverse));
    if (separation > margin) return 0;
    consider(best_face, {n, ov, AxisKind::kShapeFace, f, 0});
  }
  // Edge pairs: by parallel class (a box's 3, both directions of each cross: the lowest edge of
  // the class is the contact), or, for a polyhedron with many classes, edge by edge through the
  // normal cones: only the pairs that are faces of the Minkowski difference (on the Gauss map,
  // the arc of the shape edge's cone crosses the half circle of the triangle edge's), each in its
  // one direction. With u = d x t (d: the shape's edge, t: the triangle's), the shape's outward
  // normal at the edge must be +-u = s a1 + r a2 with s, r >= 0 (a1, a2: its faces' normals), and
  // the triangle's edge its support along N = -(+-u), i.e. N . (t x n) >= 0, which is
  // +-(d . n) >= 0; edge_cone makes the first test three dot products. The other crosses are
  // never the least overlap nor the only separating axis.
  if (shape.edges_by_cone) {
    Vec3 edges[3];
    for (int j = 0; j < 3; ++j) edges[j] = tri.v[(j + 1) % 3] - tri.v[j];
    for (int k = 0; k < shape.edge_count; ++k) {
      const Vec3* cone = shape.edge_cone + 3 * k;
      const Vec3 d = shape.vertices[shape.edge_to[k]] - shape.vertices[shape.edge_from[k]];
      // A degenerate triangle has no sides: every pair in the shape's cone is kept.
      const Real dn = tri.degenerate ? Real(0) : d.dot(tri.normal);
      for (int j = 0; j < 3; ++j) {
        const Real sign = edges[j].dot(cone[0]) < 0 ? Real(-1) : Real(1);
        if (sign * edges[j].dot(cone[1]) < 0 || sign * edges[j].dot(cone[2]) < 0 || sign * dn < 0) continue;
        const Vec3 u = sign * d.cross(edges[j]);
        const Real len = u.norm();
        // Nearly parallel edges: the cross is mostly rounding; the face axes cover that case.
        if (!(len > 1e-6 * edges[j].norm() * d.norm())) continue;
        const Vec3 n = -u / len;
        // The cone test put -n (the shape's outward normal here) in edge k's cone: the edge is
        // the shape's support along -n, and its corner gives the shape's projection.
        const Real overlap = project(tri, n).hi - n.dot(shape.vertices[shape.edge_from[k]]);
        separation = std::max(separation, -overlap);
        if (separation > margin) return 0;
        consider(best_edge, {n, overlap, AxisKind::kEdges, k, j, true});
      }
    }
  } else {
    for (int k = 0; k < shape.direction_count; ++k) {
      for (int j = 0; j < 3; ++j) {
        const Vec3 e = tri.v[(j + 1) % 3] - tri.v[j];
        const Vec3 u = shape.directions[k].cross(e);
        const Real len = u.norm();
        // Nearly parallel edges: the cross is mostly rounding; the face axes cover that case.
        if (!(len > 1e-6 * e.norm())) continue;
        const Vec3 n = u / len;
        const auto [plus, minus] = overlaps_both_ways(n);
        separation = std::max(separation, -std::min(plus, minus));
        if (separation > margin) return 0;
        consider(best_edge, {n, plus, AxisKind::kEdges, k, j});
        consider(best_edge, {-n, minus, AxisKind::kEdges, k, j});
      }
    }
  }
  if (separation > margin || !(separation == separation)) return 0;
  const bool apart = separation > 0;

  // Faces first: the triangle's face unless a face of the shape is clearly better, then an edge
  // pair only if clearly better than that.
  const auto bias = [&](Real overlap) { return kFaceBias * std::abs(overlap) + slack; };
  Axis chosen = best_face;
  if (best_tri_face.overlap < kInf &&
      (best_face.overlap == kInf || best_tri_face.overlap <= best_face.overlap + bias(best_face.overlap))) {
    chosen = best_tri_face;
  }
  const Axis face_choice = chosen;
  if (best_edge.overlap < kInf &&
      (chosen.overlap == kInf || best_edge.overlap < chosen.overlap - bias(chosen.overlap))) {
    chosen = best_edge;
  }
  if (chosen.overlap == kInf) return 0;  // no axis at all: only for shapes without faces or edges

  // Per thread, not per call: constructing 48 contacts (3 KB of default members) was 14% of a
  // box-vs-triangle call's samples.
  thread_local std::array<ContactPoint, kScratchContacts> scratch;
  const auto generate = [&](const Axis& axis) {
    switch (axis.kind) {
      case AxisKind::kTriangleFace:
        return triangle_face_contacts(shape, tri, axis.normal, slack, scratch.data());
      case AxisKind::kShapeFace:
        return shape_face_contacts(shape.face(axis.shape_index), tri, scratch.data());
      case AxisKind::kEdges:
        return edge_contacts(shape, tri, axis, slack, scratch.data());
    }
    return 0;
  };
  // Whether the axis' features hold its overlap: a contact at that depth.
  const auto reaches = [&](const Axis& axis, int n) {
    Real deepest = -kInf;
    for (int i = 0; i < n; ++i) deepest = std::max(deepest, scratch[i].depth);
    return deepest >= axis.overlap - (1e-9 * size + slack);
  };

  // One-sided: a shape behind the plane, or whose natural normal points behind it, is pushed out
  // through the front face by its directional penetration, if it overlaps at all.
  int count = -1;  // the chosen axis' contacts in scratch, once generated
  if (one_sided && (center_side < 0 || chosen.normal.dot(tri.normal) < -kBehind)) {
    if (apart) return 0;
    chosen = {tri.normal, overlap_along(tri.normal), AxisKind::kTriangleFace, 0, 0};
  } else if (apart) {
    // The gap along a separating axis is a lower bound of the distance; when the axis' features
    // hold it (a corner over the other's face at that height and its foot on the face, or the
    // crossing points of two edges), two points are that far apart and it is the distance. Only
    // otherwise is the closest pair searched (dear for a polyhedron: its faces' fans against the
    // triangle's corners, its corners and edges). The search also rounds: at 10 m from the
    // origin its distance came out ~1e-8 longer than the gap, far above `slack`, and a face
    // hovering over a facet then got one closest point instead of its patch.
    count = generate(chosen);
    if (!reaches(chosen, count)) {
      const PolytopeTrianglePair pair = closest_polytope_triangle(shape, tri);
      const Real distance = std::sqrt(pair.distance_squared);
      if (!(distance <= margin)) return 0;
      if (-chosen.overlap < distance - slack) {
        // The chosen axis' gap is short of the distance: its features are not the closest ones.
        const Vec3 normal = (pair.on_shape - pair.on_triangle) / distance;
        if (one_sided && normal.dot(tri.normal) < -kBehind) return 0;
        out[0] = make_contact(pair.on_triangle, normal, -distance);
        return 1;
      }
    }
  }

  if (count < 0) count = generate(chosen);
  if (count == 0 && chosen.kind == AxisKind::kEdges && face_choice.overlap < kInf) {
    chosen = face_choice;
    count = generate(chosen);
  }
  if (!shape.patches_hold_depth) {
    // A box is the prism over each of its faces, so a face's patch always holds the triangle's
    // deepest point along its normal. A general polyhedron is not: part of the triangle can be
    // inside it beyond the face's polygon, under a neighbouring face, and the patch then falls
    // short of the axis' overlap (moving by its depth would not separate). Then the edge pair
    // carries the contact if it is exact, else the triangle's face (its patch is the directional
    // depth along the triangle's normal, over the whole triangle). An empty patch (the triangle
    // is not over the face at all) is the extreme case.
    if (chosen.kind == AxisKind::kShapeFace && !reaches(chosen, count)) {
      int edge_count = best_edge.overlap < kInf ? generate(best_edge) : 0;
      if (edge_count > 0) {
        chosen = best_edge;
        count = edge_count;
      } else if (best_tri_face.overlap < kInf) {
        chosen = best_tri_face;
        count = generate(chosen);
      }
    }
  }
  int kept = 0;
  for (int i = 0; i < count; ++i) {
    if (scratch[i].depth >= -margin && scratch[i].depth == scratch[i].depth) scratch[kept++] = scratch[i];
  }
  if (kept == 0) {
    // Only rounding can leave the chosen feature without a point: report the triangle's
    // supporting corner along the normal at the axis' overlap.
    int corner = 0;
    for (int j = 1; j < 3; ++j) {
      if (chosen.normal.dot(tri.v[j]) > chosen.normal.dot(tri.v[corner])) corner = j;
    }
    scratch[0] = make_contact(tri.v[corner], chosen.normal, chosen.overlap);
    kept = 1;
  }
  kept = reduce_in_place(scratch.data(), kept, max_contacts, 1e-7 * size + slack);
  std::copy(scratch.begin(), scratch.begin() + kept, out);
  return kept;
}

// ---------------------------------------------------------------------------------------------
// libccd glue

struct CcdTriangle {
  const TriangleFrame* tri;
  Real inflate;  // the triangle rounded by this radius
};

struct CcdShape {
  const ConvexSupport* shape;
  Vec3 offset;  // the shape translated by this
};

Vec3 to_vec(const ccd_vec3_t* v) { return {v->v[0], v->v[1], v->v[2]}; }
void from_vec(const Vec3& x, ccd_vec3_t* v) { ccdVec3Set(v, x.x(), x.y(), x.z()); }

void ccd_triangle_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* result) {
  const auto* t = static_cast<const CcdTriangle*>(object);
  const Vec3 d = to_vec(direction);
  int best = 0;
  for (int j = 1; j < 3; ++j) {
    if (d.dot(t->tri->v[j]) > d.dot(t->tri->v[best])) best = j;
  }
  Vec3 x = t->tri->v[best];
  const Real len = d.norm();
  if (t->inflate > 0 && len > 0) x += (t->inflate / len) * d;
  from_vec(x, result);
}

void ccd_triangle_center(const void* object, ccd_vec3_t* center) {
  const auto* t = static_cast<const CcdTriangle*>(object);
  from_vec((t->tri->v[0] + t->tri->v[1] + t->tri->v[2]) / 3, center);
}

void ccd_shape_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* result) {
  const auto* s = static_cast<const CcdShape*>(object);
  from_vec(s->shape->support(to_vec(direction)) + s->offset, result);
}

void ccd_shape_center(const void* object, ccd_vec3_t* center) {
  const auto* s = static_cast<const CcdShape*>(object);
  from_vec(s->shape->center + s->offset, center);
}

// Local minimization of f(u) (the projections' overlap along the unit normal u) from `normal`:
// a pattern search over 8 tangent directions plus the last successful move (which follows a
// valley that is not aligned with the pattern, as along a rounded edge), doubling the step after
// a success and halving it after a failure. A non-zero `front` keeps u.front >= -kBehind.
// Stops at `min_step` rad and `max_evaluations` per start: 1e-7 and 150 by default, far below
// what contacts need, and 3x cheaper than polishing to 1e-12 (cylinders on ODE's drop scene:
// 190 -> 65 us per dCollide).
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

ccd_t make_ccd(Real size) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd_triangle_support;
  ccd.support2 = ccd_shape_support;
  ccd.center1 = ccd_triangle_center;
  ccd.center2 = ccd_shape_center;
  // Bounded effort: curved shapes (cylinders, the rounded triangle) make EPA converge linearly.
  ccd.max_iterations = 200;
  ccd.epa_tolerance = 1e-6 * size;
  ccd.mpr_tolerance = 1e-8 * size;
  ccd.dist_tolerance = 1e-10 * size;
  return ccd;
}

// A quick apartness test for a shape given by its support mapping (support(d): the farthest point
// along d): true when the gap along the triangle's normal (either way) or along the direction
// from the triangle to `center` is wider than the margin. Never true for shapes within the margin.
template <class Support>
bool apart_along_cheap_axes(const TriangleFrame& tri, const Vec3& center, Real margin, const Support& support) {
  const Real limit = -margin - tolerance(tri.size, std::max(tri.coord, max_abs(center)));
  const auto gap_too_wide = [&](const Vec3& u) { return project(tri, u).hi - u.dot(support(-u)) < limit; };
  if (!tri.degenerate && (gap_too_wide(tri.normal) || gap_too_wide(-tri.normal))) return true;
  const Vec3 towards = center - closest_point_on_triangle(center, tri.v[0], tri.v[1], tri.v[2]);
  const Real length = towards.norm();
  return length > 0 && gap_too_wide(towards / length);
}

// The contact position for a shape moved out along `normal`: where its deepest point lands
// (`landing`), on the triangle's supporting feature along the normal (a corner, an edge, or the
// face).
Vec3 landing_position(const TriangleFrame& tri, const Vec3& normal, const Vec3& landing, Real size) {
  const Real top = project(tri, normal).hi;
  const Real feature_slack = 1e-6 * size;
  int on_top[3];
  int count = 0;
  for (int j = 0; j < 3; ++j) {
    if (normal.dot(tri.v[j]) >= top - feature_slack) on_top[count++] = j;
  }
  if (count == 1) return tri.v[on_top[0]];
  Vec3 position;
  if (count == 2) {
    Vec3 unused;
    closest_points_on_segments(landing, landing, tri.v[on_top[0]], tri.v[on_top[1]], unused, position);
    return position;
  }
  return closest_point_on_triangle(landing, tri.v[0], tri.v[1], tri.v[2]);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Sphere

int contact_sphere_triangle(const Sphere& sphere, const Vec3& a, const Vec3& b, const Vec3& c,
                            const ContactOptions& options, ContactPoint* out) {
  if (!finite(a, b, c) || !sphere.center.allFinite() || !std::isfinite(sphere.radius)) return 0;
  const TriangleFrame tri(a, b, c);
  const Real r = sphere.radius;
  const Vec3& p = sphere.center;
  const Vec3 q = closest_point_on_triangle(p, a, b, c);
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

// ---------------------------------------------------------------------------------------------
// Capsule

int contact_capsule_triangle(const Capsule& capsule, const Vec3& a, const Vec3& b, const Vec3& c,
                             const ContactOptions& options, ContactPoint* out) {
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

  const SegmentTrianglePair pair = closest_segment_triangle(p0, p1, tri);
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
    // Behind a one-sided triangle: the least lift along n that clears it, by bisection on the
    // exact overlap test (the lifts that overlap form an interval containing 0, since the
    // capsule moved along a line sweeps a convex set).
    if (distance > r) return 0;
    const auto overlaps_at = [&](Real t) {
      const Vec3 lift = t * tri.normal;
      return segment_triangle_distance_squared(p0 + lift, p1 + lift, a, b, c) <= r * r;
    };
    Real lo = 0;
    Real hi = r - std::min(tri.signed_distance(p0), tri.signed_distance(p1)) + tiny;
    for (int iteration = 0; iteration < 200 && hi - lo > tiny; ++iteration) {
      const Real mid = (lo + hi) / 2;
      (overlaps_at(mid) ? lo : hi) = mid;
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

// ---------------------------------------------------------------------------------------------
// Box

int contact_box_triangle(const Obb& box, const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options,
                         ContactPoint* out) {
  if (!finite(a, b, c) || !box.center.allFinite() || !box.axes.allFinite() || !box.half_extents.allFinite()) return 0;
  const TriangleFrame tri(a, b, c);
  // A midphase calls this for many triangles against one box: its polytope (vertices, edges, faces
  // and their sides, over a kilobyte) is built once per box and thread, not per triangle.
  thread_local Obb last_box{Vec3::Constant(kInf), Mat3::Zero(), Vec3::Zero()};
  thread_local PolytopeArrays last_arrays;
  thread_local Polytope last_polytope;
  if (box.center != last_box.center || box.axes != last_box.axes || box.half_extents != last_box.half_extents) {
    last_polytope = polytope_of_box(box, last_arrays);
    last_box = box;
  }
  return polytope_triangle(last_polytope, tri, options, kMaxBoxTriangleContacts, out);
}

// ---------------------------------------------------------------------------------------------
// Convex polyhedra

int contact_polyhedron_triangle(const ConvexPolyhedron& polyhedron, const Vec3& a, const Vec3& b, const Vec3& c,
                                const ContactOptions& options, ContactPoint* out) {
  if (!finite(a, b, c) || polyhedron.vertices.empty() || !polyhedron.center.allFinite()) return 0;
  return polytope_triangle(polytope_of_polyhedron(polyhedron), TriangleFrame(a, b, c), options,
                           kMaxPolyhedronTriangleContacts, out);
}

// ---------------------------------------------------------------------------------------------
// Triangle pairs

int contact_triangle_triangle(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                              const Vec3& b2, const ContactOptions& options, ContactPoint* out) {
  if (!finite(a0, a1, a2) || !finite(b0, b1, b2)) return 0;
  const TriangleFrame ta(a0, a1, a2);
  const TriangleFrame tb(b0, b1, b2);
  if (ta.degenerate && tb.degenerate) {
    // Two segments (or points): no face normal anywhere, only the closest pair.
    const auto [sa, ea] = extent_of(ta);
    const auto [sb, eb] = extent_of(tb);
    Vec3 on_a;
    Vec3 on_b;
    closest_points_on_segments(sa, ea, sb, eb, on_a, on_b);
    const Real distance = (on_a - on_b).norm();
    if (!(distance <= std::max(options.margin, Real(0)))) return 0;
    Vec3 n;
    if (distance > tolerance(std::max(ta.size, tb.size), std::max(ta.coord, tb.coord))) {
      n = (on_a - on_b) / distance;
    } else {
      n = (eb - sb).cross(ea - sa);
      n = n.norm() > 0 ? Vec3(n.normalized())
                       : perpendicular_to((eb - sb).squaredNorm() > 0 ? Vec3(eb - sb) : Vec3(ea - sa));
    }
    out[0] = make_contact(on_b, n, -distance);
    return 1;
  }
  PolytopeArrays arrays;
  return polytope_triangle(polytope_of_triangle(ta, arrays), tb, options, kMaxTriangleTriangleContacts, out);
}

// ---------------------------------------------------------------------------------------------
// General convex shapes

Vec3 support_cylinder(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& direction) {
  const Vec3 axis = p1 - p0;
  const Real length = axis.norm();
  if (!(length > 0)) {
    // No axis to orient the disks by: the sphere of that radius (a conservative stand-in).
    const Real len = direction.norm();
    return len > 0 ? Vec3(p0 + (radius / len) * direction) : p0;
  }
  const Vec3 u = axis / length;
  const Real along = direction.dot(u);
  const Vec3 end = along >= 0 ? p1 : p0;
  const Vec3 radial = direction - along * u;
  const Real radial_length = radial.norm();
  // Along the axis the radial part is rounding noise, and normalizing it would pick an arbitrary
  // rim point (up to `radius` off along the direction): the disk's centre is exact there.
  if (!(radial_length > 1e-12 * direction.norm())) return end;
  return end + (radius / radial_length) * radial;
}

Vec3 support_points(const std::vector<Vec3>& points, const Vec3& direction) {
  if (points.empty()) return Vec3::Zero();
  std::size_t best = 0;
  Real best_dot = direction.dot(points[0]);
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Real x = direction.dot(points[i]);
    if (x > best_dot) {
      best_dot = x;
      best = i;
    }
  }
  return points[best];
}

int contact_convex_triangle(const ConvexSupport& shape, const Vec3& a, const Vec3& b, const Vec3& c,
                            const ContactOptions& options, ContactPoint* out) {
  // 1. GJK + EPA (libccd) against the triangle rounded by the margin. Rounding grows the Minkowski
  //    difference by a ball of radius `margin`, which adds exactly `margin` to the depth of every
  //    origin inside it (penetrating, or apart by less than the margin) along the same normal; so
  //    one call covers the separated-within-margin case and the depth is EPA's minus the margin.
  // 2. EPA's polytope lies inside the Minkowski difference, so on curved shapes (cylinders, the
  //    rounded triangle) its depth is short of the truth and its normal slightly off. The answer is
  //    therefore polished: the depth along a unit normal u is the projections' overlap
  //    f(u) = max_triangle u.p - min_shape u.x (moving the shape by f(u) along u separates them),
  //    and the least f over directions is the penetration depth (or minus the distance when apart).
  //    A local pattern search on the sphere from EPA's normal minimizes f; the reported depth is
  //    f at the reported normal, so moving by it always separates.
  if (!finite(a, b, c) || !shape.center.allFinite()) return 0;
  const TriangleFrame tri(a, b, c);
  const Real margin = std::max(options.margin, Real(0));
  // 0. Cheap separating axes first (most candidates of a loose query volume are apart): a gap
  //    wider than the margin along any direction means no contact, whichever side the shape is
  //    on, so GJK need not run. Tried: the triangle's normal both ways and the direction from the
  //    triangle's closest point to the centre.
  if (apart_along_cheap_axes(tri, shape.center, margin, [&](const Vec3& d) { return shape.support(d); })) return 0;
  Real shape_size = 0;
  for (int k = 0; k < 3; ++k) {
    const Vec3 axis = Vec3::Unit(k);
    shape_size = std::max(shape_size, axis.dot(shape.support(axis)) + axis.dot(shape.support(-axis)));
  }
  const Real size = std::max({tri.size, shape_size, margin});
  if (!(size > 0) || !(size < kInf)) return 0;
  const ccd_t ccd = make_ccd(size);

  const auto overlap_along = [&](const Vec3& u) { return project(tri, u).hi - u.dot(shape.support(-u)); };
  const CcdShape moved{&shape, Vec3::Zero()};
  const bool one_sided = tri.one_sided(options);
  bool push_out = one_sided && tri.signed_distance(shape.center) < 0;
  Vec3 normal = tri.normal;
  Real depth = 0;
  if (!push_out) {
    const CcdTriangle rounded{&tri, margin};
    ccd_real_t epa_depth = 0;
    ccd_vec3_t direction;
    ccd_vec3_t position;
    // obj1 = triangle, obj2 = shape: libccd's direction moves obj2 out, which is our normal.
    if (ccdGJKPenetration(&rounded, &moved, &ccd, &epa_depth, &direction, &position) != 0) return 0;
    Vec3 epa_normal = to_vec(&direction);
    const Real len = epa_normal.norm();
    if (!(len > 0) || !epa_normal.allFinite()) return 0;
    epa_normal /= len;
    // EPA can end in the wrong basin on deep or curved configurations. The overlap is cheap to
    // evaluate, so it is also taken along the triangle's normals, its in-plane edge normals and
    // the direction of the centre; the polish starts from the two best of these and EPA's normal.
    std::array<std::pair<Real, Vec3>, 10> starts;
    int start_count = 0;
    const auto add_start = [&](const Vec3& towards) {
      const Real norm = towards.norm();
      if (!(norm > 0) || !towards.allFinite()) return;
      const Vec3 u = towards / norm;
      if (one_sided && u.dot(tri.normal) < -kBehind) return;
      starts[start_count++] = {overlap_along(u), u};
    };
    add_start(shape.center - closest_point_on_triangle(shape.center, a, b, c));
    if (!tri.degenerate) {
      add_start(tri.normal);
      add_start(-tri.normal);
      for (int j = 0; j < 3; ++j) add_start((tri.v[(j + 1) % 3] - tri.v[j]).cross(tri.normal));  // outward
    }
    std::sort(starts.begin(), starts.begin() + start_count,
              [](const auto& x, const auto& y) { return x.first < y.first; });
    start_count = std::min(start_count, 2);
    starts[start_count++] = {overlap_along(epa_normal), epa_normal};
    depth = kInf;
    for (int k = 0; k < start_count; ++k) {
      Vec3 start = starts[k].second;
      Real value = starts[k].first;
      // A polytope's overlap is piecewise linear and EPA's polytope is exact on it (to
      // epa_tolerance) unless the margin rounds the triangle: no polish then. That is 80% of the
      // time per contact on hulls.
      if (!shape.polytope || margin > 0)
        polish_normal(overlap_along, one_sided ? tri.normal : Vec3::Zero(), start, value);
      if (value < depth) {
        depth = value;
        normal = start;
      }
    }
    if (depth < -margin) return 0;
    push_out = one_sided && normal.dot(tri.normal) < -kBehind;
  }
  if (push_out) {
    // Directional penetration along the front normal n: the least lift t such that the shape
    // moved by t*n is apart. Moving by t*n shifts the projections on any u by t*(u.n), so every u
    // with u.n > 0 bounds t by f(u)/(u.n), and the least bound is the lift (the support-function
    // form of a ray cast through the Minkowski difference). The bound is minimized from u = n by
    // the same pattern search, so the reported lift always separates.
    const CcdTriangle flat{&tri, 0};
    if (!ccdGJKIntersect(&flat, &moved, &ccd)) return 0;  // behind and apart: not seen
    const auto lift_bound = [&](const Vec3& u) {
      const Real along = u.dot(tri.normal);
      return along > 1e-6 ? overlap_along(u) / along : kInf;
    };
    Vec3 u = tri.normal;
    Real lift = lift_bound(u);
    polish_normal(lift_bound, tri.normal, u, lift);
    normal = tri.normal;
    depth = lift;
  }
  out[0] = make_contact(landing_position(tri, normal, shape.support(-normal) + depth * normal, size), normal, depth);
  return 1;
}

// ---------------------------------------------------------------------------------------------
// Cylinder

namespace {

// The part of a solid cylinder (axis p0-p1, unit direction w, length L) inside the prism over a
// non-degenerate triangle, by its depths below the triangle's plane (depth = n . v0 - n . x): the
// deepest point and the least depth. A linear function over that convex set has its extremes
// where its boundary constraints meet, so the candidates are: the cylinder's support along -+n
// (no wall active); on one wall, the extremes of the side's section (an ellipse) and the rims'
// crossings (the caps' sections are chords, whose extremes are their ends on the rims); on two
// walls, the line through a corner along n, cut by the cylinder. Closed form throughout: the
// push-out of a cylinder behind a one-sided triangle without GJK/EPA (the general routine took
// ~9 us per such triangle on ODE's drop scene, a fifth of the cylinder's time there).
struct PrismDepths {
  bool any = false;
  Real deepest = -kInf;
  Vec3 deepest_point = Vec3::Zero();
  Real shallowest = kInf;
};

PrismDepths cylinder_depths_in_prism(const Vec3& p0, const Vec3& w, Real length, Real radius, const TriangleFrame& tri,
                                     Real slack) {
  const Vec3& n = tri.normal;
  const Real plane = n.dot(tri.v[0]);
  Vec3 walls[3];
  for (int i = 0; i < 3; ++i) walls[i] = inward_wall(tri, i).normalized();
  const auto in_prism = [&](const Vec3& x, int skip1, int skip2) {
    for (int i = 0; i < 3; ++i) {
      if (i != skip1 && i != skip2 && walls[i].dot(x - tri.v[i]) < -slack) return false;
    }
    return true;
  };
  const auto axial_ok = [&](const Vec3& x) {
    const Real along = w.dot(x - p0);
    return along >= -slack && along <= length + slack;
  };
  PrismDepths result;
  const auto take = [&](const Vec3& x) {
    const Real depth = plane - n.dot(x);
    result.any = true;
    if (depth > result.deepest) {
      result.deepest = depth;
      result.deepest_point = x;
    }
    result.shallowest = std::min(result.shallowest, depth);
  };
  const Vec3 p1 = p0 + length * w;
  const auto radial = [&](const Vec3& v) { return Vec3(v - w.dot(v) * w); };  // P v, P = I - w w^T
  const Vec3 pn = radial(n);
  Vec3 u1;  // the rims' plane
  Vec3 u2;
  detail::orthonormal_completion(w, u1, u2);
  // No wall active.
  for (const Real sign : {Real(-1), Real(1)}) {
    const Vec3 x = support_cylinder(p0, p1, radius, sign * n);
    if (in_prism(x, -1, -1)) take(x);
  }
  for (int i = 0; i < 3; ++i) {
    const Vec3& o = tri.v[i];
    const Vec3 t = (tri.v[(i + 1) % 3] - o).normalized();  // the wall is o + a n + b t
    // The side's section: |q + a pn + b pt|^2 = r^2, an ellipse in (a, b) unless the axis lies
    // in the wall (then lines along the axis, whose extremes are on the rims, below).
    const Vec3 q = radial(o - p0);
    const Vec3 pt = radial(t);
    const Real m00 = pn.dot(pn), m01 = pn.dot(pt), m11 = pt.dot(pt);
    const Real det = m00 * m11 - m01 * m01;
    if (det > 1e-12) {
      const Real g0 = q.dot(pn), g1 = q.dot(pt);
      // Centre z0 = -M^-1 g; the ellipse is (z - z0)^T M (z - z0) = rho.
      const Real a0 = -(m11 * g0 - m01 * g1) / det;
      const Real b0 = -(-m01 * g0 + m00 * g1) / det;
      const Real rho = radius * radius - (q.squaredNorm() + g0 * a0 + g1 * b0);
      if (rho >= 0) {
        // Extremes of a: z0 +- sqrt(rho) M^-1 e_a / sqrt((M^-1)_aa), (M^-1)_aa = m11 / det.
        const Real scale = std::sqrt(rho / (m11 / det));
        const Real da = scale * m11 / det;
        const Real db = -scale * m01 / det;
        for (const Real sign : {Real(-1), Real(1)}) {
          const Vec3 x = o + (a0 + sign * da) * n + (b0 + sign * db) * t;
          if (axial_ok(x) && in_prism(x, i, -1)) take(x);
        }
      }
    }
    // The rims across the wall: the circle c + r (cos f u1 + sin f u2) meets the wall where
    // A cos f + B sin f = -D.
    for (const Vec3& centre : {p0, p1}) {
      const Real A = radius * walls[i].dot(u1);
      const Real B = radius * walls[i].dot(u2);
      const Real D = walls[i].dot(centre - o);
      const Real R = std::hypot(A, B);
      if (!(R > 0) || std::abs(D) > R) continue;
      const Real base = std::atan2(B, A);
      const Real spread = std::acos(std::clamp(-D / R, Real(-1), Real(1)));
      for (const Real f : {base + spread, base - spread}) {
        const Vec3 x = centre + radius * (std::cos(f) * u1 + std::sin(f) * u2);
        if (in_prism(x, i, -1)) take(x);
      }
    }
  }
  // The prism's edges: x = v_j - s n is in the cylinder for s in an interval; depth = s.
  for (int j = 0; j < 3; ++j) {
    const Vec3 q = radial(tri.v[j] - p0);
    Real lo = -kInf;
    Real hi = kInf;
    const Real alpha = pn.squaredNorm();
    const Real beta = q.dot(pn);
    const Real gamma = q.squaredNorm() - radius * radius;
    if (alpha > 1e-12) {
      const Real disc = beta * beta - alpha * gamma;
      if (disc < 0) continue;
      const Real root = std::sqrt(disc);
      lo = (beta - root) / alpha;
      hi = (beta + root) / alpha;
    } else if (gamma > 0) {
      continue;
    }
    // Axial: 0 <= w . (v_j - p0) - s (w . n) <= L.
    const Real along = w.dot(tri.v[j] - p0);
    const Real rate = w.dot(n);
    if (std::abs(rate) > 1e-12) {
      const Real s_a = along / rate;
      const Real s_b = (along - length) / rate;
      lo = std::max(lo, std::min(s_a, s_b));
      hi = std::min(hi, std::max(s_a, s_b));
    } else if (along < -slack || along > length + slack) {
      continue;
    }
    if (!(lo <= hi) || !std::isfinite(lo) || !std::isfinite(hi)) continue;
    take(tri.v[j] - hi * n);
    take(tri.v[j] - lo * n);
  }
  return result;
}

}  // namespace

int contact_cylinder_triangle(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& a, const Vec3& b, const Vec3& c,
                              const ContactOptions& options, ContactPoint* out) {
  // The same answer as contact_convex_triangle (the least overlap of the projections over unit
  // normals), found without GJK/EPA: the cylinder's lowest point along u is closed-form, so the
  // overlap f(u) is cheap, and the normals where f has its minima are mostly known in advance
  // (the faces of the Minkowski difference: the triangle's normal, the cylinder's axis, axis x
  // edge, the radial directions to the corners). f is taken along those, the least is polished by
  // the same pattern search (curved parts: rim against an edge or a corner), and any of them with
  // a gap wider than the margin proves the two apart. Shapes behind a one-sided triangle (the
  // push-out case) and degenerate inputs go to the general routine.
  if (!finite(a, b, c) || !finite(p0, p1, Vec3::Constant(radius)) || !(radius >= 0)) return 0;
  const TriangleFrame tri(a, b, c);
  const Vec3 axis = p1 - p0;
  const Real length = axis.norm();
  const Vec3 mid = (p0 + p1) / 2;
  const auto general = [&] {
    const auto support = [&](const Vec3& d) { return support_cylinder(p0, p1, radius, d); };
    const int n = contact_convex_triangle({support, mid}, a, b, c, options, out);
    return n;
  };
  const Real size = std::max({tri.size, length, 2 * radius, std::max(options.margin, Real(0))});
  if (tri.degenerate || !(length > kTiny * size)) return general();
  const bool one_sided = tri.one_sided(options);
  const Vec3 w = axis / length;
  const Real half = length / 2;
  const Real margin = std::max(options.margin, Real(0));
  const Real limit = -margin - tolerance(size, std::max({tri.coord, max_abs(p0), max_abs(p1)}));
  Real pushed_depth = 0;
  Vec3 pushed_point = Vec3::Zero();
  if (one_sided && tri.signed_distance(mid) < 0) {
    // Behind a one-sided triangle: pushed out through the front by the least lift that clears the
    // triangle, the depth of the cylinder's deepest point over it; seen only if it really meets
    // the triangle (points over it on both sides of the plane).
    const PrismDepths depths =
        cylinder_depths_in_prism(p0, w, length, radius, tri, tolerance(size, std::max(tri.coord, max_abs(mid))));
    if (!depths.any || !(depths.deepest > 0) || depths.shallowest > 0) return 0;
    pushed_depth = depths.deepest;
    pushed_point = depths.deepest_point;
  }

  // Writes the first contact and, when the normal is the triangle's face, the patch.
  const auto finish = [&](const Vec3& normal, Real depth, const ContactPoint& first) {
    out[0] = first;
    if (std::abs(normal.dot(tri.normal)) < 1 - 1e-9) return 1;

    // The triangle's face is the normal: a patch, so that a cylinder lying on its side or standing on
    // a disk rests on several points. Candidates: the two ends of the lowest line of the side (as
    // the capsule's ends) and four points of the lower disk's rim, a quarter turn apart from its
    // lowest one; those over the triangle, at their own depths along the normal.
    const Real plane = normal.dot(tri.v[0]);
    const Real along = normal.dot(w);
    Vec3 down = -(normal - along * w);  // radial direction of the lowest line
    const Real down_length = down.norm();
    if (down_length > 1e-9) {
      down /= down_length;
    } else {
      Vec3 unused;
      detail::orthonormal_completion(w, down, unused);
    }
    const Vec3 side = w.cross(down);
    const Vec3 low_end = along >= 0 ? p0 : p1;  // centre of the lower disk
    const Vec3 high_end = along >= 0 ? p1 : p0;
    Vec3 walls[3];
    for (int i = 0; i < 3; ++i) walls[i] = inward_wall(tri, i);
    const Real slack = tolerance(size, tri.coord) * size;
    std::array<ContactPoint, 8> patch;
    int count = 0;
    patch[count++] = out[0];
    const auto add = [&](const Vec3& x) {
      for (int i = 0; i < 3; ++i) {
        if (walls[i].dot(x - tri.v[i]) < -slack) return;
      }
      const Real d = plane - normal.dot(x);
      if (d >= -margin && d <= depth) patch[count++] = make_contact(x + d * normal, normal, d);
    };
    add(low_end + radius * down);
    add(high_end + radius * down);
    if (radius > 0) {
      add(low_end + radius * side);
      add(low_end - radius * side);
      add(low_end - radius * down);
    }
    count = reduce_in_place(patch.data(), count, kMaxCylinderTriangleContacts, 1e-7 * size);
    std::copy(patch.begin(), patch.begin() + count, out);
    return count;
  };
  if (pushed_depth > 0) {
    return finish(tri.normal, pushed_depth,
                  make_contact(pushed_point + pushed_depth * tri.normal, tri.normal, pushed_depth));
  }

  // The cylinder's lowest point along unit u is mid - half*sign(u.w)*w - radius*(radial part of u),
  // so the overlap is the corners' reach along u beyond mid plus the cylinder's half extent along u.
  const Vec3 corner[3] = {tri.v[0] - mid, tri.v[1] - mid, tri.v[2] - mid};
  const auto overlap_along = [&](const Vec3& u) {
    const Real along = u.dot(w);
    const Real top = std::max({u.dot(corner[0]), u.dot(corner[1]), u.dot(corner[2])});
    return top + half * std::abs(along) + radius * std::sqrt(std::max(Real(0), 1 - along * along));
  };

  // The two least candidates are polished (the least is not always in the deepest basin).
  Real values[2] = {kInf, kInf};
  Vec3 normals[2] = {tri.normal, tri.normal};
  bool apart = false;
  const auto consider = [&](const Vec3& direction) {
    const Real len = direction.norm();
    if (!(len > 0)) return;
    const Vec3 u = direction / len;
    const Real value = overlap_along(u);
    if (value < limit) apart = true;
    if (one_sided && u.dot(tri.normal) < -kBehind) return;  // separates, but is not a normal here
    if (value < values[0]) {
      values[1] = values[0];
      normals[1] = normals[0];
      values[0] = value;
      normals[0] = u;
    } else if (value < values[1]) {
      values[1] = value;
      normals[1] = u;
    }
  };
  consider(tri.normal);
  consider(-tri.normal);
  consider(w);
  consider(-w);
  consider(mid - closest_point_on_triangle(mid, a, b, c));
  if (apart) return 0;  // most candidates of the query box are apart along one of these already
  for (int j = 0; j < 3; ++j) {
    const Vec3 e = tri.v[(j + 1) % 3] - tri.v[j];
    const Vec3 u = w.cross(e);
    if (u.norm() > 1e-6 * e.norm()) {
      consider(u);
      consider(-u);
    }
    const Vec3 d = mid - tri.v[j];
    consider(d - d.dot(w) * w);
    consider(e.cross(tri.normal));  // the edge's outward normal in the plane (deep overlaps)
  }
  if (apart) return 0;
  // The least candidate is often the answer already: a flat face of the Minkowski difference
  // (the triangle's face under a rim point, a disk over a corner, the side over a corner or along
  // an edge), where no move of the pattern search at its smallest step lowers the overlap. That
  // probe (one round of moves) settles ~70% of the contacts of resting cylinders.
  const Real noise = 64 * kEps * (std::max({tri.coord, max_abs(p0), max_abs(p1)}) + size);
  Vec3 ridges[4] = {w};
  for (int j = 0; j < 3; ++j) ridges[1 + j] = (tri.v[(j + 1) % 3] - tri.v[j]).normalized();
  const Vec3 front = one_sided ? tri.normal : Vec3::Zero();
  Real best = values[0];
  Vec3 best_normal = normals[0];
  const bool flat =
      polish_normal(overlap_along, front, best_normal, best, 1e-2, 1e-6, 1, ridges, 4, noise, true, limit);
  // Else the minimum is on a curved face: a disk's rim against an edge (the faces of the Minkowski
  // difference swept by an edge and a rim point have normals across the edge, on the great circle
  // u . e = 0). Along that circle the triangle's support is the edge on the side of its outward
  // normal m, and the overlap is a smooth 1D function but for kinks where the lowest point of the
  // cylinder jumps: scanned, then golden-section search around the least sample (~1e-6 rad, so
  // the depth is within ~1e-11 of the sizes on smooth minima). The least of the circles and the
  // candidates is then polished (probed first, as above). A flat minimum can be a shallower
  // basin than a rim on an edge too: the scans are done for it as well, and refined only where
  // a sample is below it.
  if (!flat && values[1] < best) {
    best = values[1];
    best_normal = normals[1];
  }
  // The circle from n (x = 0) through m (x = 1) to -n (x = 2), without trigonometry; one-sided
  // triangles only need u . n >= 0 (x <= 1). Scanned denser near n (x ~ i^2): resting contacts
  // have normals close to the face's.
  const auto on_circle = [&](const Vec3& m, Real x) {
    const Vec3 u = x <= 1 ? Vec3((1 - x) * tri.normal + x * m) : Vec3((2 - x) * m - (x - 1) * tri.normal);
    return Vec3(u / u.norm());
  };
  const Real reach = one_sided ? 1 : 2;
  constexpr int kScan = 10;
  const auto scan_at = [&](int i) { return reach * Real(i * i) / Real(kScan * kScan); };
  // A circle that cannot hold an overlap below the best so far is not scanned (one-sided: u
  // between n and m). With x0 the cylinder's lowest point along n, d0 its depth below the plane
  // and dj its distance inside edge j's line, the overlap along u = cos(f) n + sin(f) m is at
  // least u . (v_j - x0) = d0 cos(f) + dj sin(f), which over f in [0, pi/2] is least at an end,
  // min(d0, dj), unless both are negative (then -hypot(d0, dj) bounds it). Resting
  // cylinders are shallow and mostly away from the edges: on ODE's drop scene this skips most
  // circles of the flat contacts (the scans were 33 of their ~60 overlap evaluations).
  const Vec3 lowest = support_cylinder(p0, p1, radius, -tri.normal);
  const Real lowest_depth = tri.normal.dot(tri.v[0] - lowest);
  Vec3 circle_m[3];
  int circle_least[3];
  Real circle_value[3];
  bool circle_skipped[3] = {false, false, false};
  for (int j = 0; j < 3; ++j) {
    const Vec3 m = (tri.v[(j + 1) % 3] - tri.v[j]).cross(tri.normal).normalized();
    circle_m[j] = m;
    circle_value[j] = kInf;
    circle_least[j] = 0;
    const Real inside = m.dot(tri.v[j] - lowest);
    const Real bound =
        lowest_depth < 0 && inside < 0 ? -std::hypot(lowest_depth, inside) : std::min(lowest_depth, inside);
    if (one_sided && bound >= best - noise) {
      circle_skipped[j] = true;
      continue;
    }
    for (int i = 0; i <= kScan; ++i) {
      const Real value = overlap_along(on_circle(m, scan_at(i)));
      if (value < circle_value[j]) {
        circle_value[j] = value;
        circle_least[j] = i;
      }
    }
  }
  bool refined = false;
  for (int j = 0; j < 3 && !(best < limit); ++j) {
    if (circle_skipped[j] || (flat && !(circle_value[j] < best - noise))) continue;
    refined = true;
    const Vec3& m = circle_m[j];
    const auto consider_at = [&](Real x) {
      const Vec3 u = on_circle(m, x);
      const Real value = overlap_along(u);
      if (value < best) {
        best = value;
        best_normal = u;
      }
      return value;
    };
    Real lo = scan_at(std::max(circle_least[j] - 1, 0));
    Real hi = scan_at(std::min(circle_least[j] + 1, kScan));
    constexpr Real kGolden = 0.38196601125010515;  // (3 - sqrt 5) / 2
    Real x1 = lo + kGolden * (hi - lo);
    Real x2 = hi - kGolden * (hi - lo);
    Real f1 = consider_at(x1);
    Real f2 = consider_at(x2);
    for (int iteration = 0; iteration < 24; ++iteration) {
      if (f1 < f2) {
        hi = x2;
        x2 = x1;
        f2 = f1;
        x1 = lo + kGolden * (hi - lo);
        f1 = consider_at(x1);
      } else {
        lo = x1;
        x1 = x2;
        f1 = f2;
        x2 = hi - kGolden * (hi - lo);
        f2 = consider_at(x2);
      }
    }
  }
  if ((refined || !flat) && !(best < limit)) {
    polish_normal(overlap_along, front, best_normal, best, 1e-2, 1e-6, 150, ridges, 4, noise, true, limit);
  }
  if (!(best >= -margin)) return 0;
  if (one_sided && best_normal.dot(tri.normal) < -kBehind) return general();
  return finish(
      best_normal, best,
      make_contact(
          landing_position(tri, best_normal, support_cylinder(p0, p1, radius, -best_normal) + best * best_normal, size),
          best_normal, best));
}

// ---------------------------------------------------------------------------------------------

ReductionCounts reduce_contacts(std::vector<ContactPoint>& contacts, std::size_t max_count, Real merge_distance) {
  // More than 64 contacts: the area-greedy selection looks at the deepest 64 (after merging).
  const int limit = static_cast<int>(std::clamp<std::size_t>(max_count, 1, 1 << 20));
  const std::size_t before = contacts.size();
  int merged = 0;
  contacts.resize(
      std::size_t(reduce_in_place(contacts.data(), static_cast<int>(contacts.size()), limit, merge_distance, &merged)));
  ReductionCounts counts;
  counts.merged = std::size_t(merged);
  counts.dropped = before - std::size_t(merged) - contacts.size();
  return counts;
}

}  // namespace boxtree
