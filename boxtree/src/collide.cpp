// SPDX-License-Identifier: MIT
#include "boxtree/collide.h"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "boxtree/detail/volume_kinds.h"
#include "query_internal.h"
#include "walks.h"

namespace boxtree {

bool is_rotation(const Mat3& rotation, Real tolerance) {
  if (!rotation.allFinite()) return false;
  const Mat3 gram = rotation.transpose() * rotation;
  return (gram - Mat3::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         std::abs(rotation.determinant() - 1) <= tolerance;
}

template <class Volume>
void collide(const Tree<Volume>& a, const Tree<Volume>& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  detail::collide_views(detail::TreeView<Volume>{a}, detail::TreeView<Volume>{b}, a_from_b, visit, stats, settings);
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

}  // namespace boxtree
