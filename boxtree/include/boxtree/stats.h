// SPDX-License-Identifier: MIT
#pragma once
// Tree statistics (the paper's measures, Section 4) and a full structural check.
#include <string>
#include <vector>

#include "boxtree/tree.h"

namespace boxtree {

// Level = height of a node's subtree: leaves are level 0, the root is level height(). This is
// the paper's "level" counted from the bottom, where Figures 3-4 compare the methods.
struct LevelStats {
  int level = 0;
  std::size_t nodes = 0;
  Real avg_area = 0;    // mean surface area of the level's volumes
  Real avg_volume = 0;  // mean volume
};

struct TreeStats {
  std::size_t facets = 0;
  std::size_t nodes = 0;
  int height = 0;
  std::size_t memory_bytes = 0;  // the hierarchy (volumes + links), not the mesh
  std::size_t mesh_bytes = 0;    // the mesh's vertex and index arrays
  std::vector<LevelStats> levels;
  // The paper's expected random-plane cost, sum_v S_v / S_root (Section 4). Note: by
  // Cauchy-Crofton this ratio is exactly the expected number of volumes cut by a random *line*
  // that cuts the root (tests/test_stats.cpp checks it by sampling). For random *planes* the
  // measure of planes meeting a convex body is proportional to its mean width, not its area:
  // that expectation is plane_cost_mean_width.
  Real plane_cost = 0;
  Real plane_cost_mean_width = 0;  // sum_v W_v / W_root, W = mean width
};

template <class Volume>
TreeStats compute_tree_stats(const Tree<Volume>& tree);

// What validate_tree requires of the volumes: every child volume inside its parent (trees built
// with ParentFit::enclose_children), or only every facet inside all its ancestors' volumes (what
// the queries rely on; trees built with ParentFit::fit_facets).
enum class Containment { children_in_parent, facets_in_ancestors };

// Checks every structural invariant and returns a description of the first violation, or an
// empty string: 2n-1 nodes; every facet in exactly one leaf; every node reachable exactly once;
// containment as chosen (up to `tolerance`, relative to the root's size); every leaf volume
// contains its facet's corners; the stored height is the real height.
template <class Volume>
std::string validate_tree(const Tree<Volume>& tree, Real tolerance = 1e-12,
                          Containment containment = Containment::children_in_parent);

}  // namespace boxtree
