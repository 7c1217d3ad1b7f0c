// SPDX-License-Identifier: MIT
// Statistics: per-level sums, and the meaning of plane_cost checked by Monte Carlo.
#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace boxtree
