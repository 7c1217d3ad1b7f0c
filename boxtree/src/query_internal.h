// SPDX-License-Identifier: MIT
#pragma once
// Pieces shared by the query files (query.cpp, collide.cpp, walks.h, the packed trees); not public API.
#include <algorithm>
#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/query.h"

namespace boxtree::detail {

// How the walks (walks.h) see a binary hierarchy, its View: a handle per node, whether it is a
// leaf, its facet or its two children, and its volume. One walk then serves Tree<V> (TreeView:
// the stored volume, by reference) and a packed form (packed_prism_tree.cpp's PackedPrismView: a
// decoded prism, by value), so the compact form answers with the very code of the exact one.
template <class Volume>
struct TreeView {
  using Node = NodeIndex;
  const Tree<Volume>& tree;

  bool empty() const { return tree.empty(); }
  const TriangleMesh& mesh() const { return tree.mesh(); }
  Node root() const { return tree.root(); }
  bool is_leaf(Node node) const { return tree.is_leaf(node); }
  FacetId facet(Node node) const { return tree.facet(node); }
  std::array<Node, 2> children(Node inner) const {
    const Node first = tree.first_child(inner);
    return {first, first + 1};
  }
  const Volume& volume(Node node) const { return tree.volume(node); }
};

// Counts a query's work locally and adds it to the caller's QueryStats (if any) when done.
struct StatsSink {
  QueryStats local;
  QueryStats* out;
  explicit StatsSink(QueryStats* o) : out(o) {}
  ~StatsSink() {
    if (out) *out += local;
  }
  StatsSink(const StatsSink&) = delete;
  StatsSink& operator=(const StatsSink&) = delete;
};

// The body of every "convenience" overload: runs `query(visit)` with a visitor that keeps every
// result, and returns them sorted.
template <class T, class Query, class Less = std::less<T>>
std::vector<T> collect_sorted(Query&& query, Less less = {}) {
  std::vector<T> results;
  query([&](const T& x) {
    results.push_back(x);
    return true;
  });
  std::sort(results.begin(), results.end(), less);
  return results;
}

// The leaf test of tree-vs-tree: facet fa of mesh a against facet fb of mesh b, moved into a's
// frame (touching counts).
inline bool facets_intersect(const TriangleMesh& mesh_a, FacetId fa, const TriangleMesh& mesh_b, FacetId fb,
                             const RigidTransform& a_from_b) {
  return triangles_intersect(mesh_a.corner(fa, 0), mesh_a.corner(fa, 1), mesh_a.corner(fa, 2),
                             a_from_b.apply(mesh_b.corner(fb, 0)), a_from_b.apply(mesh_b.corner(fb, 1)),
                             a_from_b.apply(mesh_b.corner(fb, 2)));
}

// The body of ray_any_hit: the first hit that `all_hits(visit)` reports (it stops there).
template <class AllHits>
std::optional<RayHit> first_hit(AllHits&& all_hits) {
  std::optional<RayHit> found;
  all_hits([&](const RayHit& hit) {
    found = hit;
    return false;
  });
  return found;
}

// Ray hits in the order the conveniences return them: by distance, then facet id.
inline bool nearer_hit(const RayHit& x, const RayHit& y) { return x.t != y.t ? x.t < y.t : x.facet < y.facet; }

}  // namespace boxtree::detail
