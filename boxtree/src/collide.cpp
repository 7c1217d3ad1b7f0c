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
  return (gram - Mat3::Identity()).cwiseAbs().maxCoeff() <= tolerance && std::abs(rotation.determinant() - 1) <= tolerance;
}

template <class Volume>
void collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  if (!a_from_b.translation.allFinite() || !is_rotation(a_from_b.rotation, 1e-6))
    throw Error("collide: the transform's rotation is not orthonormal with determinant +1, or not finite");
  QueryStats local;
  if (a.empty() || b.empty()) return;
  const TriangleMesh& mesh_a = a.mesh();
  const TriangleMesh& mesh_b = b.mesh();

  struct NodePair {
    NodeIndex a, b;
  };
  // Each step pops one pair and pushes at most two, and the depth of a pair is at most the sum of
  // the two heights, so the stack never holds more than height(a) + height(b) + 2 pairs: a fixed array, no allocation.
  NodePair stack[2 * Tree<Volume>::kMaxHeight + 4];
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
    // Split the larger volume (or the one that is not a leaf).
    const bool split_a =
        !leaf_a && (leaf_b || surface_area(a.volume(pair.a)) >= surface_area(b.volume(pair.b)));
    if (split_a) {
      const NodeIndex c = a.first_child(pair.a);
      local.volume_tests += 2;
      if (overlaps(a.volume(c + 1), b.volume(pair.b), a_from_b)) stack[top++] = {c + 1, pair.b};
      if (overlaps(a.volume(c), b.volume(pair.b), a_from_b)) stack[top++] = {c, pair.b};
    } else {
      const NodeIndex c = b.first_child(pair.b);
      local.volume_tests += 2;
      if (overlaps(a.volume(pair.a), b.volume(c + 1), a_from_b)) stack[top++] = {pair.a, c + 1};
      if (overlaps(a.volume(pair.a), b.volume(c), a_from_b)) stack[top++] = {pair.a, c};
    }
  }
  if (stats) *stats += local;
}

template <class Volume>
std::vector<FacetPair> collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
                               QueryStats* stats, const CollideSettings& settings) {
  return detail::collect_sorted<FacetPair>(
      [&](auto visit) { collide<Volume>(a, b, a_from_b, visit, stats, settings); });
}

#define BOXTREE_INSTANTIATE_COLLIDE(V)                                                                     \
  template void collide<V>(const Tree<V>&, const Tree<V>&, const RigidTransform&,                            \
                           FunctionRef<bool(const FacetPair&)>, QueryStats*, const CollideSettings&);        \
  template std::vector<FacetPair> collide<V>(const Tree<V>&, const Tree<V>&, const RigidTransform&, QueryStats*, \
                                             const CollideSettings&);
BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_COLLIDE)

}  // namespace boxtree
