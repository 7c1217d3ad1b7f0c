// SPDX-License-Identifier: MIT
#pragma once
// A triangle mesh prepared for collision, built once and shared: its tree, its bounds, which of
// its edges are real creases (active_edges.h) and whether its facets have meaningful fronts
// (consistent winding). Engine shapes and geoms hold a shared_ptr to one; any number of them may
// share it, from any number of threads, at no per-facet cost each (everything here is immutable
// after construction; the two caches below are guarded).
//
// The collider (collider.h) reads it; the engine adapters (engine/) make it from their users'
// meshes and keep it in their shapes.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "boxtree/any_tree.h"

namespace boxtree {

class CollisionMesh : public std::enable_shared_from_this<CollisionMesh> {
 public:
  // Validates the mesh and builds its tree (AnyTree::build; throws boxtree::Error on a bad mesh
  // or method), then the edge and winding data.
  static std::shared_ptr<const CollisionMesh> build(std::shared_ptr<const TriangleMesh> mesh, const Method& method,
                                                    const BuildSettings& settings = {});
  // Around an already built tree (shares it). The same tree object (AnyTree copies of one built
  // tree) gives the same CollisionMesh while any holder keeps it alive, so shapes made from one
  // shared tree also share its edge data. Throws boxtree::Error on an empty tree.
  static std::shared_ptr<const CollisionMesh> of(const AnyTree& tree);

  explicit CollisionMesh(AnyTree tree);  // prefer build() / of(); throws on an empty tree
  CollisionMesh(const CollisionMesh&) = delete;
  CollisionMesh& operator=(const CollisionMesh&) = delete;

  const AnyTree& tree() const { return tree_; }
  const TriangleMesh& mesh() const { return tree_.mesh(); }
  const Method& method() const { return tree_.method(); }
  // Axis-aligned bounds of every facet (computed once, at construction).
  const Aabb& bounds() const { return bounds_; }
  // Per facet, bit k set when edge (corner k, corner k+1) is active (active_edges.h, crease 10°).
  const std::vector<std::uint8_t>& active_edges() const { return active_edges_; }
  // Fronts: a facet's front is its counter-clockwise side. They mean something when every edge
  // that two facets share is run along in opposite directions by the two (a consistently wound
  // surface: closed meshes wound outward, terrains wound upward); the collider treats a mesh
  // without that as two-sided whatever it is asked (ContactRequest::two_sided).
  bool consistent_winding() const { return inconsistent_edges_ == 0; }
  std::size_t inconsistent_edges() const { return inconsistent_edges_; }
  // True once, the first time it is asked of an inconsistently wound mesh (false for a consistent
  // one): for an engine adapter's one-time message. Thread-safe.
  bool first_winding_report() const {
    return !consistent_winding() && !winding_reported_.exchange(true, std::memory_order_relaxed);
  }

  // This mesh's tree with `method`'s volume kind, for tree-vs-tree against a mesh of another
  // method: the own tree when the kinds agree, else a tree of `method` built on first use and
  // kept for the mesh's life (one per kind; thread-safe). Never throws for a method this mesh's
  // tree was built with elsewhere; a build failure (out of memory) propagates.
  const AnyTree& tree_as(const Method& method) const;

  // The mesh scaled by `scale` per axis (finite, non-zero; throws boxtree::Error otherwise), with
  // the tree rebuilt by the same method (as btBvhTriangleMeshShape::setLocalScaling rebuilds its
  // BVH). Facet ids are kept; a negative determinant mirrors the mesh, so each facet's corners 1
  // and 2 are swapped to keep its front on the same side of the surface (the active edges follow).
  // Scale (1, 1, 1) returns this mesh itself. Meshes of one scale are shared while alive.
  std::shared_ptr<const CollisionMesh> scaled(const Vec3& scale) const;
  // The scale this mesh was made with from its original (1, 1, 1 for a built one), and whether
  // its facets' corners 1 and 2 were swapped (a mirroring scale).
  const Vec3& scale() const { return scale_; }
  bool mirrored() const { return mirrored_; }

  // The tree, active edges and caches (not the mesh, which the caller may share).
  std::size_t memory_bytes() const;

 private:
  AnyTree tree_;
  Aabb bounds_;
  std::vector<std::uint8_t> active_edges_;
  std::size_t inconsistent_edges_ = 0;
  Vec3 scale_ = Vec3::Ones();
  bool mirrored_ = false;
  mutable std::atomic<bool> winding_reported_{false};

  mutable std::mutex cache_mutex_;
  mutable std::vector<std::unique_ptr<const AnyTree>> converted_;  // stable addresses: tree_as returns references
  mutable std::vector<std::weak_ptr<const CollisionMesh>> scaled_;
};

// Whether two methods' trees can be walked against each other (collide needs one volume kind).
bool same_volume_kind(const Method& a, const Method& b);

}  // namespace boxtree
