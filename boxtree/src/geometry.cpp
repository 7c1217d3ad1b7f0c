// SPDX-License-Identifier: MIT
// Leaf tests between one triangle and a query shape (geometry.h), and the out-of-line overlap
// tests of volume/aabb.h.
//
// Conventions shared by everything below:
//  * Every test is closed: touching counts as overlapping.
//  * Predicates are signs of small polynomials in coordinate differences (orientation
//    determinants), never comparisons of divided quantities. The triangle/triangle and
//    segment/triangle tests (triangles_intersect, and the capsule test's "do they meet") take
//    those signs exactly (exact_sign.h), for any coordinates: facets sharing a corner or an edge
//    always meet. The box, sphere and capsule tests round (centres, half extents, distances):
//    they are exact whenever their polynomials are computed exactly, e.g. for small-integer or
//    dyadic coordinates, which is what the tests use to check their touching cases exactly.
//  * A triangle whose corners are on one line (exactly) is degenerate and is treated as the
//    segment or point it is (except by the ray test, which never hits it).
//  * No heap allocation and no exceptions: these run in the inner loops of every query.
#include "boxtree/geometry.h"

#include "exact_sign.h"
#include "internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Geometry>  // cross products

namespace boxtree {
namespace {

bool is_zero(const Vec3& v) { return v.x() == 0 && v.y() == 0 && v.z() == 0; }

using detail::orient2d_sign;
using detail::orient3d_sign;

bool mixed_signs(Real x, Real y, Real z) { return (x < 0 || y < 0 || z < 0) && (x > 0 || y > 0 || z > 0); }
bool mixed_signs(int x, int y, int z) { return (x < 0 || y < 0 || z < 0) && (x > 0 || y > 0 || z > 0); }

// The axis along which the triangle abc is seen with non-zero area (exactly), or -1 if its
// corners are on one line. A plane seen along that axis maps one-to-one onto the other two, so
// 2D tests there decide coplanar configurations.
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient2d_sign(a, b, c, drop) != 0) return drop;
  return -1;
}

// Closed 2D segment intersection seen along `drop`; a zero-length segment is fine (its two
// orientations are equal, so it is either rejected or falls into the collinear case).
bool segments_intersect_2d(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int drop) {
  const int o1 = orient2d_sign(p, q, r, drop), o2 = orient2d_sign(p, q, s, drop);
  if (o1 * o2 > 0) return false;
  const int o3 = orient2d_sign(r, s, p, drop), o4 = orient2d_sign(r, s, q, drop);
  if (o3 * o4 > 0) return false;
  if ((o1 == 0 && o2 == 0) || (o3 == 0 && o4 == 0)) {
    // All four points on one line: the segments meet iff their bounding boxes do (on the two
    // coordinates seen).
    for (const int k : {(drop + 1) % 3, (drop + 2) % 3}) {
      if (std::max(p[k], q[k]) < std::min(r[k], s[k]) || std::max(r[k], s[k]) < std::min(p[k], q[k])) return false;
    }
  }
  return true;
}

// Closed point-in-triangle seen along `drop`, for either winding. A triangle of zero seen area
// contains nothing here; callers also test its edges, which is where such a point would be.
bool point_in_triangle_2d(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  if (orient2d_sign(a, b, c, drop) == 0) return false;
  return !mixed_signs(orient2d_sign(a, b, x, drop), orient2d_sign(b, c, x, drop), orient2d_sign(c, a, x, drop));
}

bool segment_meets_triangle_2d(const Vec3& s, const Vec3& e, const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  return point_in_triangle_2d(s, a, b, c, drop) || point_in_triangle_2d(e, a, b, c, drop) ||
         segments_intersect_2d(s, e, a, b, drop) || segments_intersect_2d(s, e, b, c, drop) ||
         segments_intersect_2d(s, e, c, a, drop);
}

bool triangles_intersect_2d(const Vec3 (&p)[3], const Vec3 (&q)[3], int drop) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (segments_intersect_2d(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3], drop)) return true;
    }
  }
  // No boundary crossing: they meet only if one lies inside the other.
  return point_in_triangle_2d(p[0], q[0], q[1], q[2], drop) || point_in_triangle_2d(q[0], p[0], p[1], p[2], drop);
}

// Closed segment [s, e] (possibly a point) against the triangle (a, b, c), whose corners are not
// on one line (exactly). Orientation-only version of Ericson 5.3.4 (line vs triangle by scalar
// triple products), restricted to the segment by the signs of its ends w.r.t. the plane.
bool segment_meets_triangle(const Vec3& s, const Vec3& e, const Vec3& a, const Vec3& b, const Vec3& c) {
  // A meeting point lies in both bounding boxes, so disjoint boxes (compared exactly) mean no
  // meeting. Cheap, and the signs below need not be computed for most candidate pairs.
  const Vec3 tri_lo = a.cwiseMin(b).cwiseMin(c), tri_hi = a.cwiseMax(b).cwiseMax(c);
  if ((s.cwiseMax(e).array() < tri_lo.array()).any() || (s.cwiseMin(e).array() > tri_hi.array()).any()) return false;
  const int os = orient3d_sign(a, b, c, s);
  const int oe = orient3d_sign(a, b, c, e);
  if (os * oe > 0) return false;
  if (os == 0 && oe == 0) {
    const int drop = projection_axis(a, b, c);
    return drop >= 0 && segment_meets_triangle_2d(s, e, a, b, c, drop);
  }
  // The line crosses the plane at a single point, which lies on the segment. It is in the closed
  // triangle iff the line passes on the same side of (or through) all three directed edges.
  return !mixed_signs(orient3d_sign(s, e, a, b), orient3d_sign(s, e, b, c), orient3d_sign(s, e, c, a));
}

// Closed 3D segment intersection, either segment possibly a point. Segments in one plane meet iff
// they are seen to meet along all three axes: along one of them their plane is seen one-to-one.
bool segments_meet(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 lo = p0.cwiseMin(p1).cwiseMax(q0.cwiseMin(q1)), hi = p0.cwiseMax(p1).cwiseMin(q0.cwiseMax(q1));
  if ((lo.array() > hi.array()).any()) return false;
  if (orient3d_sign(p0, p1, q0, q1) != 0) return false;  // skew lines
  for (int drop = 0; drop < 3; ++drop)
    if (!segments_intersect_2d(p0, p1, q0, q1, drop)) return false;
  return true;
}

// True if the corners are on one line (exactly): the triangle is the segment between its
// extreme corners.
// projection_axis(a, b, c) < 0, with the axes in another order (z first: a terrain's facets are
// seen with area along it, so one sign decides instead of three).
bool is_flat(const Vec3& a, const Vec3& b, const Vec3& c) {
  return orient2d_sign(a, b, c, 2) == 0 && orient2d_sign(a, b, c, 0) == 0 && orient2d_sign(a, b, c, 1) == 0;
}

// The extreme corners of a degenerate (collinear) triangle: the least and greatest in
// lexicographic order, which on a line are its two ends. A point when all three coincide.
std::pair<Vec3, Vec3> degenerate_extent(const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto less = [](const Vec3& x, const Vec3& y) {
    return std::lexicographical_compare(x.data(), x.data() + 3, y.data(), y.data() + 3);
  };
  return {std::min({a, b, c}, less), std::max({a, b, c}, less)};
}

Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const Real len2 = ab.squaredNorm();
  if (!(len2 > 0)) return a;
  const Real t = std::clamp((p - a).dot(ab) / len2, Real(0), Real(1));
  return a + t * ab;
}

Real squared_distance_to_box(const Vec3& p, const Aabb& box) {
  return (p.cwiseMax(box.min).cwiseMin(box.max) - p).squaredNorm();
}

// Relative slack for tests that must never miss a true contact: a few hundred ulps of the
// magnitudes involved, far below any modelling tolerance and above the rounding of the
// computation it protects.
constexpr Real kContactSlack = 256 * std::numeric_limits<Real>::epsilon();

// Squared distance from the segment [p0, p1] to the closed box. The squared distance along the
// segment is a convex piecewise quadratic of t whose pieces change only where a coordinate crosses
// a box face, so the minimum is the best of the per-piece minimizers (exact up to rounding).
Real segment_box_squared_distance(const Vec3& p0, const Vec3& p1, const Aabb& box) {
  const Vec3 d = p1 - p0;
  Real breaks[8];
  int count = 0;
  breaks[count++] = 0;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) continue;
    for (const Real bound : {box.min[k], box.max[k]}) {
      const Real t = (bound - p0[k]) / d[k];
      if (t > 0 && t < 1) breaks[count++] = t;
    }
  }
  breaks[count++] = 1;
  for (int i = 1; i < count; ++i) {  // insertion sort of at most 8 values
    for (int j = i; j > 0 && breaks[j] < breaks[j - 1]; --j) std::swap(breaks[j], breaks[j - 1]);
  }
  Real best = std::numeric_limits<Real>::infinity();
  for (int piece = 0; piece + 1 < count; ++piece) {
    const Real t0 = breaks[piece];
    const Real t1 = breaks[piece + 1];
    const Real mid = Real(0.5) * (t0 + t1);
    // On this piece each coordinate is below, inside or above the box: minimize the sum of the
    // squared excesses of the outside ones, a quadratic in t.
    Real num = 0;
    Real den = 0;
    for (int k = 0; k < 3; ++k) {
      const Real x = p0[k] + mid * d[k];
      const Real bound = x < box.min[k] ? box.min[k] : (x > box.max[k] ? box.max[k] : x);
      if (bound == x) continue;
      num -= d[k] * (p0[k] - bound);
      den += d[k] * d[k];
    }
    const Real t = den > 0 ? std::clamp(num / den, t0, t1) : t0;
    best = std::min(best, squared_distance_to_box(p0 + t * d, box));
    if (best == 0) break;
  }
  return best;
}

// Watertight ray/triangle (Woop, Benthin, Wald, JCGT 2013): the edge function of the directed
// edge p -> q in the sheared 2D frame, U = qx*py - qy*px for the edge opposite a (the paper's
// Fig. 5). Two triangles sharing an edge must get exactly opposite values, so the products are
// always formed in one canonical operand order; that keeps the property even if the compiler
// contracts them into a fused multiply-add.
Real edge_function(Real px, Real py, Real qx, Real qy) {
  const bool p_first = px < qx || (px == qx && py < qy);
  const Real fx = p_first ? px : qx;
  const Real fy = p_first ? py : qy;
  const Real sx = p_first ? qx : px;
  const Real sy = p_first ? qy : py;
  const Real m1 = fx * sy;
  const Real m2 = fy * sx;
  Real det = m1 - m2;  // fx*sy - fy*sx
  if (det == 0) {
    // The paper redoes a zero result in higher precision to get the true sign (Sec. 3.3). For
    // doubles, long double is no help (x87 has 64 mantissa bits, a product needs 106; elsewhere
    // it is just double), so take the exact route: here m1 == m2, hence the true value is the
    // difference of the two rounding errors, each exact by FMA (Ogita, Rump, Oishi 2005, TwoProduct),
    // and its rounded difference has the true sign. Rare, so the software FMA cost is irrelevant.
    det = std::fma(fx, sy, -m1) - std::fma(fy, sx, -m2);
  }
  return p_first ? -det : det;
}

}  // namespace

// Separating-axis test of an axis-aligned box (half extents ha, at the origin) against a box with
// center t, axes r.col(j) and half extents hb, all in the first box's frame (Gottschalk, Lin,
// Manocha, "OBBTree", SIGGRAPH 1996, Sec. 4; Ericson 4.4.1). 15 axes: 3 + 3 face normals and the
// 9 edge cross products; enough for flat boxes too (a rectangle's or a segment's candidate axes
// are among them).
bool detail::boxes_overlap(const Vec3& ha, const Vec3& t, const Mat3& r, const Vec3& hb) {
  // Gottschalk's epsilon on |R|: when two edges are (nearly) parallel their cross product is
  // (nearly) zero and rounding noise in R alone could decide the test. Padding the radii by
  // kEps * (box sizes), plus kEps * |t| for the rounding of the projected center distance, keeps
  // the test conservative: it may report boxes that are apart by ~1e-12 of their sizes and
  // distance as overlapping, never the reverse. The |t| term is what covers boxes that are flat
  // in two axes (segments), whose padded radii can be zero.
  constexpr Real kEps = 1e-12;
  const Real slack = kEps * t.cwiseAbs().sum();
  Mat3 abs_r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) abs_r(i, j) = std::abs(r(i, j)) + kEps;
  }
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(t[i]) <= ha[i] + hb.dot(abs_r.row(i)) + slack)) return false;
  }
  for (int j = 0; j < 3; ++j) {
    if (!(std::abs(t.dot(r.col(j))) <= ha.dot(abs_r.col(j)) + hb[j] + slack)) return false;
  }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3;
    const int i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      const int j2 = (j + 2) % 3;
      // L = A_i x B_j has components L[i1] = -r(i2, j), L[i2] = r(i1, j) in A's frame; B_m . L
      // is +-r(i, third index) because B's axes are orthonormal.
      const Real distance = std::abs(t[i2] * r(i1, j) - t[i1] * r(i2, j));
      const Real ra = ha[i1] * abs_r(i2, j) + ha[i2] * abs_r(i1, j);
      const Real rb = hb[j1] * abs_r(i, j2) + hb[j2] * abs_r(i, j1);
      if (!(distance <= ra + rb + slack)) return false;
    }
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Ray / triangle

RayShear ray_shear(const Vec3& dir) {
  // Sec. 3.1: the dominant direction axis becomes z; swapping x and y for a negative z keeps the
  // winding (only a culling test would care, but it costs nothing).
  RayShear s;
  const Vec3 abs_dir = dir.cwiseAbs();
  s.kz = abs_dir.x() >= abs_dir.y() ? (abs_dir.x() >= abs_dir.z() ? 0 : 2) : (abs_dir.y() >= abs_dir.z() ? 1 : 2);
  if (!(abs_dir[s.kz] > 0)) return s;  // zero or NaN direction
  s.kx = (s.kz + 1) % 3;
  s.ky = (s.kx + 1) % 3;
  if (dir[s.kz] < 0) std::swap(s.kx, s.ky);
  s.shear_x = dir[s.kx] / dir[s.kz];
  s.shear_y = dir[s.ky] / dir[s.kz];
  s.shear_z = 1 / dir[s.kz];
  s.valid = true;
  return s;
}

bool intersect_ray_triangle(const Ray& ray, const Vec3& a, const Vec3& b, const Vec3& c, TriangleHit& hit) {
  return intersect_ray_triangle(ray, ray_shear(ray.direction), a, b, c, hit);
}

bool intersect_ray_triangle(const Ray& ray, const RayShear& shear, const Vec3& a, const Vec3& b, const Vec3& c,
                            TriangleHit& hit) {
  if (!shear.valid) return false;
  const int kx = shear.kx, ky = shear.ky, kz = shear.kz;
  const Real shear_x = shear.shear_x, shear_y = shear.shear_y, shear_z = shear.shear_z;

  // Vertices relative to the origin, sheared so that the ray becomes the +z axis. Each vertex is
  // transformed by the same expression regardless of the triangle, so shared vertices agree.
  const Vec3 pa = a - ray.origin;
  const Vec3 pb = b - ray.origin;
  const Vec3 pc = c - ray.origin;
  const Real ax = pa[kx] - shear_x * pa[kz];
  const Real ay = pa[ky] - shear_y * pa[kz];
  const Real bx = pb[kx] - shear_x * pb[kz];
  const Real by = pb[ky] - shear_y * pb[kz];
  const Real cx = pc[kx] - shear_x * pc[kz];
  const Real cy = pc[ky] - shear_y * pc[kz];

  // Scaled barycentrics: u_a, u_b, u_c weight the corners a, b, c.
  const Real u_a = edge_function(bx, by, cx, cy);
  const Real u_b = edge_function(cx, cy, ax, ay);
  const Real u_c = edge_function(ax, ay, bx, by);
  // Two-sided and closed: reject only a mix of strictly positive and strictly negative.
  if (mixed_signs(u_a, u_b, u_c)) return false;
  const Real det = u_a + u_b + u_c;
  if (det == 0) return false;  // ray in the triangle's plane, or a degenerate projection

  const Real t_scaled = u_a * (shear_z * pa[kz]) + u_b * (shear_z * pb[kz]) + u_c * (shear_z * pc[kz]);
  const Real inv_det = 1 / det;
  const Real t = t_scaled * inv_det;
  if (!(t >= ray.t_min && t <= ray.t_max)) return false;  // also rejects NaN
  // Degenerate triangles are never hit. Tested last: rounding of the shear can give a collinear
  // triangle a tiny non-zero projected area, and the check is only needed for would-be hits.
  if (is_zero((b - a).cross(c - a))) return false;
  hit.t = t;
  hit.u = u_b * inv_det;
  hit.v = u_c * inv_det;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Triangle / triangle

namespace {

// triangles_intersect on exact signs throughout, for the pairs whose rounded signs cannot decide
// (touching, coplanar, degenerate, or within rounding of those); the bounding boxes are already
// known to meet.
bool triangles_intersect_exact(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                               const Vec3& b2) {
  // Guigue & Devillers, "Fast and Robust Triangle-Triangle Overlap Test Using Orientation
  // Predicates", JGT 8(1), 2003, on exact signs (exact_sign.h), so that touching and coplanar
  // pairs are decided right whatever the coordinates: a shared corner or edge of two facets of
  // one mesh is always found. First: sides of b's corners w.r.t. a's plane, which most candidate
  // pairs that pass the boxes end on (all on one side); degeneracy is decided exactly only where
  // the rounded normal cannot (certain_axis).
  const Vec3 a[3] = {a0, a1, a2};
  const Vec3 b[3] = {b0, b1, b2};
  const detail::PlaneSide plane_a(a0, a1, a2);
  const bool a_flat = plane_a.certain_axis() < 0 && is_flat(a0, a1, a2);
  int side_b[3] = {0, 0, 0};  // orient3d(a0, a1, a2, b_i)
  if (!a_flat) {
    for (int i = 0; i < 3; ++i) side_b[i] = plane_a(b[i]);
    if ((side_b[0] > 0 && side_b[1] > 0 && side_b[2] > 0) || (side_b[0] < 0 && side_b[1] < 0 && side_b[2] < 0)) {
      return false;
    }
  }
  const detail::PlaneSide plane_b(b0, b1, b2);
  const bool b_flat = plane_b.certain_axis() < 0 && is_flat(b0, b1, b2);
  if (a_flat || b_flat) {
    // A degenerate triangle is the segment (or point) between its extreme corners.
    if (a_flat && b_flat) {
      const auto [sa, ea] = degenerate_extent(a0, a1, a2);
      const auto [sb, eb] = degenerate_extent(b0, b1, b2);
      return segments_meet(sa, ea, sb, eb);
    }
    if (a_flat) {
      const auto [s, e] = degenerate_extent(a0, a1, a2);
      return segment_meets_triangle(s, e, b0, b1, b2);
    }
    const auto [s, e] = degenerate_extent(b0, b1, b2);
    return segment_meets_triangle(s, e, a0, a1, a2);
  }
  int side_a[3];                                             // orient3d(b0, b1, b2, a_i)
  if (side_b[0] == 0 && side_b[1] == 0 && side_b[2] == 0) {  // coplanar: seen along an axis that keeps a's area
    const int axis = plane_a.certain_axis();
    return triangles_intersect_2d(a, b, axis >= 0 ? axis : projection_axis(a0, a1, a2));
  }
  for (int i = 0; i < 3; ++i) side_a[i] = plane_b(a[i]);
  if ((side_a[0] > 0 && side_a[1] > 0 && side_a[2] > 0) || (side_a[0] < 0 && side_a[1] < 0 && side_a[2] < 0)) {
    return false;
  }

  // Each triangle now straddles or touches the other's plane. Pick in each a pivot corner that is
  // alone on its (closed) side, so that the two edges leaving it cut the other plane at the two
  // ends of the triangle's interval on the planes' common line. sign = the pivot's side.
  const auto pivot = [](const int(&side)[3], int& index, int& sign) {
    int positive = 0;
    int negative = 0;
    for (int i = 0; i < 3; ++i) {
      positive += side[i] > 0;
      negative += side[i] < 0;
    }
    for (int i = 0; i < 3; ++i) {
      if ((positive == 1 && side[i] > 0) || (positive != 1 && negative == 1 && side[i] < 0) ||
          (positive != 1 && negative != 1 && side[i] == 0)) {
        index = i;
        // A zero pivot (the other two strictly on one side) counts as being on the opposite side.
        sign = side[i] > 0 ? 1 : (side[i] < 0 ? -1 : (positive == 2 ? -1 : 1));
        return;
      }
    }
  };
  int ia = 0, sign_a = 1, ib = 0, sign_b = 1;
  pivot(side_a, ia, sign_a);
  pivot(side_b, ib, sign_b);
  // Rotate each triangle to start at its pivot (keeps its orientation), then flip the other
  // triangle's orientation where needed so that each pivot is on the positive side of the other
  // triangle's plane.
  Vec3 p[3] = {a[ia], a[(ia + 1) % 3], a[(ia + 2) % 3]};
  Vec3 q[3] = {b[ib], b[(ib + 1) % 3], b[(ib + 2) % 3]};
  if (sign_a < 0) std::swap(q[1], q[2]);
  if (sign_b < 0) std::swap(p[1], p[2]);
  // The intervals [p-edge (p0,p2), p-edge (p0,p1)] and [q-edge (q0,q1), q-edge (q0,q2)] are
  // ordered consistently along the common line; they overlap iff each starts before the other
  // ends, and each of those comparisons is one orientation sign (G&D, Sec. 3).
  return orient3d_sign(p[0], p[1], q[0], q[1]) <= 0 && orient3d_sign(p[0], p[2], q[2], q[0]) <= 0;
}

}  // namespace

namespace detail {

// The body of both triangles_intersect, inlined in both (gcc otherwise calls it from the one on
// six corners, which then costs more than before the triangles were prepared).
[[gnu::always_inline]] inline bool intersect_prepared(const PreparedTriangle& a, const PreparedTriangle& b) {
  // Disjoint bounding boxes (compared exactly) mean disjoint triangles: cheap, and most candidate
  // pairs of a tree walk end here.
  if ((a.hi_.array() < b.lo_.array()).any() || (b.hi_.array() < a.lo_.array()).any()) return false;
  // Guigue & Devillers (below) on rounded signs, each of which is used only where it is farther
  // from zero than a bound on its rounding error (exact_sign.h's first-stage bound, taken once per
  // plane over the other triangle's bounding box): then every sign is the exact one, none is zero
  // (no touching, coplanar or degenerate case), and the answer is triangles_intersect_exact's.
  // Any sign within its bound hands the pair to triangles_intersect_exact.
  // A degenerate triangle's rounded normal is within its bound, so its plane decides no side:
  // such pairs go to the exact test without a check of their own.
  const auto exact = [&] {
    return triangles_intersect_exact(*a.corner_[0], *a.corner_[1], *a.corner_[2], *b.corner_[0], *b.corner_[1],
                                     *b.corner_[2]);
  };
  // The sides of `other`'s corners w.r.t. the plane of `t`; false when a sign is not certain.
  const auto sides = [](const PreparedTriangle& t, const PreparedTriangle& other, int(&side)[3]) {
    const Vec3& origin = *t.corner_[0];
    // |d - a| per axis over the box of the points, times the normal's product magnitudes.
    const Vec3 reach = (other.hi_ - origin).cwiseAbs().cwiseMax((other.lo_ - origin).cwiseAbs());
    const Real bound = 1e-15 * reach.dot(t.magnitude_);
    for (int i = 0; i < 3; ++i) {
      const Real det = t.normal_.dot(*other.corner_[i] - origin);
      if (!(std::abs(det) > bound)) return false;
      side[i] = det > 0 ? 1 : -1;
    }
    return true;
  };
  int side_b[3];  // orient3d(a0, a1, a2, b_i)
  int side_a[3];  // orient3d(b0, b1, b2, a_i)
  if (!sides(a, b, side_b)) return exact();
  if (side_b[0] == side_b[1] && side_b[1] == side_b[2]) return false;
  if (!sides(b, a, side_a)) return exact();
  if (side_a[0] == side_a[1] && side_a[1] == side_a[2]) return false;
  // Each triangle straddles the other's plane: the pivot is the corner alone on its side.
  const auto pivot = [](const int(&side)[3]) { return side[0] == side[1] ? 2 : (side[0] == side[2] ? 1 : 0); };
  const int ia = pivot(side_a), ib = pivot(side_b);
  const Vec3* p[3] = {a.corner_[ia], a.corner_[(ia + 1) % 3], a.corner_[(ia + 2) % 3]};
  const Vec3* q[3] = {b.corner_[ib], b.corner_[(ib + 1) % 3], b.corner_[(ib + 2) % 3]};
  if (side_a[ia] < 0) std::swap(q[1], q[2]);
  if (side_b[ib] < 0) std::swap(p[1], p[2]);
  if (orient3d_sign(*p[0], *p[1], *q[0], *q[1]) > 0) return false;
  if (orient3d_sign(*p[0], *p[2], *q[2], *q[0]) > 0) return false;
  // A zero here is a touching end of the two intervals: decided exactly, as a meeting.
  return true;
}

bool triangles_intersect(const PreparedTriangle& a, const PreparedTriangle& b) { return intersect_prepared(a, b); }

}  // namespace detail

bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2) {
  const detail::PreparedTriangle a(a0, a1, a2), b(b0, b1, b2);
  return detail::intersect_prepared(a, b);
}

// ---------------------------------------------------------------------------------------------
// Triangle / volumes and shapes

namespace detail {

bool triangle_overlaps_box(const Vec3& a, const Vec3& b, const Vec3& c, const Aabb& box) {
  // Box face normals first, on the untranslated coordinates (no rounding at all).
  for (int k = 0; k < 3; ++k) {
    if (std::max({a[k], b[k], c[k]}) < box.min[k] || std::min({a[k], b[k], c[k]}) > box.max[k]) return false;
  }
  // A corner in the box decides exactly. The axes below are rounded (the centre, the half
  // extents), and a corner on the box's boundary could come out an ulp outside: every query with
  // an infinite side is clipped to a box that the triangle touches at its boundary.
  for (const Vec3* p : {&a, &b, &c})
    if ((p->array() >= box.min.array()).all() && (p->array() <= box.max.array()).all()) return true;
  const Vec3 center = box.center();
  const Vec3 h = (box.max - box.min) * Real(0.5);
  const Vec3 v[3] = {a - center, b - center, c - center};
  const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  // Nine axes edge x box axis k: components (k+1, k+2) are (e[k+2], -e[k+1]).
  for (int m = 0; m < 3; ++m) {
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3;
      const int j = (k + 2) % 3;
      const Real p0 = e[m][j] * v[0][i] - e[m][i] * v[0][j];
      const Real p1 = e[m][j] * v[1][i] - e[m][i] * v[1][j];
      const Real p2 = e[m][j] * v[2][i] - e[m][i] * v[2][j];
      const Real radius = h[i] * std::abs(e[m][j]) + h[j] * std::abs(e[m][i]);
      if (std::min({p0, p1, p2}) > radius || std::max({p0, p1, p2}) < -radius) return false;
    }
  }
  // Triangle normal. The paper projects one corner only, assuming n is perpendicular to the
  // triangle; for a nearly degenerate triangle the computed n is mostly rounding noise and is not,
  // so all three corners are projected: then n is a valid separating axis whatever its accuracy.
  const Vec3 n = e[0].cross(e[1]);
  const Real d0 = n.dot(v[0]);
  const Real d1 = n.dot(v[1]);
  const Real d2 = n.dot(v[2]);
  const Real radius = h.dot(n.cwiseAbs());
  return !(std::min({d0, d1, d2}) > radius || std::max({d0, d1, d2}) < -radius);
}

}  // namespace detail

bool triangle_overlaps_aabb(const Vec3& a, const Vec3& b, const Vec3& c, const Aabb& query) {
  // Akenine-Moller, "Fast 3D Triangle-Box Overlap Testing", JGT 6(1), 2001. A zero axis (a
  // degenerate triangle's normal, an edge parallel to a box axis or of zero length) projects
  // everything to 0 with radius 0 and so never separates: no special case is needed, and for a
  // degenerate triangle the remaining axes (box faces, edge x box axes) are exactly the
  // separating axes of a segment against a box (Ericson 5.3.3).
  // NaN anywhere (a NaN query box, or an oriented box with a NaN centre or axis, which reaches
  // here as NaN corners) would fail every separating comparison, i.e. "overlap".
  if (a.hasNaN() || b.hasNaN() || c.hasNaN() || query.min.hasNaN() || query.max.hasNaN()) return false;
  // An infinite side (a half-space query) would make the centre or the half extents below
  // infinite or NaN, and NaN never separates. The triangle lies in its own bounds, so the box
  // clipped to them overlaps it exactly when the box does, and is finite for a finite triangle.
  Aabb box = query;
  if ((!box.min.allFinite() || !box.max.allFinite()) && !clip_infinite_sides(box, Aabb::from_triangle(a, b, c)))
    return false;
  for (int k = 0; k < 3; ++k) {
    if (!(box.min[k] <= box.max[k])) return false;  // empty or NaN box
  }
  return detail::triangle_overlaps_box(a, b, c, box);
}

bool triangle_overlaps_obb(const Vec3& a, const Vec3& b, const Vec3& c, const Obb& box) {
  return detail::ObbTriangleTest(box)(a, b, c);
}

namespace detail {

ObbTriangleTest::ObbTriangleTest(const Obb& box)
    : box_from_world_(box.axes.transpose()),
      center_(box.center),
      local_{-box.half_extents, box.half_extents},
      valid_(box.center.allFinite() && box.axes.allFinite() && box.half_extents.allFinite() &&
             (box.half_extents.array() >= 0).all()) {}

bool ObbTriangleTest::operator()(const Vec3& a, const Vec3& b, const Vec3& c) const {
  if (!valid_)
    return triangle_overlaps_aabb(box_from_world_ * (a - center_), box_from_world_ * (b - center_),
                                  box_from_world_ * (c - center_), local_);
  // In the box's frame the box is axis-aligned (a rotation keeps the answer). The corners are
  // taken there a coordinate at a time, each tried on its face axis at once: most leaves that fail
  // are apart along a face axis.
  const Vec3 da = a - center_;
  const Vec3 db = b - center_;
  const Vec3 dc = c - center_;
  Vec3 la, lb, lc;
  for (int k = 0; k < 3; ++k) {
    la[k] = box_from_world_.row(k).dot(da);
    lb[k] = box_from_world_.row(k).dot(db);
    lc[k] = box_from_world_.row(k).dot(dc);
    if (std::max({la[k], lb[k], lc[k]}) < local_.min[k] || std::min({la[k], lb[k], lc[k]}) > local_.max[k])
      return false;
  }
  if (la.hasNaN() || lb.hasNaN() || lc.hasNaN()) return false;
  return triangle_overlaps_box(la, lb, lc, local_);
}

}  // namespace detail

bool triangle_overlaps_sphere(const Vec3& a, const Vec3& b, const Vec3& c, const Sphere& sphere) {
  // d^2 <= r^2 alone would let a negative radius act as its magnitude.
  if (!is_valid(sphere)) return false;
  return (closest_point_on_triangle(sphere.center, a, b, c) - sphere.center).squaredNorm() <=
         sphere.radius * sphere.radius;
}

namespace {

// A quick rejection for triangle_overlaps_capsule, which most of a query's leaf tests end in:
// planes that separate the triangle from the capsule, then the triangle's shadow along the core.
// A well-shaped triangle lies on the inner side of its own plane (either side) and of the three
// planes through an edge perpendicular to it; the capsule is apart when both ends of its core lie
// beyond one of them by more than the radius. The radius is taken larger (squared: by 4e-9 of r^2
// and 2e-9 of the squared size of the triangle and of the ends' offsets), far above the rounding
// of these products, so a capsule that touches the triangle is never rejected here (the exact
// distance decides). Needles and degenerate triangles (whose computed normal may point anywhere)
// are left to the distance.
Real segment_triangle_distance_squared_until(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                                             const Vec3& c, Real enough);  // Distances, below

bool capsule_beyond_a_triangle_plane(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& capsule,
                                     const detail::CapsuleAcross& across) {
  const Vec3 e[3] = {b - a, c - b, a - c};
  const Vec3 n = e[0].cross(c - a);
  const Real n2 = n.squaredNorm();
  const Real l0 = e[0].squaredNorm();
  const Real l2 = e[2].squaredNorm();
  if (!(n2 > Real(1e-6) * l0 * l2)) return false;
  const Vec3 d0 = capsule.p0 - a;
  const Vec3 d1 = capsule.p1 - a;
  const Real size2 = std::max({d0.squaredNorm(), d1.squaredNorm(), l0, e[1].squaredNorm(), l2});
  const Real reach2 = capsule.radius * capsule.radius * Real(1 + 4e-9) + Real(2e-9) * size2;
  // The triangle's plane: both ends on one side, farther than the radius.
  const Real s0 = n.dot(d0);
  const Real s1 = n.dot(d1);
  if (((s0 > 0 && s1 > 0) || (s0 < 0 && s1 < 0)) && std::min(s0 * s0, s1 * s1) > reach2 * n2) return true;
  // The edge planes: m = e x n points away from the triangle (for either winding of n).
  const Vec3* corner[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const Vec3 m = e[i].cross(n);
    const Real t0 = m.dot(capsule.p0 - *corner[i]);
    const Real t1 = m.dot(capsule.p1 - *corner[i]);
    if (t0 > 0 && t1 > 0 && std::min(t0 * t0, t1 * t1) > reach2 * m.squaredNorm()) return true;
  }
  // The triangle seen along the core: its shadow out of the disk of the (enlarged) radius about
  // the core's line. This settles the facets beside a capsule lying on a surface, which the planes
  // above do not.
  if (!across.valid) return false;
  Real x[3];
  Real y[3];
  for (int i = 0; i < 3; ++i) {
    const Vec3 d = *corner[i] - capsule.p0;
    x[i] = across.u.dot(d);
    y[i] = across.v.dot(d);
  }
  return detail::origin_beyond_triangle_2d(x, y, reach2);
}

}  // namespace

bool triangle_overlaps_capsule(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& capsule) {
  // A NaN end would make every orientation test of segment_meets_triangle false, i.e. "meets";
  // d^2 <= r^2 alone would let a negative radius act as its magnitude.
  if (!is_valid(capsule)) return false;
  if (capsule_beyond_a_triangle_plane(a, b, c, capsule, detail::CapsuleAcross(capsule))) return false;
  const Real r2 = capsule.radius * capsule.radius;
  return segment_triangle_distance_squared_until(capsule.p0, capsule.p1, a, b, c, r2) <= r2;
}

namespace {

// The five candidates of closest_segment_triangle_boundary, in its order (p0 and q[0], p1 and
// q[1], then x[i] and y[i] for the edges), with the distances that
// segment_triangle_distance_squared_until takes (the same expressions up to the sign of the
// difference, which squaring drops).
struct BoundaryCandidates {
  Vec3 q[2], x[3], y[3];
  Real distance_squared[5];

  [[gnu::always_inline]] BoundaryCandidates(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                                            const Vec3& c) {
    q[0] = closest_point_on_triangle(p0, a, b, c);
    q[1] = closest_point_on_triangle(p1, a, b, c);
    closest_points_on_segments(p0, p1, a, b, x[0], y[0]);
    closest_points_on_segments(p0, p1, b, c, x[1], y[1]);
    closest_points_on_segments(p0, p1, c, a, x[2], y[2]);
    distance_squared[0] = (p0 - q[0]).squaredNorm();
    distance_squared[1] = (p1 - q[1]).squaredNorm();
    for (int i = 0; i < 3; ++i) distance_squared[2 + i] = (x[i] - y[i]).squaredNorm();
  }

  // The first of the closest (a default pair if no distance is below infinity).
  [[gnu::always_inline]] detail::SegmentTrianglePair first_closest(const Vec3& p0, const Vec3& p1) const {
    detail::SegmentTrianglePair best;
    int k = -1;
    for (int i = 0; i < 5; ++i) {
      if (distance_squared[i] < best.distance_squared) {
        best.distance_squared = distance_squared[i];
        k = i;
      }
    }
    if (k >= 0) {
      best.on_segment = k == 0 ? p0 : k == 1 ? p1 : x[k - 2];
      best.on_triangle = k < 2 ? q[k] : y[k - 2];
    }
    return best;
  }
};

}  // namespace

detail::SegmentTrianglePair detail::closest_segment_triangle_boundary(const Vec3& p0, const Vec3& p1, const Vec3& a,
                                                                      const Vec3& b, const Vec3& c) {
  return BoundaryCandidates(p0, p1, a, b, c).first_closest(p0, p1);
}

detail::CapsuleAcross::CapsuleAcross(const Capsule& capsule) {
  const Vec3 w = capsule.p1 - capsule.p0;
  const Real length = w.norm();
  if (!(length > 0)) return;
  orthonormal_completion(w / length, u, v);
  valid = true;
}

bool detail::triangle_overlaps_capsule(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& capsule,
                                       const CapsuleAcross& across, SegmentTrianglePair& boundary) {
  if (capsule_beyond_a_triangle_plane(a, b, c, capsule, across)) return false;
  // segment_triangle_distance_squared_until's distance is 0 (<= r^2 for a valid radius) when the
  // segment meets the triangle, else the running std::min of the five candidates' distances.
  // That minimum is NaN from the first distance on or never grows, so its early stops at a value
  // <= r^2 decide as the whole minimum does; and the decision (meets, or the minimum <= r^2) is
  // the same in either order, so the meeting test is made only for what the distances reject.
  const BoundaryCandidates candidates(capsule.p0, capsule.p1, a, b, c);
  Real least = candidates.distance_squared[0];
  for (int i = 1; i < 5; ++i) least = std::min(least, candidates.distance_squared[i]);
  if (!(least <= capsule.radius * capsule.radius)) {
    if (is_flat(a, b, c)) {
      const auto [s, e] = degenerate_extent(a, b, c);
      if (!segments_meet(capsule.p0, capsule.p1, s, e)) return false;
    } else if (!segment_meets_triangle(capsule.p0, capsule.p1, a, b, c)) {
      return false;
    }
  }
  boundary = candidates.first_closest(capsule.p0, capsule.p1);
  return true;
}

bool triangle_crosses_plane(const Vec3& a, const Vec3& b, const Vec3& c, const Plane& plane) {
  const Real da = plane.signed_distance_scaled(a);
  const Real db = plane.signed_distance_scaled(b);
  const Real dc = plane.signed_distance_scaled(c);
  return std::min({da, db, dc}) <= 0 && std::max({da, db, dc}) >= 0;
}

bool detail::origin_beyond_triangle_2d(const Real (&x)[3], const Real (&y)[3], Real reach_squared) {
  bool positive = true;
  bool negative = true;
  for (int i = 0; i < 3; ++i) {
    const int j = i == 2 ? 0 : i + 1;
    const Real ex = x[j] - x[i];
    const Real ey = y[j] - y[i];
    // The origin against the edge from corner i to corner j.
    const Real cross = ex * y[i] - ey * x[i];
    positive = positive && cross > 0;
    negative = negative && cross < 0;
    const Real length_squared = ex * ex + ey * ey;
    const Real t = length_squared > 0 ? std::clamp(-(x[i] * ex + y[i] * ey) / length_squared, Real(0), Real(1)) : 0;
    const Real dx = x[i] + t * ex;
    const Real dy = y[i] + t * ey;
    if (!(dx * dx + dy * dy > reach_squared)) return false;
  }
  return !(positive || negative);
}

// ---------------------------------------------------------------------------------------------
// Distances

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a;
  const Vec3 bc = c - b;
  const Vec3 ca = a - c;
  return detail::closest_point_on_triangle_with_edges(p, a, b, c, ab, bc, ca, ab.squaredNorm(), bc.squaredNorm(),
                                                      ca.squaredNorm());
}

// Negating a difference is exact (c - a is -(a - c) to the bit, and so are their squared norms),
// so the edges in either direction come from the three given ones.
Vec3 detail::closest_point_on_triangle_with_edges(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                                                  const Vec3& ab, const Vec3& bc, const Vec3& ca, Real ab_squared,
                                                  Real bc_squared, Real ca_squared) {
  // Ericson, Real-Time Collision Detection, 5.1.5: vertex regions by dot products, then edge
  // regions and the interior by barycentric numerators. The numerators are taken in the book's
  // first, cross-product form n . ((a - p) x (b - p)) rather than its Lagrange-identity rewrite,
  // which cancels catastrophically on thin triangles; and the interior point is the projection of
  // p on the plane rather than the barycentric combination, whose position along a needle
  // triangle is only known to ~eps * L^2 / width.
  const Vec3 ac = -ca;
  const Vec3 n = ab.cross(ac);
  const auto closest_on_edges = [&] {
    const Vec3 q0 = closest_point_on_segment(p, a, b);
    const Vec3 q1 = closest_point_on_segment(p, b, c);
    const Vec3 q2 = closest_point_on_segment(p, c, a);
    const Real d0 = (q0 - p).squaredNorm();
    const Real d1 = (q1 - p).squaredNorm();
    const Real d2 = (q2 - p).squaredNorm();
    return d0 <= d1 && d0 <= d2 ? q0 : (d1 <= d2 ? q1 : q2);
  };
  // Degenerate (zero normal) or a needle narrower than 1e-8 of its longest edge L (|n| = L *
  // width): the triangle is its edges to within that width, which is also about the accuracy the
  // region tests below would have (eps * L / width), so take the edges.
  const Real longest_squared = std::max({ab_squared, ca_squared, bc_squared});
  const Real normal_squared = n.squaredNorm();
  if (!(normal_squared > Real(1e-16) * longest_squared * longest_squared)) return closest_on_edges();

  // Parametric positions of p along the edges, from each end.
  const Real snom = (p - a).dot(ab);
  const Real sdenom = (p - b).dot(-ab);
  const Real tnom = (p - a).dot(ac);
  const Real tdenom = (p - c).dot(ca);
  if (snom <= 0 && tnom <= 0) return a;
  const Real unom = (p - b).dot(bc);
  const Real udenom = (p - c).dot(-bc);
  if (sdenom <= 0 && unom <= 0) return b;
  if (tdenom <= 0 && udenom <= 0) return c;

  const Vec3 pa = a - p;
  const Vec3 pb = b - p;
  const Vec3 pc = c - p;
  const Real vc = n.dot(pa.cross(pb));
  if (vc <= 0 && snom >= 0 && sdenom >= 0) return a + (snom / (snom + sdenom)) * ab;
  const Real va = n.dot(pb.cross(pc));
  if (va <= 0 && unom >= 0 && udenom >= 0) return b + (unom / (unom + udenom)) * bc;
  const Real vb = n.dot(pc.cross(pa));
  if (vb <= 0 && tnom >= 0 && tdenom >= 0) return a + (tnom / (tnom + tdenom)) * ac;
  // The regions cover space exactly only in exact arithmetic; a rounding miss happens within
  // ~eps * L of the boundary, where the boundary is the answer.
  if (!(va >= 0 && vb >= 0 && vc >= 0)) return closest_on_edges();
  return p + (n.dot(pa) / normal_squared) * n;
}

void closest_points_on_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3& on_p,
                                Vec3& on_q) {
  // Ericson 5.1.9 (ClosestPtSegmentSegment), with exact zero tests for zero-length segments and
  // the unclamped s taken from the cross product d1 x d2 instead of a*e - b*b: both are
  // |d1 x d2|^2, but the latter cancels catastrophically for nearly parallel segments.
  const Vec3 d1 = p1 - p0;
  const Vec3 d2 = q1 - q0;
  const Vec3 r = p0 - q0;
  const Real a = d1.squaredNorm();
  const Real e = d2.squaredNorm();
  const Real f = d2.dot(r);
  Real s = 0;
  Real t = 0;
  if (a == 0 && e == 0) {
    // both are points
  } else if (a == 0) {
    t = std::clamp(f / e, Real(0), Real(1));
  } else {
    const Real c = d1.dot(r);
    if (e == 0) {
      s = std::clamp(-c / a, Real(0), Real(1));
    } else {
      const Real b = d1.dot(d2);
      const Vec3 n = d1.cross(d2);
      const Real denom = n.squaredNorm();
      // Parallel segments: any s works as a start, the clamping below finds the closest pair.
      s = denom > 0 ? std::clamp((-r).cross(d2).dot(n) / denom, Real(0), Real(1)) : Real(0);
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, Real(0), Real(1));
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, Real(0), Real(1));
      }
    }
  }
  on_p = p0 + s * d1;
  on_q = q0 + t * d2;
}

Real segment_segment_distance_squared(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  Vec3 on_p, on_q;
  closest_points_on_segments(p0, p1, q0, q1, on_p, on_q);
  return (on_p - on_q).squaredNorm();
}

namespace {

// segment_triangle_distance_squared, or a candidate at most `enough` as soon as one is found (so
// the answer is <= enough exactly when the distance is): a test against a radius stops early.
Real segment_triangle_distance_squared_until(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                                             const Vec3& c, Real enough) {
  // Zero if the segment meets the triangle. Otherwise the closest pair has a segment end on one
  // side or a triangle edge on the other (the interior of each cannot both be closest), so the
  // distance is the least of two point/triangle and three segment/segment distances. A degenerate
  // triangle is the union of its edges, which the same minimum covers.
  if (is_flat(a, b, c)) {
    const auto [s, e] = degenerate_extent(a, b, c);
    if (segments_meet(p0, p1, s, e)) return 0;  // exact zero on touching, as for proper triangles
  } else if (segment_meets_triangle(p0, p1, a, b, c)) {
    return 0;
  }
  Real best = (closest_point_on_triangle(p0, a, b, c) - p0).squaredNorm();
  if (best <= enough) return best;
  best = std::min(best, (closest_point_on_triangle(p1, a, b, c) - p1).squaredNorm());
  if (best <= enough) return best;
  best = std::min(best, segment_segment_distance_squared(p0, p1, a, b));
  if (best <= enough) return best;
  best = std::min(best, segment_segment_distance_squared(p0, p1, b, c));
  if (best <= enough) return best;
  return std::min(best, segment_segment_distance_squared(p0, p1, c, a));
}

}  // namespace

Real segment_triangle_distance_squared(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b, const Vec3& c) {
  return segment_triangle_distance_squared_until(p0, p1, a, b, c, Real(-1));  // distances are >= 0: no early stop
}

// ---------------------------------------------------------------------------------------------
// Out-of-line box tests of volume/aabb.h

// Centres, half extents and the motion are rounded at the scale of the coordinates, not of the
// boxes: far from the origin (1e6 and beyond) two touching boxes could come out apart by an ulp
// of their position, which boxes_overlap's slack (relative to the sizes and the centre distance)
// does not cover. Padding both boxes by a few hundred ulps of the largest coordinate involved
// keeps these tests conservative (touching boxes always overlap).
namespace {
Real coordinate_pad(const Aabb& a, const Vec3& b_extreme, const Vec3& translation) {
  return kContactSlack * (a.min.cwiseAbs().maxCoeff() + a.max.cwiseAbs().maxCoeff() + b_extreme.cwiseAbs().maxCoeff() +
                          translation.cwiseAbs().maxCoeff());
}
}  // namespace

bool overlaps(const Aabb& box, const Obb& obb) {
  if (box.is_empty()) return false;
  const Vec3 pad = Vec3::Constant(coordinate_pad(box, obb.center, Vec3::Zero()));
  return detail::boxes_overlap((box.max - box.min) * Real(0.5) + pad, obb.center - box.center(), obb.axes,
                               obb.half_extents + pad);
}

bool overlaps(const Aabb& a, const Aabb& b, const RigidTransform& a_from_b) {
  if (a.is_empty() || b.is_empty()) return false;
  const Vec3 b_center = a_from_b.apply(b.center());
  const Vec3 pad = Vec3::Constant(coordinate_pad(a, b.min.cwiseAbs().cwiseMax(b.max.cwiseAbs()), a_from_b.translation));
  return detail::boxes_overlap((a.max - a.min) * Real(0.5) + pad, b_center - a.center(), a_from_b.rotation,
                               (b.max - b.min) * Real(0.5) + pad);
}

bool overlaps(const Aabb& box, const Capsule& capsule) {
  if (box.is_empty() || !is_valid(capsule)) return false;
  // Never miss a true contact: pad the radius by a few hundred ulps of the coordinates involved,
  // which covers the rounding of the distance computation (conservative, not exact).
  const Real scale = box.min.cwiseAbs().maxCoeff() + box.max.cwiseAbs().maxCoeff() + capsule.p0.cwiseAbs().maxCoeff() +
                     capsule.p1.cwiseAbs().maxCoeff() + capsule.radius;
  const Real r = capsule.radius + kContactSlack * scale;
  // Quick reject on the capsule's bounding box.
  const Vec3 lo = capsule.p0.cwiseMin(capsule.p1).array() - r;
  const Vec3 hi = capsule.p0.cwiseMax(capsule.p1).array() + r;
  if ((lo.array() > box.max.array()).any() || (hi.array() < box.min.array()).any()) return false;
  return segment_box_squared_distance(capsule.p0, capsule.p1, box) <= r * r;
}

bool overlaps(const Aabb& box, const Plane& plane) {
  if (box.is_empty()) return false;
  // The plane function is linear, so its extremes over the box are at the corners picked per axis
  // by the sign of the normal (Ericson 5.2.3, written without the center so integer boxes are exact).
  Real lo = 0;
  Real hi = 0;
  for (int k = 0; k < 3; ++k) {
    const Real n = plane.normal[k];
    lo += n * (n >= 0 ? box.min[k] : box.max[k]);
    hi += n * (n >= 0 ? box.max[k] : box.min[k]);
  }
  return lo <= plane.offset && plane.offset <= hi;
}

Obb swept_box(const Vec3& from, const Vec3& to, const Vec3& half) {
  const Vec3 motion = to - from;
  const Real length = motion.norm();
  Obb box;
  box.center = (from + to) / 2;
  if (!(length > 0)) {
    box.half_extents = half;
    return box;
  }
  const Vec3 axis = motion / length;
  Vec3 b1, b2;
  detail::orthonormal_completion(axis, b1, b2);
  box.axes.col(0) = axis;
  box.axes.col(1) = b1;
  box.axes.col(2) = b2;
  // The box's extent along a unit direction u is |u| . half (support of an axis-aligned box).
  for (int i = 0; i < 3; ++i) box.half_extents[i] = box.axes.col(i).cwiseAbs().dot(half);
  box.half_extents[0] += length / 2;
  return box;
}

}  // namespace boxtree
