// SPDX-License-Identifier: MIT
#include "boxtree/any_tree.h"

#include <algorithm>
#include <typeinfo>

#include "boxtree/detail/volume_kinds.h"

namespace boxtree {

AnyTree AnyTree::build(std::shared_ptr<const TriangleMesh> mesh, const Method& method, const BuildSettings& settings,
                       BuildStats* stats) {
  return with_method(method, [&](auto tag) {
    using V = typename decltype(tag)::type;
    auto tree = build_tree<V>(std::move(mesh), settings_for(method, settings), stats);
    if constexpr (std::is_same_v<V, Aabb>)
      return AnyTree(PackedAabbTree(tree));
    else if constexpr (is_pie_slice_v<V>)
      return AnyTree(PackedPrismTree(tree), method);
    else
      return AnyTree(std::move(tree), method);
  });
}

AnyTree::AnyTree(PackedAabbTree tree)
    : impl_(tree.empty() ? nullptr : std::make_shared<const Model<PackedAabbTree>>(std::move(tree))), method_() {}

const PackedAabbTree* AnyTree::packed() const {
  const auto* model = dynamic_cast<const Model<PackedAabbTree>*>(impl_.get());
  return model ? &model->tree : nullptr;
}

AnyTree::AnyTree(PackedPrismTree tree, const Method& method)
    : impl_(tree.empty() ? nullptr : std::make_shared<const Model<PackedPrismTree>>(std::move(tree))),
      method_(method) {}

const PackedPrismTree* AnyTree::packed_prism() const {
  const auto* model = dynamic_cast<const Model<PackedPrismTree>*>(impl_.get());
  return model ? &model->tree : nullptr;
}

namespace {
const AnyTree::Concept& checked(const std::shared_ptr<const AnyTree::Concept>& impl) {
  if (!impl) throw Error("boxtree::AnyTree: the tree is empty (default-constructed)");
  return *impl;
}
}  // namespace

const TriangleMesh& AnyTree::mesh() const { return checked(impl_).mesh(); }
const std::shared_ptr<const TriangleMesh>& AnyTree::shared_mesh() const { return checked(impl_).shared_mesh(); }
std::size_t AnyTree::facet_count() const { return impl_ ? impl_->mesh().facet_count() : 0; }
std::size_t AnyTree::node_count() const { return impl_ ? impl_->node_count() : 0; }
int AnyTree::height() const { return impl_ ? impl_->height() : 0; }
std::size_t AnyTree::memory_bytes() const { return impl_ ? impl_->memory_bytes() : 0; }

Aabb AnyTree::bounds() const {
  const TriangleMesh& m = mesh();
  Aabb box = Aabb::empty();
  for (const Triangle& t : m.triangles)
    for (VertexId v : t) box.expand(m.vertices[v]);
  return box;
}

std::optional<RayHit> AnyTree::ray_closest_hit(const Ray& ray, QueryStats* stats) const {
  return impl_ ? impl_->ray_closest_hit(ray, stats) : std::nullopt;
}
void AnyTree::ray_closest_hits(const Ray* rays, std::size_t count, std::optional<RayHit>* hits,
                               QueryStats* stats) const {
  if (impl_) {
    impl_->ray_closest_hits(rays, count, hits, stats);
  } else {
    std::fill(hits, hits + count, std::nullopt);
  }
}
void AnyTree::ray_candidates(const Ray& ray, FunctionRef<Real(FacetId, Real)> visit, QueryStats* stats) const {
  if (impl_) impl_->ray_candidates(ray, visit, stats);
}
void AnyTree::query_overlap(const Aabb& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                            FacetTest test) const {
  if (impl_) impl_->query_overlap(shape, visit, stats, test);
}
void AnyTree::query_overlap(const Obb& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                            FacetTest test) const {
  if (impl_) impl_->query_overlap(shape, visit, stats, test);
}
void AnyTree::query_overlap(const Sphere& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                            FacetTest test) const {
  if (impl_) impl_->query_overlap(shape, visit, stats, test);
}
void AnyTree::query_overlap(const Capsule& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                            FacetTest test) const {
  if (impl_) impl_->query_overlap(shape, visit, stats, test);
}

bool AnyTree::can_collide(const AnyTree& b) const {
  if (!impl_ || !b.impl_) return true;  // collide reports nothing
  const Concept& mine = *impl_;
  const Concept& theirs = *b.impl_;
  // Packed pie-slice trees share one type for the four pie kinds: their methods tell them apart.
  const bool other_pie_kind = packed_prism() != nullptr && method_.kind != b.method_.kind;
  return typeid(mine) == typeid(theirs) && !other_pie_kind;
}

void AnyTree::collide(const AnyTree& b, const RigidTransform& a_from_b, FunctionRef<bool(const FacetPair&)> visit,
                      QueryStats* stats, const CollideSettings& settings) const {
  if (!impl_ || !b.impl_) return;
  if (!can_collide(b)) {
    throw Error("boxtree::AnyTree::collide: the trees use different methods (" + method_name(method_) + " and " +
                method_name(b.method_) + "); build both with the same method");
  }
  impl_->collide(*b.impl_, a_from_b, visit, stats, settings);
}

}  // namespace boxtree
