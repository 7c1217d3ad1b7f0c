// SPDX-License-Identifier: MIT
#include "boxtree/collide.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "boxtree/detail/volume_kinds.h"
#include "query_internal.h"

namespace boxtree {

bool is_rotation(const Mat3& rotation, Real tolerance) {
  if (!rotation.allFinite()) return false;
  const Mat3 gram = rotation.transpose() * rotation;
  return (gram - Mat3::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         std::abs(rotation.determinant() - 1) <= tolerance;
}

namespace {

// The tree-vs-tree walk over two views of the same kind (query_internal.h: detail::TreeView for
// Tree<V>, detail::PackedPrismView for PackedPrismTree).
template <class View>
void collide_views(const View& a, const View& b, const RigidTransform& a_from_b,
                   FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  if (!a_from_b.translation.allFinite() || !is_rotation(a_from_b.rotation, 1e-6))
    throw Error("collide: the transform's rotation is not orthonormal with determinant +1, or not finite");
  QueryStats local;
  if (a.empty() || b.empty()) return;
  const TriangleMesh& mesh_a = a.mesh();
  const TriangleMesh& mesh_b = b.mesh();

  using Node = typename View::Node;
  struct NodePair {
    Node a, b;
  };
  // Each step pops one pair and pushes at most two, and the depth of a pair is at most the sum of
  // the two heights, so the stack never holds more than height(a) + height(b) + 2 pairs: a fixed array, no allocation.
  NodePair stack[2 * Tree<Aabb>::kMaxHeight + 4];
  int top = 0;
  ++local.volume_tests;
  if (overlaps(a.volume(a.root()), b.volume(b.root()), a_from_b)) stack[top++] = {a.root(), b.root()};
  bool stop = false;
  while (top > 0 && !stop) {
    const NodePair pair = stack[--top];
    ++local.nodes_visited;
    const bool leaf_a = a.is_leaf(pair.a);
    const bool leaf_b = b.is_leaf(pair.b);
    if (leaf_a && leaf_b) {
      const FacetId fa = a.facet(pair.a);
      const FacetId fb = b.facet(pair.b);
      ++local.leaf_tests;
      if (detail::facets_intersect(mesh_a, fa, mesh_b, fb, a_from_b)) {
        if (!visit(FacetPair{fa, fb}) || settings.stop_at_first) stop = true;
      }
      continue;
    }
    // The pair's volumes: references into a Tree, decoded prisms for the packed form (once per pair).
    const auto& volume_a = a.volume(pair.a);
    const auto& volume_b = b.volume(pair.b);
    // Split the larger volume (or the one that is not a leaf).
    const bool split_a = !leaf_a && (leaf_b || surface_area(volume_a) >= surface_area(volume_b));
    if (split_a) {
      const auto c = a.children(pair.a);
      local.volume_tests += 2;
      if (overlaps(a.volume(c[1]), volume_b, a_from_b)) stack[top++] = {c[1], pair.b};
      if (overlaps(a.volume(c[0]), volume_b, a_from_b)) stack[top++] = {c[0], pair.b};
    } else {
      const auto c = b.children(pair.b);
      local.volume_tests += 2;
      if (overlaps(volume_a, b.volume(c[1]), a_from_b)) stack[top++] = {pair.a, c[1]};
      if (overlaps(volume_a, b.volume(c[0]), a_from_b)) stack[top++] = {pair.a, c[0]};
    }
  }
  if (stats) *stats += local;
}

}  // namespace

template <class Volume>
void collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  collide_views(detail::TreeView<Volume>{a}, detail::TreeView<Volume>{b}, a_from_b, visit, stats, settings);
}

template <class Volume>
std::vector<FacetPair> collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
                               QueryStats* stats, const CollideSettings& settings) {
  return detail::collect_sorted<FacetPair>(
      [&](auto visit) { collide<Volume>(a, b, a_from_b, visit, stats, settings); });
}

#define BOXTREE_INSTANTIATE_COLLIDE(V)                                                                                 \
  template void collide<V>(const Tree<V>&, const Tree<V>&, const RigidTransform&, FunctionRef<bool(const FacetPair&)>, \
                           QueryStats*, const CollideSettings&);                                                       \
  template std::vector<FacetPair> collide<V>(const Tree<V>&, const Tree<V>&, const RigidTransform&, QueryStats*,       \
                                             const CollideSettings&);
BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_COLLIDE)

void collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  collide_views(detail::PackedPrismView{a}, detail::PackedPrismView{b}, a_from_b, visit, stats, settings);
}

std::vector<FacetPair> collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
                               QueryStats* stats, const CollideSettings& settings) {
  return detail::collect_sorted<FacetPair>([&](auto visit) { collide(a, b, a_from_b, visit, stats, settings); });
}

}  // namespace boxtree
