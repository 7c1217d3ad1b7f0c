// SPDX-License-Identifier: MIT
#include "boxtree/collision_mesh.h"

#include <cmath>
#include <map>
#include <string>

#include "boxtree/active_edges.h"
#include "boxtree/error.h"

namespace boxtree {
namespace {

Aabb facet_bounds(const TriangleMesh& mesh) {
  Aabb box = Aabb::empty();
  for (const Triangle& t : mesh.triangles)
    for (VertexId v : t) box.expand(mesh.vertices[v]);
  return box;
}

// The form AnyTree::build gives for the tree's own method (packed for aabb and pie slices): a
// tree of that form collides with every other built tree of the same method.
bool is_built_form(const AnyTree& tree) {
  const Method& m = tree.method();
  if (m.kind == VolumeKind::aabb) return tree.packed() != nullptr;
  const bool pie = m.kind != VolumeKind::obb_all && m.kind != VolumeKind::obb_max && m.kind != VolumeKind::obb_min;
  if (pie && m.hybrid_level == 0) return tree.packed_prism() != nullptr;
  return tree.packed() == nullptr && tree.packed_prism() == nullptr;
}

}  // namespace

bool same_volume_kind(const Method& a, const Method& b) {
  if (a.kind != b.kind) return false;
  return a.kind == VolumeKind::aabb || (a.hybrid_level > 0) == (b.hybrid_level > 0);
}

CollisionMesh::CollisionMesh(AnyTree tree) : tree_(std::move(tree)) {
  if (tree_.empty()) throw Error("boxtree::CollisionMesh: the tree is empty");
  bounds_ = facet_bounds(tree_.mesh());
  active_edges_ = compute_active_edges(tree_.mesh(), 10, &inconsistent_edges_);
}

std::shared_ptr<const CollisionMesh> CollisionMesh::build(std::shared_ptr<const TriangleMesh> mesh,
                                                          const Method& method, const BuildSettings& settings) {
  if (!mesh) throw Error("boxtree::CollisionMesh::build: no mesh");
  return std::make_shared<const CollisionMesh>(AnyTree::build(std::move(mesh), method, settings));
}

std::shared_ptr<const CollisionMesh> CollisionMesh::of(const AnyTree& tree) {
  if (tree.empty()) throw Error("boxtree::CollisionMesh: the tree is empty");
  // Keyed by the built tree's address: an entry's CollisionMesh holds that tree, so the address
  // cannot be reused while the entry can still be locked.
  static std::mutex mutex;
  static std::map<const void*, std::weak_ptr<const CollisionMesh>> shared;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = shared[tree.identity()];
  if (auto existing = slot.lock()) return existing;
  auto made = std::make_shared<const CollisionMesh>(tree);
  slot = made;
  // Forget expired entries now and then, so that the map stays as small as the live meshes.
  if (shared.size() > 64) {
    for (auto it = shared.begin(); it != shared.end();) it = it->second.expired() ? shared.erase(it) : std::next(it);
  }
  return made;
}

const AnyTree& CollisionMesh::tree_as(const Method& method) const {
  if (same_volume_kind(tree_.method(), method) && is_built_form(tree_)) return tree_;
  std::lock_guard<std::mutex> lock(cache_mutex_);
  for (const auto& converted : converted_)
    if (same_volume_kind(converted->method(), method)) return *converted;
  converted_.push_back(std::make_unique<const AnyTree>(AnyTree::build(tree_.shared_mesh(), method)));
  return *converted_.back();
}

std::shared_ptr<const CollisionMesh> CollisionMesh::scaled(const Vec3& scale) const {
  if (!scale.allFinite() || (scale.array() == 0).any())
    throw Error("boxtree::CollisionMesh::scaled: the scale must be finite and non-zero on every axis");
  const Vec3 total = scale_.cwiseProduct(scale);
  if (scale == Vec3::Ones()) return shared_from_this();
  std::lock_guard<std::mutex> lock(cache_mutex_);
  for (auto it = scaled_.begin(); it != scaled_.end();) {
    auto mesh = it->lock();
    if (!mesh) {
      it = scaled_.erase(it);
      continue;
    }
    if (mesh->scale_ == total) return mesh;
    ++it;
  }
  const bool mirror = scale.prod() < 0;
  auto copy = std::make_shared<TriangleMesh>(tree_.mesh());
  for (Vec3& v : copy->vertices) v = v.cwiseProduct(scale);
  if (mirror)
    for (Triangle& t : copy->triangles) std::swap(t[1], t[2]);
  auto made = std::make_shared<CollisionMesh>(AnyTree::build(std::move(copy), tree_.method()));
  made->scale_ = total;
  made->mirrored_ = mirrored_ != mirror;
  scaled_.push_back(made);
  return made;
}

std::size_t CollisionMesh::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + tree_.memory_bytes() + active_edges_.capacity();
  std::lock_guard<std::mutex> lock(cache_mutex_);
  for (const auto& converted : converted_) bytes += converted->memory_bytes() + sizeof(AnyTree);
  return bytes;
}

}  // namespace boxtree
