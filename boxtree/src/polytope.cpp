// SPDX-License-Identifier: MIT
// Exact separating-axis test between two small convex polytopes (volume/polytope.h).
//
// Why the candidate axes suffice. P and Q are disjoint iff the origin is outside their Minkowski
// difference M = P - Q, and then some facet plane of M separates (a face normal of M is a
// separating axis). If M is full-dimensional its facets are a 2-face of P or Q plus a vertex of
// the other, or an edge of P plus a non-parallel edge of Q; so the face normals of both and the
// edge cross products are enough (Gottschalk, Lin, Manocha, "OBBTree", SIGGRAPH 1996; Ericson,
// Real-Time Collision Detection, 4.4). When both are flat (rectangles, triangles, segments,
// points), M can lie in a plane with normal n, or on a line, or be a point. Then the separating
// axes are n itself (a face normal or an edge cross product) and, in the plane, a vector
// perpendicular to each edge of M (edges of M are edges of P or Q) but not parallel to n. The
// volumes' polytope_of() supply, for every edge, face normals spanning the plane normal to that
// edge (boxes: all three axes; prisms: the axis, the side normals and the cap direction along
// the base's longest edge, see volume_prism.cpp), so the axes above are also enough for the
// flat and degenerate cases, in exact arithmetic.
//
// Rounding. Every axis is used as it was computed, so a noisy axis (the cross product of nearly
// parallel edges) is still a valid axis: separation along it is real as long as the projections
// themselves are accurate, which the padding below guarantees. What rounding can cost is
// tightness: when two flat polytopes are nearly coplanar, M is a thin slab whose side facets
// are crosses of nearly parallel edges and meet at sharp ridges, so a small in-plane gap shows
// up as an even smaller gap along those normals. For that case the test also projects on n x e
// for every edge e of both, where n is a direction along which both are thin: these axes are
// exactly the edge normals of the two shadows in the plane normal to n, and disjoint shadows
// mean disjoint polytopes, whatever the thickness.
#include <algorithm>
#include <cmath>
#include <limits>

#include "boxtree/volume/polytope.h"

namespace boxtree {
namespace {

// The projections are padded by kSatEps * |axis|_1 * (R + |o|), with R the largest offset of a
// vertex from the common origin o of the projections (the polytopes' size and distance) and |o|
// the magnitude of the coordinates (which bounds the rounding of the vertices themselves). A dot
// product of n terms is accurate to n * eps * |axis|_1 * |v|_inf, so 1e-12 leaves a margin of
// over 1000 on the computation and on the rounding of corners and transforms upstream.
constexpr Real kSatEps = 1e-12;
// A direction along which both polytopes are this thin (relative to R) triggers the in-plane
// axes described above. Any value is sound; larger ones only cost a few more axes in more
// cases. 1e-3 keeps the ridge loss (about kSatEps / thickness, relative) below 1e-9.
constexpr Real kThin = 1e-3;
constexpr int kMaxThinNormals = 3;

struct Interval {
  Real lo;
  Real hi;
};

Interval project(const ConvexPolytope& p, const Vec3& axis, const Vec3& origin) {
  Interval r{std::numeric_limits<Real>::infinity(), -std::numeric_limits<Real>::infinity()};
  for (int i = 0; i < p.vertex_count; ++i) {
    const Real x = axis.dot(p.vertices[i] - origin);
    r.lo = std::min(r.lo, x);
    r.hi = std::max(r.hi, x);
  }
  return r;
}

struct SatContext {
  const ConvexPolytope& a;
  const ConvexPolytope& b;
  Vec3 origin;
  Real scale;  // R + |o|
  std::array<Vec3, kMaxThinNormals> thin;
  int thin_count = 0;

  // True if `axis` separates (by more than the padding). Zero (or NaN) axes never separate.
  bool separates(const Vec3& axis, bool record_thin) {
    const Real length = axis.cwiseAbs().sum();
    if (!(length > 0)) return false;
    const Real pad = kSatEps * length * scale;
    const Interval ia = project(a, axis, origin);
    const Interval ib = project(b, axis, origin);
    if (ia.lo > ib.hi + pad || ib.lo > ia.hi + pad) return true;
    if (record_thin && thin_count < kMaxThinNormals && (ia.hi - ia.lo) + (ib.hi - ib.lo) <= kThin * length * scale) {
      thin[thin_count++] = axis;
    }
    return false;
  }
};

}  // namespace

ConvexPolytope ConvexPolytope::transformed(const RigidTransform& a_from_b) const {
  ConvexPolytope r;
  r.vertex_count = vertex_count;
  r.face_count = face_count;
  r.edge_count = edge_count;
  for (int i = 0; i < vertex_count; ++i) r.vertices[i] = a_from_b.apply(vertices[i]);
  for (int i = 0; i < face_count; ++i) r.face_normals[i] = a_from_b.rotation * face_normals[i];
  for (int i = 0; i < edge_count; ++i) r.edge_directions[i] = a_from_b.rotation * edge_directions[i];
  return r;
}

bool sat_overlap(const ConvexPolytope& a, const ConvexPolytope& b) {
  if (a.vertex_count == 0 || b.vertex_count == 0) return false;
  SatContext sat{a, b, a.vertices[0], 0, {}, 0};
  // Invalid input (NaN or infinite coordinates, e.g. from a bad transform) overlaps nothing.
  Real reach = 0;
  for (int i = 0; i < a.vertex_count; ++i) {
    if (!a.vertices[i].allFinite()) return false;
    reach = std::max(reach, (a.vertices[i] - sat.origin).cwiseAbs().maxCoeff());
  }
  for (int i = 0; i < b.vertex_count; ++i) {
    if (!b.vertices[i].allFinite()) return false;
    reach = std::max(reach, (b.vertices[i] - sat.origin).cwiseAbs().maxCoeff());
  }
  sat.scale = reach + sat.origin.cwiseAbs().maxCoeff();

  for (int i = 0; i < a.face_count; ++i) {
    if (sat.separates(a.face_normals[i], true)) return false;
  }
  for (int i = 0; i < b.face_count; ++i) {
    if (sat.separates(b.face_normals[i], true)) return false;
  }
  for (int i = 0; i < a.edge_count; ++i) {
    for (int j = 0; j < b.edge_count; ++j) {
      if (sat.separates(a.edge_directions[i].cross(b.edge_directions[j]), true)) return false;
    }
  }
  // Nearly coplanar flat polytopes: the shadows' edge normals (see the top of the file).
  for (int k = 0; k < sat.thin_count; ++k) {
    const Vec3 n = sat.thin[k];
    for (int i = 0; i < a.edge_count; ++i) {
      if (sat.separates(n.cross(a.edge_directions[i]), false)) return false;
    }
    for (int j = 0; j < b.edge_count; ++j) {
      if (sat.separates(n.cross(b.edge_directions[j]), false)) return false;
    }
  }
  return true;
}

}  // namespace boxtree
