// SPDX-License-Identifier: MIT
// contact_box_triangle, contact_polyhedron_triangle and contact_triangle_triangle (contact.h): one
// shared separating-axis routine (polytope_triangle) over the polytope description of
// contact_polytope.h. Every face normal of the Minkowski difference (the shape's faces, the
// triangle's normal, edge x edge crosses) is tried, so the least overlap is the exact penetration
// depth when the shapes overlap and a lower bound of the distance when they are apart. Face axes
// are preferred unless an edge axis is clearly better (as the box colliders of ODE and Bullet
// do): face contacts come as a stable patch of points, edge contacts as one.
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_polytope.h"

namespace boxtree {
namespace detail {
namespace {

// Face axes win unless an edge axis is better by this fraction of the face overlap: a box resting
// on a face keeps a patch of contacts instead of flickering to a single edge contact.
constexpr Real kFaceBias = 0.05;

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

// project_points over a polyhedron's vertex_columns (x, y, z rows of `count`): each value is
// (u0 x + u1 y) + u2 z, the products and sums of Vec3::dot in its order, so equal to
// u.dot(corner) to the bit, and the same least and greatest value (taken in two lanes, then of
// the lanes: only a +0 and a -0 could come out the other way round). With SSE2, two corners per
// instruction: minpd(a, b) is a < b ? a : b, so minpd(x, lo) is std::min(lo, x) (and maxpd the
// same for std::max), as in packed_tree.cpp.
[[gnu::noinline]] Interval project_columns(const Real* columns, int count, const Vec3& u) {
  const Real* x = columns;
  const Real* y = columns + count;
  const Real* z = columns + 2 * count;
  Real lo = kInf;
  Real hi = -kInf;
  int i = 0;
#if defined(__SSE2__)
  const __m128d u0 = _mm_set1_pd(u[0]);
  const __m128d u1 = _mm_set1_pd(u[1]);
  const __m128d u2 = _mm_set1_pd(u[2]);
  __m128d lo2 = _mm_set1_pd(kInf);
  __m128d hi2 = _mm_set1_pd(-kInf);
  for (; i + 1 < count; i += 2) {
    const __m128d xy = _mm_add_pd(_mm_mul_pd(u0, _mm_loadu_pd(x + i)), _mm_mul_pd(u1, _mm_loadu_pd(y + i)));
    const __m128d value = _mm_add_pd(xy, _mm_mul_pd(u2, _mm_loadu_pd(z + i)));
    lo2 = _mm_min_pd(value, lo2);
    hi2 = _mm_max_pd(value, hi2);
  }
  alignas(16) Real lanes[4];
  _mm_store_pd(lanes, lo2);
  _mm_store_pd(lanes + 2, hi2);
  lo = std::min(lanes[0], lanes[1]);
  hi = std::max(lanes[2], lanes[3]);
#endif
  for (; i < count; ++i) {
    const Real value = (u[0] * x[i] + u[1] * y[i]) + u[2] * z[i];
    lo = std::min(lo, value);
    hi = std::max(hi, value);
  }
  return {lo, hi};
}

[[gnu::always_inline]] inline Interval project(const Polytope& p, const Vec3& u) {
  if (p.kind == Polytope::Kind::kBox) {
    // Centre and radius: three dot products instead of eight.
    const Real c = u.dot(p.center);
    const Real radius = p.half_extents.dot((p.axes.transpose() * u).cwiseAbs());
    return {c - radius, c + radius};
  }
  if (p.vertex_columns) return project_columns(p.vertex_columns, p.vertex_count, u);
  return project_points(p.vertices, p.vertex_count, u);
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
// contact is exactly the directional penetration depth along N (when there are more than
// kScratchContacts, the deepest are kept). Contacts with depth < least_depth are left out; the
// others come in the same order as with no such bound (-kInf) while the scratch has room.
int triangle_face_contacts(const Polytope& shape, const TriangleFrame& tri, const Vec3& normal, Real slack,
                           Real least_depth, ContactPoint* out) {
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
  const auto depth_of = [&](const Vec3& x) { return plane - normal.dot(x); };
  // Into `out` while there is room; once it is full (a shape of many corners deep in the prism),
  // in place of the shallowest if deeper, so that the deepest are kept whatever order they come in.
  const auto keep = [&](const ContactPoint& contact) {
    if (count < kScratchContacts) {
      out[count++] = contact;
      return;
    }
    int shallowest = 0;
    for (int i = 1; i < count; ++i) {
      if (out[i].depth < out[shallowest].depth) shallowest = i;
    }
    if (contact.depth > out[shallowest].depth) out[shallowest] = contact;
  };
  const auto add = [&](const Vec3& x, Real depth) { keep(make_contact(x + depth * normal, normal, depth)); };
  // The corners' signed distances to the walls, worked out once (up to kCachedCorners corners):
  // every corner is on three or more edges, which read the same values. With them, bit i of
  // below[v] (above[v]) is whether corner v is strictly on the outer (inner) side of wall i.
  constexpr int kCachedCorners = 64;
  std::array<std::array<Real, 3>, kCachedCorners> wall_distance;
  std::array<unsigned, kCachedCorners> below;
  std::array<unsigned, kCachedCorners> above;
  const bool cached = shape.vertex_count <= kCachedCorners;
  for (int v = 0; cached && v < shape.vertex_count; ++v) {
    below[v] = 0;
    above[v] = 0;
    for (int i = 0; i < 3; ++i) {
      const Real d = walls[i].dot(shape.vertices[v] - tri.v[i]);
      wall_distance[v][i] = d;
      below[v] |= unsigned(d < 0) << i;
      above[v] |= unsigned(d > 0) << i;
    }
  }
  const auto distance = [&](int v, int i) {
    return cached ? wall_distance[v][i] : walls[i].dot(shape.vertices[v] - tri.v[i]);
  };
  for (int v = 0; v < shape.vertex_count; ++v) {
    bool inside = true;
    for (int i = 0; i < 3 && inside; ++i) inside = !(distance(v, i) < -slack);
    if (!inside) continue;
    const Real depth = depth_of(shape.vertices[v]);
    if (!(depth < least_depth)) add(shape.vertices[v], depth);
  }
  for (int e = 0; e < shape.edge_count; ++e) {
    const int from = shape.edge_from[e];
    const int to = shape.edge_to[e];
    // The walls whose planes the edge crosses strictly (its ends on opposite sides).
    unsigned crossed = 7;
    if (cached) {
      crossed = (below[from] & above[to]) | (above[from] & below[to]);
      if (crossed == 0) continue;
    }
    const Vec3& p = shape.vertices[from];
    const Vec3& q = shape.vertices[to];
    for (int i = 0; i < 3; ++i) {
      if (!((crossed >> i) & 1)) continue;
      const Real fp = distance(from, i);
      const Real fq = distance(to, i);
      if (!((fp < 0 && fq > 0) || (fp > 0 && fq < 0))) continue;
      const Vec3 x = p + (fp / (fp - fq)) * (q - p);
      const Real depth = depth_of(x);
      if (!(depth < least_depth) && inside_prism(x, i)) add(x, depth);
    }
  }
  // Lines v - t*N through the triangle's corners against the shape's bounding half-spaces
  // (Cyrus-Beck): the largest t is the deepest point of the shape under that corner.
  // The three lines in one pass over the half-spaces (a half-space's rate is the same for all
  // three); each line's bounds are still met in the half-spaces' order.
  Real t_lo[3] = {-kInf, -kInf, -kInf};
  Real t_hi[3] = {kInf, kInf, kInf};
  for (int k = 0; k < shape.bound_count; ++k) {
    // bound.normal . (v - t N) <= offset  <=>  -t (bound.normal . N) <= offset - bound.normal . v
    const Real rate = -shape.bounds[k].normal.dot(normal);
    for (int j = 0; j < 3; ++j) {
      const Real room = -shape.bounds[k].signed_distance_scaled(tri.v[j]);
      if (std::abs(rate) <= kEps) {
        if (room < -slack) t_hi[j] = -kInf;
        continue;
      }
      const Real t = room / rate;
      if (rate > 0) {
        t_hi[j] = std::min(t_hi[j], t);
      } else {
        t_lo[j] = std::max(t_lo[j], t);
      }
    }
  }
  for (int j = 0; j < 3 && shape.bound_count > 0; ++j) {
    if (t_lo[j] <= t_hi[j] + slack && std::isfinite(t_hi[j]) && !(t_hi[j] < least_depth)) {
      keep(make_contact(tri.v[j], normal, t_hi[j]));
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

// The separating axes of a box (polytope_of_box) against a triangle, worked out in the box's frame
// as Akenine-Moller's triangle-box test does ("Fast 3D Triangle-Box Overlap Testing", JGT 6(1),
// 2001): there the box is centred and axis-aligned, so its projection on an axis is |n| . h, a
// face axis reads one coordinate of the corners, and an edge axis e_k x E has one zero
// component. The same axes, in the same order and with the same tie-breaking as the general loop
// of polytope_triangle; the values differ from it by rounding only. A face axis of the box is
// one axis for its two opposite faces (each one's overlap is the other's reverse). Returns false
// as soon as an axis separates by more than `margin`.
bool box_axes(const Polytope& box, const TriangleFrame& tri, Real margin, Real center_side, Axis& best_face,
              Axis& best_tri_face, Axis& best_edge, Real& separation) {
  const auto consider = [](Axis& best, const Axis& axis) {
    if (axis.overlap < best.overlap) best = axis;
  };
  const Mat3 box_from_world = box.axes.transpose();
  const Vec3& h = box.half_extents;
  Vec3 local[3];
  for (int i = 0; i < 3; ++i) local[i] = box_from_world * (tri.v[i] - box.center);
  // Projections of the triangle's corners on n (local), and the box's radius along it.
  const auto both_ways = [&](const Vec3& n) {
    const Real p0 = n.dot(local[0]);
    const Real p1 = n.dot(local[1]);
    const Real p2 = n.dot(local[2]);
    const Real radius = h.dot(n.cwiseAbs());
    // Moving the box along +n: the triangle's top minus the box's bottom; along -n, the reverse.
    return std::pair<Real, Real>{std::max({p0, p1, p2}) + radius, radius - std::min({p0, p1, p2})};
  };
  if (!tri.degenerate) {
    const auto [up, down] = both_ways(box_from_world * tri.normal);
    separation = std::max(separation, -std::min(up, down));
    const Real sigma = center_side >= 0 ? 1 : -1;
    consider(best_tri_face, {sigma * tri.normal, sigma > 0 ? up : down, AxisKind::kTriangleFace, 0, 0});
  }
  if (separation > margin) return false;
  for (int k = 0; k < 3; ++k) {
    // Face 2k (outward +a_k, N = -a_k) and face 2k + 1 (outward -a_k, N = +a_k).
    const Real lo = std::min({local[0][k], local[1][k], local[2][k]});
    const Real hi = std::max({local[0][k], local[1][k], local[2][k]});
    const Real along_minus = h[k] - lo;  // moving the box along -a_k clears the triangle
    const Real along_plus = hi + h[k];
    separation = std::max(separation, -std::min(along_minus, along_plus));
    if (separation > margin) return false;
    consider(best_face, {-box.faces[2 * k].normal, along_minus, AxisKind::kShapeFace, 2 * k, 0});
    consider(best_face, {-box.faces[2 * k + 1].normal, along_plus, AxisKind::kShapeFace, 2 * k + 1, 0});
  }
  constexpr int kNext[3] = {1, 2, 0};
  constexpr int kAfterNext[3] = {2, 0, 1};
  const Vec3 local_edges[3] = {local[1] - local[0], local[2] - local[1], local[0] - local[2]};
  // Each edge's length, for the parallel test of its three crosses.
  const Real edge_lengths[3] = {local_edges[0].norm(), local_edges[1].norm(), local_edges[2].norm()};
  for (int k = 0; k < 3; ++k) {
    const int i = kNext[k];
    const int j = kAfterNext[k];
    for (int t = 0; t < 3; ++t) {
      const Vec3& e = local_edges[t];
      // u = e_k x e: component k is zero, (i, j) are (ui, uj) = (-e_j, e_i). Its length from the
      // two: the zero adds +0 to the sum of squares, which changes nothing.
      const Real ui = -e[j];
      const Real uj = e[i];
      const Real len = std::sqrt(ui * ui + uj * uj);
      if (!(len > 1e-6 * edge_lengths[t])) continue;
      const Real inverse = 1 / len;
      const Real p0 = ui * local[0][i] + uj * local[0][j];
      const Real p1 = ui * local[1][i] + uj * local[1][j];
      const Real p2 = ui * local[2][i] + uj * local[2][j];
      const Real radius = h[i] * std::abs(ui) + h[j] * std::abs(uj);
      const Real plus = (std::max({p0, p1, p2}) + radius) * inverse;
      const Real minus = (radius - std::min({p0, p1, p2})) * inverse;
      separation = std::max(separation, -std::min(plus, minus));
      if (separation > margin) return false;
      if (plus < best_edge.overlap || minus < best_edge.overlap) {
        // The normal as the general loop makes it, from the world's edge: exactly across the
        // box's edges even when the axes are orthonormal to single precision only (an engine's
        // rotation), where A u would lean by ~1e-7 and edge_contacts could miss the edge pair.
        const Vec3 world = box.axes.col(k).cross(tri.v[kNext[t]] - tri.v[t]);
        const Real world_length = world.norm();
        if (!(world_length > 0)) continue;
        const Vec3 n = world / world_length;
        consider(best_edge, {n, plus, AxisKind::kEdges, k, t});
        consider(best_edge, {-n, minus, AxisKind::kEdges, k, t});
      }
    }
  }
  return true;
}

}  // namespace

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
  if (shape.kind == Polytope::Kind::kBox) {
    if (!box_axes(shape, tri, margin, center_side, best_face, best_tri_face, best_edge, separation)) return 0;
  } else if (!tri.degenerate) {
    const auto [up, down] = overlaps_both_ways(tri.normal);
    separation = std::max(separation, -std::min(up, down));
    // Whichever side the shape's centre is on.
    const Real sigma = center_side >= 0 ? 1 : -1;
    consider(best_tri_face, {sigma * tri.normal, sigma > 0 ? up : down, AxisKind::kTriangleFace, 0, 0});
  }
  // Apart by more than the margin along any axis: no contact, the other axes need not be tried
  // (most candidates of a query volume are apart along the triangle's normal or a face's).
  if (separation > margin) return 0;
  if (shape.face_columns) {
    // The loop below over face_columns: per face the triangle's corners on the inward normal
    // (the dot products of project(tri, n) in their order), their least and greatest, and the
    // two overlaps, with the same operations, then the same decisions face by face.
    const int faces = shape.face_count;
    const Real* nx = shape.face_columns;
    const Real* ny = nx + faces;
    const Real* nz = ny + faces;
    const Real* lo = nz + faces;
    const Real* hi = lo + faces;
    const Vec3& a = tri.v[0];
    const Vec3& b = tri.v[1];
    const Vec3& c = tri.v[2];
    const auto decide = [&](int f, Real along, Real reverse) {
      separation = std::max(separation, -std::min(along, reverse));
      if (along < best_face.overlap) best_face = {-shape.faces[f].normal, along, AxisKind::kShapeFace, f, 0};
      return separation > margin;
    };
    int f = 0;
#if defined(__SSE2__)
    // Faces f and f + 1 in the two lanes; std::max(p, q) is maxpd(q, p), std::min(p, q) minpd(q, p).
    const auto along_axis = [&](const Vec3& v, int at) {
      const __m128d xy = _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(nx + at), _mm_set1_pd(v[0])),
                                    _mm_mul_pd(_mm_loadu_pd(ny + at), _mm_set1_pd(v[1])));
      return _mm_add_pd(xy, _mm_mul_pd(_mm_loadu_pd(nz + at), _mm_set1_pd(v[2])));
    };
    for (; f + 1 < faces; f += 2) {
      const __m128d pa = along_axis(a, f);
      const __m128d pb = along_axis(b, f);
      const __m128d pc = along_axis(c, f);
      const __m128d top = _mm_max_pd(pc, _mm_max_pd(pb, pa));
      const __m128d bottom = _mm_min_pd(pc, _mm_min_pd(pb, pa));
      alignas(16) Real along[2];
      alignas(16) Real reverse[2];
      _mm_store_pd(along, _mm_sub_pd(top, _mm_loadu_pd(lo + f)));
      _mm_store_pd(reverse, _mm_sub_pd(_mm_loadu_pd(hi + f), bottom));
      if (decide(f, along[0], reverse[0]) || decide(f + 1, along[1], reverse[1])) return 0;
    }
#endif
    for (; f < faces; ++f) {
      const Real pa = (nx[f] * a[0] + ny[f] * a[1]) + nz[f] * a[2];
      const Real pb = (nx[f] * b[0] + ny[f] * b[1]) + nz[f] * b[2];
      const Real pc = (nx[f] * c[0] + ny[f] * c[1]) + nz[f] * c[2];
      if (decide(f, std::max(std::max(pa, pb), pc) - lo[f], hi[f] - std::min(std::min(pa, pb), pc))) return 0;
    }
  } else {
    for (int f = 0; f < shape.face_count && shape.kind != Polytope::Kind::kBox; ++f) {
      const Vec3 n = -shape.faces[f].normal;
      const auto [ov, reverse] = overlaps_both_ways_on_face(f, n);
      separation = std::max(separation, -std::min(ov, reverse));
      if (separation > margin) return 0;
      consider(best_face, {n, ov, AxisKind::kShapeFace, f, 0});
    }
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
    // Edge k against triangle edge j, given cone_dot[c] = edges[j] . cone[c] and
    // dn = d . tri.normal (0 for a degenerate triangle: it has no sides, every pair in the
    // shape's cone is kept): the cone test inline, the pairs that pass (a few per edge of the
    // triangle) in edge_axis. True when the pair's axis separates by more than the margin.
    const auto edge_axis = [&](int k, int j, Real sign) {
      const Vec3 d = shape.vertices[shape.edge_to[k]] - shape.vertices[shape.edge_from[k]];
      const Vec3 u = sign * d.cross(edges[j]);
      const Real len = u.norm();
      // Nearly parallel edges: the cross is mostly rounding; the face axes cover that case.
      if (!(len > 1e-6 * edges[j].norm() * d.norm())) return false;
      const Vec3 n = -u / len;
      // The cone test put -n (the shape's outward normal here) in edge k's cone: the edge is
      // the shape's support along -n, and its corner gives the shape's projection.
      const Real overlap = project(tri, n).hi - n.dot(shape.vertices[shape.edge_from[k]]);
      separation = std::max(separation, -overlap);
      if (separation > margin) return true;
      consider(best_edge, {n, overlap, AxisKind::kEdges, k, j, true});
      return false;
    };
    const auto edge_pair = [&](int k, int j, Real cone0, Real cone1, Real cone2, Real dn) {
      const Real sign = cone0 < 0 ? Real(-1) : Real(1);
      if (sign * cone1 < 0 || sign * cone2 < 0 || sign * dn < 0) return false;
      return edge_axis(k, j, sign);
    };
    int k = 0;
#if defined(__SSE2__)
    if (shape.edge_columns) {
      // Edges k and k + 1 in the two lanes, from edge_columns: the same dot products as below
      // ((x0 y0 + x1 y1) + x2 y2) and the same cone test as edge_pair, as a mask: sign * x < 0 is
      // x > 0 when sign = -1 (edges[j] . cone[0] < 0) and x < 0 when sign = 1 (both false for
      // NaN, as the scalar comparisons). The pairs that pass go to edge_axis in the same order.
      const int edge_total = shape.edge_count;
      const Real* columns = shape.edge_columns;
      const auto dot2 = [&](int row, const Vec3& v) {
        const Real* at = columns + row * edge_total + k;
        const __m128d xy = _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(at), _mm_set1_pd(v[0])),
                                      _mm_mul_pd(_mm_loadu_pd(at + edge_total), _mm_set1_pd(v[1])));
        return _mm_add_pd(xy, _mm_mul_pd(_mm_loadu_pd(at + 2 * edge_total), _mm_set1_pd(v[2])));
      };
      const __m128d zero = _mm_setzero_pd();
      for (; k + 1 < edge_total; k += 2) {
        const __m128d dn = tri.degenerate ? zero : dot2(0, tri.normal);
        const __m128d dn_above = _mm_cmpgt_pd(dn, zero);
        const __m128d dn_below = _mm_cmplt_pd(dn, zero);
        int keep[3];
        alignas(16) Real first[3][2];  // [j][lane]: edges[j] . cone[0], whose sign is the pair's
        for (int j = 0; j < 3; ++j) {
          const __m128d c0 = dot2(3, edges[j]);
          const __m128d c1 = dot2(6, edges[j]);
          const __m128d c2 = dot2(9, edges[j]);
          const __m128d flip = _mm_cmplt_pd(c0, zero);
          const __m128d above = _mm_or_pd(_mm_or_pd(_mm_cmpgt_pd(c1, zero), _mm_cmpgt_pd(c2, zero)), dn_above);
          const __m128d below = _mm_or_pd(_mm_or_pd(_mm_cmplt_pd(c1, zero), _mm_cmplt_pd(c2, zero)), dn_below);
          keep[j] = ~_mm_movemask_pd(_mm_or_pd(_mm_and_pd(flip, above), _mm_andnot_pd(flip, below))) & 3;
          _mm_store_pd(first[j], c0);
        }
        if ((keep[0] | keep[1] | keep[2]) == 0) continue;
        for (int lane = 0; lane < 2; ++lane) {
          for (int j = 0; j < 3; ++j) {
            if (((keep[j] >> lane) & 1) && edge_axis(k + lane, j, first[j][lane] < 0 ? Real(-1) : Real(1))) return 0;
          }
        }
      }
    }
#endif
    for (; k < shape.edge_count; ++k) {
      const Vec3* cone = shape.edge_cone + 3 * k;
      const Vec3 d = shape.vertices[shape.edge_to[k]] - shape.vertices[shape.edge_from[k]];
      const Real dn = tri.degenerate ? Real(0) : d.dot(tri.normal);
      for (int j = 0; j < 3; ++j) {
        if (edge_pair(k, j, edges[j].dot(cone[0]), edges[j].dot(cone[1]), edges[j].dot(cone[2]), dn)) return 0;
      }
    }
  } else if (shape.kind != Polytope::Kind::kBox) {
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
  // The triangle's face contacts below -margin are dropped by the filter at the end and read by
  // nothing else but `reaches` (the deepest of all): when that is not asked (all_depths false)
  // and the scratch cannot fill up (so that they cannot take the place of later ones), they are
  // not made at all.
  const bool scratch_holds_all = shape.vertex_count + 3 * shape.edge_count + 3 <= kScratchContacts;
  const auto generate = [&](const Axis& axis, bool all_depths = false) {
    switch (axis.kind) {
      case AxisKind::kTriangleFace:
        return triangle_face_contacts(shape, tri, axis.normal, slack,
                                      all_depths || !scratch_holds_all ? -kInf : -margin, scratch.data());
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
    count = generate(chosen, true);
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

}  // namespace detail

using namespace detail;  // the narrowphase's helpers (contact_internal.h, contact_polytope.h)

BoxTriangleContacts::BoxTriangleContacts(const Obb& box)
    : valid_(box.center.allFinite() && box.axes.allFinite() && box.half_extents.allFinite()),
      polytope_(polytope_of_box(box, arrays_)) {}

int BoxTriangleContacts::operator()(const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options,
                                    ContactPoint* out) const {
  if (!valid_ || !finite(a, b, c)) return 0;
  return polytope_triangle(polytope_, TriangleFrame(a, b, c), options, kMaxBoxTriangleContacts, out);
}

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

int contact_polyhedron_triangle(const ConvexPolyhedron& polyhedron, const Vec3& a, const Vec3& b, const Vec3& c,
                                const ContactOptions& options, ContactPoint* out) {
  if (!finite(a, b, c) || polyhedron.vertices.empty() || !polyhedron.center.allFinite()) return 0;
  return polytope_triangle(polytope_of_polyhedron(polyhedron), TriangleFrame(a, b, c), options,
                           kMaxPolyhedronTriangleContacts, out);
}

int contact_polyhedron_triangle(const ConvexPolyhedron& local, const RigidTransform& mesh_from_local, const Vec3& a,
                                const Vec3& b, const Vec3& c, const ContactOptions& options, ContactPoint* out) {
  const Mat3& r = mesh_from_local.rotation;
  const Vec3& t = mesh_from_local.translation;
  const Mat3 local_from_mesh = r.transpose();
  const Vec3 la = local_from_mesh * (a - t);
  const Vec3 lb = local_from_mesh * (b - t);
  const Vec3 lc = local_from_mesh * (c - t);
  // A reflection reverses the winding, so the corners trade places to keep the triangle's front.
  const bool mirrored = r.determinant() < 0;
  const int n = contact_polyhedron_triangle(local, la, mirrored ? lc : lb, mirrored ? lb : lc, options, out);
  for (int i = 0; i < n; ++i) {
    out[i].position = r * out[i].position + t;
    out[i].normal = r * out[i].normal;
  }
  return n;
}

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

}  // namespace boxtree
