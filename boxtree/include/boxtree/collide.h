// SPDX-License-Identifier: MIT
#pragma once
// Tree vs tree: every pair of intersecting facets of two meshes under a relative rigid motion.
#include <vector>

#include "boxtree/query.h"

namespace boxtree {

struct FacetPair {
  FacetId a = 0;  // facet of tree a
  FacetId b = 0;  // facet of tree b
  bool operator==(const FacetPair& o) const { return a == o.a && b == o.b; }
  bool operator<(const FacetPair& o) const { return a != o.a ? a < o.a : b < o.b; }
};

struct CollideSettings {
  bool stop_at_first = false;  // early out: report one intersecting pair and stop
};

// Descends both trees, always splitting the node with the larger volume (surface area), tests
// volume pairs exactly (separating axes in a's frame) and runs the exact triangle-triangle test
// (triangles_intersect: touching counts) only at leaf pairs, on a's corners and b's corners moved
// by a_from_b.apply: exact at the identity (a mesh against itself reports every pair of facets
// that share a corner), else exact on the rounded moved corners. `a_from_b` maps b's frame to a's;
// its rotation must be orthonormal (checked: throws boxtree::Error if not, or if not finite).
// `visit` returns false to stop.
template <class Volume>
void collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats = nullptr,
             const CollideSettings& settings = {});

// Convenience: all pairs (or the first, with stop_at_first), sorted.
template <class Volume>
std::vector<FacetPair> collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
                               QueryStats* stats = nullptr, const CollideSettings& settings = {});

// True if `rotation` is orthonormal with determinant +1, within `tolerance`.
bool is_rotation(const Mat3& rotation, Real tolerance = 1e-9);

}  // namespace boxtree
