// SPDX-License-Identifier: MIT
#pragma once
// The packed form of an axis-aligned boxtree, for the engines' hot paths (what AnyTree holds for
// the `aabb` method): the hierarchy of a Tree<Aabb> with every two levels collapsed into one
// 4-wide node of one cache line, about 21 bytes per facet.
//
// Why a second form: Tree<Aabb> keeps one exact double box per node (48 B + a 4 B link, 2n - 1
// nodes: 104 B per facet), which the paper's measurements and the oriented kinds' machinery
// need. A midphase is bound by memory latency: each node it enters is a dependent load. Here a
// node holds the boxes of up to four children (the binary tree's children and grandchildren),
// quantized to 16 bits per coordinate over the mesh's bounds, and their links, in 64 bytes; a
// query enters about half as many nodes as in the binary tree, each one cache line. Leaves are
// not stored (a link with the leaf flag is the facet id). Every packed node's children are nodes
// of the source tree: the bottom-up pairing is kept, only read two levels at a time.
//
// Conservative, never exact: each packed box contains the exact one with at least one
// quantization step (the mesh's extent / 65,529 on that axis) to spare on every side, so
// rounding in the queries never culls a facet. Queries that test triangles exactly give exactly
// Tree<Aabb>'s results; FacetTest::leaf_volume reports a superset of Tree<Aabb>'s (the facets
// whose packed leaf box meets the shape; for an Aabb shape, which is tested on the grid, also
// those within two steps of it).
//
// Immutable after construction; every query is const and safe from many threads.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/query.h"

namespace boxtree {

class PackedAabbTree {
 public:
  static constexpr int kWidth = 4;
  struct alignas(64) Node {
    std::uint16_t min[3][kWidth];  // quantized lower corners, [axis][child]
    std::uint16_t max[3][kWidth];  // quantized upper corners
    std::uint32_t link[kWidth];    // kLeafFlag | facet id, the index of an inner node, or kEmpty
  };
  static constexpr std::uint32_t kLeafFlag = Tree<Aabb>::kLeafFlag;
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;  // an unused child slot (not a facet id)
  static constexpr int kMaxHeight = Tree<Aabb>::kMaxHeight;
  static constexpr int kSpareSteps = 1;  // quantization steps added outside every exact box

  PackedAabbTree() = default;
  // Packs `tree` in depth-first order (a node's first inner child is the next node). Shares its
  // mesh.
  explicit PackedAabbTree(const Tree<Aabb>& tree);

  bool empty() const { return mesh_ == nullptr; }
  const TriangleMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const { return mesh_; }
  std::size_t facet_count() const { return mesh_ ? mesh_->facet_count() : 0; }
  // Nodes of the packed hierarchy: 4-wide inner nodes plus leaves (facets).
  std::size_t node_count() const { return empty() ? 0 : nodes_.size() + facet_count(); }
  // Edges on the longest root-to-leaf path of the packed hierarchy.
  int height() const { return height_; }
  std::size_t memory_bytes() const { return nodes_.capacity() * sizeof(Node); }

  // The exact bounds of the mesh's facets (the root's volume).
  const Aabb& bounds() const { return bounds_; }
  // The root: kLeafFlag | 0 for a single facet, else inner node 0.
  std::uint32_t root_link() const { return root_link_; }
  static bool is_leaf(std::uint32_t link) { return (link & kLeafFlag) != 0 && link != kEmpty; }
  static FacetId facet(std::uint32_t link) { return link & ~kLeafFlag; }
  const std::vector<Node>& nodes() const { return nodes_; }

  // Child `slot` of `node`'s box in the mesh's frame (the packed, enlarged box).
  Aabb child_box(const Node& node, int slot) const {
    Aabb box;
    for (int i = 0; i < 3; ++i) {
      box.min[i] = origin_[i] + Real(node.min[i][slot]) * step_[i];
      box.max[i] = origin_[i] + Real(node.max[i][slot]) * step_[i];
    }
    return box;
  }

  // The quantization: coordinate x on axis i is origin[i] + q * step[i], q in [0, 65535].
  const Vec3& origin() const { return origin_; }
  const Vec3& step() const { return step_; }
  const Vec3& inv_step() const { return inv_step_; }
  // Largest q with value(q) <= x, and smallest q with value(q) >= x, clamped to [0, 65535].
  std::uint16_t quantize_down(Real x, int axis) const;
  std::uint16_t quantize_up(Real x, int axis) const;

 private:
  Real value(Real q, int axis) const { return origin_[axis] + q * step_[axis]; }

  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<Node> nodes_;
  std::uint32_t root_link_ = 0;
  Aabb bounds_;
  Vec3 origin_ = Vec3::Zero();
  Vec3 step_ = Vec3::Ones();
  Vec3 inv_step_ = Vec3::Ones();
  int height_ = 0;
};

static_assert(sizeof(PackedAabbTree::Node) == 64, "four 16-bit boxes and four links: one cache line");

// The queries of query.h and collide.h, with the same contracts, on the packed form.
std::optional<RayHit> ray_closest_hit(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats = nullptr);
// The closest hits of `count` rays: hits[i] is exactly ray_closest_hit(tree, rays[i]). For many
// rays at once (sensors, visibility, bakes): the rays' walks take turns node by node, so that on
// a mesh larger than the caches one ray's loads overlap the others' work.
void ray_closest_hits(const PackedAabbTree& tree, const Ray* rays, std::size_t count, std::optional<RayHit>* hits,
                      QueryStats* stats = nullptr);
void ray_candidates(const PackedAabbTree& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats = nullptr);
std::optional<RayHit> ray_any_hit(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats = nullptr);
void ray_all_hits(const PackedAabbTree& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats = nullptr);
std::vector<RayHit> ray_all_hits(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats = nullptr);

// Shape: Aabb (tested on the quantized grid, integers only), Obb, Sphere, Capsule.
template <class Shape>
void query_overlap(const PackedAabbTree& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit,
                   QueryStats* stats = nullptr, FacetTest test = FacetTest::exact_triangle);
template <class Shape>
std::vector<FacetId> query_overlap(const PackedAabbTree& tree, const Shape& shape, QueryStats* stats = nullptr,
                                   FacetTest test = FacetTest::exact_triangle);

void collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats = nullptr,
             const CollideSettings& settings = {});
std::vector<FacetPair> collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
                               QueryStats* stats = nullptr, const CollideSettings& settings = {});

}  // namespace boxtree
