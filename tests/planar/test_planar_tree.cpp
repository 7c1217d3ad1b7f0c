// SPDX-License-Identifier: MIT
// The planar boxtree: the pairing's invariants (Theorem 2.2), the tree, point location against
// brute force on every generator, and the stabbing number against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/planar/partition.h"
#include "boxtree/planar/planar_tree.h"

namespace boxtree::planar {
namespace {

// Test sizes scale with BOXTREE_TEST_SCALE (default 1).
std::size_t scaled(std::size_t n) {
  const char* scale = std::getenv("BOXTREE_TEST_SCALE");
  return scale ? std::size_t(std::max(1.0, double(n) * std::atof(scale))) : n;
}

struct Case {
  std::string generator;
  std::size_t count;
  std::uint64_t seed;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const std::string& name : partition_generator_names())
    for (std::size_t count :
         {std::size_t(1), std::size_t(2), std::size_t(5), std::size_t(9), std::size_t(64), scaled(700), scaled(3000)})
      out.push_back({name, count, 1000 + count});
  return out;
}

// Checks the invariants of one build: every round pairs at least (m + 3) / 12 of its m cells
// (Theorem 2.2 with the halving for disjointness), pairs of a round are disjoint and made of
// nodes that existed before the round, the shortened cells stay a partition (check_rounds
// asserts it), no fallback was needed, and the tree is valid (parents enclose children).
void check_build(const std::vector<Rect>& cells, const std::string& what) {
  SCOPED_TRACE(what);
  PlanarBuildSettings settings;
  settings.check_rounds = true;
  PlanarBuildStats stats;
  const std::vector<PlanarMerge> merges = planar_pairing(cells, settings, &stats);
  EXPECT_EQ(stats.fallback_rounds, 0);
  ASSERT_EQ(merges.size(), cells.size() - 1);
  const std::size_t n = cells.size();
  std::size_t done = 0;
  for (std::size_t r = 0; r < stats.rounds.size(); ++r) {
    const PlanarRoundStats& round = stats.rounds[r];
    EXPECT_GE(12 * round.pairs, round.cells + 3)
        << "round " << r << " of " << round.cells << " cells paired " << round.pairs << " ("
        << round.low_degree_segments << " low-degree segments, " << round.offers << " offers)";
    std::set<std::uint32_t> used;
    for (std::size_t k = done; k < done + round.pairs; ++k) {
      for (std::uint32_t child : {merges[k].first, merges[k].second}) {
        EXPECT_LT(child, n + done) << "a pair uses a node made in the same round";
        EXPECT_TRUE(used.insert(child).second) << "pairs of one round share node " << child;
      }
    }
    done += round.pairs;
  }
  EXPECT_EQ(done, merges.size());

  const PlanarTree tree = build_planar_tree(cells);
  EXPECT_NO_THROW(validate_planar_tree(tree));
  EXPECT_EQ(tree.domain(), bounding_rect(cells));
  // Each round adds at most one level.
  EXPECT_LE(tree.height(), int(stats.rounds.size()));
  EXPECT_GE(tree.height(), int(std::ceil(std::log2(double(n)))));
}

TEST(PlanarTree, PairingInvariantsOnEveryGenerator) {
  for (const Case& c : cases())
    check_build(make_partition(c.generator, c.count, c.seed), c.generator + " " + std::to_string(c.count));
}

TEST(PlanarTree, PairingInvariantsOnManySmallPartitions) {
  for (std::uint64_t seed = 0; seed < scaled(300); ++seed) {
    const std::vector<std::string> names = partition_generator_names();
    const std::string name = names[seed % names.size()];
    check_build(make_partition(name, 3 + seed % 40, seed), name + " seed " + std::to_string(seed));
  }
}

// The reference for point location, written apart from the library's predicates: the cells
// that hold p, each cell taken as [min, max) on both axes after a point on the domain's max side
// (closed there, by locate_point's contract) is moved one ulp back inside. In a partition at
// most one cell holds any point.
std::vector<RectId> cells_holding(const std::vector<Rect>& cells, Vec2 p) {
  const Real inf = std::numeric_limits<Real>::infinity();
  Real max_x = -inf, max_y = -inf;
  for (const Rect& c : cells) {
    max_x = std::max(max_x, c.max.x());
    max_y = std::max(max_y, c.max.y());
  }
  if (p.x() == max_x) p.x() = std::nextafter(p.x(), -inf);
  if (p.y() == max_y) p.y() = std::nextafter(p.y(), -inf);
  std::vector<RectId> holding;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const Rect& c = cells[i];
    if (c.min.x() <= p.x() && p.x() < c.max.x() && c.min.y() <= p.y() && p.y() < c.max.y())
      holding.push_back(RectId(i));
  }
  return holding;
}

std::optional<RectId> reference_locate(const std::vector<Rect>& cells, const Vec2& p) {
  const std::vector<RectId> holding = cells_holding(cells, p);
  EXPECT_LE(holding.size(), 1u) << "cells of a partition overlap at (" << p.x() << ", " << p.y() << ")";
  if (holding.empty()) return std::nullopt;
  return holding.front();
}

// Point location against the reference, at random points, at every cell corner and edge
// midpoint (points shared by several cells: the half-open rule picks one), and outside; the
// library's own scan (locate_point_brute_force) and its cell predicate against it too.
void check_locate(const std::vector<Rect>& cells, const std::string& what) {
  SCOPED_TRACE(what);
  const PlanarTree tree = build_planar_tree(cells);
  const Rect domain = tree.domain();
  std::vector<Vec2> points;
  Random random(cells.size());
  for (int i = 0; i < 300; ++i) {
    const Real y = random.uniform(domain.min.y() - 0.1, domain.max.y() + 0.1);  // y first: see tests/support/random.h
    const Real x = random.uniform(domain.min.x() - 0.1, domain.max.x() + 0.1);
    points.emplace_back(x, y);
  }
  const std::size_t stride = std::max<std::size_t>(1, cells.size() / 200);
  for (std::size_t i = 0; i < cells.size(); i += stride) {
    const Rect& c = cells[i];
    points.push_back(c.min);
    points.push_back(c.max);
    points.emplace_back(c.min.x(), c.max.y());
    points.emplace_back(c.max.x(), c.min.y());
    points.emplace_back(c.center().x(), c.min.y());
    points.emplace_back(c.min.x(), c.center().y());
    points.push_back(c.center());
  }
  const std::size_t cell_stride = std::max<std::size_t>(1, cells.size() / 64);
  for (const Vec2& p : points) {
    const std::optional<RectId> expected = reference_locate(cells, p);
    PlanarQueryStats stats;
    const std::optional<RectId> got = locate_point(tree, p, &stats);
    ASSERT_EQ(got, expected) << "at (" << p.x() << ", " << p.y() << ")";
    ASSERT_EQ(locate_point_brute_force(cells, p), expected) << "at (" << p.x() << ", " << p.y() << ")";
    if (expected) {
      EXPECT_GE(stats.nodes_visited, std::uint64_t(tree.height() > 0 ? 2 : 1));
      EXPECT_TRUE(cell_contains_half_open(cells[*expected], domain, p)) << "at (" << p.x() << ", " << p.y() << ")";
    }
    // The predicate says no for other cells (a sample of them, and the neighbours that share p).
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (expected && RectId(i) == *expected) continue;
      if (i % cell_stride != 0 && !contains(cells[i], p)) continue;
      EXPECT_FALSE(cell_contains_half_open(cells[i], domain, p))
          << "cell " << i << " at (" << p.x() << ", " << p.y() << ")";
    }
  }
}

TEST(PlanarTree, PointLocationMatchesBruteForceOnEveryGenerator) {
  for (const Case& c : cases())
    check_locate(make_partition(c.generator, c.count, c.seed), c.generator + " " + std::to_string(c.count));
}

TEST(PlanarTree, PointLocationOnAGridCellCorners) {
  // Every grid vertex is a cross junction shared by four cells.
  const std::vector<Rect> cells = make_grid_partition(7, 5);
  const PlanarTree tree = build_planar_tree(cells);
  for (int i = 0; i <= 7; ++i)
    for (int j = 0; j <= 5; ++j) {
      const Vec2 p(Real(i) / 7, Real(j) / 5);
      EXPECT_EQ(locate_point(tree, p), reference_locate(cells, p));
      EXPECT_TRUE(locate_point(tree, p).has_value());
    }
}

// The stabbing number by the sweep equals the maximum of point_depth over the centres of the
// grid cells of all box coordinates (where the maximum of open boxes is attained).
TEST(PlanarTree, StabbingNumberMatchesBruteForce) {
  for (const std::string& name : partition_generator_names()) {
    for (std::size_t count : {1, 2, 6, 20, 45}) {
      const PlanarTree tree = build_planar_tree(make_partition(name, count, 77 + count));
      std::vector<Real> xs, ys;
      for (std::size_t i = 0; i < tree.node_count(); ++i) {
        const Rect& b = tree.box(PlanarNode(i));
        xs.insert(xs.end(), {b.min.x(), b.max.x()});
        ys.insert(ys.end(), {b.min.y(), b.max.y()});
      }
      std::sort(xs.begin(), xs.end());
      xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
      std::sort(ys.begin(), ys.end());
      ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
      std::size_t brute = 0;
      for (std::size_t i = 0; i + 1 < xs.size(); ++i)
        for (std::size_t j = 0; j + 1 < ys.size(); ++j)
          brute = std::max(brute, point_depth(tree, Vec2((xs[i] + xs[i + 1]) / 2, (ys[j] + ys[j + 1]) / 2)));
      EXPECT_EQ(stabbing_number(tree), brute) << name << " " << count;
      // A point lies in its leaf and in every ancestor's box at least.
      EXPECT_GE(stabbing_number(tree), std::size_t(1));
    }
  }
}

TEST(PlanarTree, SingleCell) {
  const PlanarTree tree = build_planar_tree({Rect::from_bounds(2, 3, 4, 5)});
  EXPECT_EQ(tree.node_count(), 1u);
  EXPECT_EQ(tree.height(), 0);
  EXPECT_EQ(locate_point(tree, Vec2(3, 4)), std::optional<RectId>(0));
  EXPECT_EQ(locate_point(tree, Vec2(4, 5)), std::optional<RectId>(0));  // the domain's max sides are closed
  EXPECT_EQ(locate_point(tree, Vec2(5, 4)), std::nullopt);
  EXPECT_EQ(stabbing_number(tree), 1u);
}

// ---- validate_planar_tree, shown broken trees: one invariant of its contract at a time ----

// A built tree's arrays, to break one thing and rebuild with PlanarTree's constructor.
struct PlanarParts {
  std::vector<Rect> cells, boxes;
  std::vector<std::uint32_t> links;
  int height = 0;

  explicit PlanarParts(const PlanarTree& tree) : cells(tree.cells()), height(tree.height()) {
    for (std::size_t i = 0; i < tree.node_count(); ++i) {
      const PlanarNode node = PlanarNode(i);
      boxes.push_back(tree.box(node));
      links.push_back(tree.is_leaf(node) ? (PlanarTree::kLeafFlag | tree.cell_id(node)) : tree.first_child(node));
    }
  }
  PlanarTree tree() const { return PlanarTree(cells, boxes, links, height); }
  bool is_leaf(std::size_t i) const { return (links[i] & PlanarTree::kLeafFlag) != 0; }
  // The first inner node whose two children are leaves.
  std::size_t leaf_pair_parent() const {
    for (std::size_t i = 0; i < links.size(); ++i)
      if (!is_leaf(i) && is_leaf(links[i]) && is_leaf(links[i] + 1)) return i;
    ADD_FAILURE() << "no inner node with two leaf children";
    return 0;
  }
};

// The message validate_planar_tree throws, or "" if it accepts the tree.
std::string planar_problem(const PlanarTree& tree) {
  try {
    validate_planar_tree(tree);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

class ValidatePlanarTree : public ::testing::Test {
 protected:
  ValidatePlanarTree() : parts(build_planar_tree(make_grid_partition(4, 4))) {}
  PlanarParts parts;  // a copy of a valid tree, for each test to break
};

TEST_F(ValidatePlanarTree, TheUnbrokenCopyIsValid) {
  ASSERT_EQ(parts.links.size(), 31u);
  EXPECT_EQ(planar_problem(parts.tree()), "");
}

TEST_F(ValidatePlanarTree, Empty) { EXPECT_EQ(planar_problem(PlanarTree()), "planar tree: empty"); }

TEST_F(ValidatePlanarTree, NodeCountNot2nMinus1) {
  parts.boxes.push_back(parts.boxes.back());
  parts.links.push_back(parts.links.back());
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: node count is not 2n-1");
}

TEST_F(ValidatePlanarTree, LeafWithACellOutOfRange) {
  const std::size_t leaf = parts.links[parts.leaf_pair_parent()];
  parts.links[leaf] = PlanarTree::kLeafFlag | std::uint32_t(parts.cells.size());
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: leaf " + std::to_string(leaf) + " has a bad or repeated cell");
}

TEST_F(ValidatePlanarTree, TwoLeavesWithOneCell) {
  // Sibling leaves both name the second one's cell, with its box: the first of them met (from
  // the last node down) passes, the other repeats it.
  const std::size_t first = parts.links[parts.leaf_pair_parent()];
  parts.links[first] = parts.links[first + 1];
  parts.boxes[first] = parts.boxes[first + 1];
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: leaf " + std::to_string(first) + " has a bad or repeated cell");
}

TEST_F(ValidatePlanarTree, LeafBoxIsNotItsCell) {
  const std::size_t leaf = parts.links[parts.leaf_pair_parent()];
  parts.boxes[leaf].max.x() -= 0.01;
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: leaf " + std::to_string(leaf) + "'s box is not its cell");
}

TEST_F(ValidatePlanarTree, ChildLinkBackwardsOrPastTheEnd) {
  const std::size_t parent = parts.leaf_pair_parent();
  const std::string expected = "planar tree: node " + std::to_string(parent) + " has bad children";
  parts.links[parent] = std::uint32_t(parent);
  EXPECT_EQ(planar_problem(parts.tree()), expected);
  parts.links[parent] = std::uint32_t(parts.links.size() - 1);
  EXPECT_EQ(planar_problem(parts.tree()), expected);
}

TEST_F(ValidatePlanarTree, ParentBoxNotTheSmallestEnclosing) {
  const std::size_t parent = parts.leaf_pair_parent();
  const std::string expected =
      "planar tree: node " + std::to_string(parent) + "'s box is not the smallest enclosing its children";
  const Rect exact = parts.boxes[parent];
  parts.boxes[parent].max.y() += 0.01;  // encloses them, but not the smallest
  EXPECT_EQ(planar_problem(parts.tree()), expected);
  parts.boxes[parent] = exact;
  parts.boxes[parent].min.x() += 0.01;  // does not enclose them
  EXPECT_EQ(planar_problem(parts.tree()), expected);
}

TEST_F(ValidatePlanarTree, NodeWithTwoParents) {
  // Node 1 takes node 2's children and box, and the root's box is made to fit: every box is the
  // smallest around its children, but nodes 1 and 2 share them.
  ASSERT_EQ(parts.links[0], 1u);
  ASSERT_FALSE(parts.is_leaf(1));
  ASSERT_FALSE(parts.is_leaf(2));
  parts.links[1] = parts.links[2];
  parts.boxes[1] = parts.boxes[0] = parts.boxes[2];
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: a node has two parents");
}

TEST_F(ValidatePlanarTree, NodeUnreachable) {
  // By hand, over 2 x 2 cells: node 1 is nobody's child, and shares its children 4, 5 with node
  // 2 (which comes after it, so the two-parents check cannot see it):
  //   0 -> (2, 3)   1 -> (4, 5)   2 -> (4, 5)   3, 4, 5, 6: leaves of cells 0..3
  const std::vector<Rect> cells = make_grid_partition(2, 2);
  const std::uint32_t leaf = PlanarTree::kLeafFlag;
  const std::vector<std::uint32_t> links = {2, 4, 4, leaf | 0, leaf | 1, leaf | 2, leaf | 3};
  std::vector<Rect> boxes = {Rect(), Rect(), Rect(), cells[0], cells[1], cells[2], cells[3]};
  boxes[1] = boxes[2] = Rect::enclosing(cells[1], cells[2]);
  boxes[0] = Rect::enclosing(boxes[2], cells[0]);
  EXPECT_EQ(planar_problem(PlanarTree(cells, boxes, links, 2)), "planar tree: a node is unreachable");
}

TEST_F(ValidatePlanarTree, StoredHeightWrong) {
  ++parts.height;
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: stored height is wrong");
  parts.height -= 2;
  EXPECT_EQ(planar_problem(parts.tree()), "planar tree: stored height is wrong");
}

TEST(PlanarTree, InvalidInputIsRejected) {
  std::vector<Rect> overlapping = make_grid_partition(4, 4);
  overlapping[5].max.y() += 0.1;
  EXPECT_THROW(build_planar_tree(overlapping), Error);
  std::vector<Rect> holed = make_grid_partition(4, 4);
  holed.erase(holed.begin() + 6);
  EXPECT_THROW(build_planar_tree(holed), Error);
  EXPECT_THROW(build_planar_tree({}), Error);
  PlanarBuildSettings bad;
  bad.max_segment_degree = 1;
  EXPECT_THROW(build_planar_tree(make_grid_partition(2, 2), bad), Error);
}

TEST(PlanarTree, DeterministicAndMovedDomain) {
  // The same partition moved and scaled gives the same topology.
  std::vector<Rect> cells = make_pinwheel_partition(200, 9);
  const PlanarTree a = build_planar_tree(cells);
  for (Rect& c : cells) {
    c.min = c.min * 8 + Vec2(-3, 100);
    c.max = c.max * 8 + Vec2(-3, 100);
  }
  const PlanarTree b = build_planar_tree(cells);
  ASSERT_EQ(a.node_count(), b.node_count());
  for (std::size_t i = 0; i < a.node_count(); ++i) {
    ASSERT_EQ(a.is_leaf(PlanarNode(i)), b.is_leaf(PlanarNode(i)));
    if (a.is_leaf(PlanarNode(i))) {
      EXPECT_EQ(a.cell_id(PlanarNode(i)), b.cell_id(PlanarNode(i)));
    }
  }
}

}  // namespace
}  // namespace boxtree::planar
