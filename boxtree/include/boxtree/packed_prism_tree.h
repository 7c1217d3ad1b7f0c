// SPDX-License-Identifier: MIT
#pragma once
// The packed form of a pie-slice boxtree (Tree<PieMax>, Tree<PieMin>, Tree<PieMaxGeneral>,
// Tree<PieMinGeneral>), what AnyTree holds for those methods: 48 bytes per facet where the exact
// tree takes 216, with the same query results.
//
// Why a second form: Tree<PieSlice> keeps one exact double prism per node (13 doubles, 104 B,
// + a 4 B link, 2n - 1 nodes), which the builder, the statistics and the paper's measurements
// need. A query needs less:
//  - Leaves are not stored. A pie-slice leaf is its facet with zero thickness
//    (prism_from_triangle), so a child link with the leaf flag is the facet id, and the walks
//    rebuild the leaf prism from the mesh when they test it: the very prism Tree<PieSlice>
//    stores, so leaf tests, and with them every result, are Tree<PieSlice>'s.
//  - An inner node is its base triangle as three float points (relative to the mesh's bounds
//    centre, in units of a power of two near the mesh's size, so that float error is relative to
//    the mesh, not to its distance from the world origin) and its height as a float: ten floats.
//    The sweep axis is not stored: it is the base triangle's unit normal, the winding giving its
//    sign. With the two child links that is 48 B per inner node, n - 1 inner nodes.
//
// Conservative: every decoded prism contains its exact prism (all six corners strictly inside,
// checked in double at construction with the decoded prism's own planes), so it contains every
// facet below it and the (conservative) prism tests never cull a facet that Tree<PieSlice>
// reaches. How the margin is chosen and why the check is enough: src/packed_prism_tree.cpp.
// Node traversal order and so the work counters (QueryStats) differ from Tree<PieSlice>'s; the
// sets of reported facets, hits and pairs do not.
//
// Ownership as for Tree: shares the mesh. Immutable after construction; every query is const
// and safe from many threads.
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <type_traits>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/query.h"
#include "boxtree/volume/pie_slice.h"

namespace boxtree {

template <class V>
struct is_pie_slice : std::false_type {};
template <PrincipalAxis K, TriangleRule R>
struct is_pie_slice<PieSlice<K, R>> : std::true_type {};
// The plain pie-slice kinds (not their hybrids): the trees PackedPrismTree packs.
template <class V>
inline constexpr bool is_pie_slice_v = is_pie_slice<V>::value;

class PackedPrismTree {
 public:
  struct Node {
    float base[3][3];        // 36 B: base corners, (x - origin) / unit, wound counterclockwise about the axis
    float height;            //  4 B: along the axis, / unit
    std::uint32_t child[2];  //  8 B: kLeafFlag | facet id, or the index of an inner node
  };
  static constexpr std::uint32_t kLeafFlag = Tree<PieMin>::kLeafFlag;
  static constexpr int kMaxHeight = Tree<PieMin>::kMaxHeight;

  PackedPrismTree() = default;
  // Packs `tree` (V: one of the four PieSlice kinds) in depth-first preorder (a node's first
  // inner child is the next node). Shares its mesh.
  template <class V, class = std::enable_if_t<is_pie_slice_v<V>>>
  explicit PackedPrismTree(const Tree<V>& tree);

  bool empty() const { return mesh_ == nullptr; }
  const TriangleMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const { return mesh_; }
  std::size_t facet_count() const { return mesh_ ? mesh_->facet_count() : 0; }
  // Nodes of the hierarchy, leaves included (as Tree's: 2n - 1); only the n - 1 inner ones are stored.
  std::size_t node_count() const { return empty() ? 0 : nodes_.size() + facet_count(); }
  // Edges on the longest root-to-leaf path (the exact tree's).
  int height() const { return height_; }
  std::size_t memory_bytes() const { return nodes_.capacity() * sizeof(Node); }

  // The root: kLeafFlag | 0 for a single facet, else inner node 0.
  std::uint32_t root_link() const { return root_link_; }
  static bool is_leaf(std::uint32_t link) { return (link & kLeafFlag) != 0; }
  static FacetId facet(std::uint32_t link) { return link & ~kLeafFlag; }
  const std::vector<Node>& nodes() const { return nodes_; }

  // The decoding: a stored coordinate q stands for origin + unit * q (unit a power of two).
  const Vec3& origin() const { return origin_; }
  Real unit() const { return unit_; }

  // The prism an inner node stands for (it contains the exact tree's prism of that node).
  Prism prism(const Node& node) const {
    Vec3 rel[3];
    for (int k = 0; k < 3; ++k) rel[k] = Vec3(node.base[k][0], node.base[k][1], node.base[k][2]);
    Prism p;
    // The normal from the stored values themselves (differences of floats are exact in double):
    // the same axis wherever the mesh lies.
    const Vec3 normal = (rel[1] - rel[0]).cross(rel[2] - rel[0]);
    p.axis = normal / normal.norm();
    for (int k = 0; k < 3; ++k) p.base[k] = origin_ + unit_ * rel[k];
    p.height = unit_ * Real(node.height);
    return p;
  }
  Prism prism(std::uint32_t inner) const { return prism(nodes_[inner]); }
  // A leaf's prism: the facet itself, as Tree<PieSlice> stores it.
  Prism leaf_prism(FacetId f) const {
    return prism_from_triangle(mesh_->corner(f, 0), mesh_->corner(f, 1), mesh_->corner(f, 2));
  }
  // The prism of any link (inner node or leaf).
  Prism prism_of_link(std::uint32_t link) const { return is_leaf(link) ? leaf_prism(facet(link)) : prism(link); }

 private:
  template <class V>
  void pack(const Tree<V>& tree);
  Node encode(const Prism& exact) const;
  std::optional<Node> encode_grown(const Prism& exact, const std::array<Vec3, 3>& grown_base, Real d,
                                   const std::array<Vec3, 6>& must_hold) const;

  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<Node> nodes_;
  std::uint32_t root_link_ = 0;
  Vec3 origin_ = Vec3::Zero();
  Real unit_ = 1;
  int height_ = 0;
};

static_assert(sizeof(PackedPrismTree::Node) == 48, "ten floats and two links");

template <class V, class>
PackedPrismTree::PackedPrismTree(const Tree<V>& tree) {
  pack(tree);
}

// The queries of query.h and collide.h, with the same contracts and the same results as on the
// Tree<PieSlice> the packed tree was made from (src/query.cpp, src/collide.cpp: the same walks).
std::optional<RayHit> ray_closest_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats = nullptr);
void ray_candidates(const PackedPrismTree& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats = nullptr);
std::optional<RayHit> ray_any_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats = nullptr);
void ray_all_hits(const PackedPrismTree& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats = nullptr);
std::vector<RayHit> ray_all_hits(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats = nullptr);

// Shape: Aabb, Obb, Sphere, Capsule.
template <class Shape>
void query_overlap(const PackedPrismTree& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit,
                   QueryStats* stats = nullptr, FacetTest test = FacetTest::exact_triangle);
template <class Shape>
std::vector<FacetId> query_overlap(const PackedPrismTree& tree, const Shape& shape, QueryStats* stats = nullptr,
                                   FacetTest test = FacetTest::exact_triangle);

void query_plane(const PackedPrismTree& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit,
                 QueryStats* stats = nullptr);
std::vector<FacetId> query_plane(const PackedPrismTree& tree, const Plane& plane, QueryStats* stats = nullptr);

void collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats = nullptr,
             const CollideSettings& settings = {});
std::vector<FacetPair> collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
                               QueryStats* stats = nullptr, const CollideSettings& settings = {});

}  // namespace boxtree
