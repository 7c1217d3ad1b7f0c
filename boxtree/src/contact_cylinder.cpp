// SPDX-License-Identifier: MIT
// contact_cylinder_triangle and support_cylinder (contact.h): the least overlap of a cylinder and
// a triangle over unit normals, closed-form along the known flat cases and searched along the
// curved ones (a rim against an edge); contact_convex_triangle (contact_convex.cpp) for the rest.
#include <algorithm>
#include <array>
#include <cmath>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_internal.h"

namespace boxtree {

using namespace detail;  // the narrowphase's helpers (contact_internal.h)

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

}  // namespace boxtree
