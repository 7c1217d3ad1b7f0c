// SPDX-License-Identifier: MIT
// Statistics: per-level sums, and the meaning of plane_cost checked by Monte Carlo.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

TEST(Stats, LevelsAddUp) {
  for (const auto& [name, mesh] : test::procedural_meshes()) {
    const Tree<Aabb> tree = build_tree<Aabb>(mesh);
    const TreeStats s = compute_tree_stats(tree);
    EXPECT_EQ(s.facets, mesh.facet_count());
    EXPECT_EQ(s.nodes, 2 * s.facets - 1);
    EXPECT_EQ(s.height, tree.height());
    ASSERT_EQ(s.levels.size(), std::size_t(tree.height()) + 1) << name;
    std::size_t nodes = 0;
    double area = 0;
    for (const LevelStats& l : s.levels) {
      nodes += l.nodes;
      area += l.avg_area * double(l.nodes);
    }
    EXPECT_EQ(nodes, s.nodes) << name;
    EXPECT_EQ(s.levels[0].nodes, s.facets) << name << ": level 0 is the leaves";
    EXPECT_EQ(s.levels.back().nodes, 1u) << name << ": the top level is the root";
    const double root_area = surface_area(tree.volume(tree.root()));
    if (root_area > 0) {
      EXPECT_NEAR(s.plane_cost, area / root_area, 1e-9 * s.plane_cost) << name;
    }
    EXPECT_GE(s.memory_bytes, s.nodes * (sizeof(Aabb) + 4));
  }
}

// Sum S_v / S_root is, by Cauchy-Crofton, the expected number of volumes that a random line
// cutting the root volume also cuts (the motion-invariant measure of lines meeting a convex body
// is proportional to its surface area). Sampled here with isotropic lines.
TEST(Stats, PlaneCostIsTheExpectedCountOfRandomLineCuts) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_bumpy_sphere(24, 12, 0.3, 5));
  const TreeStats s = compute_tree_stats(tree);
  const Aabb root = tree.volume(tree.root());
  const Vec3 centre = root.center();
  const double radius = root.extent().norm() / 2;
  Random r(3);
  double cut_total = 0;
  int lines = 0;
  while (lines < 20000) {
    // Isotropic uniform line: uniform direction, uniform point in a disc perpendicular to it.
    const Vec3 d = r.unit_vector();
    const Vec3 u = d.unitOrthogonal();
    const Vec3 w = d.cross(u);
    double x, y;
    do {
      x = r.uniform(-1, 1);
      y = r.uniform(-1, 1);
    } while (x * x + y * y > 1);
    Ray line{centre + radius * (x * u + y * w), d, -std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
    const RayPrecomputed pre(line);
    if (!intersect_ray(root, pre, line.t_min, line.t_max)) continue;
    ++lines;
    for (NodeIndex node = 0; node < tree.node_count(); ++node)
      cut_total += intersect_ray(tree.volume(node), pre, line.t_min, line.t_max);
  }
  const double mean = cut_total / lines;
  EXPECT_NEAR(mean, s.plane_cost, 0.03 * s.plane_cost) << "sampled " << mean << " vs formula " << s.plane_cost;
}

// Random planes (uniform normal, uniform offset: the motion-invariant measure) that cut the
// root cut on average sum W_v / W_root volumes, W = mean width (Crofton) -- not sum S_v / S_root.
TEST(Stats, MeanWidthCostIsTheExpectedCountOfRandomPlaneCuts) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_bumpy_sphere(24, 12, 0.3, 5));
  const TreeStats s = compute_tree_stats(tree);
  const Aabb root = tree.volume(tree.root());
  const Vec3 centre = root.center();
  const double radius = root.extent().norm() / 2;
  Random r(4);
  double cut_total = 0;
  int planes = 0;
  while (planes < 20000) {
    Plane plane{r.unit_vector(), 0};
    plane.offset = plane.normal.dot(centre) + r.uniform(-radius, radius);
    if (!overlaps(root, plane)) continue;
    ++planes;
    for (NodeIndex node = 0; node < tree.node_count(); ++node) cut_total += overlaps(tree.volume(node), plane);
  }
  const double mean = cut_total / planes;
  EXPECT_NEAR(mean, s.plane_cost_mean_width, 0.03 * s.plane_cost_mean_width)
      << "sampled " << mean << " vs formula " << s.plane_cost_mean_width;
  // The two measures really differ on this tree, so the check above can tell them apart.
  EXPECT_GT(std::abs(s.plane_cost - s.plane_cost_mean_width), 0.1 * s.plane_cost_mean_width);
}

// ---- validate_tree, shown broken trees: one invariant of its contract broken at a time ----

// A built tree's arrays, to break one thing and rebuild with Tree's constructor.
struct TreeParts {
  std::shared_ptr<const TriangleMesh> mesh;
  std::vector<Aabb> volumes;
  std::vector<std::uint32_t> links;
  int height = 0;

  explicit TreeParts(const Tree<Aabb>& tree) : mesh(tree.shared_mesh()), height(tree.height()) {
    for (NodeIndex i = 0; i < tree.node_count(); ++i) {
      volumes.push_back(tree.volume(i));
      links.push_back(tree.is_leaf(i) ? (Tree<Aabb>::kLeafFlag | tree.facet(i)) : tree.first_child(i));
    }
  }
  Tree<Aabb> tree() const { return Tree<Aabb>(mesh, volumes, links, height); }
  bool is_leaf(NodeIndex i) const { return (links[i] & Tree<Aabb>::kLeafFlag) != 0; }
  FacetId facet(NodeIndex i) const { return links[i] & ~Tree<Aabb>::kLeafFlag; }
  // The first inner node whose two children are leaves.
  NodeIndex leaf_pair_parent() const {
    for (NodeIndex i = 0; i < links.size(); ++i)
      if (!is_leaf(i) && is_leaf(links[i]) && is_leaf(links[i] + 1)) return i;
    ADD_FAILURE() << "no inner node with two leaf children";
    return 0;
  }
};

class ValidateTree : public ::testing::Test {
 protected:
  ValidateTree() : built(build_tree<Aabb>(make_terrain(4, 4, 1))), parts(built) {}
  Tree<Aabb> built;
  TreeParts parts;  // a copy of `built`, for each test to break
  std::size_t n() const { return built.facet_count(); }
  std::string node(NodeIndex i) const { return std::to_string(i); }
};

TEST_F(ValidateTree, TheUnbrokenCopyIsValid) {
  // Every test below breaks this copy in one place: anything it reports comes from that change.
  ASSERT_EQ(n(), 32u);
  EXPECT_EQ(validate_tree(parts.tree()), "");
  EXPECT_EQ(validate_tree(parts.tree(), 1e-12, Containment::facets_in_ancestors), "");
  EXPECT_EQ(validate_tree(Tree<Aabb>()), "");  // no facets, no nodes
}

TEST_F(ValidateTree, NoNodes) { EXPECT_EQ(validate_tree(Tree<Aabb>(parts.mesh, {}, {}, 0)), "tree has no nodes"); }

TEST_F(ValidateTree, NodeCountNot2nMinus1) {
  parts.volumes.push_back(parts.volumes.back());
  parts.links.push_back(parts.links.back());
  EXPECT_EQ(validate_tree(parts.tree()), "node count 64 != 2n-1 = 63");
}

TEST_F(ValidateTree, LeafNamesAFacetOutOfRange) {
  const NodeIndex leaf = parts.links[parts.leaf_pair_parent()];
  parts.links[leaf] = Tree<Aabb>::kLeafFlag | FacetId(n());
  EXPECT_EQ(validate_tree(parts.tree()), "leaf " + node(leaf) + " names facet 32 of 32");
}

TEST_F(ValidateTree, FacetInTwoLeavesAndAnotherInNone) {
  // Sibling leaves both name the second one's facet (with its box: every volume still holds its
  // facet and sits inside its parent).
  const NodeIndex first = parts.links[parts.leaf_pair_parent()];
  const FacetId lost = parts.facet(first), doubled = parts.facet(first + 1);
  parts.links[first] = parts.links[first + 1];
  parts.volumes[first] = parts.volumes[first + 1];
  const std::string expected = lost < doubled ? "facet " + std::to_string(lost) + " is in 0 leaves"
                                              : "facet " + std::to_string(doubled) + " is in 2 leaves";
  EXPECT_EQ(validate_tree(parts.tree()), expected);
}

TEST_F(ValidateTree, LeafVolumeMissesItsFacet) {
  // The leaf's box shrunk to a point near its centre: still inside its parent, but no corner of
  // its facet (a terrain's corners lie on a grid of 25 in x and y).
  const NodeIndex leaf = parts.links[parts.leaf_pair_parent()];
  const Vec3 point = parts.volumes[leaf].center() + Vec3(0.123, 0.0456, 0);
  parts.volumes[leaf] = Aabb{point, point};
  EXPECT_EQ(validate_tree(parts.tree()),
            "leaf " + node(leaf) + " does not contain corner 0 of facet " + std::to_string(parts.facet(leaf)));
}

TEST_F(ValidateTree, ChildOutsideItsParent) {
  const NodeIndex parent = parts.leaf_pair_parent();
  const NodeIndex child = parts.links[parent];
  parts.volumes[child].max += Vec3::Constant(1e-3);  // still holds its facet
  EXPECT_EQ(validate_tree(parts.tree()), "volume of node " + node(child) + " is not inside its parent " + node(parent));
  // Within the tolerance (relative to the root's size, here about 200) it passes.
  EXPECT_EQ(validate_tree(parts.tree(), 1e-4), "");
  // With facets_in_ancestors, a child may stick out of its parent.
  EXPECT_EQ(validate_tree(parts.tree(), 1e-12, Containment::facets_in_ancestors), "");
}

TEST_F(ValidateTree, AncestorMissesAFacetBelowIt) {
  // An inner node's box shrunk to a point off the terrain's grid of corners.
  const NodeIndex parent = parts.leaf_pair_parent();
  const NodeIndex first = parts.links[parent];
  const Vec3 point = parts.volumes[parent].center() + Vec3(0.123, 0.0456, 0);
  parts.volumes[parent] = Aabb{point, point};
  EXPECT_EQ(validate_tree(parts.tree(), 1e-12, Containment::facets_in_ancestors),
            "node " + node(parent) + " does not contain corner 0 of facet " + std::to_string(parts.facet(first)) +
                " below it");
  // children_in_parent sees the same tree as a child outside its parent.
  EXPECT_EQ(validate_tree(parts.tree()), "volume of node " + node(first) + " is not inside its parent " + node(parent));
}

TEST_F(ValidateTree, ChildLinkBackwardsOrPastTheEnd) {
  const NodeIndex parent = parts.leaf_pair_parent();
  parts.links[parent] = parent;
  EXPECT_EQ(validate_tree(parts.tree()), "node " + node(parent) + " has child link " + node(parent));
  parts.links[parent] = std::uint32_t(parts.links.size() - 1);  // its second child would be past the end
  EXPECT_EQ(validate_tree(parts.tree()),
            "node " + node(parent) + " has child link " + std::to_string(parts.links.size() - 1));
}

TEST_F(ValidateTree, NodeReachedTwice) {
  // Node 1 takes node 2's children (and the root's box, so that they fit inside it): they are
  // reached through both.
  ASSERT_EQ(parts.links[0], 1u);
  ASSERT_FALSE(parts.is_leaf(1));
  ASSERT_FALSE(parts.is_leaf(2));
  parts.links[1] = parts.links[2];
  parts.volumes[1] = parts.volumes[0];
  EXPECT_EQ(validate_tree(parts.tree()), "node " + node(parts.links[2]) + " reached twice");
}

TEST_F(ValidateTree, NodeUnreachable) {
  // An inner node turned into a leaf of its first child's facet (its box holds it): its two
  // children are cut off, and nothing else changes.
  const NodeIndex parent = parts.leaf_pair_parent();
  const NodeIndex first = parts.links[parent];
  parts.links[parent] = parts.links[first];
  EXPECT_EQ(validate_tree(parts.tree()), "node " + node(first) + " is unreachable");
}

TEST_F(ValidateTree, StoredHeightWrong) {
  const int real = parts.height;
  parts.height = real + 1;
  EXPECT_EQ(validate_tree(parts.tree()),
            "stored height " + std::to_string(real + 1) + " != real height " + std::to_string(real));
  parts.height = real - 1;
  EXPECT_EQ(validate_tree(parts.tree()),
            "stored height " + std::to_string(real - 1) + " != real height " + std::to_string(real));
}

}  // namespace
}  // namespace boxtree
