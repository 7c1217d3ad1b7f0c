// SPDX-License-Identifier: MIT
#pragma once
// The boxtree: a binary bounding-volume hierarchy whose leaves are in bijection with the facets
// of a triangle mesh (paper, Section 1). Built by build_tree (build.h), read by the queries
// (query.h, collide.h) and statistics (stats.h).
//
// Layout: flat arrays indexed by NodeIndex; the root is node 0; the two children of an inner
// node are adjacent (first_child, first_child + 1). Volumes (hot, read by every query) are kept
// apart from the links.
//
// Ownership: a tree shares ownership of its mesh (std::shared_ptr<const TriangleMesh>), so a
// tree may outlive the caller's handle on the mesh; the mesh must not be modified while a tree
// refers to it. A built tree is immutable: all queries are const and safe from many threads.
#include <cstdint>
#include <memory>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/mesh.h"

namespace boxtree {

using NodeIndex = std::uint32_t;

template <class Volume>
class Tree {
 public:
  // Bit 31 set: a leaf, the low bits are its facet id. Clear: an inner node, the low bits are
  // the index of its first child (the second is first + 1).
  static constexpr std::uint32_t kLeafFlag = 0x80000000u;
  static constexpr std::uint32_t kMaxFacets = kLeafFlag - 1;
  // Queries walk the tree with a fixed stack of this many entries; the builder's O(log n)
  // height guarantee (at most log_{4/3} n, i.e. < 75 for kMaxFacets) keeps trees well below it.
  static constexpr int kMaxHeight = 120;

  Tree() = default;
  Tree(std::shared_ptr<const TriangleMesh> mesh, std::vector<Volume> volumes, std::vector<std::uint32_t> links,
       int height)
      : mesh_(std::move(mesh)), volumes_(std::move(volumes)), links_(std::move(links)), height_(height) {
    BOXTREE_ASSERT(volumes_.size() == links_.size(), "one volume per node");
    BOXTREE_ASSERT(height_ <= kMaxHeight, "tree height within the queries' fixed stack");
  }

  const TriangleMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TriangleMesh>& shared_mesh() const { return mesh_; }

  bool empty() const { return links_.empty(); }
  std::size_t node_count() const { return links_.size(); }
  std::size_t facet_count() const { return mesh_ ? mesh_->facet_count() : 0; }
  // Edges on the longest root-to-leaf path: 0 for a single facet.
  int height() const { return height_; }

  static constexpr NodeIndex root() { return 0; }
  bool is_leaf(NodeIndex node) const { return (links_[node] & kLeafFlag) != 0; }
  FacetId facet(NodeIndex leaf) const { return links_[leaf] & ~kLeafFlag; }
  NodeIndex first_child(NodeIndex inner) const { return links_[inner]; }
  const Volume& volume(NodeIndex node) const { return volumes_[node]; }

  // Bytes of the hierarchy itself (volumes + links), not counting the mesh.
  std::size_t memory_bytes() const {
    return volumes_.capacity() * sizeof(Volume) + links_.capacity() * sizeof(std::uint32_t);
  }

 private:
  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<Volume> volumes_;       // hot: one per node
  std::vector<std::uint32_t> links_;  // 4 B per node: first child or leaf flag | facet
  int height_ = 0;
};

}  // namespace boxtree
