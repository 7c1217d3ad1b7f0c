// SPDX-License-Identifier: MIT
#pragma once
// A convex polyhedron prepared for the separating-axis narrowphase (contact_polyhedron_triangle in
// contact.h): its corners, face planes and face polygons, and its edges grouped by direction.
// Engines describe convex hulls this way already (ODE's dCreateConvex takes planes, points and
// polygons); with the faces known, the exact penetration depth of a hull against a triangle is a
// minimum over a finite set of axes, with no GJK/EPA iteration.
//
// Made by make_convex_polyhedron, which checks the description; moved into another frame by
// transform_polyhedron. The fields are what the narrowphase reads; treat them as read-only.
#include <vector>

#include "boxtree/shapes.h"

namespace boxtree {

struct ConvexPolyhedron {
  std::vector<Vec3> vertices;  // the corners that lie on some face
  // Face f: unit outward normal and offset (normal . x == offset on the face, <= inside; the
  // offset is the largest normal . x over the corners: a supporting plane).
  std::vector<Plane> faces;
  // Face f: the polyhedron's extent along the face's normal (offset minus the least normal . x
  // over the corners). With it a face's own axis costs the triangle's three dot products instead
  // of a projection of every corner.
  std::vector<Real> face_width;
  // Face f's corners are loops[face_begin[f] .. face_begin[f + 1]), counter-clockwise seen from
  // outside; sides[k] is the outward half-space of the edge loops[k] -> next corner, within the
  // face's plane (a point of the plane is on the face iff it is inside all of its face's sides).
  std::vector<int> face_begin;
  std::vector<int> loops;
  std::vector<Plane> sides;
  // Every edge once (corner indices) and the class of parallel edges it belongs to.
  std::vector<int> edge_from;
  std::vector<int> edge_to;
  std::vector<int> edge_direction;
  // The edge's normal cone (the normals a1, a2 of the two faces it joins bound it), which tells
  // which edge pairs can be in contact at all: per edge e (direction d = to - from,
  // arc = a1 x a2) three vectors that turn the cone test of d x t against any triangle edge t
  // into dot products with t: (a1 + a2) x d, (arc x a1) x d and (a2 x arc) x d.
  std::vector<Vec3> edge_cone;
  std::vector<Vec3> directions;  // unit, one per class of parallel edges
  Vec3 center = Vec3::Zero();    // mean of the corners: an interior point
  Real size = 0;                 // diagonal of the corners' bounding box
  Real coord = 0;                // largest coordinate magnitude (for rounding tolerances)
  // The numbers the narrowphase's loops over all corners, faces or edges read, again by
  // coordinate (structure of arrays), so that those loops run two or four values at a time:
  // vertex_columns: 3 rows of vertex count, every corner's x, then y, then z; face_columns: 5
  // rows of face count, the inward normal's (-normal) x, y, z, then -offset and
  // -offset + face_width (the polyhedron's projection on the inward normal); edge_columns: 12
  // rows of edge count, to - from (x, y, z), then edge_cone's three vectors (x, y, z each).
  // Filled by make_convex_polyhedron and transform_polyhedron (update_columns).
  std::vector<Real> vertex_columns;
  std::vector<Real> face_columns;
  std::vector<Real> edge_columns;

  int face_count() const { return int(faces.size()); }
};

// A polyhedron from its corners and its faces (each a loop of indices into `points`, either
// winding; each face's orientation is taken from the side the other points are on). Throws
// boxtree::Error, naming the face or point, unless: there are at least 4 points, all finite, and 4
// faces; every index is in range and no face repeats a corner; every face is planar and convex
// and has every point on its inner side (within 1e-6 of the size); every edge is shared by exactly
// two faces (a closed surface); and no face has more than kMaxPolyhedronFaceCorners corners.
// Points on no face (inside) are dropped; the corners are renumbered in order of first use.
constexpr int kMaxPolyhedronFaceCorners = 64;
ConvexPolyhedron make_convex_polyhedron(const std::vector<Vec3>& points, const std::vector<std::vector<int>>& faces);

// `out` = `in` moved by `transform` (x -> rotation * x + translation; rotation orthonormal, a
// reflection too). Reuses out's storage (no allocation once warm), except for a reflection,
// which makes the polyhedron anew. (A hull against many triangles needs no move at all: the
// placed contact_polyhedron_triangle of contact.h takes the triangles into the hull's frame.)
void transform_polyhedron(const ConvexPolyhedron& in, const RigidTransform& transform, ConvexPolyhedron& out);

// Fills vertex_columns, face_columns and edge_columns from the other fields (for a polyhedron
// whose corners, faces or cones were changed by hand).
void update_columns(ConvexPolyhedron& polyhedron);

}  // namespace boxtree
