// SPDX-License-Identifier: MIT
#include "boxtree/query.h"

#include <algorithm>

#include "boxtree/detail/volume_kinds.h"
#include "query_internal.h"

namespace boxtree {
namespace {

using detail::PackedPrismView;
using detail::StatsSink;
using detail::TreeView;

constexpr int kStackSize = Tree<Aabb>::kMaxHeight + 2;

// Depth-first walk of every node whose volume passes `node_test`; `leaf` is called for each
// such leaf's facet and returns false to stop the walk. View: detail::TreeView or
// detail::PackedPrismView (query_internal.h).
template <class View, class NodeTest, class Leaf>
void walk(const View& tree, NodeTest&& node_test, Leaf&& leaf, QueryStats& stats) {
  if (tree.empty()) return;
  typename View::Node stack[kStackSize];
  int top = 0;
  ++stats.volume_tests;
  if (!node_test(tree.volume(tree.root()))) return;
  stack[top++] = tree.root();
  while (top > 0) {
    const auto node = stack[--top];
    ++stats.nodes_visited;
    if (tree.is_leaf(node)) {
      if (!leaf(tree.facet(node))) return;
      continue;
    }
    const auto child = tree.children(node);
    stats.volume_tests += 2;
    if (node_test(tree.volume(child[1]))) stack[top++] = child[1];
    if (node_test(tree.volume(child[0]))) stack[top++] = child[0];
  }
}

// Front-to-back walk of the nodes the ray meets within [ray.t_min, t_max]; `leaf(facet, t_max)`
// returns the new t_max, which prunes every node entered farther than it.
template <class View, class Leaf>
void ordered_ray_walk(const View& tree, const Ray& ray, Leaf&& leaf, QueryStats& stats) {
  if (tree.empty() || !is_valid(ray)) return;
  const RayPrecomputed pre(ray);
  Real t_max = ray.t_max;
  struct Entry {
    typename View::Node node;
    Real t_enter;
  };
  Entry stack[kStackSize];
  int top = 0;
  Real t_enter = 0;
  ++stats.volume_tests;
  if (!intersect_ray(tree.volume(tree.root()), pre, ray.t_min, t_max, &t_enter)) return;
  stack[top++] = {tree.root(), t_enter};
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.t_enter > t_max) continue;  // a closer hit was found since this node was pushed
    const auto node = entry.node;
    ++stats.nodes_visited;
    if (tree.is_leaf(node)) {
      t_max = std::min(t_max, leaf(tree.facet(node), t_max));
      if (!(t_max >= ray.t_min)) return;
      continue;
    }
    const auto child = tree.children(node);
    Real t0 = 0, t1 = 0;
    stats.volume_tests += 2;
    const bool hit0 = intersect_ray(tree.volume(child[0]), pre, ray.t_min, t_max, &t0);
    const bool hit1 = intersect_ray(tree.volume(child[1]), pre, ray.t_min, t_max, &t1);
    // Push the farther child first so the nearer one is explored first.
    if (hit0 && hit1) {
      if (t0 <= t1) {
        stack[top++] = {child[1], t1};
        stack[top++] = {child[0], t0};
      } else {
        stack[top++] = {child[0], t0};
        stack[top++] = {child[1], t1};
      }
    } else if (hit0) {
      stack[top++] = {child[0], t0};
    } else if (hit1) {
      stack[top++] = {child[1], t1};
    }
  }
}

// The bodies of the public queries, once for every View.

template <class View>
std::optional<RayHit> closest_hit_of(const View& tree, const Ray& ray, QueryStats* stats) {
  StatsSink sink(stats);
  const TriangleMesh* mesh = tree.empty() ? nullptr : &tree.mesh();
  std::optional<RayHit> best;
  const RayShear shear = ray_shear(ray.direction);
  ordered_ray_walk(
      tree, ray,
      [&](FacetId f, Real t_max) {
        ++sink.local.leaf_tests;
        TriangleHit hit;
        Ray clipped = ray;
        clipped.t_max = t_max;
        if (intersect_ray_triangle(clipped, shear, mesh->corner(f, 0), mesh->corner(f, 1), mesh->corner(f, 2), hit)) {
          if (!best || hit.t < best->t || (hit.t == best->t && f < best->facet)) best = RayHit{f, hit.t, hit.u, hit.v};
        }
        return best ? best->t : t_max;
      },
      sink.local);
  return best;
}

template <class View>
void candidates_of(const View& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit, QueryStats* stats) {
  StatsSink sink(stats);
  ordered_ray_walk(
      tree, ray,
      [&](FacetId f, Real t_max) {
        ++sink.local.leaf_tests;
        return visit(f, t_max);
      },
      sink.local);
}

template <class View>
void all_hits_of(const View& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit, QueryStats* stats) {
  StatsSink sink(stats);
  if (tree.empty() || !is_valid(ray)) return;
  const TriangleMesh& mesh = tree.mesh();
  const RayPrecomputed pre(ray);
  const RayShear shear = ray_shear(ray.direction);
  walk(
      tree, [&](const auto& v) { return intersect_ray(v, pre, ray.t_min, ray.t_max); },
      [&](FacetId f) {
        ++sink.local.leaf_tests;
        TriangleHit hit;
        if (!intersect_ray_triangle(ray, shear, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), hit))
          return true;
        return visit(RayHit{f, hit.t, hit.u, hit.v});
      },
      sink.local);
}

// An invalid shape (shapes.h) matches nothing, in both FacetTest modes: checked here once, so
// that no volume or triangle test has to read a negative radius or an inverted box the same way.
template <class View, class Shape>
void overlap_of(const View& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                FacetTest test) {
  StatsSink sink(stats);
  if (tree.empty() || !is_valid(shape)) return;
  const TriangleMesh& mesh = tree.mesh();
  walk(
      tree, [&](const auto& v) { return overlaps(v, shape); },
      [&](FacetId f) {
        if (test == FacetTest::exact_triangle) {
          ++sink.local.leaf_tests;
          if (!triangle_overlaps(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), shape)) return true;
        }
        return visit(f);
      },
      sink.local);
}

template <class View>
void plane_of(const View& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit, QueryStats* stats) {
  StatsSink sink(stats);
  if (tree.empty() || !is_valid(plane)) return;
  const TriangleMesh& mesh = tree.mesh();
  walk(
      tree, [&](const auto& v) { return overlaps(v, plane); },
      [&](FacetId f) {
        ++sink.local.leaf_tests;
        if (!triangle_crosses_plane(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), plane)) return true;
        return visit(f);
      },
      sink.local);
}

}  // namespace

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

// ---- The packed pie-slice tree (packed_prism_tree.h): the same walks over decoded prisms ----

std::optional<RayHit> ray_closest_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return closest_hit_of(PackedPrismView{tree}, ray, stats);
}

void ray_candidates(const PackedPrismTree& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats) {
  candidates_of(PackedPrismView{tree}, ray, visit, stats);
}

void ray_all_hits(const PackedPrismTree& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats) {
  all_hits_of(PackedPrismView{tree}, ray, visit, stats);
}

std::optional<RayHit> ray_any_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::first_hit([&](auto visit) { ray_all_hits(tree, ray, visit, stats); });
}

std::vector<RayHit> ray_all_hits(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::collect_sorted<RayHit>([&](auto visit) { ray_all_hits(tree, ray, visit, stats); }, detail::nearer_hit);
}

template <class Shape>
void query_overlap(const PackedPrismTree& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                   FacetTest test) {
  overlap_of(PackedPrismView{tree}, shape, visit, stats, test);
}

template <class Shape>
std::vector<FacetId> query_overlap(const PackedPrismTree& tree, const Shape& shape, QueryStats* stats, FacetTest test) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_overlap<Shape>(tree, shape, visit, stats, test); });
}

void query_plane(const PackedPrismTree& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit, QueryStats* stats) {
  plane_of(PackedPrismView{tree}, plane, visit, stats);
}

std::vector<FacetId> query_plane(const PackedPrismTree& tree, const Plane& plane, QueryStats* stats) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_plane(tree, plane, visit, stats); });
}

#define BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(S)                                                         \
  template void query_overlap<S>(const PackedPrismTree&, const S&, FunctionRef<bool(FacetId)>, QueryStats*, \
                                 FacetTest);                                                                \
  template std::vector<FacetId> query_overlap<S>(const PackedPrismTree&, const S&, QueryStats*, FacetTest);
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Aabb)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Obb)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Sphere)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Capsule)

}  // namespace boxtree
