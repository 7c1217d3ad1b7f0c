// SPDX-License-Identifier: MIT
#pragma once
// Internal edges: a body sliding over a flat or concave part of a mesh must not bump on the
// edges between facets. Per-facet contact routines (contact.h) see one triangle at a time, so a
// shape over facet A that touches the shared edge of facet B gets a tilted edge normal from B.
// The fix (like Bullet's btAdjustInternalEdgeContacts, and Jolt's "active edges"): precompute
// which edges are real, convex creases ("active"), and give contacts that land on an inactive
// edge or vertex the facet's own normal.
#include <cstdint>
#include <vector>

#include "boxtree/contact.h"

namespace boxtree {

// Per facet, bit k (k = 0, 1, 2) set when edge (corner k, corner k+1 mod 3) is active: a boundary
// edge, an edge shared by more than two facets, or one between two facets that fold convexly by
// more than `crease_degrees`. Flat and concave shared edges are inactive. Vertices are welded by
// exact position, so triangle soups (STL) get their adjacency. An edge shared by two facets that
// run along it in the same direction (inconsistent winding: one of them faces the other way)
// cannot be judged and stays active; `inconsistent_edges`, if given, receives how many there are
// (0: every edge of two facets is wound consistently, so facet fronts are meaningful).
std::vector<std::uint8_t> compute_active_edges(const TriangleMesh& mesh, Real crease_degrees = 10,
                                               std::size_t* inconsistent_edges = nullptr);

enum class EdgeContact {
  keep,       // on the face, or on an active edge: unchanged
  corrected,  // on an inactive edge or vertex: now along the face normal
  discard,    // on an inactive edge but pointing along the surface (the shape is beside this
              // facet, over its neighbour, which reports the real contact)
};

// For a contact from a routine of contact.h on the triangle a, b, c: if it lies on an inactive
// edge, or on a vertex whose two edges in this facet are inactive, and its normal is not the face
// normal, either turns it to the face normal on the contact's side (depth projected onto it), or,
// when the normal is more than 60 degrees from the face normal, says to discard it.
EdgeContact correct_internal_edge_contact(ContactPoint& contact, const Vec3& a, const Vec3& b, const Vec3& c,
                                          std::uint8_t active_edges);

// correct_internal_edge_contact for the contacts of one facet, with the facet's normal, size and
// edges worked out once: the same verdicts and the same corrected contacts. The corners must
// outlive it.
class InternalEdgeCorrection {
 public:
  InternalEdgeCorrection(const Vec3& a, const Vec3& b, const Vec3& c, std::uint8_t active_edges);
  EdgeContact operator()(ContactPoint& contact) const;

 private:
  const Vec3* corners_[3];
  std::uint8_t active_edges_;
  bool judged_ = false;  // false: every contact is kept (all edges active, or a degenerate facet)
  Vec3 normal_ = Vec3::Zero();
  Vec3 edges_[3];
  Real edge_squared_[3] = {0, 0, 0};
  Real scale_ = 0;
};

}  // namespace boxtree
