// SPDX-License-Identifier: MIT
#pragma once
// Pieces shared by the query files (query.cpp, collide.cpp, walks.h, the packed trees); not public API.
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/query.h"
#include "internal.h"

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
  return boxtree::triangles_intersect(mesh_a.corner(fa, 0), mesh_a.corner(fa, 1), mesh_a.corner(fa, 2),
                                      a_from_b.apply(mesh_b.corner(fb, 0)), a_from_b.apply(mesh_b.corner(fb, 1)),
                                      a_from_b.apply(mesh_b.corner(fb, 2)));
}

// facets_intersect for the leaf pairs of one tree-vs-tree walk, which meet the same facets again
// and again (a leaf of one tree against the leaves of a subtree of the other, neighbouring leaves
// against the same ones): the facets of each side are kept prepared (b's corners moved into a's
// frame, bounding box, plane) in a small cache indexed by facet id, so that a facet met again pays
// nothing for them. The same answers as facets_intersect, from the same rounded values. Holds the
// meshes and the transform by reference.
class FacetPairTest {
 public:
  FacetPairTest(const TriangleMesh& mesh_a, const TriangleMesh& mesh_b, const RigidTransform& a_from_b)
      : mesh_a_(mesh_a), mesh_b_(mesh_b), a_from_b_(a_from_b) {}
  FacetPairTest(const FacetPairTest&) = delete;  // the slots' triangles point into the slots
  FacetPairTest& operator=(const FacetPairTest&) = delete;

  bool operator()(FacetId fa, FacetId fb) {
    SlotA& a = slot_a_[fa % kSlots];
    if (a.facet != fa) {
      a.triangle.reset(mesh_a_.corner(fa, 0), mesh_a_.corner(fa, 1), mesh_a_.corner(fa, 2));
      a.facet = fa;
    }
    SlotB& b = slot_b_[fb % kSlots];
    if (b.facet != fb) {
      for (int k = 0; k < 3; ++k) b.corner[k] = a_from_b_.apply(mesh_b_.corner(fb, k));
      b.triangle.reset(b.corner[0], b.corner[1], b.corner[2]);
      b.facet = fb;
    }
    return triangles_intersect(a.triangle, b.triangle);
  }

 private:
  static constexpr unsigned kSlots = 16;
  static constexpr std::uint64_t kNone = ~std::uint64_t(0);  // no facet id
  struct SlotA {
    std::uint64_t facet = kNone;
    PreparedTriangle triangle;
  };
  struct SlotB {
    std::uint64_t facet = kNone;
    PreparedTriangle triangle;  // of `corner`
    Vec3 corner[3];             // in a's frame
  };
  const TriangleMesh& mesh_a_;
  const TriangleMesh& mesh_b_;
  const RigidTransform& a_from_b_;
  SlotA slot_a_[kSlots];
  SlotB slot_b_[kSlots];
};

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
