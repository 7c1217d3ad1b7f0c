// SPDX-License-Identifier: MIT
#pragma once
// Bottom-up construction (paper, Section 3): leaves are the facets; in each round a maximal set
// of disjoint pairs of neighbouring nodes is merged, cheapest merged volume first, and unpaired
// nodes are carried to the next round.
#include <cstdint>
#include <memory>
#include <vector>

#include "boxtree/tree.h"

namespace boxtree {

// What a pair costs: the merged volume's surface area (default; by Cauchy's formula it is
// proportional to the chance that a random plane cuts it, paper Section 4) or its volume.
enum class MergeCost { surface_area, volume };

// How a parent's volume is computed once the tree's shape is known.
//  enclose_children: the paper's rule applied to the children's volumes (their 16 box corners or
//    12 prism corners): every child lies inside its parent, but the slack of each level is
//    carried into the next, so upper-level oriented volumes grow loose.
//  fit_facets: the same rule applied to the leaf volumes below the node (the facets, or for boxes
//    the facets' enclosing rectangles; as top-down builders such as FCL's fit every node to its
//    primitives), keeping the children's volume where that is the smaller one. Every leaf volume
//    lies inside every ancestor's volume (what the queries rely on), but an inner node's volume
//    may stick out of its parent's. Costs O(n log n) more build time. Pie slices
//    whose projected hull exceeds PieSlice::kMaxFittedHull points keep the children's rule.
//    Hybrids: the upper boxes are the leaf volumes' exact bounding boxes. No effect on aabb (exact).
enum class ParentFit { enclose_children, fit_facets };

// How the greedy builder ranks candidate pairs for the oriented kinds (axis-aligned boxes are
// always ranked by their exact merged box, which is cheap):
//  merged_volume (default): the paper's rule to the letter: every candidate's parent volume is
//    fitted (PCA, minimum-area rectangle or triangle) and ranked by its cost; a fit per candidate.
//  bounding_box: by the cost (BuildSettings::cost) of the axis-aligned box around both nodes, a
//    cheap proxy of the merged volume's size, so the tree has the aabb build's shape; only the
//    chosen pairs' parents are fitted (n - 1 fits, in the final layout). A faster build, but
//    looser trees (more volume tests per query). Earlier figures: bench/RESULTS.md, "Notes from
//    earlier measurements".
enum class PairRanking { merged_volume, bounding_box };

// A tree's shape given from outside the greedy rounds: its parents in build order. Leaves
// 0..n-1 are the facets; parent k (node n + k) merges nodes first[k] and second[k], both built
// before it; every node but the last parent (the root) is merged exactly once, so each vector
// holds n - 1 entries. An order that breaks this is a programmer error (asserted).
struct MergeOrder {
  std::vector<std::uint32_t> first;
  std::vector<std::uint32_t> second;
  int rounds = 0;                   // reported as BuildStats::rounds
  std::size_t candidate_pairs = 0;  // reported as BuildStats::candidate_pairs
};
// The merge order for a mesh, called by build_tree after validating it; throws boxtree::Error
// for a mesh it does not apply to.
using MergeRule = MergeOrder (*)(const TriangleMesh& mesh);

struct BuildSettings {
  MergeCost cost = MergeCost::surface_area;
  // Besides mesh adjacency, each node is offered as partner to its `near_window` successors in
  // a Morton (Z-order) ordering of node centres. This pairs nodes that are near but not
  // connected (triangle soups, separate components) and guarantees that every round pairs at
  // least a quarter of the nodes, so the height stays O(log n).
  int near_window = 2;
  // A vertex shared by more than this many facets links them in a chain (in facet order) instead
  // of all pairs, bounding the work per round around high-valence vertices (e.g. a cone's apex).
  int max_neighbors = 16;
  // For hybrid volume kinds (volume/hybrid.h) only: nodes at this level and above (level =
  // subtree height, leaves 0) get axis-aligned boxes. Must be >= 1 for hybrids.
  int hybrid_level = 0;
  ParentFit parent_fit = ParentFit::enclose_children;
  PairRanking ranking = PairRanking::merged_volume;
  // Which pairs are merged: the greedy rounds above (nullptr, the default), or the merge order a
  // rule gives (MergeRule below), such as planar::terrain_merge_order, the paper's Section 3.1
  // rule (planar/terrain.h). With a rule, parents always enclose their children and
  // cost/near_window/max_neighbors/parent_fit/ranking do not apply.
  MergeRule merge_rule = nullptr;
};

struct BuildStats {
  int rounds = 0;
  std::size_t candidate_pairs = 0;  // summed over rounds
  double seconds = 0;
};

// Validates the mesh (throws boxtree::Error, see validate_mesh) and builds its tree.
// Deterministic: the same mesh and settings give the same tree.
template <class Volume>
Tree<Volume> build_tree(std::shared_ptr<const TriangleMesh> mesh, const BuildSettings& settings = {},
                        BuildStats* stats = nullptr);

// Convenience: copies the mesh into the tree.
template <class Volume>
Tree<Volume> build_tree(const TriangleMesh& mesh, const BuildSettings& settings = {}, BuildStats* stats = nullptr) {
  return build_tree<Volume>(std::make_shared<const TriangleMesh>(mesh), settings, stats);
}

}  // namespace boxtree
