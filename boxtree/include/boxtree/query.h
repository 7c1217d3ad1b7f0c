// SPDX-License-Identifier: MIT
#pragma once
// Queries on one tree: rays and segments, volume overlap (the midphase engines call), planes,
// and point stabbing. All are plain functions over a const tree, safe to call from many threads
// at once; none allocates on the heap except the conveniences that return a std::vector.
// Visitors are called once per reported result and return true to continue, false to stop.
#include <cstdint>
#include <optional>
#include <vector>

#include "boxtree/detail/function_ref.h"
#include "boxtree/geometry.h"
#include "boxtree/tree.h"

namespace boxtree {

// Work counters, the paper's measure of a query's cost.
struct QueryStats {
  std::uint64_t nodes_visited = 0;  // nodes whose volume passed its test and were entered
  std::uint64_t volume_tests = 0;   // volume tests (node vs query shape, or node pair)
  std::uint64_t leaf_tests = 0;     // exact triangle tests
  QueryStats& operator+=(const QueryStats& o) {
    nodes_visited += o.nodes_visited;
    volume_tests += o.volume_tests;
    leaf_tests += o.leaf_tests;
    return *this;
  }
};

struct RayHit {
  FacetId facet = 0;
  Real t = 0;  // hit point = ray.origin + t * ray.direction
  Real u = 0;  // barycentrics: point = (1-u-v)*a + u*b + v*c
  Real v = 0;
};

// Closest hit with t in [ray.t_min, ray.t_max]; among equal t, the smallest facet id.
template <class Volume>
std::optional<RayHit> ray_closest_hit(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats = nullptr);

// The engines' ray path: the leaves whose volume the ray meets within [t_min, t_max], nearest
// volume entry first, with no triangle test. `visit(facet, t_max)` gets the current t_max and
// returns the new one (e.g. the closest hit so far, so that farther nodes are skipped; anything
// below ray.t_min stops the walk). Lets an engine run its own exact ray/triangle code and keep
// its own results (Bullet's btTriangleRaycastCallback) while the tree prunes by distance.
template <class Volume>
void ray_candidates(const Tree<Volume>& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats = nullptr);

// Some hit in range (the first found: cheapest for shadow/visibility rays).
template <class Volume>
std::optional<RayHit> ray_any_hit(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats = nullptr);

// Every hit in range, in traversal order.
template <class Volume>
void ray_all_hits(const Tree<Volume>& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats = nullptr);

// Convenience: every hit, sorted by (t, facet).
template <class Volume>
std::vector<RayHit> ray_all_hits(const Tree<Volume>& tree, const Ray& ray, QueryStats* stats = nullptr);

// What a reported facet satisfies in an overlap query.
enum class FacetTest {
  exact_triangle,  // the facet's triangle overlaps the shape (default)
  leaf_volume,     // only the facet's leaf volume overlaps it: a superset, for engines that
                   // run their own exact test per candidate (like Bullet's processAllTriangles)
  none,            // every facet the walk reaches, without a test of its own: a superset of
                   // leaf_volume's, for callers whose per-facet work starts with the exact test
};

// Facets overlapping a query shape, given in the tree's frame. Shape is one of Aabb, Obb,
// Sphere, Capsule.
template <class Volume, class Shape>
void query_overlap(const Tree<Volume>& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit,
                   QueryStats* stats = nullptr, FacetTest test = FacetTest::exact_triangle);

// Convenience: the facets, sorted by id.
template <class Volume, class Shape>
std::vector<FacetId> query_overlap(const Tree<Volume>& tree, const Shape& shape, QueryStats* stats = nullptr,
                                   FacetTest test = FacetTest::exact_triangle);

// Facets cut by (or touching) a plane.
template <class Volume>
void query_plane(const Tree<Volume>& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit,
                 QueryStats* stats = nullptr);
template <class Volume>
std::vector<FacetId> query_plane(const Tree<Volume>& tree, const Plane& plane, QueryStats* stats = nullptr);

// The paper's stabbing number at a point: how many node volumes (closed) contain it.
template <class Volume>
std::size_t stabbing_count(const Tree<Volume>& tree, const Vec3& point, QueryStats* stats = nullptr);

}  // namespace boxtree
