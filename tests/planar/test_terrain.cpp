// SPDX-License-Identifier: MIT
// The terrain merge rule (paper, Section 3.1) as a build strategy: a valid tree whose queries
// agree with brute force, for every volume kind; non-terrains are rejected.
#include <gtest/gtest.h>

#include <algorithm>

#include "boxtree/build.h"
#include "boxtree/detail/volume_kinds.h"
#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/planar/planar_tree.h"
#include "boxtree/planar/terrain.h"
#include "boxtree/query.h"
#include "support/brute_force.h"

namespace boxtree {
namespace {

BuildSettings terrain_settings() {
  BuildSettings settings;
  settings.merge_rule = planar::terrain_merge_order;
  return settings;
}

// Structure: every facet in exactly one leaf, children after parents, the stored height.
template <class V>
void check_structure(const Tree<V>& tree) {
  const std::size_t count = tree.node_count();
  ASSERT_EQ(count, 2 * tree.facet_count() - 1);
  std::vector<int> seen(tree.facet_count(), 0), height(count, 0);
  for (std::size_t i = count; i-- > 0;) {
    const NodeIndex node = NodeIndex(i);
    if (tree.is_leaf(node)) {
      ++seen[tree.facet(node)];
      continue;
    }
    const NodeIndex c = tree.first_child(node);
    ASSERT_GT(c, node);
    height[i] = 1 + std::max(height[c], height[c + 1]);
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
  EXPECT_EQ(height[0], tree.height());
}

template <class V>
class TerrainRule : public ::testing::Test {};
using Kinds = ::testing::Types<Aabb, ObbMin, PieMin, Hybrid<ObbMin>>;
TYPED_TEST_SUITE(TerrainRule, Kinds);

TYPED_TEST(TerrainRule, RaysAndBoxesMatchBruteForce) {
  const auto mesh = std::make_shared<const TriangleMesh>(make_terrain(12, 9, 4, 30, 5));
  BuildSettings settings = terrain_settings();
  if constexpr (is_hybrid_v<TypeParam>) settings.hybrid_level = 2;
  BuildStats stats;
  const Tree<TypeParam> tree = build_tree<TypeParam>(mesh, settings, &stats);
  check_structure(tree);
  EXPECT_GT(stats.rounds, 0);
  Random random(8);
  for (int i = 0; i < 150; ++i) {
    Ray ray;
    const Real origin_z = random.uniform(-5, 15);  // z first: see tests/support/random.h
    const Real origin_y = random.uniform(-2, 32);
    const Real origin_x = random.uniform(-2, 32);
    ray.origin = Vec3(origin_x, origin_y, origin_z);
    ray.direction = i % 3 == 0 ? Vec3(0, 0, -1) : random.unit_vector();
    if (i % 3 == 0) ray.origin.z() = 20;
    const auto got = ray_closest_hit(tree, ray);
    const auto expected = test::brute_ray_closest_hit(*mesh, ray);
    ASSERT_EQ(got.has_value(), expected.has_value()) << "ray " << i;
    if (got) {
      EXPECT_EQ(got->facet, expected->facet) << "ray " << i;
    }
  }
  for (int i = 0; i < 60; ++i) {
    const Real c_z = random.uniform(0, 6);  // z first: see tests/support/random.h
    const Real c_y = random.uniform(0, 30);
    const Real c_x = random.uniform(0, 30);
    const Vec3 c(c_x, c_y, c_z);
    const Aabb box = Aabb::from_points(c - Vec3::Constant(1.5), c + Vec3::Constant(1.5));
    EXPECT_EQ(test::violations(query_overlap(tree, box), test::brute_overlap(*mesh, box)), "") << "box " << i;
  }
}

TEST(TerrainRuleAabb, ParentsAreTheSmallestBoxesAroundChildren) {
  // For boxes, "lift into the smallest horizontal slab enclosing the children" is exactly the
  // smallest box around both children; the xy-extent is that of the planar tree's node.
  const auto mesh = std::make_shared<const TriangleMesh>(make_terrain(16, 16, 2));
  const Tree<Aabb> tree = build_tree<Aabb>(mesh, terrain_settings());
  check_structure(tree);
  for (std::size_t i = 0; i < tree.node_count(); ++i) {
    if (tree.is_leaf(NodeIndex(i))) continue;
    const NodeIndex c = tree.first_child(NodeIndex(i));
    const Aabb expected = Aabb::enclosing(tree.volume(c), tree.volume(c + 1));
    EXPECT_EQ(tree.volume(NodeIndex(i)).min, expected.min);
    EXPECT_EQ(tree.volume(NodeIndex(i)).max, expected.max);
  }
  // The terrain's cells are its grid squares, and the planar pairing's height over them plus
  // the one level pairing the two triangles of a square is the tree's height.
  const planar::TerrainCells cells = planar::terrain_cells(*mesh);
  EXPECT_EQ(cells.cells.size(), 256u);
  EXPECT_EQ(tree.height(), planar::build_planar_tree(cells.cells).height() + 1);
}

TEST(TerrainRuleAabb, RejectsMeshesThatAreNotGridTerrains) {
  EXPECT_THROW(build_tree<Aabb>(make_uv_sphere(12, 8), terrain_settings()), Error);
  try {
    build_tree<Aabb>(make_triangle_soup(50, 3), terrain_settings());
    ADD_FAILURE() << "accepted a triangle soup";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("terrain merge rule"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace boxtree
