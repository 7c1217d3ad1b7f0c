// SPDX-License-Identifier: MIT
#pragma once
// The planar boxtree of a rectilinear subdivision (paper, Section 2, Theorem 2.2), built
// bottom-up by the segment-graph pairing rule, and point location through it.
//
// Round structure (build_planar_tree):
//   1. the current cells (a partition of the domain; leaves at first) define maximal segments;
//      a segment's degree in the paper's graph G is the number of cells along its two sides;
//   2. for one colour (vertical or horizontal segments, whichever pairs more), each segment of
//      degree <= max_segment_degree offers one pair of cells across it whose bounding box is
//      covered by the pair plus full-height (full-width) slices of other cells along the segment;
//   3. a maximal set of compatible offers is taken left to right (pairs disjoint, no paired
//      cell covered by another pair's box);
//   4. each pair becomes a parent whose box encloses its children's original boxes; the cells
//      the pair's box covers are "shortened" across the segment, so the cells form a partition
//      again (the pair's cell is its bounding box in shortened coordinates).
// A parent's box always encloses the unshortened boxes of its children; the cells only steer
// the pairing.
//
// Ownership: a PlanarTree owns a copy of the input rectangles; it is immutable once built.
#include <cstdint>
#include <optional>
#include <vector>

#include "boxtree/planar/rect.h"

namespace boxtree::planar {

using PlanarNode = std::uint32_t;

class PlanarTree {
 public:
  // Bit 31 set: a leaf, the low bits are its rectangle id. Clear: the first child's index (the
  // second is first + 1). The root is node 0; children follow their parent (depth-first).
  static constexpr std::uint32_t kLeafFlag = 0x80000000u;
  static constexpr int kMaxHeight = 200;

  PlanarTree() = default;
  PlanarTree(std::vector<Rect> cells, std::vector<Rect> boxes, std::vector<std::uint32_t> links, int height);

  bool empty() const { return links_.empty(); }
  std::size_t node_count() const { return links_.size(); }
  std::size_t cell_count() const { return cells_.size(); }
  int height() const { return height_; }  // edges on the longest root-to-leaf path

  static constexpr PlanarNode root() { return 0; }
  bool is_leaf(PlanarNode node) const { return (links_[node] & kLeafFlag) != 0; }
  RectId cell_id(PlanarNode leaf) const { return links_[leaf] & ~kLeafFlag; }
  PlanarNode first_child(PlanarNode inner) const { return links_[inner]; }
  const Rect& box(PlanarNode node) const { return boxes_[node]; }
  const Rect& cell(RectId id) const { return cells_[id]; }
  const std::vector<Rect>& cells() const { return cells_; }
  const Rect& domain() const { return boxes_.front(); }

 private:
  std::vector<Rect> cells_;           // the input partition, by id
  std::vector<Rect> boxes_;           // one per node (hot)
  std::vector<std::uint32_t> links_;  // one per node
  int height_ = 0;
};

struct PlanarBuildSettings {
  // Segments of degree up to this offer a pair (the paper: 4, Lemma 2.1 and Theorem 2.2).
  int max_segment_degree = 4;
  // Check the input with validate_partition first (throws boxtree::Error on overlap or gap).
  bool validate_input = true;
  // Re-validate the shortened cells after every round (tests; O(n log n) per round).
  bool check_rounds = false;
};

struct PlanarRoundStats {
  std::size_t cells = 0;                // m: size of the partition entering the round
  std::size_t low_degree_segments = 0;  // of the chosen colour, degree <= max_segment_degree
  std::size_t offers = 0;               // segments that offered a valid pair
  std::size_t pairs = 0;                // pairs merged (the paper guarantees >= (m + 3) / 12)
  std::size_t shortened = 0;            // cells shortened after the merge
  bool vertical = true;                 // colour: pairs across vertical segments
};

struct PlanarBuildStats {
  std::vector<PlanarRoundStats> rounds;
  // Rounds in which the pairing found nothing and the remaining nodes were paired by a plain
  // nearest-centre fallback (never observed; reported so that tests can assert it).
  int fallback_rounds = 0;
  double validate_seconds = 0;
  double build_seconds = 0;  // pairing rounds and layout, without validation
};

// Builds the planar boxtree of a rectangular partition (cell i of the input is leaf cell_id i).
// Throws boxtree::Error if the input is empty or (validate_input) not a partition.
PlanarTree build_planar_tree(std::vector<Rect> cells, const PlanarBuildSettings& settings = {},
                             PlanarBuildStats* stats = nullptr);

struct PlanarQueryStats {
  std::uint64_t nodes_visited = 0;  // nodes whose box contains the point
};

// The cell containing p, cells taken half-open ([min, max) on each axis, closed at the
// domain's max sides) so that every point of the domain has exactly one; nullopt outside.
std::optional<RectId> locate_point(const PlanarTree& tree, const Vec2& p, PlanarQueryStats* stats = nullptr);
// Reference: the same convention by scanning every cell.
std::optional<RectId> locate_point_brute_force(const std::vector<Rect>& cells, const Vec2& p);
bool cell_contains_half_open(const Rect& cell, const Rect& domain, const Vec2& p);

// The paper's stabbing number of a planar boxtree: the maximum over points of the number of
// node boxes whose interior contains the point (exact, by a sweep over the boxes: O(n log n)).
std::size_t stabbing_number(const PlanarTree& tree);
// The number of node boxes whose interior contains p (brute force over the nodes).
std::size_t point_depth(const PlanarTree& tree, const Vec2& p);

// Throws boxtree::Error naming the first broken invariant: links form a binary tree over all
// cells, each leaf's box is its cell, each parent's box is the smallest enclosing its children's,
// and the height is right.
void validate_planar_tree(const PlanarTree& tree);

// The pairing's topology alone, for builders that fit other volumes to it (the terrain rule):
// merges in creation order; node ids 0..n-1 are the cells, n + i is the parent made by merge i.
struct PlanarMerge {
  std::uint32_t first, second;
};
std::vector<PlanarMerge> planar_pairing(std::vector<Rect> cells, const PlanarBuildSettings& settings = {},
                                        PlanarBuildStats* stats = nullptr);

}  // namespace boxtree::planar
