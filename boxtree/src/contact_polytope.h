// SPDX-License-Identifier: MIT
#pragma once
// The convex-polytope description of the separating-axis narrowphase (contact_sat.cpp): boxes,
// convex polyhedra and triangles (triangle a of a triangle pair) seen the same way. Not part of
// the public API.
#include "boxtree/convex_polyhedron.h"
#include "contact_internal.h"

namespace boxtree::detail {

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
  // Polyhedra: ConvexPolyhedron's vertex_columns, face_columns and edge_columns (null when they
  // do not match the counts); the loops over all corners, faces and edge cones read these.
  const Real* vertex_columns = nullptr;
  const Real* face_columns = nullptr;
  const Real* edge_columns = nullptr;

  PolytopeFace face(int f) const {
    return {faces[f].normal, faces[f].offset, face_begin[f + 1] - face_begin[f], sides + face_begin[f]};
  }

  // The closest point of the polytope to a point outside it (of its surface, for a polyhedron:
  // over the faces cut into fans of triangles).
  Vec3 closest_point(const Vec3& x) const;
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

// The descriptions of a box and a triangle (their arrays in `arrays`) and of a polyhedron (its
// own arrays). Defined in contact_polytope.cpp.
Polytope polytope_of_box(const Obb& box, PolytopeArrays& arrays);
Polytope polytope_of_triangle(const TriangleFrame& tri, PolytopeArrays& arrays);
Polytope polytope_of_polyhedron(const ConvexPolyhedron& polyhedron);

// contact_box_triangle (contact.h) for one box against many triangles (a midphase's candidates):
// the box's polytope is built once, by the constructor. It points into this object's own arrays,
// so the object is neither copied nor moved. Defined in contact_sat.cpp.
class BoxTriangleContacts {
 public:
  explicit BoxTriangleContacts(const Obb& box);
  BoxTriangleContacts(const BoxTriangleContacts&) = delete;
  BoxTriangleContacts& operator=(const BoxTriangleContacts&) = delete;
  int operator()(const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options, ContactPoint* out) const;

 private:
  bool valid_;
  PolytopeArrays arrays_;
  Polytope polytope_;
};

// Contacts of a convex polytope against a triangle by separating axes (at most max_contacts,
// written to `out`; contact.h's conventions). Defined in contact_sat.cpp.
int polytope_triangle(const Polytope& shape, const TriangleFrame& tri, const ContactOptions& options, int max_contacts,
                      ContactPoint* out);

}  // namespace boxtree::detail
