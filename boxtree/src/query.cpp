// SPDX-License-Identifier: MIT
#include "boxtree/query.h"

#include <algorithm>

#include "boxtree/detail/volume_kinds.h"
#include "query_internal.h"
#include "walks.h"

namespace boxtree {

using detail::all_hits_of;
using detail::candidates_of;
using detail::closest_hit_of;
using detail::overlap_of;
using detail::plane_of;
using detail::StatsSink;
using detail::TreeView;
using detail::walk;

template <class Volume>
std::optional<RayHit> ray_closest_hit(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats) {
  return closest_hit_of(TreeView<Volume>{tree}, ray, stats);
}

template <class Volume>
void ray_candidates(const Tree<Volume>& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats) {
  candidates_of(TreeView<Volume>{tree}, ray, visit, stats);
}

template <class Volume>
void ray_all_hits(const Tree<Volume>& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit, QueryStats* stats) {
  all_hits_of(TreeView<Volume>{tree}, ray, visit, stats);
}

template <class Volume>
std::optional<RayHit> ray_any_hit(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats) {
  return detail::first_hit([&](auto visit) { ray_all_hits<Volume>(tree, ray, visit, stats); });
}

template <class Volume>
std::vector<RayHit> ray_all_hits(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats) {
  return detail::collect_sorted<RayHit>([&](auto visit) { ray_all_hits<Volume>(tree, ray, visit, stats); },
                                        detail::nearer_hit);
}

template <class Volume, class Shape>
void query_overlap(const Tree<Volume>& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                   FacetTest test) {
  overlap_of(TreeView<Volume>{tree}, shape, visit, stats, test);
}

template <class Volume, class Shape>
std::vector<FacetId> query_overlap(const Tree<Volume>& tree, const Shape& shape, QueryStats* stats, FacetTest test) {
  return detail::collect_sorted<FacetId>(
      [&](auto visit) { query_overlap<Volume, Shape>(tree, shape, visit, stats, test); });
}

template <class Volume>
void query_plane(const Tree<Volume>& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit, QueryStats* stats) {
  plane_of(TreeView<Volume>{tree}, plane, visit, stats);
}

template <class Volume>
std::vector<FacetId> query_plane(const Tree<Volume>& tree, const Plane& plane, QueryStats* stats) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_plane<Volume>(tree, plane, visit, stats); });
}

template <class Volume>
std::size_t stabbing_count(const Tree<Volume>& tree, const Vec3& point, QueryStats* stats) {
  StatsSink sink(stats);
  // Every node passed by the walk contains the point, inner nodes included: count them all.
  const std::uint64_t before = sink.local.nodes_visited;
  walk(
      TreeView<Volume>{tree}, [&](const Volume& v) { return contains(v, point); }, [](FacetId) { return true; },
      sink.local);
  return std::size_t(sink.local.nodes_visited - before);
}

#define BOXTREE_INSTANTIATE_QUERIES(V)                                                                        \
  template std::optional<RayHit> ray_closest_hit<V>(const Tree<V>&, const Ray&, QueryStats*);                 \
  template void ray_candidates<V>(const Tree<V>&, const Ray&, FunctionRef<Real(FacetId, Real)>, QueryStats*); \
  template std::optional<RayHit> ray_any_hit<V>(const Tree<V>&, const Ray&, QueryStats*);                     \
  template void ray_all_hits<V>(const Tree<V>&, const Ray&, FunctionRef<bool(const RayHit&)>, QueryStats*);   \
  template std::vector<RayHit> ray_all_hits<V>(const Tree<V>&, const Ray&, QueryStats*);                      \
  template void query_plane<V>(const Tree<V>&, const Plane&, FunctionRef<bool(FacetId)>, QueryStats*);        \
  template std::vector<FacetId> query_plane<V>(const Tree<V>&, const Plane&, QueryStats*);                    \
  template std::size_t stabbing_count<V>(const Tree<V>&, const Vec3&, QueryStats*);                           \
  BOXTREE_INSTANTIATE_OVERLAP(V, Aabb)                                                                        \
  BOXTREE_INSTANTIATE_OVERLAP(V, Obb)                                                                         \
  BOXTREE_INSTANTIATE_OVERLAP(V, Sphere)                                                                      \
  BOXTREE_INSTANTIATE_OVERLAP(V, Capsule)

#define BOXTREE_INSTANTIATE_OVERLAP(V, S)                                                                          \
  template void query_overlap<V, S>(const Tree<V>&, const S&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest); \
  template std::vector<FacetId> query_overlap<V, S>(const Tree<V>&, const S&, QueryStats*, FacetTest);

BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_QUERIES)

}  // namespace boxtree
