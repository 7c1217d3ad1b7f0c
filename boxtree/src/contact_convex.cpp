// SPDX-License-Identifier: MIT
// contact_convex_triangle and support_points (contact.h): general convex shapes by GJK + EPA from
// libccd against the triangle rounded by the margin, then a local polish of the normal on the
// exact projection overlap; and landing_position (contact_internal.h), the contact position of a
// shape moved out along a normal.
#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <utility>

#include <ccd/ccd.h>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_internal.h"

namespace boxtree {
namespace detail {
namespace {

static_assert(std::is_same_v<ccd_real_t, Real>, "libccd must be built in double precision (CCD_DOUBLE)");

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

}  // namespace

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

}  // namespace detail

using namespace detail;  // the narrowphase's helpers (contact_internal.h)

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

}  // namespace boxtree
