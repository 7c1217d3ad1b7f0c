// SPDX-License-Identifier: MIT
#pragma once
// Tree vs tree with temporal coherence: the front of the last descent as the next call's start
// (generalized front tracking: Ehmann and Lin, "Accurate and Fast Proximity Queries Between
// Polyhedra Using Convex Surface Decomposition", Computer Graphics Forum 20(3), Eurographics 2001).
//
// A tree-vs-tree descent (collide.h) walks the bounding-volume test tree: the pairs (node of a,
// node of b), each pair's children being its larger node's children against the other node. The
// descent stops at a cut of that tree, its front: pairs whose volumes are apart, and leaf pairs.
// Between two steps of a simulation the bodies move little and the front hardly changes, so the
// next call starts from it instead of from the roots:
//   - a pair of the front that is apart stays in the front. Its record keeps a lower bound of
//     the distance between the two volumes, and the call keeps the distance every point of b's
//     volumes may have moved in a's frame since (the sum of each call's bound): while that motion
//     is below the pair's distance, the pair is still apart and is not tested again (the "apart
//     pairs re-checked cheaply" of a resting pile). Otherwise its volumes are tested again. A
//     leaf pair whose facets do not intersect is kept the same way, by the facets' separation
//     along either facet's normal (most leaf pairs of a resting contact), so that its exact test
//     is not repeated either;
//   - a pair that now overlaps is descended from, as in a fresh descent; the pairs where that
//     descent stops join the front;
//   - where every child of a pair is apart, one of them was tested in this call, and the pair
//     itself is apart, the children are replaced by the pair (pulled back up), so the front
//     follows separating bodies back up the tree instead of growing without bound.
// The facet pairs reported are those of a fresh descent (collide(a, b, a_from_b, ...)): every
// intersecting facet pair (touching counts), by the same exact leaf test; only their order
// differs (sort them for an order-independent result, as collider.h's collide_meshes does).
// Volumes are tested on their six face axes, padded against rounding, and skipped only when
// apart by more than the pad: no pair a fresh descent reports is missed.
//
// Memory: the front is kept as the descended part of the test tree in preorder, 24 bytes per
// record, at most CollideFront::max_records() records (8,192 by default), in two buffers (the
// last front and the one being written): at most 2 x 24 x max_records bytes, 384 KiB per pair of
// meshes by default. A call whose front would pass the cap is completed without keeping one; the
// front and its memory are dropped and the next kFreshCallsAfterOverflow calls descend fresh
// (packed_tree.h's collide), then one tries again. A visitor that stops the walk (returns false)
// also drops the front.
//
// For the packed aabb form (packed_tree.h), which AnyTree holds for the `aabb` method (the
// engine adapters' default); the other layouts have no front (collider.h's collide_meshes
// descends fresh for them).
//
// The engine adapters leave it off by default: on a resting pile it tests far fewer volumes than
// a fresh descent, but takes about as long in ODE and longer in Bullet (figures: bench/RESULTS.md,
// "Notes from earlier measurements").
#include <cstdint>
#include <vector>

#include "boxtree/packed_tree.h"

namespace boxtree {

// What the last call with a front did.
struct FrontStats {
  std::size_t records_in = 0;   // records the call started from (0: a fresh descent)
  std::size_t records_out = 0;  // records kept for the next call
  std::size_t kept_apart = 0;   // front pairs not tested again (their distance covers the motion)
  std::size_t kept_whole = 0;   // subtrees of inner records kept as they were, without a visit per record
  std::size_t retested = 0;     // front pairs tested again
  std::size_t descended = 0;    // pairs descended from (overlapping volumes, not a leaf pair)
  std::size_t pulled_up = 0;    // pairs whose children were replaced by the pair
  bool overflowed = false;      // the front passed max_records() and was dropped
  bool fresh = false;           // the call descended fresh (after an overflow, or a stop)
};

// The per-pair state: the front of the last call and what it needs to trust it (the two trees,
// the last pose, the motion since). Owns no tree: the trees must outlive the front's use with
// them; a call with other trees (or other sizes) than the last one's starts afresh, as does a
// call after clear(). Not shared between threads.
class CollideFront {
 public:
  static constexpr std::size_t kDefaultMaxRecords = 8192;
  static constexpr int kFreshCallsAfterOverflow = 16;
  // A record: a pair of node references (the root, or an inner node's child slot). A cut record
  // (a pair of the front) holds the motion after which the pair must be tested again (-infinity:
  // on every call, a leaf pair that may touch). An inner record (a pair descended through, its
  // children following in preorder) holds by which tree it split, how many records its subtree
  // spans (itself included), and the least expiry of the subtree's cut records: while the motion
  // is below it, the whole subtree is kept as it is, without a visit per record.
  struct Record {
    enum Split : std::uint8_t { kCut = 0, kSplitA = 1, kSplitB = 2 };
    std::uint32_t a = 0, b = 0;
    Real expiry = 0;
    std::uint32_t span = 1;
    std::uint8_t split = kCut;
  };
  static_assert(sizeof(Record) == 24, "a record is 24 bytes");

  explicit CollideFront(std::size_t max_records = kDefaultMaxRecords) : max_records_(max_records) {}

  void clear();
  bool empty() const { return records_.empty(); }
  // Records kept: the front's pairs and the pairs above them that were descended through.
  std::size_t size() const { return records_.size(); }
  // The front's pairs alone (apart pairs and leaf pairs).
  std::size_t cut_size() const;
  std::size_t max_records() const { return max_records_; }
  // Bytes held (both record buffers' capacity).
  std::size_t memory_bytes() const { return (records_.capacity() + spare_.capacity()) * sizeof(Record); }
  const FrontStats& last_call() const { return last_; }

 private:
  friend void collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
                      CollideFront& front, FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats);

  std::vector<Record> records_, spare_;  // the front in preorder; the buffer the next call writes
  std::size_t max_records_;
  const PackedAabbTree* tree_a_ = nullptr;
  const PackedAabbTree* tree_b_ = nullptr;
  std::size_t nodes_a_ = 0, nodes_b_ = 0;
  RigidTransform last_pose_;
  Real travel_ = 0;  // bound on how far any point of b's volumes moved in a's frame since the front began
  int fresh_calls_ = 0;
  FrontStats last_;
};

// Tree vs tree from `front` (empty: from the roots), leaving the new front in it. Same contract
// as collide(a, b, a_from_b, visit, stats) of packed_tree.h, the order of the pairs aside;
// QueryStats counts the volume pairs tested (volume_tests), the records and pairs visited
// (nodes_visited) and the facet pairs tested (leaf_tests).
void collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b, CollideFront& front,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats = nullptr);

}  // namespace boxtree
