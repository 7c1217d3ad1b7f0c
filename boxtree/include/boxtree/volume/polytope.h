// SPDX-License-Identifier: MIT
#pragma once
// A small convex polytope description shared by every volume kind, for exact separating-axis
// tests between any two kinds (boxes, oriented boxes, prisms, mixed) in one place.
// Candidate axes (Gottschalk et al. 1996; Ericson, Real-Time Collision Detection 4.4): the face
// normals of both, and the cross products of every edge direction of one with every edge
// direction of the other. Degenerate (zero-thickness) polytopes are fine: zero axes are skipped.
#include <array>

#include "boxtree/shapes.h"

namespace boxtree {

struct ConvexPolytope {
  std::array<Vec3, 8> vertices;
  int vertex_count = 0;
  std::array<Vec3, 5> face_normals;  // not necessarily unit length
  int face_count = 0;
  std::array<Vec3, 4> edge_directions;  // one per parallel class, not necessarily unit length
  int edge_count = 0;

  // The same polytope in frame A, given in frame B (x_a = a_from_b(x_b)).
  ConvexPolytope transformed(const RigidTransform& a_from_b) const;
};

// Closed test (touching counts). Conservative by a relative tolerance of about 1e-12 of the
// polytopes' size and distance: it may report polytopes that are that close as overlapping,
// never the reverse.
bool sat_overlap(const ConvexPolytope& a, const ConvexPolytope& b);

}  // namespace boxtree
