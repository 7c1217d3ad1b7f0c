// SPDX-License-Identifier: MIT
// The packed axis-aligned tree (packed_tree.h) against the exact Tree<Aabb> it is packed from and
// against brute force: a valid 4-wide packing, conservative boxes, the same query results.
#include <gtest/gtest.h>

#include <map>

#include "boxtree/any_tree.h"
#include "boxtree/build.h"
#include "boxtree/packed_tree.h"
#include "support/brute_force.h"
#include "support/checks.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

// Where each facet's leaf sits: (inner node, slot), or (-1, 0) for a single-facet tree.
std::map<FacetId, std::pair<long, int>> leaf_slots(const PackedAabbTree& packed) {
  std::map<FacetId, std::pair<long, int>> slots;
  if (PackedAabbTree::is_leaf(packed.root_link())) slots[PackedAabbTree::facet(packed.root_link())] = {-1, 0};
  for (std::size_t n = 0; n < packed.nodes().size(); ++n)
    for (int slot = 0; slot < PackedAabbTree::kWidth; ++slot) {
      const std::uint32_t link = packed.nodes()[n].link[slot];
      if (PackedAabbTree::is_leaf(link)) {
        EXPECT_TRUE(slots.emplace(PackedAabbTree::facet(link), std::make_pair(long(n), slot)).second)
            << "facet " << PackedAabbTree::facet(link) << " in two leaves";
      }
    }
  return slots;
}

Aabb packed_leaf_box(const PackedAabbTree& packed, const std::pair<long, int>& slot) {
  return slot.first < 0 ? packed.bounds() : packed.child_box(packed.nodes()[std::size_t(slot.first)], slot.second);
}

// The packed tree's structure: every facet in exactly one leaf, every node with two to four
// children (used slots first), the first inner child laid out next, and every packed box holding
// the exact boxes of all facets below it with at least one grid step to spare.
void expect_valid_packing(const Tree<Aabb>& tree, const PackedAabbTree& packed, const std::string& name) {
  const TriangleMesh& mesh = tree.mesh();
  EXPECT_EQ(packed.memory_bytes(), sizeof(PackedAabbTree::Node) * packed.nodes().size()) << name;
  EXPECT_LE(packed.memory_bytes(), 32 * mesh.facet_count()) << name;
  EXPECT_LE(packed.height(), tree.height()) << name;
  EXPECT_EQ(packed.node_count(), packed.nodes().size() + mesh.facet_count()) << name;
  const auto slots = leaf_slots(packed);
  ASSERT_EQ(slots.size(), mesh.facet_count()) << name << ": every facet in exactly one leaf";
  EXPECT_TRUE(contains(packed.bounds(), Aabb(mesh_bounds(mesh)))) << name;
  if (PackedAabbTree::is_leaf(packed.root_link())) return;
  // Exact box of the facets below each link, bottom-up (children come after their parent).
  std::vector<Aabb> below(packed.nodes().size());
  const auto box_of_link = [&](std::uint32_t link) {
    if (!PackedAabbTree::is_leaf(link)) return below[link];
    const FacetId f = PackedAabbTree::facet(link);
    return Aabb::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
  };
  const Vec3 spare = packed.step() * 0.999;
  int max_height = 0;
  std::vector<int> depth(packed.nodes().size(), 0);
  for (std::size_t n = packed.nodes().size(); n-- > 0;) {
    const PackedAabbTree::Node& node = packed.nodes()[n];
    int used = 0;
    Aabb all = Aabb::empty();
    bool first_inner = true;
    for (int slot = 0; slot < PackedAabbTree::kWidth; ++slot) {
      const std::uint32_t link = node.link[slot];
      if (link == PackedAabbTree::kEmpty) continue;
      EXPECT_EQ(used, slot) << name << ": used slots first";
      ++used;
      if (!PackedAabbTree::is_leaf(link)) {
        EXPECT_GT(link, n) << name << ": children after their parent";
        if (first_inner) {
          EXPECT_EQ(link, n + 1) << name << ": first inner child next";
        }
        first_inner = false;
      }
      const Aabb exact = box_of_link(link);
      const Aabb box = packed.child_box(node, slot);
      for (int i = 0; i < 3; ++i) {
        EXPECT_GE(node.min[i][slot], 1) << name << ": boxes lie in [1, 65534] on the grid";
        EXPECT_LE(node.max[i][slot], 0xFFFE) << name << ": boxes lie in [1, 65534] on the grid";
      }
      EXPECT_TRUE((box.min.array() <= (exact.min - spare).array()).all() &&
                  (box.max.array() >= (exact.max + spare).array()).all())
          << name << ": packed box must hold the facets below it with a step to spare";
      all = Aabb::enclosing(all, exact);
    }
    EXPECT_GE(used, 2) << name;
    below[n] = all;
  }
  for (std::size_t n = 0; n < packed.nodes().size(); ++n)
    for (std::uint32_t link : packed.nodes()[n].link)
      if (link != PackedAabbTree::kEmpty) {
        const int d = depth[n] + 1;
        if (PackedAabbTree::is_leaf(link)) {
          max_height = std::max(max_height, d);
        } else {
          depth[link] = d;
        }
      }
  EXPECT_EQ(packed.height(), max_height) << name;
}

// Exact-triangle queries give brute force's answer; leaf-volume queries report exactly the facets
// whose packed leaf box meets the shape (for an Aabb query, tested on the grid: also those within
// two grid steps of it), so always a superset of the exact tree's leaf-volume answer.
template <class Shape>
void expect_overlaps(const Tree<Aabb>& tree, const PackedAabbTree& packed,
                     const std::map<FacetId, std::pair<long, int>>& slots, const Shape& shape,
                     const std::string& what) {
  EXPECT_EQ(violations(query_overlap(packed, shape), brute_overlap(packed.mesh(), shape)), "") << what;
  const std::vector<FacetId> got = query_overlap(packed, shape, nullptr, FacetTest::leaf_volume);
  const std::vector<FacetId> exact_leaves = query_overlap(tree, shape, nullptr, FacetTest::leaf_volume);
  EXPECT_TRUE(std::includes(got.begin(), got.end(), exact_leaves.begin(), exact_leaves.end())) << what;
  std::vector<FacetId> expected;
  for (const auto& [facet, slot] : slots) {
    Aabb box = packed_leaf_box(packed, slot);
    if (overlaps(box, shape)) expected.push_back(facet);
  }
  if constexpr (std::is_same_v<Shape, Aabb>) {
    EXPECT_TRUE(std::includes(got.begin(), got.end(), expected.begin(), expected.end())) << what;
    for (FacetId f : got) {
      Aabb box = packed_leaf_box(packed, slots.at(f));
      box.min -= packed.step() * 2.001;
      box.max += packed.step() * 2.001;
      EXPECT_TRUE(overlaps(box, shape)) << what << ": facet " << f << " is farther than two grid steps";
    }
  } else {
    EXPECT_EQ(got, expected) << what;
  }
}

void check_packed(const TriangleMesh& mesh, const std::string& name, int queries) {
  const Tree<Aabb> tree = build_tree<Aabb>(mesh);
  const PackedAabbTree packed(tree);
  expect_valid_packing(tree, packed, name);
  check_rays(packed, queries, 3, name);
  const auto slots = leaf_slots(packed);
  const Aabb box = mesh_bounds(mesh);
  Random r(41);
  std::size_t reported = 0;
  for (int i = 0; i < queries; ++i) {
    const QueryShapes q = random_query_shapes(r, box, i);
    expect_overlaps(tree, packed, slots, q.aabb, name + " aabb");
    expect_overlaps(tree, packed, slots, q.obb, name + " obb");
    expect_overlaps(tree, packed, slots, q.sphere, name + " sphere");
    expect_overlaps(tree, packed, slots, q.capsule, name + " capsule");
    reported += query_overlap(packed, q.sphere).size();
  }
  EXPECT_GT(reported, 0u) << name << ": the test must exercise overlaps";
}

TEST(PackedTree, MatchesExactTreeAndBruteForceOnProceduralMeshes) {
  for (const auto& [name, mesh] : procedural_meshes()) check_packed(mesh, name, 120);
}

TEST(PackedTree, MatchesExactTreeAndBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"stanford_bunny_res3.obj", "env.obj", "rob.obj", "bullet_kiva_pod_lowres.obj"})
    check_packed(load_shared_mesh(name), name, 80);
}

TEST(PackedTree, FlatAndFarMeshes) {
  // A flat sheet (zero height extent: the grid's z step must stay usable) and the same far away.
  TriangleMesh flat = make_terrain(20, 20, 1);
  for (Vec3& v : flat.vertices) v.z() = 0.25;
  check_packed(flat, "flat", 150);
  TriangleMesh far = flat;
  for (Vec3& v : far.vertices) v += Vec3(1e6, -2e6, 3e5);
  check_packed(far, "flat far", 150);
}

TEST(PackedTree, WatertightRays) {
  for (const TriangleMesh& mesh : {make_uv_sphere(40, 20), make_bumpy_sphere(30, 15, 0.1, 3)})
    check_watertight_tree(PackedAabbTree(build_tree<Aabb>(mesh)), Vec3::Zero(), "sphere", 3000);
  const TriangleMesh terrain_box = make_closed_terrain(12, 5);
  check_watertight_tree(PackedAabbTree(build_tree<Aabb>(terrain_box)), inside_point(terrain_box), "closed terrain",
                        2000);
}

TEST(PackedTree, CollideMatchesBruteForce) {
  const PackedAabbTree a(build_tree<Aabb>(make_bumpy_sphere(24, 12, 0.3, 7)));
  const PackedAabbTree b(build_tree<Aabb>(make_uv_sphere(16, 8, 0.8)));
  EXPECT_GT(check_collide(a, b, 12, 0.8, "spheres"), 0u);
  const PackedAabbTree soup(build_tree<Aabb>(make_triangle_soup(400, 3, 1.0, 0.15)));
  EXPECT_GT(check_collide(soup, a, 8, 0.5, "soup vs sphere"), 0u);
}

// A small body on a large mesh: collide gathers the large tree's facets in the body's root box
// and walks the body's tree with each (packed_tree.cpp, collide_through_facets) instead of the
// joint walk. Both orders of the trees, rotated and far from the origin, touching exactly at a
// shared vertex, and stopping early.
TEST(PackedTree, CollideSmallBodyOnLargeMesh) {
  // 64 x 64 cells of 1 unit; bodies under a cell across (their root boxes hold a few dozen
  // terrain facets, fewer than half their own facets).
  const TriangleMesh terrain = make_terrain(64, 64, 3, 64, 4);
  const TriangleMesh body = make_bumpy_sphere(16, 10, 0.2, 5);  // radius ~1: scaled below
  for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(3e4, -2e4, 1e3)}) {
    TriangleMesh ground = terrain;
    for (Vec3& v : ground.vertices) v += offset;
    TriangleMesh small = body;
    for (Vec3& v : small.vertices) v *= 0.6;
    const PackedAabbTree a(build_tree<Aabb>(ground));
    const PackedAabbTree b(build_tree<Aabb>(small));
    Random r(41);
    std::size_t pairs = 0;
    for (int pose = 0; pose < 40; ++pose) {
      // Somewhere over the terrain, at its height there (a vertex's), sunk a little or not at all.
      const Vec3& anchor = ground.vertices[r.next() % ground.vertices.size()];
      RigidTransform t;
      t.rotation = random_rotation(r);
      t.translation = anchor + Vec3(0, 0, r.uniform(0.1, 0.7));
      const std::vector<FacetPair> got = collide(a, b, t);
      EXPECT_EQ(violations(got, brute_collide(ground, small, t)), "") << "pose " << pose;
      // The other order: b's facets first in each pair.
      std::vector<FacetPair> swapped = collide(b, a, t.inverse());
      for (FacetPair& p : swapped) std::swap(p.a, p.b);
      std::sort(swapped.begin(), swapped.end());
      EXPECT_EQ(swapped, got) << "pose " << pose << " (small tree first)";
      pairs += got.size();
      CollideSettings first;
      first.stop_at_first = true;
      EXPECT_EQ(collide(a, b, t, nullptr, first).size(), std::min<std::size_t>(1, got.size())) << "pose " << pose;
    }
    EXPECT_GT(pairs, 0u) << "the poses must make contact";
    // Exactly touching: the body's lowest vertex on a terrain vertex, no rotation (exact).
    std::size_t lowest = 0;
    for (std::size_t i = 1; i < small.vertices.size(); ++i)
      if (small.vertices[i].z() < small.vertices[lowest].z()) lowest = i;
    const Vec3& target = ground.vertices[33 * 65 + 20];
    const RigidTransform touching{Mat3::Identity(), target - small.vertices[lowest]};
    ASSERT_EQ(touching.apply(small.vertices[lowest]), target);
    const std::vector<FacetPair> touched = collide(a, b, touching);
    EXPECT_EQ(violations(touched, brute_collide(ground, small, touching)), "");
    EXPECT_FALSE(touched.empty()) << "touching counts";
  }
}

// ray_closest_hits walks several rays in turns: each answer must be brute force's closest hit and
// bit-identical to ray_closest_hit's (the same walk), whatever the batch size around the lane
// count, with invalid rays, misses and segments mixed in, and the statistics the sum of the
// single queries'.
// `brute_every`: brute force on every that-many'th ray (large meshes; the single query is
// cross-checked against brute force on every ray elsewhere).
void check_batched_rays(const TriangleMesh& mesh, const std::string& name, std::uint64_t seed,
                        std::size_t brute_every = 1) {
  const PackedAabbTree packed(build_tree<Aabb>(mesh));
  const Aabb box = mesh_bounds(mesh);
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  Random r(seed);
  std::vector<Ray> rays;
  for (int i = 0; i < 301; ++i) {
    Ray ray;
    ray.origin = random_point_near(r, box, 0.5);
    if (i % 2 == 0) {
      const FacetId f = FacetId(r.next() % mesh.facet_count());
      const Vec3 target = (mesh.corner(f, 0) + mesh.corner(f, 1) + mesh.corner(f, 2)) / 3;
      ray.direction = target - ray.origin;
    } else {
      ray.direction = r.unit_vector();
    }
    if (i % 5 == 0) ray.t_max = r.uniform(0.2, 2);
    if (i % 37 == 3) ray.origin.x() = nan;          // invalid: no hit
    if (i % 41 == 4) ray.direction = Vec3::Zero();  // invalid: no hit
    if (i % 43 == 5) ray.t_min = ray.t_max = 1e30;  // starts beyond the mesh
    rays.push_back(ray);
  }
  int hits = 0;
  for (const std::size_t count :
       {std::size_t(0), std::size_t(1), std::size_t(7), std::size_t(8), std::size_t(9), rays.size()}) {
    std::vector<std::optional<RayHit>> got(count, RayHit{});  // every slot must be written
    QueryStats batch_stats;
    ray_closest_hits(packed, rays.data(), count, got.data(), &batch_stats);
    QueryStats single_stats;
    for (std::size_t i = 0; i < count; ++i) {
      const std::optional<RayHit> single = ray_closest_hit(packed, rays[i], &single_stats);
      ASSERT_EQ(got[i].has_value(), single.has_value()) << name << " ray " << i;
      if (i % brute_every == 0) {
        const std::vector<RayHit> expected = brute_ray_all_hits(mesh, rays[i]);
        ASSERT_EQ(got[i].has_value(), !expected.empty()) << name << " ray " << i << " of " << count;
        if (got[i]) {
          EXPECT_EQ(got[i]->facet, expected.front().facet) << name << " ray " << i;
          EXPECT_EQ(got[i]->t, expected.front().t) << name << " ray " << i;
        }
      }
      if (!got[i]) continue;
      ++hits;
      EXPECT_EQ(got[i]->facet, single->facet);
      EXPECT_EQ(got[i]->t, single->t);
      EXPECT_EQ(got[i]->u, single->u);
      EXPECT_EQ(got[i]->v, single->v);
    }
    EXPECT_EQ(batch_stats.nodes_visited, single_stats.nodes_visited) << name << " batch of " << count;
    EXPECT_EQ(batch_stats.volume_tests, single_stats.volume_tests) << name << " batch of " << count;
    EXPECT_EQ(batch_stats.leaf_tests, single_stats.leaf_tests) << name << " batch of " << count;
  }
  EXPECT_GT(hits, 100) << name << ": the test must exercise hits";
}

TEST(PackedTree, BatchedRaysMatchSingleRaysAndBruteForce) {
  for (const auto& [name, mesh] : procedural_meshes()) {
    if (compute_mesh_stats(mesh).degenerate_facets == mesh.facet_count()) continue;  // never hit
    check_batched_rays(mesh, name, 5);
  }
  check_batched_rays(make_terrain(64, 64, 3), "terrain 64", 6);
  // Above the size where the rays' walks take turns (2 MB of hierarchy and mesh; these three are
  // the tree's nodes, the triangles and the vertices).
  const TriangleMesh large = make_terrain(256, 256, 4);
  const PackedAabbTree large_tree(build_tree<Aabb>(large));
  ASSERT_GT(
      large_tree.memory_bytes() + large.triangles.size() * sizeof(Triangle) + large.vertices.size() * sizeof(Vec3),
      std::size_t(2) << 20);
  check_batched_rays(large, "terrain 256", 7, 10);
}

TEST(PackedTree, BatchedRaysOnTinyTrees) {
  // One facet (the root is a leaf: answered when the walk starts) and two.
  TriangleMesh one;
  one.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  one.triangles = {{0, 1, 2}};
  TriangleMesh two = one;
  two.vertices.push_back(Vec3(1, 1, 0));
  two.triangles.push_back({1, 3, 2});
  for (const TriangleMesh& mesh : {one, two}) {
    const PackedAabbTree packed(build_tree<Aabb>(mesh));
    std::vector<Ray> rays;
    for (int i = 0; i < 20; ++i) rays.push_back(Ray{Vec3(0.05 * i, 0.25, 1), Vec3(0, 0, -1)});
    std::vector<std::optional<RayHit>> got(rays.size());
    ray_closest_hits(packed, rays.data(), rays.size(), got.data());
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const std::optional<RayHit> single = ray_closest_hit(packed, rays[i]);
      ASSERT_EQ(got[i].has_value(), single.has_value()) << mesh.facet_count() << " facets, ray " << i;
      if (single) {
        EXPECT_EQ(got[i]->facet, single->facet);
      }
    }
    EXPECT_TRUE(got[0].has_value());
    EXPECT_EQ(got[19].has_value(), mesh.facet_count() == 2);  // (0.95, 0.25): only in the second triangle
  }
  // An empty tree answers every ray with no hit.
  const PackedAabbTree empty;
  std::vector<Ray> rays(3, Ray{Vec3::Zero(), Vec3::UnitZ()});
  std::vector<std::optional<RayHit>> got(3, RayHit{});
  ray_closest_hits(empty, rays.data(), rays.size(), got.data());
  for (const auto& hit : got) EXPECT_FALSE(hit.has_value());
}

TEST(PackedTree, AnyTreeBatchedRaysForEveryForm) {
  // AnyTree::ray_closest_hits: the packed batch for aabb (above the size where the walks take
  // turns), one ray after another for the other forms; the same answers as ray_closest_hit, and
  // an empty AnyTree answers no hit.
  auto small = std::make_shared<const TriangleMesh>(make_bumpy_sphere(30, 15, 0.2, 4));
  auto large = std::make_shared<const TriangleMesh>(make_terrain(256, 256, 5));
  Random r(17);
  for (const auto& [mesh, method] : {std::pair{large, "aabb"}, std::pair{small, "aabb"}, std::pair{small, "obb-min"},
                                     std::pair{small, "pie-min-general"}}) {
    const AnyTree any = AnyTree::build(mesh, parse_method(method));
    const Aabb box = mesh_bounds(*mesh);
    std::vector<Ray> rays;
    for (int i = 0; i < 60; ++i) {
      const Vec3 origin = random_point_near(r, box, 0.5);
      rays.push_back(Ray{origin, box.center() + 0.3 * box.extent().cwiseProduct(r.unit_vector()) - origin});
    }
    std::vector<std::optional<RayHit>> got(rays.size());
    QueryStats batch, single;
    any.ray_closest_hits(rays.data(), rays.size(), got.data(), &batch);
    int hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const auto expected = any.ray_closest_hit(rays[i], &single);
      ASSERT_EQ(got[i].has_value(), expected.has_value()) << method << " ray " << i;
      if (!expected) continue;
      ++hits;
      EXPECT_EQ(got[i]->facet, expected->facet) << method << " ray " << i;
      EXPECT_EQ(got[i]->t, expected->t) << method << " ray " << i;
    }
    EXPECT_EQ(batch.leaf_tests, single.leaf_tests) << method;
    EXPECT_GT(hits, 20) << method;
  }
  std::vector<Ray> rays(2, Ray{Vec3::Zero(), Vec3::UnitZ()});
  std::vector<std::optional<RayHit>> got(2, RayHit{});
  AnyTree().ray_closest_hits(rays.data(), rays.size(), got.data());
  EXPECT_FALSE(got[0].has_value() || got[1].has_value());
}

TEST(PackedTree, UnboundedAndBadQueries) {
  const TriangleMesh mesh = make_terrain(16, 16, 2);
  const PackedAabbTree packed(build_tree<Aabb>(mesh));
  const Real inf = std::numeric_limits<Real>::infinity();
  // An infinite box holds every facet; a box around nothing, none.
  EXPECT_EQ(query_overlap(packed, Aabb{Vec3::Constant(-inf), Vec3::Constant(inf)}).size(), mesh.facet_count());
  Aabb half_space{Vec3(-inf, -inf, -inf), Vec3(inf, inf, inf)};
  half_space.max.x() = mesh_bounds(mesh).center().x();
  EXPECT_EQ(violations(query_overlap(packed, half_space), brute_overlap(mesh, half_space)), "");
  EXPECT_TRUE(query_overlap(packed, Aabb{Vec3::Constant(100), Vec3::Constant(101)}).empty());
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_TRUE(query_overlap(packed, Aabb{Vec3(nan, 0, 0), Vec3(1, 1, 1)}).empty());
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

TEST(PackedTree, AnyTreeHoldsThePackedFormForAabb) {
  auto mesh = std::make_shared<const TriangleMesh>(make_bumpy_sphere(30, 15, 0.2, 4));
  const AnyTree any = AnyTree::build(mesh, parse_method("aabb"));
  ASSERT_NE(any.packed(), nullptr);
  EXPECT_EQ(any.get<Aabb>(), nullptr);
  EXPECT_LE(any.memory_bytes(), 32 * mesh->facet_count());
  EXPECT_EQ(any.node_count(), any.packed()->node_count());
  const Sphere s{Vec3(0.5, 0.2, 0.8), 0.4};
  std::vector<FacetId> got;
  any.query_overlap(s, [&](FacetId f) {
    got.push_back(f);
    return true;
  });
  std::sort(got.begin(), got.end());
  EXPECT_EQ(violations(got, brute_overlap(*mesh, s)), "");
  EXPECT_FALSE(got.empty());
  // Oriented methods keep their exact trees.
  EXPECT_EQ(AnyTree::build(mesh, parse_method("obb-min")).packed(), nullptr);
}

// Spheres that only just touch facets: centred off a terrain vertex with the radius that reaches
// it, grown or shrunk by a few ulps, and spheres centred far outside the tree's grid (1e4 m away:
// beyond it on every axis), on a rough and on a flat terrain (whose grid is a sliver in height:
// every centre over it is beyond the grid). The packed walk (its node test in float on the grid,
// the part beyond the grid taken in double) must report exactly the facets that
// triangle_overlaps_sphere accepts, never losing one to its node culling, and those facets must
// be the independent oracle's (brute_force.h).
class PackedTreeSphere : public ::testing::TestWithParam<Real> {};

TEST_P(PackedTreeSphere, QueryTouchingVerticesIsTriangleOverlapsSphere) {
  const TriangleMesh terrain = make_terrain(24, 24, 5, 24, GetParam());
  const PackedAabbTree packed(build_tree<Aabb>(terrain));
  const auto reference = [&](const Sphere& sphere) {
    std::vector<FacetId> out;
    for (FacetId f = 0; f < terrain.facet_count(); ++f)
      if (triangle_overlaps_sphere(terrain.corner(f, 0), terrain.corner(f, 1), terrain.corner(f, 2), sphere))
        out.push_back(f);
    return out;
  };
  Random r(23);
  std::size_t reported = 0;
  for (int i = 0; i < 400; ++i) {
    const Vec3& vertex = terrain.vertices[r.next() % terrain.vertices.size()];
    const Real dx = r.uniform(-1, 1);
    const Real dy = r.uniform(-1, 1);
    const Real dz = r.uniform(0.2, 1);
    // Far ones: 1e4 m away on a 24 m terrain (the grid step is ~1 mm: 1e7 steps).
    const Real reach = i % 4 == 3 ? 1e4 : r.uniform(0.05, 3.0);
    const Vec3 center = vertex + Vec3(dx, dy, dz).normalized() * reach;
    const Real ulps = r.uniform(-4, 4);
    const Sphere sphere{center, (center - vertex).norm() * (1 + ulps * std::numeric_limits<Real>::epsilon())};
    const std::vector<FacetId> expected = reference(sphere);
    EXPECT_EQ(query_overlap(packed, sphere), expected) << "sphere " << i;
    EXPECT_EQ(violations(expected, brute_overlap(terrain, sphere)), "") << "sphere " << i;
    reported += expected.size();
  }
  EXPECT_GT(reported, 400u);
}

INSTANTIATE_TEST_SUITE_P(RoughAndFlat, PackedTreeSphere, ::testing::Values(Real(3), Real(0)));

// A sphere resting on a flat terrain of 1 m cells (radius 1, centre 0.9 m over it: it meets the
// plane in a disk of radius 0.44 m) is culled in all three axes: the facets its bounding box
// covers in x and y (about 2 x 2 cells, 8 to 18 facets) are not all tested, only those near the
// disk. A node test that gave up on the flat grid's height tested them all.
TEST(PackedTree, SphereOnAFlatTerrainTestsOnlyTheFacetsNearIt) {
  const TriangleMesh flat = make_terrain(24, 24, 5, 24, 0);
  const PackedAabbTree packed(build_tree<Aabb>(flat));
  for (const Vec3& center : {Vec3(10.5, 10.5, 0.9), Vec3(7.25, 13.8, 0.9), Vec3(12, 4, 0.9)}) {
    QueryStats stats;
    const std::vector<FacetId> got = query_overlap(packed, Sphere{center, 1.0}, &stats);
    EXPECT_EQ(violations(got, brute_overlap(flat, Sphere{center, 1.0})), "");
    EXPECT_LE(stats.leaf_tests, got.size() + 4) << center.transpose();
  }
}

// Oriented boxes that only just touch facets: axis-aligned boxes with a face through a vertex
// (exact contact), and turned boxes grown or shrunk by a few ulps around a vertex. The packed
// walk (quantized node boxes, the box's frame taken once per query) must report exactly the
// facets that triangle_overlaps_obb accepts, never losing one to its node culling, and those
// facets must be the independent oracle's (brute_force.h).
TEST(PackedTree, ObbQueryTouchingVerticesIsTriangleOverlapsObb) {
  const TriangleMesh terrain = make_terrain(24, 24, 5, 24, 3);
  const PackedAabbTree packed(build_tree<Aabb>(terrain));
  const auto reference = [&](const Obb& box) {
    std::vector<FacetId> out;
    for (FacetId f = 0; f < terrain.facet_count(); ++f)
      if (triangle_overlaps_obb(terrain.corner(f, 0), terrain.corner(f, 1), terrain.corner(f, 2), box))
        out.push_back(f);
    return out;
  };
  Random r(17);
  std::size_t reported = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3& vertex = terrain.vertices[r.next() % terrain.vertices.size()];
    const Real half_x = r.uniform(0.1, 2.0);
    const Real half_y = r.uniform(0.1, 2.0);
    const Real half_z = r.uniform(0.1, 2.0);
    Obb box;
    box.half_extents = Vec3(half_x, half_y, half_z);
    if (i % 2 == 0) {
      // Resting on the vertex: the bottom face through it.
      box.axes = Mat3::Identity();
      box.center = vertex + Vec3(0, 0, half_z);
    } else {
      // Turned, with the vertex a few ulps inside or outside its bottom face.
      box.axes = random_rotation(r);
      const Real ulps = r.uniform(-4, 4);
      const Real below = half_z * (1 + ulps * std::numeric_limits<Real>::epsilon());
      box.center = vertex + box.axes.col(2) * below;
    }
    const std::vector<FacetId> expected = reference(box);
    EXPECT_EQ(query_overlap(packed, box), expected) << "box " << i;
    EXPECT_EQ(violations(expected, brute_overlap(terrain, box)), "") << "box " << i;
    reported += expected.size();
  }
  EXPECT_GT(reported, 0u);
}

}  // namespace
}  // namespace boxtree
