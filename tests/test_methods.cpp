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

template <class V>
class Methods : public ::testing::Test {};

#define BOXTREE_TYPE_LIST_ENTRY(V) , V
using AllVolumeKinds = ::testing::Types<Aabb BOXTREE_FOR_EACH_NON_AABB_VOLUME(BOXTREE_TYPE_LIST_ENTRY)>;
#undef BOXTREE_TYPE_LIST_ENTRY

class VolumeNames {
public:
  template <class V>
  static std::string GetName(int) {
    if constexpr (is_hybrid_v<V>) {
      return std::string(V::Lower::kind_name) + "+aabb@3";
    } else {
      return V::kind_name;
    }
  }
};
TYPED_TEST_SUITE(Methods, AllVolumeKinds, VolumeNames);

// Containment is checked with a tolerance of 1e-9 of the root's size: the oriented fits are
// computed in floating point and padded outward, not exact.
TYPED_TEST(Methods, TreeInvariants) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) {
      const Tree<TypeParam> tree = build_for_test<TypeParam>(mesh);
      EXPECT_EQ(validate_tree(tree, 1e-9), "") << name;
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
    for (const auto& [name, mesh] : procedural_meshes()) check_rays(build_for_test<TypeParam>(mesh), 120, 3, name);
  }
}

TYPED_TEST(Methods, WatertightRays) {
  {
    check_watertight<TypeParam>(make_bumpy_sphere(24, 12, 0.1, 3), Vec3::Zero(), "bumpy_sphere", 1000);
    const TriangleMesh solid = make_closed_terrain(8, 2);
    check_watertight<TypeParam>(solid, inside_point(solid), "closed terrain", 1000);
  }
}

TYPED_TEST(Methods, OverlapsMatchBruteForce) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) check_overlaps(build_for_test<TypeParam>(mesh), 15, name);
  }
}

TYPED_TEST(Methods, PlanesAndStabbingMatchBruteForce) {
  {
    for (const auto& [name, mesh] : procedural_meshes()) {
      const Tree<TypeParam> tree = build_for_test<TypeParam>(mesh);
      const Aabb box = mesh_bounds(mesh);
      Random r(31);
      for (int i = 0; i < 40; ++i) {
        Plane plane{i % 8 == 0 ? Vec3(Vec3::Unit(i % 3)) : r.unit_vector(), 0};
        plane.offset = plane.normal.dot(random_point_near(r, box, 0.05));
        EXPECT_EQ(query_plane(tree, plane), brute_plane(mesh, plane)) << name << " plane " << i;
        Vec3 p = i % 2 ? mesh.corner(FacetId(r.next() % mesh.facet_count()), 0) : random_point_near(r, box);
        std::size_t expected = 0;
        for (NodeIndex node = 0; node < tree.node_count(); ++node) expected += contains(tree.volume(node), p);
        EXPECT_EQ(stabbing_count(tree, p), expected) << name;
      }
    }
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
      const Tree<TypeParam> a = build_for_test<TypeParam>(mesh_a);
      const Tree<TypeParam> b = build_for_test<TypeParam>(mesh_b);
      Random r(5);
      for (int pose = 0; pose < 6; ++pose) {
        RigidTransform t;
        if (pose > 0) {
          t.rotation = random_rotation(r);
          t.translation = r.uniform_vec3(-0.5, 0.5);
        }
        const std::vector<FacetPair> got = collide(a, b, t);
        EXPECT_EQ(got, brute_collide(mesh_a, mesh_b, t)) << "pose " << pose;
        total += got.size();
      }
    }
    EXPECT_GT(total, 0u);
  }
}

TEST(Methods, NamesParseAndRoundTrip) {
  for (const std::string& name : method_names()) EXPECT_EQ(method_name(parse_method(name)), name);
  EXPECT_EQ(method_name(parse_method("pie-min+aabb@4")), "pie-min+aabb@4");
  EXPECT_EQ(parse_method("obb-max+aabb@2").hybrid_level, 2);
  for (const char* bad : {"", "octree", "aabb+aabb@3", "pie-min+aabb@", "pie-min+aabb@0", "pie-min+aabb@x", "pie-min+obb@2"}) {
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

}  // namespace
}  // namespace boxtree
