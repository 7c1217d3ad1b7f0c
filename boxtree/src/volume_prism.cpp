// SPDX-License-Identifier: MIT
// Pie slices (right triangular prisms) as node volumes (volume/pie_slice.h; paper, Section 3.3):
// geometry, queries, fits. Conventions as in volume_obb.cpp: closed sets, conservative by a few
// hundred ulps of the magnitudes involved, invalid query shapes overlap nothing.
//
// Most tests describe the prism by supporting planes ("slabs"), each computed from the prism's
// own corners so that it holds for the stored prism even where its axis is not exactly normal
// to its base (rounding, or a leaf of a needle-shaped facet whose normal is ill-conditioned):
//   0     the axial slab, a . (x - o) between the corners' extremes;
//   1..3  the side planes through each base edge and the axis, oriented away from the opposite
//         corner, bounded on one side only;
//   4, 5  slabs along u (the base's longest edge) and v = axis x u, the corners' extremes.
// 1..3 alone bound a proper triangle; 4 and 5 close the degenerate ones (a segment base gives
// a strip from 1..3 that needs end caps; a point base gives no side planes at all).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "boxtree/detail/fit.h"
#include "boxtree/error.h"
#include "boxtree/geometry.h"
#include "boxtree/volume/pie_slice.h"
#include "internal.h"

namespace boxtree {

namespace {

constexpr Real kEpsilon = std::numeric_limits<Real>::epsilon();
constexpr Real kInf = std::numeric_limits<Real>::infinity();
// Slack of the slab tests, relative to |n|_1 * (|p - o|_inf + reach): covers the rounding of the
// plane normals (a cross product), of the corners, and of each projection.
constexpr Real kSlabSlack = 64 * kEpsilon;
constexpr Real kShapeSlack = 256 * kEpsilon;
constexpr Real kRayPad = 4 * kEpsilon;
// Margin of a parent around its children's corners, relative to their spread and to the
// coordinates' magnitude (see prism_enclosing).
constexpr Real kParentPad = 512 * kEpsilon;
constexpr Real kCornerPad = 8 * kEpsilon;

struct PrismSlabs {
  Vec3 origin;  // base[0]
  std::array<Vec3, 6> normal;
  std::array<Real, 6> lo;
  std::array<Real, 6> hi;
  Real reach = 0;  // max |corner - origin|_inf
};

int longest_edge_index(const Prism& prism) {
  int longest = 0;
  Real best = -1;
  for (int i = 0; i < 3; ++i) {
    const Real len = (prism.base[(i + 1) % 3] - prism.base[i]).squaredNorm();
    if (len > best) {
      best = len;
      longest = i;
    }
  }
  return longest;
}

// Unit in-plane directions: u along the longest base edge (any direction normal to the axis if
// the base is a point), v = axis x u.
void in_plane_frame(const Prism& prism, Vec3& u, Vec3& v) {
  const int longest = longest_edge_index(prism);
  const Vec3 edge = prism.base[(longest + 1) % 3] - prism.base[longest];
  // Remove the axial part so that u is normal to the axis even for a slightly tilted base.
  const Vec3 flat = edge - prism.axis.dot(edge) * prism.axis;
  const Real len = flat.norm();
  if (len > 0 && std::isfinite(len)) {
    u = flat / len;
    v = prism.axis.cross(u);
  } else {
    detail::orthonormal_completion(prism.axis, u, v);
  }
}

PrismSlabs slabs_of(const Prism& prism) {
  PrismSlabs s;
  s.origin = prism.base[0];
  const std::array<Vec3, 6> c = corners(prism);
  std::array<Vec3, 6> rel;
  for (int k = 0; k < 6; ++k) {
    rel[k] = c[k] - s.origin;
    s.reach = std::max(s.reach, rel[k].cwiseAbs().maxCoeff());
  }
  const auto extremes = [&](int slab) {
    Real lo = kInf, hi = -kInf;
    for (const Vec3& r : rel) {
      const Real x = s.normal[slab].dot(r);
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    s.lo[slab] = lo;
    s.hi[slab] = hi;
  };
  s.normal[0] = prism.axis;
  extremes(0);
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const int opposite = (i + 2) % 3;
    Vec3 n = (prism.base[j] - prism.base[i]).cross(prism.axis);
    if (n.dot(rel[opposite] - rel[i]) > 0) n = -n;
    s.normal[1 + i] = n;
    s.lo[1 + i] = -kInf;
    s.hi[1 + i] = std::max(n.dot(rel[i]), n.dot(rel[j]));
  }
  in_plane_frame(prism, s.normal[4], s.normal[5]);
  extremes(4);
  extremes(5);
  return s;
}

// Is p within the slabs, each widened by `tolerance` (a distance along its normal) plus slack?
bool inside_slabs(const PrismSlabs& s, const Vec3& p, Real tolerance) {
  const Vec3 rel = p - s.origin;
  const Real scale = rel.cwiseAbs().maxCoeff() + s.reach;
  for (int k = 0; k < 6; ++k) {
    const Vec3& n = s.normal[k];
    const Real x = n.dot(rel);
    const Real norm = k >= 1 && k <= 3 ? n.norm() : Real(1);
    const Real widen = tolerance * norm + kSlabSlack * n.cwiseAbs().sum() * scale;
    if (!(x >= s.lo[k] - widen && x <= s.hi[k] + widen)) return false;
  }
  return true;
}

// closest_point_on_triangle treats a needle (|n|^2 <= 1e-16 L^4) as its edges, which may
// overstate a distance by up to the needle's width |n| / L: the slack that keeps distance-based
// tests conservative on it.
Real needle_slack(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Real longest = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  const Real normal = (b - a).cross(c - a).squaredNorm();
  if (!(longest > 0) || normal > Real(1e-16) * longest * longest) return 0;
  return std::sqrt(normal / longest);
}

// The three-dimensional base corners of the planar triangle t (coordinates in the basis u, v
// about `origin`), at height w along the axis a.
std::array<Vec3, 3> lift(const detail::Triangle2& t, const Vec3& origin, const Vec3& u, const Vec3& v, const Vec3& a,
                         Real w) {
  std::array<Vec3, 3> base;
  for (int i = 0; i < 3; ++i) base[i] = origin + u * t.corners[i].x() + v * t.corners[i].y() + a * w;
  return base;
}

// The triangle with every side moved outward by d (Minkowski-like offset of its sides): each
// corner moves by d (n1 + n2) / (1 + n1 . n2) for the unit outward normals n1, n2 of its two
// sides. False if the triangle is degenerate or has an angle under ~0.1 degree (the offset
// corner would run off by d / sin(angle / 2)); the caller then uses a thin triangle instead.
bool offset(const detail::Triangle2& t, Real d, detail::Triangle2& out) {
  const Vec2 e1 = t.corners[1] - t.corners[0];
  const Vec2 e2 = t.corners[2] - t.corners[0];
  const Real orientation = e1.x() * e2.y() - e1.y() * e2.x();
  if (!(orientation != 0)) return false;
  std::array<Vec2, 3> normal;
  for (int i = 0; i < 3; ++i) {
    const Vec2 e = t.corners[(i + 1) % 3] - t.corners[i];
    const Real length = e.norm();
    if (!(length > 0)) return false;
    normal[i] = (orientation > 0 ? Vec2(e.y(), -e.x()) : Vec2(-e.y(), e.x())) / length;
  }
  for (int i = 0; i < 3; ++i) {
    const Vec2& n1 = normal[(i + 2) % 3];  // the side ending at corner i
    const Vec2& n2 = normal[i];            // the side starting there
    const Real c = 1 + n1.dot(n2);
    if (!(c > 1e-6)) return false;
    out.corners[i] = t.corners[i] + (n1 + n2) * (d / c);
  }
  return true;
}

// A thin right triangle around the points' bounding rectangle in the frame (u, perp(u)), grown by
// d: legs 2W and 2H around a W x H rectangle. For (nearly) collinear points along u it is as
// thin as they are.
detail::Triangle2 thin_triangle(const std::vector<Vec2>& points, const Vec2& u, Real d) {
  const Vec2 v(-u.y(), u.x());
  Real a0 = kInf, a1 = -kInf, b0 = kInf, b1 = -kInf;
  for (const Vec2& q : points) {
    a0 = std::min(a0, u.dot(q));
    a1 = std::max(a1, u.dot(q));
    b0 = std::min(b0, v.dot(q));
    b1 = std::max(b1, v.dot(q));
  }
  const Real w = a1 - a0 + 2 * d;
  const Real h = b1 - b0 + 2 * d;
  const Vec2 origin = u * (a0 - d) + v * (b0 - d);
  detail::Triangle2 t;
  t.corners = {origin, Vec2(origin + 2 * w * u), Vec2(origin + 2 * h * v)};
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Geometry

std::array<Vec3, 6> corners(const Prism& prism) {
  const Vec3 up = prism.axis * prism.height;
  return {prism.base[0], prism.base[1], prism.base[2], prism.base[0] + up, prism.base[1] + up, prism.base[2] + up};
}

ConvexPolytope polytope_of(const Prism& prism) {
  ConvexPolytope p;
  const auto c = corners(prism);
  std::copy(c.begin(), c.end(), p.vertices.begin());
  p.vertex_count = 6;
  for (int i = 0; i < 3; ++i) p.edge_directions[i] = prism.base[(i + 1) % 3] - prism.base[i];
  p.edge_directions[3] = prism.height > 0 ? prism.axis : Vec3::Zero();
  p.edge_count = 4;
  // Face normals: the axis, the three sides, and the cap along the longest base edge. The cap is
  // no face of a proper prism but is one of a prism on a segment (a rectangle's end); with it,
  // every edge has face normals spanning the plane normal to it, which keeps the separating-axis
  // test exact for flat and degenerate prisms (polytope.cpp). A point base has no sides: the
  // faces are then the axis and two directions normal to it.
  p.face_normals[0] = prism.axis;
  Vec3 u, v;
  in_plane_frame(prism, u, v);
  const bool point_base = !(p.edge_directions[0].squaredNorm() > 0 || p.edge_directions[1].squaredNorm() > 0 ||
                            p.edge_directions[2].squaredNorm() > 0);
  if (point_base) {
    p.face_normals[1] = u;
    p.face_normals[2] = v;
    p.face_count = 3;
  } else {
    for (int i = 0; i < 3; ++i) p.face_normals[1 + i] = p.edge_directions[i].cross(prism.axis);
    p.face_normals[4] = u;
    p.face_count = 5;
  }
  return p;
}

namespace {
Real base_area(const Prism& prism) {
  return Real(0.5) * (prism.base[1] - prism.base[0]).cross(prism.base[2] - prism.base[0]).norm();
}
Real base_perimeter(const Prism& prism) {
  return (prism.base[1] - prism.base[0]).norm() + (prism.base[2] - prism.base[1]).norm() +
         (prism.base[0] - prism.base[2]).norm();
}
}  // namespace

Real surface_area(const Prism& prism) { return 2 * base_area(prism) + base_perimeter(prism) * prism.height; }

Real volume(const Prism& prism) { return base_area(prism) * prism.height; }

Real mean_width(const Prism& prism) { return prism.height / 2 + base_perimeter(prism) / 4; }

Vec3 center(const Prism& prism) {
  return (prism.base[0] + prism.base[1] + prism.base[2]) / 3 + prism.axis * (prism.height / 2);
}

Aabb bounding_aabb(const Prism& prism) {
  Aabb box;
  for (const Vec3& c : corners(prism)) box.expand(c);
  // Rounded outward so that it holds every point contains() accepts (up to ~250 ulps of the
  // reach beyond the prism's slabs) and the rounding of the corners: the upper levels of hybrid
  // trees are these boxes, and a point in a child must be in its parent.
  const Vec3 pad = 4 * kEpsilon * box.min.cwiseAbs().cwiseMax(box.max.cwiseAbs()) +
                   Vec3::Constant(512 * kEpsilon * (box.max - box.min).maxCoeff());
  box.min -= pad;
  box.max += pad;
  return box;
}

// ---------------------------------------------------------------------------------------------
// Queries

bool contains(const Prism& prism, const Vec3& p, Real tolerance) {
  // `tolerance` is a distance from each supporting plane (see the top of the file).
  return inside_slabs(slabs_of(prism), p, tolerance);
}

bool contains(const Prism& outer, const Prism& inner, Real tolerance) {
  const PrismSlabs s = slabs_of(outer);
  for (const Vec3& c : corners(inner)) {
    if (!inside_slabs(s, c, tolerance)) return false;
  }
  return true;
}

bool overlaps(const Prism& prism, const Aabb& query) {
  if (!is_valid(query)) return false;
  // Infinite sides (half-spaces, shapes.h) clipped to the prism's bounds, which hold the prism:
  // the same answer, in finite arithmetic.
  Aabb clipped = query;
  if ((!query.min.allFinite() || !query.max.allFinite()) && !clip_infinite_sides(clipped, bounding_aabb(prism)))
    return false;
  return sat_overlap(polytope_of(prism), polytope_of(clipped));
}

bool overlaps(const Prism& prism, const Obb& query) {
  if (!is_valid(query)) return false;
  return sat_overlap(polytope_of(prism), polytope_of(query));
}

bool overlaps(const Prism& prism, const Sphere& query) {
  if (!is_valid(query)) return false;
  // With the axis normal to the base, the prism is the product of the triangle and [0, h] along
  // the axis, so the squared distance is the in-plane one plus the axial one: move the point
  // along the axis to the nearest height in [0, h] and take its distance to the base triangle.
  const Vec3& o = prism.base[0];
  const Real base_offset = (prism.axis.dot(prism.base[1] - o) + prism.axis.dot(prism.base[2] - o)) / 3;
  const Real s = prism.axis.dot(query.center - o) - base_offset;
  const Real raise = std::clamp(s, Real(0), std::max(prism.height, Real(0)));
  const Vec3 q = query.center - raise * prism.axis;
  const Vec3 closest = closest_point_on_triangle(q, prism.base[0], prism.base[1], prism.base[2]);
  const Real scale = (query.center - o).cwiseAbs().maxCoeff() + (prism.base[1] - o).cwiseAbs().maxCoeff() +
                     (prism.base[2] - o).cwiseAbs().maxCoeff() + prism.height + query.radius;
  const Real r = query.radius + kShapeSlack * scale + needle_slack(prism.base[0], prism.base[1], prism.base[2]);
  return (q - closest).squaredNorm() <= r * r;
}

bool overlaps(const Prism& prism, const Capsule& query) {
  if (!is_valid(query)) return false;
  const auto c = corners(prism);
  const PrismSlabs s = slabs_of(prism);
  const Real scale =
      (query.p0 - c[0]).cwiseAbs().maxCoeff() + (query.p1 - c[0]).cwiseAbs().maxCoeff() + s.reach + query.radius;
  const Real r = query.radius + kShapeSlack * scale;
  // Quick reject on bounding boxes.
  const Aabb box = bounding_aabb(prism);
  if ((query.p0.cwiseMin(query.p1).array() - r > box.max.array()).any() ||
      (query.p0.cwiseMax(query.p1).array() + r < box.min.array()).any()) {
    return false;
  }
  // Exact: the distance from a segment to a convex body is zero if an end is inside, else the
  // least distance to its boundary, here two triangles and three rectangles (two triangles each).
  if (inside_slabs(s, query.p0, 0)) return true;
  const int triangles[8][3] = {{0, 1, 2}, {3, 4, 5}, {0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}, {2, 0, 3}, {2, 3, 5}};
  const int count = prism.height > 0 ? 8 : 1;
  for (int k = 0; k < count; ++k) {
    const Vec3& a = c[triangles[k][0]];
    const Vec3& b = c[triangles[k][1]];
    const Vec3& d = c[triangles[k][2]];
    const Real rk = r + needle_slack(a, b, d);
    if (segment_triangle_distance_squared(query.p0, query.p1, a, b, d) <= rk * rk) return true;
  }
  return false;
}

bool overlaps(const Prism& prism, const Plane& plane) {
  if (!plane.normal.allFinite() || !std::isfinite(plane.offset)) return false;
  Real lo = kInf, hi = -kInf, magnitude = 0;
  for (const Vec3& c : corners(prism)) {
    const Real d = plane.signed_distance_scaled(c);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    magnitude = std::max(magnitude, c.cwiseAbs().maxCoeff());
  }
  const Real slack = kShapeSlack * (plane.normal.cwiseAbs().sum() * magnitude + std::abs(plane.offset));
  return lo <= slack && hi >= -slack;
}

bool overlaps(const Prism& a, const Prism& b, const RigidTransform& a_from_b) {
  return sat_overlap(polytope_of(a), polytope_of(b).transformed(a_from_b));
}

bool intersect_ray(const Prism& prism, const RayPrecomputed& ray, Real t_min, Real t_max, Real* t_enter) {
  // Cyrus-Beck clipping against the slabs (Cyrus & Beck, "Generalized two- and three-dimensional
  // clipping", Computers & Graphics 3(1), 1978). Each slab is widened by a margin m covering the
  // rounding of n . (o - origin) and of n . d over the only t that matter: a ray can touch the
  // prism only at t |d| <= |o - origin| + |reach|, so m = kSlabSlack |n|_1 (|o - origin|_inf +
  // reach) (with a factor sqrt(3) of margin for the norms). Then every t at which the exact ray
  // is in the prism satisfies the computed constraints, and kRayPad covers the divisions. A flat
  // or degenerate prism is a slab of width 2m, so rays in its plane or along it still touch it.
  if (!ray.origin.allFinite() || !ray.direction.allFinite()) return false;  // invalid rays hit nothing
  const PrismSlabs s = slabs_of(prism);
  const Vec3 rel = ray.origin - s.origin;
  const Real scale = rel.cwiseAbs().maxCoeff() + s.reach;
  Real t_near = t_min;
  Real t_far = t_max;
  for (int k = 0; k < 6; ++k) {
    const Vec3& n = s.normal[k];
    const Real margin = kSlabSlack * n.cwiseAbs().sum() * scale;
    const Real o = n.dot(rel);
    const Real d = n.dot(ray.direction);
    const Real lo = s.lo[k] - margin;
    const Real hi = s.hi[k] + margin;
    if (d == 0) {
      if (!(o >= lo && o <= hi)) return false;
      continue;
    }
    Real t0 = (lo - o) / d;
    Real t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    if (std::isfinite(t0)) t_near = std::max(t_near, t0 - std::abs(t0) * kRayPad);
    if (std::isfinite(t1)) t_far = std::min(t_far, t1 + std::abs(t1) * kRayPad);
    if (!(t_near <= t_far)) return false;
  }
  if (t_enter) *t_enter = t_near;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Fits

Prism prism_from_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Paper, Section 3.3: the facet itself, zero height. The axis is the facet's unit normal from
  // the Gram-Schmidt frame of volume_obb.cpp (accurate even for needles: the corners' axial
  // coordinates agree to rounding); a collinear facet gets a unit axis normal to it, a point any.
  Prism prism;
  prism.base = {a, b, c};
  prism.height = 0;
  Vec3 u, v, normal;
  detail::facet_frame(a, b, c, u, v, normal);
  prism.axis = normal;
  return prism;
}

Prism prism_enclosing(const Prism& x, const Prism& y, PrincipalAxis axis, TriangleRule rule) {
  // Paper, Section 3.3: the 12 corners of the children as one population.
  Vec3 points[12];
  const auto cx = corners(x);
  const auto cy = corners(y);
  std::copy(cx.begin(), cx.end(), points);
  std::copy(cy.begin(), cy.end(), points + 6);
  return *prism_enclosing_points(points, 12, axis, rule, 12);
}

std::optional<Prism> prism_enclosing_points(const Vec3* points, std::size_t count, PrincipalAxis axis,
                                            TriangleRule rule, std::size_t max_hull) {
  // The sweep axis is the points' max (or min) principal component; the points projected on the
  // plane normal to it get a minimum-area enclosing triangle (isosceles: the paper's rule;
  // general: O'Rourke et al.); the prism spans the points' extent along the axis.
  BOXTREE_ASSERT(count > 0, "prism_enclosing_points: no points");
  Vec3 centroid = Vec3::Zero();
  for (std::size_t k = 0; k < count; ++k) centroid += points[k];
  centroid /= Real(count);
  const Mat3 principal = detail::principal_axes(points, count);
  const int fixed = axis == PrincipalAxis::min ? 2 : 0;
  const Vec3 a = principal.col(fixed);
  const Vec3 u = principal.col(fixed == 0 ? 1 : 0);
  const Vec3 v = principal.col(fixed == 0 ? 2 : 1);
  std::vector<Vec2> planar(count);
  Real w_lo = kInf, w_hi = -kInf, spread = 0, magnitude = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 r = points[k] - centroid;
    planar[k] = Vec2(u.dot(r), v.dot(r));
    const Real w = a.dot(r);
    w_lo = std::min(w_lo, w);
    w_hi = std::max(w_hi, w);
    spread = std::max(spread, r.cwiseAbs().maxCoeff());
    magnitude = std::max(magnitude, points[k].cwiseAbs().maxCoeff());
  }
  // The triangle fits are cubic in the hull size (min_area_triangle): give up on large hulls.
  if (count > max_hull) {
    planar = detail::convex_hull_2d(std::move(planar));
    if (planar.size() > max_hull) return std::nullopt;
  }
  const detail::Triangle2 triangle =
      rule == TriangleRule::isosceles ? detail::min_area_isosceles_triangle(planar) : detail::min_area_triangle(planar);
  const auto build = [&](const detail::Triangle2& t, Real pad) {
    Prism p;
    p.base = lift(t, centroid, u, v, a, w_lo - pad);
    p.axis = a;
    p.height = (w_hi - w_lo) + 2 * pad;
    return p;
  };
  // Every corner of the children must be inside the parent by `margin` in every slab: the
  // children's corners are only within an ulp of the coordinates of the exact children, and
  // contains() accepts points up to kSlabSlack beyond a prism's slabs (at most ~250 ulps of the
  // spread for points near a child); a margin that covers both makes every point a child
  // contains also contained by its parent (what a stabbing query needs). The fits guarantee
  // containment in the plane; offsetting the triangle's sides and the axial range by the margin
  // (and re-checking, since lifting to 3D rounds again) gives the rest.
  const Real margin = kParentPad * spread + kCornerPad * magnitude;
  const auto encloses = [&](const Prism& p) {
    const PrismSlabs s = slabs_of(p);
    for (std::size_t k = 0; k < count; ++k) {
      if (!inside_slabs(s, points[k], -margin / 2)) return false;
    }
    return true;
  };
  // Offsets of 1, 2, 4, ... margins until the corners are inside; a thin triangle along the
  // fitted triangle's longest side where the offset is ill-conditioned (needle triangles).
  Prism best;
  bool done = false;
  for (int step = 0; step < 40 && !done; ++step) {
    const Real d = std::ldexp(margin, step);
    detail::Triangle2 grown;
    if (!offset(triangle, d, grown)) break;
    best = build(grown, d);
    done = encloses(best);
  }
  if (!done) {
    int longest = 0;
    for (int i = 1; i < 3; ++i) {
      if ((triangle.corners[(i + 1) % 3] - triangle.corners[i]).squaredNorm() >
          (triangle.corners[(longest + 1) % 3] - triangle.corners[longest]).squaredNorm()) {
        longest = i;
      }
    }
    const Vec2 side = triangle.corners[(longest + 1) % 3] - triangle.corners[longest];
    const Vec2 direction = side.norm() > 0 ? Vec2(side.normalized()) : Vec2::UnitX();
    for (int step = 0; step < 60 && !done; ++step) {
      const Real d = std::ldexp(margin, step) + (step > 0 ? std::ldexp(kEpsilon, step) * spread : 0);
      best = build(thin_triangle(planar, direction, d), d);
      done = encloses(best);
    }
  }
  BOXTREE_ASSERT(done, "prism_enclosing_points: could not enclose the points (non-finite input?)");
  return best;
}

}  // namespace boxtree
