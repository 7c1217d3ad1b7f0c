// SPDX-License-Identifier: MIT
#pragma once
// The generic walks behind the queries of query.h and collide.h, written once over a View of a
// binary hierarchy (query_internal.h: TreeView for Tree<V>; a packed form brings its own view,
// as packed_prism_tree.cpp does). Not public API; includes no packed layout.
#include <algorithm>
#include <optional>

#include "boxtree/error.h"
#include "query_internal.h"

namespace boxtree::detail {

constexpr int kStackSize = Tree<Aabb>::kMaxHeight + 2;

// Depth-first walk of every node whose volume passes `node_test`; `leaf` is called for each
// such leaf's facet and returns false to stop the walk.
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

// An invalid shape (shapes.h) matches nothing, in every FacetTest mode: checked here once, so
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

// The tree-vs-tree walk over two views of the same kind.
template <class View>
void collide_views(const View& a, const View& b, const RigidTransform& a_from_b,
                   FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  if (!a_from_b.translation.allFinite() || !is_rotation(a_from_b.rotation, 1e-6))
    throw Error("collide: the transform's rotation is not orthonormal with determinant +1, or not finite");
  QueryStats local;
  if (a.empty() || b.empty()) return;
  detail::FacetPairTest facets_intersect(a.mesh(), b.mesh(), a_from_b);

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
      if (facets_intersect(fa, fb)) {
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

}  // namespace boxtree::detail
