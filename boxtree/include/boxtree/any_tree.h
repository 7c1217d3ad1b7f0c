// SPDX-License-Identifier: MIT
#pragma once
// A tree of any hierarchy method, chosen at run time: what the engine adapters (engine/) hold,
// since a physics program picks its method from a setting, not a template argument. Inside, it
// is a Tree<V> for the method's volume type V; every query forwards to the typed free functions
// of query.h and collide.h (one virtual call per query, not per node).
//
// For the plain `aabb` method, build() holds the packed form (packed_tree.h: the same hierarchy
// 4-wide, ~21 B per facet, quantized boxes; leaf_volume queries then report the facets whose packed
// leaf box meets the shape), since that is what an engine's midphase wants; construct from a
// Tree<Aabb> to hold the exact one instead. Likewise for the plain pie-slice methods (pie-max,
// pie-min, pie-max-general, pie-min-general, with or without -tight; not their hybrids): build()
// holds the packed prism tree (packed_prism_tree.h: float prisms, 48 B per facet instead of 216,
// the same results as the exact tree); construct from a Tree<PieSlice> to hold the exact one.
//
// Copies share the same immutable tree (cheap; safe to use from many threads).
#include <memory>
#include <optional>

#include "boxtree/collide.h"
#include "boxtree/method.h"
#include "boxtree/packed_prism_tree.h"
#include "boxtree/packed_tree.h"
#include "boxtree/query.h"

namespace boxtree {

class AnyTree {
 public:
  AnyTree() = default;
  template <class Volume>
  AnyTree(Tree<Volume> tree, const Method& method);
  explicit AnyTree(PackedAabbTree tree);
  // `method`: the pie-slice method the tree was built with (collide checks that both agree).
  AnyTree(PackedPrismTree tree, const Method& method);

  // Validates the mesh (throws boxtree::Error) and builds its tree with `method` (packed for
  // the plain `aabb` and pie-slice methods).
  static AnyTree build(std::shared_ptr<const TriangleMesh> mesh, const Method& method,
                       const BuildSettings& settings = {}, BuildStats* stats = nullptr);

  bool empty() const { return !impl_; }
  const Method& method() const { return method_; }
  const TriangleMesh& mesh() const;
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const;
  std::size_t facet_count() const;
  std::size_t node_count() const;
  int height() const;
  std::size_t memory_bytes() const;  // the hierarchy, not the mesh
  // Axis-aligned bounds of the mesh's facets (of the root volume's corners for oriented kinds: a
  // box that contains every facet).
  Aabb bounds() const;

  // The typed tree, or nullptr if this holds another volume kind.
  template <class Volume>
  const Tree<Volume>* get() const;
  // The packed tree, or nullptr if this holds another form.
  const PackedAabbTree* packed() const;
  // The packed pie-slice tree, or nullptr if this holds another form.
  const PackedPrismTree* packed_prism() const;

  // The queries of query.h and collide.h.
  std::optional<RayHit> ray_closest_hit(const Ray& ray, QueryStats* stats = nullptr) const;
  // hits[i] = ray_closest_hit(rays[i]) for i < count; for `aabb`, packed_tree.h's batched walk
  // (faster on meshes larger than the caches), for the other methods one ray after another.
  void ray_closest_hits(const Ray* rays, std::size_t count, std::optional<RayHit>* hits,
                        QueryStats* stats = nullptr) const;
  void ray_candidates(const Ray& ray, FunctionRef<Real(FacetId, Real)> visit, QueryStats* stats = nullptr) const;
  void query_overlap(const Aabb& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats = nullptr,
                     FacetTest test = FacetTest::exact_triangle) const;
  void query_overlap(const Obb& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats = nullptr,
                     FacetTest test = FacetTest::exact_triangle) const;
  void query_overlap(const Sphere& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats = nullptr,
                     FacetTest test = FacetTest::exact_triangle) const;
  void query_overlap(const Capsule& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats = nullptr,
                     FacetTest test = FacetTest::exact_triangle) const;
  // Both trees must be of the same method (throws boxtree::Error otherwise; can_collide tells
  // beforehand, and collider.h's collide_meshes converts instead).
  void collide(const AnyTree& b, const RigidTransform& a_from_b, FunctionRef<bool(const FacetPair&)> visit,
               QueryStats* stats = nullptr, const CollideSettings& settings = {}) const;

  // Whether collide(b, ...) accepts b: both hold the same tree type (and, for packed pie-slice
  // trees, the same pie kind).
  bool can_collide(const AnyTree& b) const;
  // Identifies the built tree: copies of one AnyTree share it (null for an empty tree).
  const void* identity() const { return impl_.get(); }

  struct Concept;
  template <class TreeType>
  struct Model;

 private:
  std::shared_ptr<const Concept> impl_;
  Method method_;
};

// ---- implementation: one virtual interface, one model per tree type ----
struct AnyTree::Concept {
  virtual ~Concept() = default;
  virtual const TriangleMesh& mesh() const = 0;
  virtual const std::shared_ptr<const TriangleMesh>& shared_mesh() const = 0;
  virtual std::size_t node_count() const = 0;
  virtual int height() const = 0;
  virtual std::size_t memory_bytes() const = 0;
  virtual std::optional<RayHit> ray_closest_hit(const Ray&, QueryStats*) const = 0;
  virtual void ray_closest_hits(const Ray*, std::size_t, std::optional<RayHit>*, QueryStats*) const = 0;
  virtual void ray_candidates(const Ray&, FunctionRef<Real(FacetId, Real)>, QueryStats*) const = 0;
  virtual void query_overlap(const Aabb&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest) const = 0;
  virtual void query_overlap(const Obb&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest) const = 0;
  virtual void query_overlap(const Sphere&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest) const = 0;
  virtual void query_overlap(const Capsule&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest) const = 0;
  // `b` is known to hold the same volume kind.
  virtual void collide(const Concept& b, const RigidTransform&, FunctionRef<bool(const FacetPair&)>, QueryStats*,
                       const CollideSettings&) const = 0;
};

// TreeType: Tree<V> for a volume kind V, PackedAabbTree or PackedPrismTree.
template <class TreeType>
struct AnyTree::Model final : AnyTree::Concept {
  explicit Model(TreeType t) : tree(std::move(t)) {}
  TreeType tree;

  const TriangleMesh& mesh() const override { return tree.mesh(); }
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const override { return tree.shared_mesh(); }
  std::size_t node_count() const override { return tree.node_count(); }
  int height() const override { return tree.height(); }
  std::size_t memory_bytes() const override { return tree.memory_bytes(); }
  std::optional<RayHit> ray_closest_hit(const Ray& r, QueryStats* s) const override {
    return boxtree::ray_closest_hit(tree, r, s);
  }
  void ray_closest_hits(const Ray* rays, std::size_t count, std::optional<RayHit>* hits, QueryStats* s) const override {
    if constexpr (std::is_same_v<TreeType, PackedAabbTree>) {
      boxtree::ray_closest_hits(tree, rays, count, hits, s);
    } else {
      for (std::size_t i = 0; i < count; ++i) hits[i] = boxtree::ray_closest_hit(tree, rays[i], s);
    }
  }
  void ray_candidates(const Ray& r, FunctionRef<Real(FacetId, Real)> v, QueryStats* s) const override {
    boxtree::ray_candidates(tree, r, v, s);
  }
  void query_overlap(const Aabb& q, FunctionRef<bool(FacetId)> v, QueryStats* s, FacetTest t) const override {
    boxtree::query_overlap(tree, q, v, s, t);
  }
  void query_overlap(const Obb& q, FunctionRef<bool(FacetId)> v, QueryStats* s, FacetTest t) const override {
    boxtree::query_overlap(tree, q, v, s, t);
  }
  void query_overlap(const Sphere& q, FunctionRef<bool(FacetId)> v, QueryStats* s, FacetTest t) const override {
    boxtree::query_overlap(tree, q, v, s, t);
  }
  void query_overlap(const Capsule& q, FunctionRef<bool(FacetId)> v, QueryStats* s, FacetTest t) const override {
    boxtree::query_overlap(tree, q, v, s, t);
  }
  void collide(const Concept& b, const RigidTransform& a_from_b, FunctionRef<bool(const FacetPair&)> v, QueryStats* s,
               const CollideSettings& c) const override {
    boxtree::collide(tree, static_cast<const Model&>(b).tree, a_from_b, v, s, c);
  }
};

template <class Volume>
AnyTree::AnyTree(Tree<Volume> tree, const Method& method)
    : impl_(tree.empty() ? nullptr : std::make_shared<const Model<Tree<Volume>>>(std::move(tree))), method_(method) {}

template <class Volume>
const Tree<Volume>* AnyTree::get() const {
  const auto* model = dynamic_cast<const Model<Tree<Volume>>*>(impl_.get());
  return model ? &model->tree : nullptr;
}

}  // namespace boxtree
