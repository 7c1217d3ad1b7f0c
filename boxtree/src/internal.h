// SPDX-License-Identifier: MIT
#pragma once
// Helpers shared by several source files of the library; not part of the public API.
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "boxtree/mesh.h"
#include "boxtree/shapes.h"
#include "boxtree/volume/aabb.h"
#include "boxtree/volume/obb.h"
#include "exact_sign.h"

namespace boxtree::detail {

// Separating-axis test of the box {|x_i| <= ha_i} against the box with center t, axes r.col(j)
// and half extents hb, both in the first box's frame (Gottschalk, Lin, Manocha, "OBBTree",
// SIGGRAPH 1996, Sec. 4; Ericson, Real-Time Collision Detection, 4.4.1). 15 axes, enough for
// flat boxes too. Conservative by ~1e-12 of the sizes and distance (Gottschalk's epsilon on |R|
// plus 1e-12 * |t|_1): may report boxes that close as overlapping, never the reverse. NaN input
// gives false. Defined in geometry.cpp.
bool boxes_overlap(const Vec3& ha, const Vec3& t, const Mat3& r, const Vec3& hb);

// The body of triangle_overlaps_aabb (Akenine-Moller's test) for a finite, non-empty box and
// corners without NaN (not checked). Defined in geometry.cpp.
bool triangle_overlaps_box(const Vec3& a, const Vec3& b, const Vec3& c, const Aabb& box);

// The triangle / oriented box test with the box's frame and validity taken once, for one box
// against many triangles (a query's leaf tests); triangle_overlaps_obb is this applied to one
// triangle. Defined in geometry.cpp.
class ObbTriangleTest {
 public:
  explicit ObbTriangleTest(const Obb& box);
  bool operator()(const Vec3& a, const Vec3& b, const Vec3& c) const;

 private:
  Mat3 box_from_world_;
  Vec3 center_;
  Aabb local_;
  bool valid_;
};

// Whether the origin of a plane lies farther than sqrt(reach_squared) from the triangle with
// corners (x[i], y[i]) there: the test of a triangle's shadow along an axis (its corners in a frame
// of the plane across the axis, about the axis's point) against the disk of a radius about the
// axis, where a cylinder's side or a capsule's core grown by its radius casts its shadow. Apart,
// the two shapes are apart along the direction between the nearest points of the two shadows.
// Point-to-segment distances for the edges; the origin on one side of all three edges (their
// cross products of one sign) is inside, at distance zero. Defined in geometry.cpp.
bool origin_beyond_triangle_2d(const Real (&x)[3], const Real (&y)[3], Real reach_squared);

// closest_point_on_triangle (geometry.h) given the triangle's edges ab = b - a, bc = c - b,
// ca = a - c and their squaredNorm()s, for callers that have them (one facet, many points): the
// same point, bit for bit. Defined in geometry.cpp.
Vec3 closest_point_on_triangle_with_edges(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& ab,
                                          const Vec3& bc, const Vec3& ca, Real ab_squared, Real bc_squared,
                                          Real ca_squared);

// A pair of points, one on a segment and one on a triangle, and their squared distance.
struct SegmentTrianglePair {
  Vec3 on_segment = Vec3::Zero();
  Vec3 on_triangle = Vec3::Zero();
  Real distance_squared = std::numeric_limits<Real>::infinity();
};

// The closest of the pairs with an end of the segment [p0, p1] or an edge of the triangle on their
// side: p0 and p1 with their closest points on the triangle, then the segment's closest points
// (closest_points_on_segments) to the edges ab, bc and ca. The first of equally close ones in that
// order; a default pair if no distance is below infinity. The closest pair of the segment and the
// triangle is this one unless the segment crosses the triangle's interior. Defined in geometry.cpp.
SegmentTrianglePair closest_segment_triangle_boundary(const Vec3& p0, const Vec3& p1, const Vec3& a, const Vec3& b,
                                                      const Vec3& c);

// triangle_overlaps_capsule for a valid capsule (is_valid; not checked): the same decision for
// every input, bit for bit. When true, `boundary` is closest_segment_triangle_boundary(capsule.p0,
// capsule.p1, a, b, c), computed on the way: a collider's leaf test hands it to the narrowphase
// (contact_capsule_triangle_from). Defined in geometry.cpp.
// The plane across a capsule's core, for the test of a triangle's shadow along the core: two
// unit vectors orthogonal to the core and to each other (orthonormal_completion of its direction),
// worked out once per capsule. `valid` is false for a core of no length (no shadow test).
struct CapsuleAcross {
  explicit CapsuleAcross(const Capsule& capsule);
  Vec3 u = Vec3::Zero();
  Vec3 v = Vec3::Zero();
  bool valid = false;
};
bool triangle_overlaps_capsule(const Vec3& a, const Vec3& b, const Vec3& c, const Capsule& capsule,
                               const CapsuleAcross& across, SegmentTrianglePair& boundary);

// One triangle of triangles_intersect as that test uses it, prepared once for the pairs that
// share it (a leaf of one tree against the leaves of a subtree of the other): its bounding box and
// its rounded plane (exact_sign.h's rounded_normal through its first corner). Holds pointers to
// the corners, which must outlive it.
class PreparedTriangle {
 public:
  PreparedTriangle() = default;
  PreparedTriangle(const Vec3& p0, const Vec3& p1, const Vec3& p2) { reset(p0, p1, p2); }
  void reset(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
    corner_[0] = &p0;
    corner_[1] = &p1;
    corner_[2] = &p2;
    lo_ = p0.cwiseMin(p1).cwiseMin(p2);
    hi_ = p0.cwiseMax(p1).cwiseMax(p2);
    rounded_normal(p0, p1, p2, normal_, magnitude_);
  }

 private:
  friend inline bool intersect_prepared(const PreparedTriangle& a, const PreparedTriangle& b);  // geometry.cpp only
  const Vec3* corner_[3] = {nullptr, nullptr, nullptr};
  Vec3 lo_, hi_;
  Vec3 normal_, magnitude_;
};

// triangles_intersect (geometry.h) on two prepared triangles: the same answer from the same
// rounded values, the part a triangle shares between its pairs done once. Defined in geometry.cpp.
bool triangles_intersect(const PreparedTriangle& a, const PreparedTriangle& b);

// (b1, b2, n) orthonormal for a unit n (Duff, Burgess, Christensen, Hery, Kensler, Liani,
// Villemin, "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017): branch-free of any
// threshold. Defined in volume_obb.cpp.
void orthonormal_completion(const Vec3& n, Vec3& b1, Vec3& b2);

// The convex hull of points[0..count), as convex_hull_2d of detail/fit.h without allocating:
// counter-clockwise from the lexicographically smallest point, without collinear or duplicate
// points, exact (Andrew's monotone chain on an exact orientation test); 0, 1 or 2 points for
// degenerate input. Sorts `points` in place, writes the hull to `hull` (room for 2 * count
// points) and returns its size. Finite input only (not checked). Defined in fit.cpp.
int convex_hull_2d(Vec2* points, int count, Vec2* hull);

// The final layout of a tree built by a MergeRule (build.cpp): nodes in build order
// (leaves 0..leaf_count-1 are the facets, parents after, children `first`/`second`) laid out
// depth-first from `root` with the two children of a node in adjacent slots, as Tree expects.
// depth_first_order gives the links and, per slot, the node's build index (children always get
// larger slots than their parent); depth_first_layout also copies the volumes.
inline void depth_first_order(const std::vector<std::uint32_t>& first, const std::vector<std::uint32_t>& second,
                              std::uint32_t root, std::size_t node_count, std::size_t leaf_count,
                              std::uint32_t leaf_flag, std::vector<std::uint32_t>& out_links,
                              std::vector<std::uint32_t>& out_nodes) {
  out_links.assign(node_count, 0);
  out_nodes.assign(node_count, 0);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{root, 0}};  // (build index, output slot)
  std::uint32_t next_slot = 1;
  while (!stack.empty()) {
    const auto [node, slot] = stack.back();
    stack.pop_back();
    out_nodes[slot] = node;
    if (node < leaf_count) {
      out_links[slot] = leaf_flag | node;
      continue;
    }
    out_links[slot] = next_slot;
    stack.push_back({second[node], next_slot + 1});
    stack.push_back({first[node], next_slot});
    next_slot += 2;
  }
}

template <class Volume>
void depth_first_layout(const std::vector<Volume>& volumes, const std::vector<std::uint32_t>& first,
                        const std::vector<std::uint32_t>& second, std::uint32_t root, std::size_t leaf_count,
                        std::uint32_t leaf_flag, std::vector<Volume>& out_volumes,
                        std::vector<std::uint32_t>& out_links) {
  std::vector<std::uint32_t> nodes;
  depth_first_order(first, second, root, volumes.size(), leaf_count, leaf_flag, out_links, nodes);
  out_volumes.resize(volumes.size());
  for (std::size_t slot = 0; slot < nodes.size(); ++slot) out_volumes[slot] = volumes[nodes[slot]];
}

}  // namespace boxtree::detail
