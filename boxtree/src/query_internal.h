#pragma once
// Pieces shared by the query files (query.cpp, collide.cpp, packed_tree.cpp); not public API.
#include <algorithm>
#include <functional>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/query.h"

namespace boxtree::detail {

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
