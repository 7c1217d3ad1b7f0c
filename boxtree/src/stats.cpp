// SPDX-License-Identifier: MIT
#include "boxtree/stats.h"

#include <sstream>

#include "boxtree/detail/volume_kinds.h"

namespace boxtree {
namespace {

// Subtree heights of every node (leaves 0), by a reverse pass over a pre-order of the tree:
// children always come after their parent in pre-order.
template <class Volume>
std::vector<int> node_levels(const Tree<Volume>& tree) {
  std::vector<NodeIndex> preorder;
  preorder.reserve(tree.node_count());
  std::vector<NodeIndex> stack{tree.root()};
  while (!stack.empty()) {
    const NodeIndex node = stack.back();
    stack.pop_back();
    preorder.push_back(node);
    if (!tree.is_leaf(node)) {
      stack.push_back(tree.first_child(node) + 1);
      stack.push_back(tree.first_child(node));
    }
  }
  std::vector<int> level(tree.node_count(), 0);
  for (auto it = preorder.rbegin(); it != preorder.rend(); ++it) {
    if (tree.is_leaf(*it)) continue;
    const NodeIndex c = tree.first_child(*it);
    level[*it] = 1 + std::max(level[c], level[c + 1]);
  }
  return level;
}

}  // namespace

template <class Volume>
TreeStats compute_tree_stats(const Tree<Volume>& tree) {
  TreeStats s;
  if (tree.empty()) return s;
  s.facets = tree.facet_count();
  s.nodes = tree.node_count();
  s.height = tree.height();
  s.memory_bytes = tree.memory_bytes();
  s.mesh_bytes = tree.mesh().vertices.size() * sizeof(Vec3) + tree.mesh().triangles.size() * sizeof(Triangle);
  const std::vector<int> level = node_levels(tree);
  s.levels.resize(std::size_t(tree.height()) + 1);
  Real area_sum = 0;
  Real width_sum = 0;
  for (NodeIndex node = 0; node < tree.node_count(); ++node) {
    LevelStats& l = s.levels[std::size_t(level[node])];
    const Real area = surface_area(tree.volume(node));
    l.nodes += 1;
    l.avg_area += area;
    l.avg_volume += volume(tree.volume(node));
    area_sum += area;
    width_sum += mean_width(tree.volume(node));
  }
  for (std::size_t i = 0; i < s.levels.size(); ++i) {
    LevelStats& l = s.levels[i];
    l.level = int(i);
    if (l.nodes > 0) {
      l.avg_area /= Real(l.nodes);
      l.avg_volume /= Real(l.nodes);
    }
  }
  const Real root_area = surface_area(tree.volume(tree.root()));
  // A flat root (a planar mesh) has no interior for planes to cut "at random"; fall back to
  // counting nodes, the limit of the ratio as the thickness goes to zero uniformly.
  s.plane_cost = root_area > 0 ? area_sum / root_area : Real(s.nodes);
  const Real root_width = mean_width(tree.volume(tree.root()));
  s.plane_cost_mean_width = root_width > 0 ? width_sum / root_width : Real(s.nodes);
  return s;
}

template <class Volume>
std::string validate_tree(const Tree<Volume>& tree, Real tolerance, Containment containment) {
  std::ostringstream problem;
  const std::size_t n = tree.facet_count();
  if (tree.empty()) return n == 0 ? "" : "tree has no nodes";
  if (tree.node_count() != 2 * n - 1) {
    problem << "node count " << tree.node_count() << " != 2n-1 = " << 2 * n - 1;
    return problem.str();
  }
  const Aabb root_box = bounding_aabb(tree.volume(tree.root()));
  const Real scale =
      std::max<Real>(1, root_box.extent().cwiseAbs().maxCoeff() +
                            std::max(root_box.min.cwiseAbs().maxCoeff(), root_box.max.cwiseAbs().maxCoeff()));
  const Real tol = tolerance * scale;

  std::vector<int> seen_node(tree.node_count(), 0);
  std::vector<int> seen_facet(n, 0);
  std::vector<NodeIndex> parent(tree.node_count(), tree.root());
  // Walk without trusting the links: check each before following it.
  std::vector<NodeIndex> stack{tree.root()};
  while (!stack.empty()) {
    const NodeIndex node = stack.back();
    stack.pop_back();
    if (node >= tree.node_count()) return "link out of range";
    if (seen_node[node]++) {
      problem << "node " << node << " reached twice";
      return problem.str();
    }
    if (tree.is_leaf(node)) {
      const FacetId f = tree.facet(node);
      if (f >= n) {
        problem << "leaf " << node << " names facet " << f << " of " << n;
        return problem.str();
      }
      seen_facet[f]++;
      for (int k = 0; k < 3; ++k)
        if (!contains(tree.volume(node), tree.mesh().corner(f, k), tol)) {
          problem << "leaf " << node << " does not contain corner " << k << " of facet " << f;
          return problem.str();
        }
      if (containment == Containment::facets_in_ancestors) {
        for (NodeIndex up = node; up != tree.root();) {
          up = parent[up];
          for (int k = 0; k < 3; ++k)
            if (!contains(tree.volume(up), tree.mesh().corner(f, k), tol)) {
              problem << "node " << up << " does not contain corner " << k << " of facet " << f << " below it";
              return problem.str();
            }
        }
      }
      continue;
    }
    const NodeIndex c = tree.first_child(node);
    if (c <= node || c + 1 >= tree.node_count()) {
      problem << "node " << node << " has child link " << c;
      return problem.str();
    }
    parent[c] = parent[c + 1] = node;
    for (NodeIndex child : {c, c + 1})
      if (containment == Containment::children_in_parent && !contains(tree.volume(node), tree.volume(child), tol)) {
        problem << "volume of node " << child << " is not inside its parent " << node;
        return problem.str();
      }
    stack.push_back(c + 1);
    stack.push_back(c);
  }
  for (std::size_t i = 0; i < tree.node_count(); ++i)
    if (!seen_node[i]) {
      problem << "node " << i << " is unreachable";
      return problem.str();
    }
  for (std::size_t f = 0; f < n; ++f)
    if (seen_facet[f] != 1) {
      problem << "facet " << f << " is in " << seen_facet[f] << " leaves";
      return problem.str();
    }
  const std::vector<int> level = node_levels(tree);
  if (level[tree.root()] != tree.height()) {
    problem << "stored height " << tree.height() << " != real height " << level[tree.root()];
    return problem.str();
  }
  return "";
}

#define BOXTREE_INSTANTIATE_STATS(V)                        \
  template TreeStats compute_tree_stats<V>(const Tree<V>&); \
  template std::string validate_tree<V>(const Tree<V>&, Real, Containment);
BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_STATS)

}  // namespace boxtree
