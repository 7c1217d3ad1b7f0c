// SPDX-License-Identifier: MIT
// contact_cylinder_triangle and support_cylinder (contact.h): the least overlap of a cylinder and
// a triangle over unit normals, closed-form along the known flat cases and searched along the
// curved ones (a rim against an edge); contact_convex_triangle (contact_convex.cpp) for the rest.
#include <algorithm>
#include <array>
#include <cmath>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_cylinder.h"
#include "contact_internal.h"

namespace boxtree {

using namespace detail;  // the narrowphase's helpers (contact_internal.h)

detail::CylinderSupport::CylinderSupport(const Vec3& end0, const Vec3& end1, Real cylinder_radius)
    : p0(end0), p1(end1), radius(cylinder_radius) {
  const Vec3 axis = p1 - p0;
  length = axis.norm();
  if (length > 0) u = axis / length;
}

Vec3 detail::CylinderSupport::operator()(const Vec3& direction) const {
  if (!(length > 0)) {
    // No axis to orient the disks by: the sphere of that radius (a conservative stand-in).
    const Real len = direction.norm();
    return len > 0 ? Vec3(p0 + (radius / len) * direction) : p0;
  }
  const Real along = direction.dot(u);
  const Vec3 end = along >= 0 ? p1 : p0;
  const Vec3 radial = direction - along * u;
  const Real radial_length = radial.norm();
  // Along the axis the radial part is rounding noise, and normalizing it would pick an arbitrary
  // rim point (up to `radius` off along the direction): the disk's centre is exact there.
  if (!(radial_length > 1e-12 * direction.norm())) return end;
  return end + (radius / radial_length) * radial;
}

Vec3 support_cylinder(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& direction) {
  return detail::CylinderSupport(p0, p1, radius)(direction);
}

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

// `support`: support_cylinder(p0, p0 + length w, radius, .).
PrismDepths cylinder_depths_in_prism(const Vec3& p0, const Vec3& w, Real length, Real radius,
                                     const CylinderSupport& support, const TriangleFrame& tri, Real slack) {
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
  const Vec3& p1 = support.p1;
  const auto radial = [&](const Vec3& v) { return Vec3(v - w.dot(v) * w); };  // P v, P = I - w w^T
  const Vec3 pn = radial(n);
  Vec3 u1;  // the rims' plane
  Vec3 u2;
  detail::orthonormal_completion(w, u1, u2);
  // No wall active.
  for (const Real sign : {Real(-1), Real(1)}) {
    const Vec3 x = support(sign * n);
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

// Whether the triangle's face normal n is the least overlap's normal, proved by a bound rather
// than searched for: -1 if the cylinder is apart along n (by more than `limit` below zero), 1 if n
// is proved the least, 0 if not proved (the search decides). With x0 the cylinder's lowest point
// along n, d0 its depth below the plane and rho >= 0 the in-plane distance from its foot
// t = x0 + d0 n to the triangle's edges (t inside), every unit u = cos(a) n + sin(a) m (m in the
// plane, a in [0, pi/2]) has overlap
//   f(u) = max_T u.y - min_C u.x >= u.(t - x0) + rho sin(a) = d0 cos(a) + rho sin(a),
// since the triangle holds the disk of radius rho about t. That is least at an end of the arc:
// f(u) >= min(d0, rho) over the front hemisphere, so rho >= max(d0, 0) makes n the least there
// (d0 <= 0: C and T are then |d0| apart, along n). The back hemisphere, by the same bound at the
// highest point (height h, foot clearance rho'): f(u) >= min(h, rho'). Two-sided triangles need
// it >= d0 (n the least over the sphere); one-sided ones need only that the two really meet
// (d0 > 0 and the foot t inside the cylinder, or that bound >= 0), since normals behind the
// triangle are never answers there.
// `support`: support_cylinder(p0, p0 + length w, radius, .).
int flat_contact_is_least(const Vec3& p0, const Vec3& w, Real length, Real radius, const CylinderSupport& support,
                          const TriangleFrame& tri, bool one_sided, Real limit) {
  const Vec3& n = tri.normal;
  const Vec3 low = support(-n);
  const Real d0 = n.dot(tri.v[0] - low);
  if (d0 < limit) return -1;
  // Whether the in-plane distance from `foot` to every edge (inside) is at least `needed`: never
  // for a NaN `needed`; a NaN distance is passed over, as the least of them would pass it over.
  // Most candidates fail at the first or second edge.
  const auto clear_by = [&](const Vec3& foot, Real needed) {
    if (std::isnan(needed)) return false;
    for (int i = 0; i < 3; ++i) {
      const Vec3 wall = inward_wall(tri, i);
      if (wall.dot(foot - tri.v[i]) / wall.norm() < needed) return false;
    }
    return true;
  };
  const Vec3 foot = low + d0 * n;
  if (!clear_by(foot, std::max(d0, Real(0)))) return 0;
  if (one_sided && d0 > 0) {
    const Real along = w.dot(foot - p0);
    if (along >= 0 && along <= length && (foot - p0 - along * w).squaredNorm() <= radius * radius) return 1;
  } else if (one_sided) {
    return 1;
  }
  const Vec3 high = support(n);
  const Real height = n.dot(high - tri.v[0]);
  const Real needed = one_sided ? Real(0) : d0;
  return height >= needed && clear_by(high - height * n, needed) ? 1 : 0;
}

// The overlap along an arc of normals u = c a1 + s a2 (a1, a2 orthonormal) on which one corner or
// edge v of the triangle and one rim (centre c) of the cylinder are the supports:
//   g(u) = u . q + r sqrt(1 - (u . w)^2),  q = v - c,
// in the frame: g(c, s) = q1 c + q2 s + r sqrt(1 - (w1 c + w2 s)^2), the support function of the
// rim's shadow (an ellipse) moved by q, so that g(u) >= u . x(u') for the support point x(u')
// of any other normal u' of the arc.
struct RimArc {
  Real q1 = 0;
  Real q2 = 0;
  Real w1 = 0;
  Real w2 = 0;
  Real radius = 0;

  // g at u, and the support point there (the gradient of g extended homogeneously):
  // q + r (u - (u.w) w)/side, side = sqrt(1 - (u.w)^2); where the shadow has a corner (side ~ 0:
  // u is +-w, the shadow a segment), its centre q, a point of the shadow all the same (all that
  // the bounds below need).
  void value_and_support(const Vec2& u, Real& g, Vec2& x) const {
    const Real along = w1 * u.x() + w2 * u.y();
    const Real side = std::sqrt(std::max(Real(0), 1 - along * along));
    g = q1 * u.x() + q2 * u.y() + radius * side;
    if (!(side > 1e-9)) {
      x = Vec2(q1, q2);
    } else {
      x = Vec2(q1 + radius * (u.x() - along * w1) / side, q2 + radius * (u.y() - along * w2) / side);
    }
  }
  // g and its first two derivatives along the arc (by angle) at unit u.
  void derivatives(const Vec2& u, Real& g, Real& g1, Real& g2) const {
    const Real along = w1 * u.x() + w2 * u.y();
    const Real turn = w2 * u.x() - w1 * u.y();  // d along / dt
    const Real s = std::sqrt(std::max(Real(1e-300), 1 - along * along));
    const Real linear = q1 * u.x() + q2 * u.y();
    g = linear + radius * s;
    g1 = q2 * u.x() - q1 * u.y() - radius * along * turn / s;
    g2 = -linear - radius * ((turn * turn - along * along) / s + along * along * turn * turn / (s * s * s));
  }
};

// (cos, sin) of a small angle (|a| <= 0.1: Taylor series, error < 1e-18), else libm's.
Vec2 turn_by(Real a) {
  if (std::abs(a) > 0.1) return {std::cos(a), std::sin(a)};
  const Real a2 = a * a;
  return {1 - a2 / 2 * (1 - a2 / 12 * (1 - a2 / 30 * (1 - a2 / 56 * (1 - a2 / 90)))),
          a * (1 - a2 / 6 * (1 - a2 / 20 * (1 - a2 / 42 * (1 - a2 / 72))))};
}
Vec2 rotated(const Vec2& u, const Vec2& r) { return {u.x() * r.x() - u.y() * r.y(), u.y() * r.x() + u.x() * r.y()}; }
Real cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// The least of g over the arc from unit lo to unit hi (counter-clockwise, less than a half turn),
// by branch and bound: on a sub-arc with support points x_lo, x_hi at its ends, g(u) is at least
// max(u . x_lo, u . x_hi) (the support function of the chord [x_lo, x_hi]), whose least over the
// sub-arc is found in closed form. Sub-arcs whose bound is not below `best` - `noise` are dropped;
// the others are halved, down to 1/16 of the arc, where the ends' slopes and Newton's method on g'
// (kept inside a sign change of g') end the search. `consider(u)` gets the minima found (and
// lowers `best`): every minimum of g on the arc that is below `best` - `noise` is found, to the
// precision of the Newton iteration (~1e-9 rad, so g to ~1e-18 of the sizes).
template <class Consider>
void rim_arc_least(const RimArc& arc, const Vec2& lo, const Vec2& hi, const Real& best, Real noise,
                   Consider&& consider) {
  struct Node {
    Vec2 lo, hi;
    Real g_lo, g_hi;
    Vec2 x_lo, x_hi;
    int depth;
  };
  constexpr int kDepth = 4;
  Node stack[2 * kDepth + 2];
  int size = 0;
  Node root{lo, hi, 0, 0, Vec2::Zero(), Vec2::Zero(), 0};
  arc.value_and_support(lo, root.g_lo, root.x_lo);
  arc.value_and_support(hi, root.g_hi, root.x_hi);
  stack[size++] = root;
  while (size > 0) {
    const Node node = stack[--size];
    // The chord's bound: g >= u . x_lo up to the chord's normal u*, u . x_hi after it (the ends'
    // support points); each a sinusoid, least at an end of its part or along -x if that is inside.
    const auto inside = [](const Vec2& from, const Vec2& to, const Vec2& u) {
      return cross2(from, u) >= 0 && cross2(u, to) >= 0;
    };
    const auto least = [&](const Vec2& x, const Vec2& from, const Vec2& to) {
      const Real at_ends = std::min(from.dot(x), to.dot(x));
      return inside(from, to, -x) ? std::min(at_ends, -x.norm()) : at_ends;
    };
    // Each part below only raises the bound (a max): the later ones are skipped once the sub-arc
    // is dropped without them (the same decisions, fewer products).
    Real bound = least(node.x_lo, node.lo, node.hi);
    if (bound >= best - noise) continue;
    bound = std::max(bound, least(node.x_hi, node.lo, node.hi));
    if (bound >= best - noise) continue;
    const Vec2 chord = node.x_hi - node.x_lo;
    Vec2 split(-chord.y(), chord.x());  // u . x_lo = u . x_hi there
    const Real split_length = split.norm();
    if (split_length > 0) {
      split /= split_length;
      if (!inside(node.lo, node.hi, split)) split = -split;
      if (inside(node.lo, node.hi, split))
        bound = std::max(bound, std::min(least(node.x_lo, node.lo, split), least(node.x_hi, split, node.hi)));
    }
    if (bound >= best - noise) continue;
    Vec2 middle = node.lo + node.hi;
    middle /= middle.norm();
    if (node.depth == kDepth) {
      // The slopes at the ends: an end is the least if g rises from it; else g' changes sign
      // inside, and Newton's method on g' (kept inside the bracket of that sign change, bisecting
      // where a step would leave it) finds the minimum.
      Real g = 0, g1_lo = 0, g1_hi = 0, g2 = 0;
      arc.derivatives(node.lo, g, g1_lo, g2);
      arc.derivatives(node.hi, g, g1_hi, g2);
      if (!(g1_lo < 0)) consider(node.lo);
      if (!(g1_hi > 0)) consider(node.hi);
      if (!(g1_lo < 0 && g1_hi > 0)) continue;
      const Real half_width = std::atan2(std::abs(cross2(node.lo, middle)), node.lo.dot(middle));
      Real a = -half_width;
      Real b = half_width;
      Real t = 0;
      Vec2 u = middle;
      Real g1 = 0;
      arc.derivatives(u, g, g1, g2);
      for (int iteration = 0; iteration < 30 && g1 != 0; ++iteration) {
        (g1 < 0 ? a : b) = t;
        Real next = g2 > 0 ? t - g1 / g2 : (a + b) / 2;
        if (!(next > a && next < b)) next = (a + b) / 2;
        const Real moved = std::abs(next - t);
        u = rotated(u, turn_by(next - t));
        t = next;
        arc.derivatives(u, g, g1, g2);
        if (moved < 1e-9 || b - a < 1e-12) break;  // g is then within ~g'' 1e-18 of its least
      }
      consider(u);
      continue;
    }
    Real g_middle = 0;
    Vec2 x_middle;
    arc.value_and_support(middle, g_middle, x_middle);
    const Node left{node.lo, middle, node.g_lo, g_middle, node.x_lo, x_middle, node.depth + 1};
    const Node right{middle, node.hi, g_middle, node.g_hi, x_middle, node.x_hi, node.depth + 1};
    // The lower end first (popped first).
    if (node.g_lo < node.g_hi) {
      stack[size++] = right;
      stack[size++] = left;
    } else {
      stack[size++] = left;
      stack[size++] = right;
    }
  }
}

}  // namespace

detail::CylinderTriangleContacts::CylinderTriangleContacts(const Vec3& p0, const Vec3& p1, Real radius)
    : valid_(finite(p0, p1, Vec3::Constant(radius)) && radius >= 0),
      axis_(p0, p1, radius),
      mid_((p0 + p1) / 2),
      coord_(std::max(max_abs(p0), max_abs(p1))) {
  if (axis_.length > 0) {
    rebuilt_ = CylinderSupport(p0, p0 + axis_.length * axis_.u, radius);
    detail::orthonormal_completion(axis_.u, across0_, across1_);
  }
}

int contact_cylinder_triangle(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& a, const Vec3& b, const Vec3& c,
                              const ContactOptions& options, ContactPoint* out) {
  return detail::CylinderTriangleContacts(p0, p1, radius)(a, b, c, options, out);
}

int detail::CylinderTriangleContacts::operator()(const Vec3& a, const Vec3& b, const Vec3& c,
                                                 const ContactOptions& options, ContactPoint* out) const {
  // The least overlap of the projections over unit normals (contact_convex_triangle's answer),
  // found without GJK/EPA as the least over the critical normals of the overlap f(u), one family
  // per kind of face of the Minkowski difference of the two shapes: the triangle's face against a
  // point of the cylinder (n), a corner against a disk (w) or the side (the radial direction from
  // the corner to the axis), an edge against the side (w x e) or a rim (across e: a 1D search on
  // a smooth function, rim_arc_least). Where the shapes penetrate, the least of f is on one such
  // face (a convex body's nearest boundary point from inside is a smooth one), so the least of the
  // candidates is the least overlap; apart, it may also be on a ridge (a corner against a rim),
  // whose normals are candidates too. f is exact along any normal, so every candidate is an upper
  // bound and any with a gap wider than the margin proves the two apart. Shapes behind a
  // one-sided triangle (the push-out case) and degenerate inputs go to the general routine.
  if (!finite(a, b, c) || !valid_) return 0;
  const TriangleFrame tri(a, b, c);
  const Vec3& p0 = axis_.p0;
  const Vec3& p1 = axis_.p1;
  const Real radius = axis_.radius;
  const Real length = axis_.length;
  const Vec3& mid = mid_;
  const auto general = [&] {
    const auto support = [&](const Vec3& d) { return axis_(d); };
    const int n = contact_convex_triangle({support, mid}, a, b, c, options, out);
    return n;
  };
  const Real size = std::max({tri.size, length, 2 * radius, std::max(options.margin, Real(0))});
  if (tri.degenerate || !(length > kTiny * size)) return general();
  const bool one_sided = tri.one_sided(options);
  const Vec3& w = axis_.u;
  const Real half = length / 2;
  const Real margin = std::max(options.margin, Real(0));
  const Real limit = -margin - tolerance(size, std::max(tri.coord, coord_));
  {
    // The shadows along the axis apart by more than the margin and twice the tolerance: the two
    // are apart along a direction across the axis by more than `limit` asks of the candidates
    // below, which then return nothing (the push-out too: a cylinder meeting the triangle's
    // prism on both sides of its plane meets the triangle), so nothing is returned here without
    // them. This settles the query box's candidates beside the cylinder (beyond its side) at
    // the cost of a 2D point-triangle distance.
    Real x[3];
    Real y[3];
    for (int i = 0; i < 3; ++i) {
      const Vec3 d = tri.v[i] - mid_;
      x[i] = across0_.dot(d);
      y[i] = across1_.dot(d);
    }
    const Real reach = radius - limit + tolerance(size, std::max(tri.coord, coord_));
    if (detail::origin_beyond_triangle_2d(x, y, reach * reach)) return 0;
  }
  Real pushed_depth = 0;
  Vec3 pushed_point = Vec3::Zero();
  if (one_sided && tri.signed_distance(mid) < 0) {
    // Behind a one-sided triangle: pushed out through the front by the least lift that clears the
    // triangle, the depth of the cylinder's deepest point over it; seen only if it really meets
    // the triangle (points over it on both sides of the plane).
    const PrismDepths depths = cylinder_depths_in_prism(p0, w, length, radius, rebuilt_, tri,
                                                        tolerance(size, std::max(tri.coord, max_abs(mid))));
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
  if (const int proven = flat_contact_is_least(p0, w, length, radius, rebuilt_, tri, one_sided, limit)) {
    if (proven < 0) return 0;
    const Vec3 low = axis_(-tri.normal);
    const Real depth = tri.normal.dot(tri.v[0] - low);
    if (!(depth >= -margin)) return 0;
    return finish(tri.normal, depth,
                  make_contact(landing_position(tri, tri.normal, low + depth * tri.normal, size), tri.normal, depth));
  }

  // The cylinder's lowest point along unit u is mid - half*sign(u.w)*w - radius*(radial part of u),
  // so the overlap is the corners' reach along u beyond mid plus the cylinder's half extent along u.
  const Vec3 corner[3] = {tri.v[0] - mid, tri.v[1] - mid, tri.v[2] - mid};
  // The overlaps along u and along -u, whose products are those along u negated (exactly), so
  // that the cylinder's part is shared and the corners' reach along -u is minus their least one.
  const auto overlaps_along = [&](const Vec3& u, Real& value, Real& opposite) {
    const Real along = u.dot(w);
    const Real reach[3] = {u.dot(corner[0]), u.dot(corner[1]), u.dot(corner[2])};
    // |u - (u.w) w|, from 1 - (u.w)^2 unless that cancels (u near +-w, the disks' normals).
    const Real across = 1 - along * along;
    const Real side = across > 1e-4 ? std::sqrt(across) : Vec3(u - along * w).norm();
    const Real extent = half * std::abs(along);
    const Real rim = radius * side;
    value = std::max({reach[0], reach[1], reach[2]}) + extent + rim;
    opposite = -std::min({reach[0], reach[1], reach[2]}) + extent + rim;
  };

  const Real noise = 64 * kEps * (std::max(tri.coord, coord_) + size);
  Real best = kInf;
  Real behind_best = kInf;  // one-sided: the least overlap along the normals behind the triangle
  Vec3 best_normal = tri.normal;
  bool apart = false;
  const auto take = [&](const Vec3& u, Real value) {
    if (value < limit) apart = true;
    if (one_sided && u.dot(tri.normal) < -kBehind) {  // separates, but is not a normal here
      behind_best = std::min(behind_best, value);
      return;
    }
    if (value < best) {
      best = value;
      best_normal = u;
    }
  };
  // Along the unit vector of `direction` (nothing for a zero one), and along its reverse too when
  // `both` (from the same products: overlaps_along gives both).
  const auto consider_along = [&](const Vec3& direction, bool both) {
    const Real len = direction.norm();
    if (!(len > 0)) return;
    const Vec3 u = direction / len;
    Real value = 0;
    Real opposite = 0;
    overlaps_along(u, value, opposite);
    take(u, value);
    if (both) take(-u, opposite);
  };
  const auto consider = [&](const Vec3& direction) { consider_along(direction, false); };
  // consider(direction) and then consider(-direction).
  const auto consider_both = [&](const Vec3& direction) { consider_along(direction, true); };
  // The flat faces of the Minkowski difference and the curved ones around a corner: the face
  // under a point of the cylinder (n), a disk over a corner (w), the side along an edge (w x e),
  // the side over a corner (the radial direction from the corner to the axis). Where the two are
  // apart, the corners against the rims too (a ridge: its normals are the directions from a corner
  // to its nearest rim point). The in-plane edge normals are kinks of the overlap on the circle
  // that bounds a one-sided triangle's normals.
  if (one_sided) {
    consider(tri.normal);
  } else {
    consider_both(tri.normal);
  }
  consider_both(w);
  consider(mid - closest_point_on_triangle(mid, a, b, c));
  if (apart) return 0;  // most candidates of the query box are apart along one of these already
  Vec3 edge_normal[3];
  for (int j = 0; j < 3; ++j) {
    const Vec3 e = tri.v[(j + 1) % 3] - tri.v[j];
    edge_normal[j] = e.cross(tri.normal).normalized();
    const Vec3 u = w.cross(e);
    if (u.norm() > 1e-6 * e.norm()) consider_both(u);
    const Vec3 d = mid - tri.v[j];
    consider(d - d.dot(w) * w);
    if (!one_sided) consider(edge_normal[j]);
  }
  if (apart) return 0;
  // A corner inside the cylinder: the two meet, and no ridge is the answer.
  bool meet = false;
  for (int j = 0; j < 3; ++j) {
    const Vec3 d = tri.v[j] - p0;
    const Real along = d.dot(w);
    meet = meet || (along >= 0 && along <= length && (d - along * w).squaredNorm() <= radius * radius);
  }
  for (int j = 0; j < 3 && !meet; ++j) {
    for (const Vec3& centre : {p0, p1}) {
      const Vec3 d = tri.v[j] - centre;
      const Vec3 radial = d - d.dot(w) * w;
      const Real radial_length = radial.norm();
      if (radial_length > 0) consider(centre + (radius / radial_length) * radial - tri.v[j]);
    }
  }
  if (apart) return 0;
  // A rim against an edge: the curved faces of the Minkowski difference whose normals are across
  // an edge e, on the great circle u(t) = cos(t) n + sin(t) m (m: the edge's outward normal in the
  // plane), where the edge is the triangle's support for t in [0, pi]. Between the kink where
  // u . w changes sign (u = +-w x e, a candidate above) and the ends, one rim (centre c) is the
  // cylinder's support and the overlap is the smooth support function of the rim's shadow across
  // e (an ellipse), minimized by rim_arc_least. The front quarter (t <= pi/2) holds answers; the
  // quarter behind holds those of two-sided triangles and, for one-sided ones, shows whether the
  // least over the front may be on its bounding circle (below).
  const Vec2 quarter_ends[3] = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0)};
  const auto split_at_kink = [&](const Vec3& a1, const Vec3& a2, const Vec2& lo, const Vec2& hi, const Vec3& v) {
    RimArc arc;
    arc.w1 = w.dot(a1);
    arc.w2 = w.dot(a2);
    arc.radius = radius;
    // u . w = 0 at +-(w2, -w1): a kink of the overlap (the rims swap), inside or not.
    Vec2 kink(arc.w2, -arc.w1);
    const Real kink_length = kink.norm();
    Vec2 ends[3] = {lo, hi, hi};
    int pieces = 1;
    if (kink_length > 0) {
      kink /= kink_length;
      if (cross2(lo, kink) < 0) kink = -kink;
      if (cross2(lo, kink) > 0 && cross2(kink, hi) > 0) {
        ends[1] = kink;
        pieces = 2;
      }
    }
    for (int k = 0; k < pieces; ++k) {
      const Vec2 centre = ends[k] + ends[k + 1];
      const bool lower_end = arc.w1 * centre.x() + arc.w2 * centre.y() >= 0;
      const Vec3 q = v - (lower_end ? p0 : p1);
      arc.q1 = q.dot(a1);
      arc.q2 = q.dot(a2);
      rim_arc_least(arc, ends[k], ends[k + 1], best, noise, [&](const Vec2& u) { consider(u.x() * a1 + u.y() * a2); });
    }
  };
  // Quick bounds of a quarter: for any point x of the cylinder, the overlap along
  // u = cos(t) n + sin(t) m is at least u . (v_j - x) = dn cos(t) + dm sin(t), which over a
  // quarter is least at an end (unless both of its ends' values are negative). Taken with the
  // cylinder's lowest point along n and its support along the front quarter's middle, and with
  // its highest point and the support along the middle of the quarter behind.
  const Vec3 lowest = axis_(-tri.normal);
  const Vec3 highest = axis_(tri.normal);
  const auto quarter_bound = [](Real along_n, Real along_m) {
    return along_n < 0 && along_m < 0 ? -std::hypot(along_n, along_m) : std::min(along_n, along_m);
  };
  // A quarter's bound from the lowest (highest) point first, the middle's support only if that
  // bound does not already drop the quarter: the larger of the two either way.
  const auto bound_of = [&](const Vec3& v, const Vec3& m, int quarter) {
    const bool front = quarter == 0;
    const Vec3 end = v - (front ? lowest : highest);
    const Real bound = quarter_bound(front ? end.dot(tri.normal) : -end.dot(tri.normal), end.dot(m));
    if (!(bound < best - noise)) return bound;
    const Vec3 middle = v - axis_(front ? Vec3(-(tri.normal + m)) : Vec3(tri.normal - m));
    return std::max(bound, quarter_bound(front ? middle.dot(tri.normal) : -middle.dot(tri.normal), middle.dot(m)));
  };
  for (int j = 0; j < 3 && !apart; ++j) {
    const Vec3& m = edge_normal[j];
    for (int quarter = 0; quarter < 2; ++quarter) {
      if (bound_of(tri.v[j], m, quarter) >= best - noise) continue;
      split_at_kink(tri.normal, m, quarter_ends[quarter], quarter_ends[quarter + 1], tri.v[j]);
    }
  }
  if (apart || !(best >= limit)) return 0;
  // A one-sided triangle's normals are bounded by the circle u . n = 0, where the least over the
  // front may lie rather than at a critical point of the overlap. It does only if the least over
  // the sphere is behind, below every critical point in front. Then the least on that circle is
  // taken too: between the edges' normals m_(k-1) and m_k the corner v_k is the triangle's support,
  // and the overlap is the same rim's support function as across the edges (arcs split where
  // u . w changes sign; the kinks themselves, the m_j and +-n x w, are candidates).
  if (one_sided && behind_best < best - noise) {
    const Vec3 across = tri.normal.cross(w);
    consider_both(across);
    for (const Vec3& m : edge_normal) consider(m);
    for (int k = 0; k < 3; ++k) {
      const Vec3& a1 = edge_normal[(k + 2) % 3];
      const Vec3 a2 = tri.normal.cross(a1);
      const Vec3& end = edge_normal[k];
      split_at_kink(a1, a2, Vec2(1, 0), Vec2(end.dot(a1), end.dot(a2)), tri.v[k]);
    }
  }
  if (!(best >= -margin)) return 0;
  return finish(best_normal, best,
                make_contact(landing_position(tri, best_normal, axis_(-best_normal) + best * best_normal, size),
                             best_normal, best));
}

}  // namespace boxtree
