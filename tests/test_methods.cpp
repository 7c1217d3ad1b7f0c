// SPDX-License-Identifier: MIT
// Every hierarchy method (the paper's six, the general-triangle pie slices, and the hybrids)
// through the same checks: tree invariants, and every query and tree-vs-tree against brute force.
// Brute force uses only the exact triangle tests, so "all methods give the same answer" follows.
#include <gtest/gtest.h>

#include <cmath>

#include "boxtree/collide.h"
#include "boxtree/detail/volume_kinds.h"
#include "boxtree/method.h"
#include "boxtree/stats.h"
#include "support/checks.h"

namespace boxtree {
namespace {

using namespace test;

// A volume kind and its parent rule (BuildSettings::parent_fit): every kind with the paper's
// rule, and every oriented kind and hybrid also with parents fitted to their facets ("-tight").
template <class V, ParentFit kFit = ParentFit::enclose_children>
struct Config {
  using Volume = V;
  static constexpr ParentFit fit = kFit;
  static BuildSettings settings() {
    BuildSettings s = test_settings<V>();
    s.parent_fit = kFit;
    return s;
  }
  static Tree<V> build(const TriangleMesh& mesh) { return build_tree<V>(mesh, settings()); }
};

template <class C>
class Methods : public ::testing::Test {};

#define BOXTREE_CONFIG_ENTRY(V) , Config<V>
#define BOXTREE_TIGHT_CONFIG_ENTRY(V) , Config<V, ParentFit::fit_facets>
using AllConfigs = ::testing::Types<Config<Aabb> BOXTREE_FOR_EACH_NON_AABB_VOLUME(BOXTREE_CONFIG_ENTRY)
                                        BOXTREE_FOR_EACH_NON_AABB_VOLUME(BOXTREE_TIGHT_CONFIG_ENTRY)>;
#undef BOXTREE_CONFIG_ENTRY
#undef BOXTREE_TIGHT_CONFIG_ENTRY

class ConfigNames {
 public:
  template <class C>
  static std::string GetName(int) {
    using V = typename C::Volume;
    const std::string tight = C::fit == ParentFit::fit_facets ? "-tight" : "";
    if constexpr (is_hybrid_v<V>) {
      return std::string(V::Lower::kind_name) + tight + "+aabb@3";
    } else {
      return V::kind_name + tight;
    }
  }
};
TYPED_TEST_SUITE(Methods, AllConfigs, ConfigNames);

// Containment is checked with a tolerance of 1e-9 of the root's size: the oriented fits are
// computed in floating point and padded outward, not exact. Tight trees need only keep every
// facet inside its ancestors.
TYPED_TEST(Methods, TreeInvariants) {
  {
    const Containment containment =
        TypeParam::fit == ParentFit::fit_facets ? Containment::facets_in_ancestors : Containment::children_in_parent;
    for (const auto& [name, mesh] : procedural_meshes()) {
      const auto tree = TypeParam::build(mesh);
      EXPECT_EQ(validate_tree(tree, 1e-9, containment), "") << name;
      const std::size_t n = mesh.facet_count();
      if (n > 1) {
        EXPECT_LE(tree.height(), int(std::ceil(std::log(double(n)) / std::log(4.0 / 3.0)))) << name;
      }
      const TreeStats s = compute_tree_stats(tree);
      EXPECT_EQ(s.levels.front().nodes, n);
      EXPECT_GT(s.plane_cost, 0);
    }
  }
}

TYPED_TEST(Methods, RaysMatchBruteForce) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) check_rays(TypeParam::build(mesh), 120, 3, name);
  }
}

TYPED_TEST(Methods, WatertightRays) {
  {
    using V = typename TypeParam::Volume;
    check_watertight<V>(make_bumpy_sphere(24, 12, 0.1, 3), Vec3::Zero(), "bumpy_sphere", 1000, TypeParam::settings());
    const TriangleMesh solid = make_closed_terrain(8, 2);
    check_watertight<V>(solid, inside_point(solid), "closed terrain", 1000, TypeParam::settings());
  }
}

TYPED_TEST(Methods, OverlapsMatchBruteForce) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) check_overlaps(TypeParam::build(mesh), 15, name);
  }
}

TYPED_TEST(Methods, PlanesAndStabbingMatchBruteForce) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) check_planes_and_stabbing(TypeParam::build(mesh), 40, name);
  }
}

TYPED_TEST(Methods, CollideMatchesBruteForce) {
  {
    const std::pair<TriangleMesh, TriangleMesh> pairs[] = {
        {make_bumpy_sphere(20, 10, 0.2, 1), make_bumpy_sphere(16, 8, 0.3, 2)},
        {make_triangle_soup(300, 3, 1, 0.2), make_triangle_soup(300, 4, 1, 0.2)},
        {make_terrain(10, 10, 1, 10, 3), make_uv_sphere(12, 6, 2, Vec3(5, 5, 1))},
    };
    std::size_t total = 0;
    for (const auto& [mesh_a, mesh_b] : pairs) {
      const auto a = TypeParam::build(mesh_a);
      const auto b = TypeParam::build(mesh_b);
      total += check_collide(a, b, 6, 0.5, "pair");
    }
    EXPECT_GT(total, 0u);
  }
}

TEST(Methods, NamesParseAndRoundTrip) {
  for (const std::string& name : method_names()) EXPECT_EQ(method_name(parse_method(name)), name);
  EXPECT_EQ(method_name(parse_method("pie-min+aabb@4")), "pie-min+aabb@4");
  EXPECT_EQ(parse_method("obb-max+aabb@2").hybrid_level, 2);
  for (const std::string& name : method_names()) {
    if (name == "aabb") continue;
    const Method tight = parse_method(name + "-tight+aabb@5");
    EXPECT_TRUE(tight.tight);
    EXPECT_EQ(tight.hybrid_level, 5);
    EXPECT_EQ(method_name(tight), name + "-tight+aabb@5");
    EXPECT_EQ(settings_for(parse_method(name + "-tight")).parent_fit, ParentFit::fit_facets);
    EXPECT_EQ(settings_for(parse_method(name)).parent_fit, ParentFit::enclose_children);
  }
  for (const char* bad : {"", "octree", "aabb+aabb@3", "pie-min+aabb@", "pie-min+aabb@0", "pie-min+aabb@x",
                          "pie-min+obb@2", "aabb-tight", "-tight", "obb-min-tight-tight", "obb-min+aabb@3-tight"}) {
    try {
      parse_method(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  try {
    parse_method("octree");
  } catch (const Error& e) {
    for (const std::string& name : method_names()) EXPECT_NE(std::string(e.what()).find(name), std::string::npos);
  }
}

// The hybrid switch: below the level the method's own volumes, from the level up boxes.
TEST(Methods, HybridSwitchesAtItsLevel) {
  BuildSettings settings;
  settings.hybrid_level = 4;
  const Tree<Hybrid<PieMin>> tree = build_tree<Hybrid<PieMin>>(make_terrain(16, 16, 1), settings);
  const TreeStats s = compute_tree_stats(tree);
  std::vector<int> level(tree.node_count(), 0);
  for (std::size_t i = tree.node_count(); i-- > 0;) {
    if (tree.is_leaf(NodeIndex(i))) continue;
    const NodeIndex c = tree.first_child(NodeIndex(i));
    level[i] = 1 + std::max(level[c], level[c + 1]);
  }
  for (NodeIndex i = 0; i < tree.node_count(); ++i) EXPECT_EQ(tree.volume(i).is_box, level[i] >= 4) << i;
  EXPECT_THROW(build_tree<Hybrid<PieMin>>(make_terrain(4, 4, 1)), Error);  // no level given
}

// ParentFit::fit_facets keeps the tree's shape and makes the volumes no larger node by node (it
// keeps the children's rule where that is smaller); on a curved surface it makes the upper
// levels much smaller, since the slack of each level is no longer carried upward.
TEST(Methods, TightParentsAreNeverLargerAndShrinkUpperLevels) {
  const TriangleMesh sphere = make_bumpy_sphere(48, 24, 0.05, 7);
  BuildSettings tight;
  tight.parent_fit = ParentFit::fit_facets;
  const Tree<ObbMin> paper = build_tree<ObbMin>(sphere);
  const Tree<ObbMin> fitted = build_tree<ObbMin>(sphere, tight);
  ASSERT_EQ(paper.node_count(), fitted.node_count());
  Real paper_total = 0, fitted_total = 0;
  for (NodeIndex i = 0; i < paper.node_count(); ++i) {
    ASSERT_EQ(paper.is_leaf(i), fitted.is_leaf(i));
    if (paper.is_leaf(i)) continue;
    EXPECT_EQ(paper.first_child(i), fitted.first_child(i));
    EXPECT_LE(surface_area(fitted.volume(i)), surface_area(paper.volume(i))) << i;
    paper_total += surface_area(paper.volume(i));
    fitted_total += surface_area(fitted.volume(i));
  }
  EXPECT_LT(fitted_total, 0.9 * paper_total);
  // Pie slices: the same, and hulls too large for the triangle fit keep the children's rule.
  const Tree<PieMinGeneral> pie_paper = build_tree<PieMinGeneral>(sphere);
  const Tree<PieMinGeneral> pie_fitted = build_tree<PieMinGeneral>(sphere, tight);
  for (NodeIndex i = 0; i < pie_paper.node_count(); ++i)
    EXPECT_LE(surface_area(pie_fitted.volume(i)), surface_area(pie_paper.volume(i))) << i;
}

}  // namespace
}  // namespace boxtree
