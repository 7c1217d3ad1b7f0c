// SPDX-License-Identifier: MIT
// The packed pie-slice tree (packed_prism_tree.h) against the exact Tree<PieSlice> it is packed
// from and against brute force, for the four pie-slice kinds: a faithful packing (the same
// hierarchy, every facet in one leaf, every decoded prism holding its exact prism), and the same
// answers to every query.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include "boxtree/any_tree.h"
#include "boxtree/build.h"
#include "boxtree/packed_prism_tree.h"
#include "support/brute_force.h"
#include "support/checks.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

// Query counts times BOXTREE_TEST_SCALE.
int scaled(int n) { return std::max(1, int(n * test_scale())); }

// Is p in the prism {x + t axis : x in the base triangle, t in [0, height]}? Solved for the
// barycentric and axial coordinates, without slack: an independent formulation of what the
// packing's own check (src/packed_prism_tree.cpp) verifies with its planes.
bool in_prism(const Prism& prism, const Vec3& p) {
  Mat3 frame;
  frame.col(0) = prism.base[1] - prism.base[0];
  frame.col(1) = prism.base[2] - prism.base[0];
  frame.col(2) = prism.axis;
  const Vec3 x = frame.fullPivLu().solve(Vec3(p - prism.base[0]));
  return x[0] >= 0 && x[1] >= 0 && x[0] + x[1] <= 1 && x[2] >= 0 && x[2] <= prism.height;
}

// The packed tree is the exact tree's hierarchy, leaves dropped: walked side by side, every inner
// node's decoded prism holds its exact prism's six corners (and is barely larger), every leaf
// link is the exact leaf's facet, and every facet is in exactly one leaf.
template <class V>
void expect_faithful_packing(const Tree<V>& tree, const PackedPrismTree& packed, const std::string& name) {
  const std::size_t n = tree.facet_count();
  EXPECT_EQ(packed.node_count(), tree.node_count()) << name;
  EXPECT_EQ(packed.height(), tree.height()) << name;
  EXPECT_EQ(packed.nodes().size(), n - 1) << name;
  EXPECT_EQ(packed.memory_bytes(), 48 * (n - 1)) << name;
  std::vector<int> seen(n, 0);
  Real exact_area = 0, packed_area = 0;
  struct Pending {
    NodeIndex exact;
    std::uint32_t link;
  };
  std::vector<Pending> pending{{tree.root(), packed.root_link()}};
  while (!pending.empty()) {
    const Pending p = pending.back();
    pending.pop_back();
    ASSERT_EQ(tree.is_leaf(p.exact), PackedPrismTree::is_leaf(p.link)) << name;
    if (tree.is_leaf(p.exact)) {
      ASSERT_EQ(PackedPrismTree::facet(p.link), tree.facet(p.exact)) << name;
      ++seen[tree.facet(p.exact)];
      continue;
    }
    const Prism& exact = tree.volume(p.exact).prism;
    const Prism decoded = packed.prism(p.link);
    EXPECT_NEAR(decoded.axis.norm(), 1, 1e-12) << name;
    EXPECT_GT(decoded.axis.dot(exact.axis), 0.99) << name << ": the winding gives the axis its sign";
    for (const Vec3& corner : corners(exact))
      EXPECT_TRUE(in_prism(decoded, corner))
          << name << " node " << p.exact << ": exact corner outside the packed prism";
    exact_area += surface_area(exact);
    packed_area += surface_area(decoded);
    const PackedPrismTree::Node& node = packed.nodes()[p.link];
    // Preorder: the first inner child is the next node.
    for (std::uint32_t link : node.child) {
      if (PackedPrismTree::is_leaf(link)) continue;
      EXPECT_EQ(link, p.link + 1) << name;
      break;
    }
    for (int k = 0; k < 2; ++k) pending.push_back({tree.first_child(p.exact) + NodeIndex(k), node.child[k]});
  }
  for (FacetId f = 0; f < n; ++f) EXPECT_EQ(seen[f], 1) << name << ": facet " << f << " in exactly one leaf";
  // The margins are a few float roundings of the coordinates (relative to the mesh's centre):
  // in total the packed prisms are barely larger, about 1e-5 of the surface area (1e-3 on a cone
  // for pie-max, whose flat groups of facets get sliver bases that grow by a few percent: see
  // around_rectangle in src/packed_prism_tree.cpp). Not for degenerate facets only, whose exact
  // prisms have no area at all.
  if (compute_mesh_stats(tree.mesh()).degenerate_facets < n) {
    EXPECT_LE(packed_area, exact_area * 1.01) << name;
  }
}

// Every query of the packed tree against brute force and against the exact tree.
template <class V>
void expect_same_answers(const Tree<V>& tree, const PackedPrismTree& packed, int queries, const std::string& name) {
  const TriangleMesh& mesh = tree.mesh();
  check_rays(packed, queries, 3, name);
  const Aabb box = mesh_bounds(mesh);
  Random r(29);
  std::size_t reported = 0;
  for (int i = 0; i < queries; ++i) {
    // Rays: the closest hit and the candidates (every leaf whose prism the ray meets) as the exact tree's.
    Ray ray{random_point_near(r, box, 0.5), Vec3::Zero()};
    const Real scale = r.uniform(0.5, 2);  // first: see tests/support/random.h
    ray.direction = (random_point_near(r, box, 0) - ray.origin) * scale;
    if (ray.direction.isZero(0)) continue;
    const auto closest = ray_closest_hit(packed, ray);
    const auto expected = ray_closest_hit(tree, ray);
    ASSERT_EQ(closest.has_value(), expected.has_value()) << name << " ray " << i;
    if (closest) {
      EXPECT_EQ(closest->facet, expected->facet) << name << " ray " << i;
      EXPECT_EQ(closest->t, expected->t) << name << " ray " << i;
    }
    const auto candidates = [&](const auto& t) {
      std::vector<FacetId> facets;
      ray_candidates(t, ray, [&](FacetId f, Real t_max) {
        facets.push_back(f);
        return t_max;
      });
      std::sort(facets.begin(), facets.end());
      return facets;
    };
    EXPECT_EQ(candidates(packed), candidates(tree)) << name << " ray " << i;

    const QueryShapes q = random_query_shapes(r, box, i);
    const auto same = [&](const auto& shape, const char* what) {
      const std::vector<FacetId> got = query_overlap(packed, shape);
      EXPECT_EQ(violations(got, brute_overlap(mesh, shape)), "") << name << " " << what << " " << i;
      EXPECT_EQ(got, query_overlap(tree, shape)) << name << " " << what << " " << i;
      EXPECT_EQ(query_overlap(packed, shape, nullptr, FacetTest::leaf_volume),
                query_overlap(tree, shape, nullptr, FacetTest::leaf_volume))
          << name << " " << what << " (leaf volumes) " << i;
      return got.size();
    };
    reported += same(q.aabb, "aabb") + same(q.obb, "obb") + same(q.sphere, "sphere") + same(q.capsule, "capsule");

    Plane plane{i % 8 == 0 ? Vec3(Vec3::Unit(i % 3)) : r.unit_vector(), 0};
    plane.offset = plane.normal.dot(random_point_near(r, box, 0.05));
    const std::vector<FacetId> cut = query_plane(packed, plane);
    EXPECT_EQ(violations(cut, brute_plane(mesh, plane)), "") << name << " plane " << i;
    EXPECT_EQ(cut, query_plane(tree, plane)) << name << " plane " << i;
  }
  if (mesh.facet_count() > 10) {
    EXPECT_GT(reported, 0u) << name << ": the test must exercise overlaps";
  }
}

template <class V>
class PackedPrismTreeTest : public ::testing::Test {};
using PieKinds = ::testing::Types<PieMax, PieMin, PieMaxGeneral, PieMinGeneral>;
class KindNames {
 public:
  template <class V>
  static std::string GetName(int) {
    return V::kind_name;
  }
};
TYPED_TEST_SUITE(PackedPrismTreeTest, PieKinds, KindNames);

template <class V>
void check_packed(const TriangleMesh& mesh, const std::string& name, int queries) {
  const Tree<V> tree = build_tree<V>(mesh);
  const PackedPrismTree packed(tree);
  expect_faithful_packing(tree, packed, name);
  expect_same_answers(tree, packed, queries, name);
}

TYPED_TEST(PackedPrismTreeTest, MatchesExactTreeAndBruteForceOnProceduralMeshes) {
  for (const auto& [name, mesh] : procedural_meshes()) check_packed<TypeParam>(mesh, name, scaled(40));
}

TYPED_TEST(PackedPrismTreeTest, MatchesExactTreeAndBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  // Small real meshes (the pie-slice builds take ~0.1 ms per facet): scans, an open model, the
  // PQP pair (coordinates in the thousands, slivers, 2,180 separate triangles).
  for (const char* name : {"stanford_bunny_res4.obj", "suzanne.obj", "env.obj", "rob.obj"})
    check_packed<TypeParam>(load_shared_mesh(name), name, scaled(30));
}

// Far from the origin and tiny: float margins relative to the mesh, not to the coordinates.
TYPED_TEST(PackedPrismTreeTest, FarAndTinyMeshes) {
  const TriangleMesh terrain = make_terrain(12, 12, 5);
  const TriangleMesh sphere = make_bumpy_sphere(20, 10, 0.2, 9);
  for (const auto& [base_name, base] : {std::pair{"terrain", terrain}, std::pair{"sphere", sphere}}) {
    for (const auto& [what, scale, offset] :
         {std::tuple{"far", 1.0, Vec3(1e4, -1e4, 2e4)}, std::tuple{"tiny", 1e-4, Vec3(0, 0, 0)},
          std::tuple{"tiny and far", 1e-4, Vec3(-3e3, 1e3, 5e2)}, std::tuple{"huge", 1e9, Vec3(0, 0, 1e10)}}) {
      TriangleMesh mesh = base;
      for (Vec3& v : mesh.vertices) v = v * scale + offset;
      check_packed<TypeParam>(mesh, std::string(base_name) + " " + what, scaled(25));
    }
  }
}

TYPED_TEST(PackedPrismTreeTest, WatertightRays) {
  const TriangleMesh sphere = make_bumpy_sphere(24, 12, 0.1, 3);
  check_watertight_tree(PackedPrismTree(build_tree<TypeParam>(sphere)), Vec3::Zero(), "bumpy sphere", 600);
  const TriangleMesh solid = make_closed_terrain(8, 2);
  check_watertight_tree(PackedPrismTree(build_tree<TypeParam>(solid)), inside_point(solid), "closed terrain", 600);
}

TYPED_TEST(PackedPrismTreeTest, CollideMatchesExactTreeAndBruteForce) {
  const std::pair<TriangleMesh, TriangleMesh> pairs[] = {
      {make_bumpy_sphere(20, 10, 0.2, 1), make_bumpy_sphere(16, 8, 0.3, 2)},
      {make_triangle_soup(300, 3, 1, 0.2), make_triangle_soup(300, 4, 1, 0.2)},
      {make_terrain(10, 10, 1, 10, 3), make_uv_sphere(12, 6, 2, Vec3(5, 5, 1))},
  };
  std::size_t total = 0;
  for (const auto& [mesh_a, mesh_b] : pairs) {
    const Tree<TypeParam> a = build_tree<TypeParam>(mesh_a), b = build_tree<TypeParam>(mesh_b);
    const PackedPrismTree packed_a(a), packed_b(b);
    total += check_collide(packed_a, packed_b, 6, 0.5, "pair");
    Random r(7);
    for (int pose = 0; pose < 4; ++pose) {
      RigidTransform t;
      t.rotation = random_rotation(r);
      t.translation = r.uniform_vec3(-0.5, 0.5);
      EXPECT_EQ(collide(packed_a, packed_b, t), collide(a, b, t));
      CollideSettings first;
      first.stop_at_first = true;
      EXPECT_EQ(collide(packed_a, packed_b, t, nullptr, first).size(),
                std::min<std::size_t>(1, collide(a, b, t).size()));
    }
  }
  EXPECT_GT(total, 0u);
}

TEST(PackedPrismTree, ParentsFittedToFacets) {
  // "-tight" trees (ParentFit::fit_facets) pack the same way.
  BuildSettings tight;
  tight.parent_fit = ParentFit::fit_facets;
  const Tree<PieMin> tree = build_tree<PieMin>(make_bumpy_sphere(30, 15, 0.2, 4), tight);
  const PackedPrismTree packed(tree);
  expect_faithful_packing(tree, packed, "pie-min-tight");
  expect_same_answers(tree, packed, scaled(30), "pie-min-tight");
}

TEST(PackedPrismTree, EmptyAndBadQueries) {
  const PackedPrismTree none;
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.node_count(), 0u);
  EXPECT_FALSE(ray_closest_hit(none, Ray{Vec3::Zero(), Vec3::UnitX()}).has_value());
  EXPECT_TRUE(query_overlap(none, Sphere{Vec3::Zero(), 1}).empty());
  EXPECT_TRUE(query_plane(none, Plane{Vec3::UnitZ(), 0}).empty());

  const TriangleMesh mesh = make_terrain(16, 16, 2);
  const Tree<PieMin> tree = build_tree<PieMin>(mesh);
  const PackedPrismTree packed(tree);
  const Real inf = std::numeric_limits<Real>::infinity(), nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_EQ(query_overlap(packed, Aabb{Vec3::Constant(-1e30), Vec3::Constant(1e30)}).size(), mesh.facet_count());
  EXPECT_TRUE(query_overlap(packed, Aabb{Vec3::Constant(100), Vec3::Constant(101)}).empty());
  EXPECT_TRUE(query_overlap(packed, Aabb{Vec3(nan, 0, 0), Vec3(1, 1, 1)}).empty());
  const Aabb infinite{Vec3::Constant(-inf), Vec3::Constant(inf)};
  EXPECT_EQ(query_overlap(packed, infinite), query_overlap(tree, infinite));
  EXPECT_TRUE(query_overlap(packed, Sphere{Vec3(nan, 0, 0), 1}).empty());
  Ray bad;
  bad.origin = Vec3(nan, 0, 0);
  EXPECT_FALSE(ray_closest_hit(packed, bad).has_value());
  // ray_candidates stops when the visitor returns a t below t_min.
  Ray down{mesh_bounds(mesh).center() + Vec3(0, 0, 10), Vec3(0, 0, -1)};
  int visited = 0;
  ray_candidates(packed, down, [&](FacetId, Real) {
    ++visited;
    return Real(-1);
  });
  EXPECT_EQ(visited, 1);
}

TEST(PackedPrismTree, AnyTreeHoldsThePackedFormForPieMethods) {
  auto mesh = std::make_shared<const TriangleMesh>(make_bumpy_sphere(30, 15, 0.2, 4));
  auto other = std::make_shared<const TriangleMesh>(make_uv_sphere(12, 6, 0.9));
  for (const char* name : {"pie-max", "pie-min", "pie-max-general", "pie-min-general", "pie-min-tight"}) {
    const AnyTree any = AnyTree::build(mesh, parse_method(name));
    ASSERT_NE(any.packed_prism(), nullptr) << name;
    EXPECT_EQ(any.packed(), nullptr) << name;
    EXPECT_EQ(any.get<PieMin>(), nullptr) << name;
    EXPECT_EQ(any.get<PieMax>(), nullptr) << name;
    EXPECT_LE(any.memory_bytes(), 64 * mesh->facet_count()) << name;
    EXPECT_EQ(any.node_count(), 2 * mesh->facet_count() - 1) << name;
    const Sphere s{Vec3(0.5, 0.2, 0.8), 0.4};
    std::vector<FacetId> got;
    any.query_overlap(s, [&](FacetId f) {
      got.push_back(f);
      return true;
    });
    std::sort(got.begin(), got.end());
    EXPECT_EQ(violations(got, brute_overlap(*mesh, s)), "") << name;
    EXPECT_FALSE(got.empty()) << name;
    const Ray ray{Vec3(3, 0.1, 0.2), Vec3(-1, 0, 0)};
    const auto hit = any.ray_closest_hit(ray);
    const auto expected = brute_ray_closest_hit(*mesh, ray);
    ASSERT_TRUE(hit && expected) << name;
    EXPECT_EQ(hit->facet, expected->facet) << name;
    // Tree vs tree through AnyTree: the same method collides, another pie method is refused.
    const AnyTree b = AnyTree::build(other, parse_method(name));
    std::vector<FacetPair> pairs;
    any.collide(b, RigidTransform{}, [&](const FacetPair& p) {
      pairs.push_back(p);
      return true;
    });
    std::sort(pairs.begin(), pairs.end());
    EXPECT_EQ(violations(pairs, brute_collide(*mesh, *other, RigidTransform{})), "") << name;
    EXPECT_FALSE(pairs.empty()) << name;
  }
  const AnyTree max = AnyTree::build(mesh, parse_method("pie-max"));
  const AnyTree min = AnyTree::build(other, parse_method("pie-min"));
  EXPECT_THROW(max.collide(min, RigidTransform{}, [](const FacetPair&) { return true; }), Error);
  // Hybrids keep their exact trees; an exact pie-slice tree can still be held explicitly.
  EXPECT_EQ(AnyTree::build(mesh, parse_method("pie-min+aabb@3")).packed_prism(), nullptr);
  const AnyTree exact(build_tree<PieMin>(mesh), parse_method("pie-min"));
  EXPECT_NE(exact.get<PieMin>(), nullptr);
  EXPECT_EQ(exact.packed_prism(), nullptr);
}

}  // namespace
}  // namespace boxtree
