// SPDX-License-Identifier: MIT
// Every single-tree query against brute force, on procedural and real meshes.
#include <gtest/gtest.h>

#include <thread>

#include <Eigen/Geometry>

#include "boxtree/build.h"
#include "boxtree/query.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "support/brute_force.h"
#include "support/checks.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

using namespace test;

TEST(QueryRay, MatchesBruteForceOnProceduralMeshes) {
  for (const auto& [name, mesh] : test::procedural_meshes()) check_rays(build_tree<Aabb>(mesh), 300, 1, name);
}

TEST(QueryRay, MatchesBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"stanford_bunny_res3.obj", "bunny_libigl_closed.obj", "env.obj", "rob.obj", "suzanne.obj",
                           "bullet_kiva_pod_lowres.obj", "bullet_leoTest1.obj"})
    check_rays(build_tree<Aabb>(test::load_shared_mesh(name)), 150, 2, name);
}

TEST(QueryRay, WatertightThroughSharedEdgesAndVertices) {
  check_watertight<Aabb>(make_uv_sphere(40, 20), Vec3::Zero(), "sphere", 4000);
  check_watertight<Aabb>(make_bumpy_sphere(30, 15, 0.1, 3), Vec3::Zero(), "bumpy_sphere", 4000);
  check_watertight<Aabb>(test::make_cone(64), Vec3(0, 0, 0.3), "cone", 2000);
  const TriangleMesh terrain_box = test::make_closed_terrain(12, 5);
  check_watertight<Aabb>(terrain_box, inside_point(terrain_box), "closed terrain", 2000);
}

TEST(QueryRay, WatertightOnRealClosedMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"ode_bunny.obj", "bunny_libigl_closed.obj", "spot.obj"}) {
    const TriangleMesh mesh = test::load_shared_mesh(name);
    check_watertight<Aabb>(mesh, inside_point(mesh), name, 2000);
  }
}

TEST(QueryRay, BadRaysReturnNothing) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_uv_sphere(8, 4));
  Ray nan_ray;
  nan_ray.origin = Vec3(std::nan(""), 0, 0);
  EXPECT_FALSE(ray_closest_hit(tree, nan_ray).has_value());
  Ray reversed;
  reversed.origin = Vec3(0, 0, 5);
  reversed.direction = Vec3(0, 0, -1);
  reversed.t_min = 2;
  reversed.t_max = 1;
  EXPECT_FALSE(ray_closest_hit(tree, reversed).has_value());
  reversed.t_max = 10;
  EXPECT_TRUE(ray_closest_hit(tree, reversed).has_value());
}

TEST(QueryOverlap, MatchesBruteForceOnProceduralMeshes) {
  for (const auto& [name, mesh] : test::procedural_meshes()) check_overlaps(build_tree<Aabb>(mesh), 60, name);
}

TEST(QueryOverlap, MatchesBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"stanford_bunny_res2.obj", "env.obj", "bullet_diff_ring.obj", "utah_teapot.obj"})
    check_overlaps(build_tree<Aabb>(test::load_shared_mesh(name)), 25, name);
}

// Bad query shapes (NaN, inverted or empty boxes, negative radii) report nothing and never crash.
TEST(QueryOverlap, BadShapesReportNothing) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_terrain(8, 8, 1));
  const double nan = std::nan("");
  EXPECT_TRUE(query_overlap(tree, Sphere{Vec3(nan, 0, 0), 1}).empty());
  EXPECT_TRUE(query_overlap(tree, Sphere{Vec3(50, 50, 5), -1}).empty());
  EXPECT_TRUE(query_overlap(tree, Sphere{Vec3(50, 50, 5), nan}).empty());
  EXPECT_TRUE(query_overlap(tree, Aabb::empty()).empty());
  EXPECT_TRUE(query_overlap(tree, Aabb{Vec3(nan, 0, 0), Vec3(100, 100, 100)}).empty());
  EXPECT_TRUE(query_overlap(tree, Capsule{Vec3(0, 0, nan), Vec3(1, 1, 1), 1}).empty());
  Obb obb{Vec3(50, 50, 5), Mat3::Identity(), Vec3(nan, 1, 1)};
  EXPECT_TRUE(query_overlap(tree, obb).empty());
  EXPECT_TRUE(query_plane(tree, Plane{Vec3(nan, 0, 1), 0}).empty());
  EXPECT_EQ(stabbing_count(tree, Vec3(nan, 1, 1)), 0u);
}

TEST(QueryOverlap, VisitorCanStopEarly) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_terrain(16, 16, 4));
  int calls = 0;
  query_overlap(tree, Aabb{Vec3::Constant(-1e9), Vec3::Constant(1e9)}, [&](FacetId) { return ++calls < 3; });
  EXPECT_EQ(calls, 3);
}

TEST(QueryPlane, MatchesBruteForce) {
  std::vector<std::pair<std::string, TriangleMesh>> meshes = test::procedural_meshes();
  if (test::shared_meshes_available()) meshes.emplace_back("bunny", test::load_shared_mesh("stanford_bunny_res2.obj"));
  for (const auto& [name, mesh] : meshes) {
    const Tree<Aabb> tree = build_tree<Aabb>(mesh);
    const Aabb box = mesh_bounds(mesh);
    Random r(31);
    for (int i = 0; i < 100; ++i) {
      Plane plane;
      plane.normal = i % 10 == 0 ? Vec3::Unit(i % 3) : r.unit_vector();  // axis-aligned planes hit flat boxes exactly
      plane.offset = plane.normal.dot(random_point_near(r, box, 0.05));
      if (i % 10 == 0) plane.offset = plane.normal.dot(mesh.corner(FacetId(r.next() % mesh.facet_count()), 0));
      QueryStats stats;
      EXPECT_EQ(query_plane(tree, plane, &stats), test::brute_plane(mesh, plane)) << name << " plane " << i;
    }
  }
}

TEST(QueryStabbing, MatchesBruteForceCount) {
  for (const auto& [name, mesh] : test::procedural_meshes()) {
    const Tree<Aabb> tree = build_tree<Aabb>(mesh);
    const Aabb box = mesh_bounds(mesh);
    Random r(41);
    for (int i = 0; i < 200; ++i) {
      // Points on the surface (many containing boxes) and random points.
      Vec3 p = random_point_near(r, box);
      if (i % 2) p = mesh.corner(FacetId(r.next() % mesh.facet_count()), int(r.next() % 3));
      std::size_t expected = 0;
      for (NodeIndex node = 0; node < tree.node_count(); ++node) expected += contains(tree.volume(node), p);
      EXPECT_EQ(stabbing_count(tree, p), expected) << name;
      if (i % 2) {
        EXPECT_GE(expected, 1u) << name << ": a mesh corner lies in its leaf box";
      }
    }
  }
}

// Queries are const and share nothing mutable: many threads on one tree give the
// single-threaded answers.
TEST(QueryThreads, ConcurrentQueriesAgreeWithSingleThreaded) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_bumpy_sphere(80, 40, 0.2, 8));
  const Aabb box = mesh_bounds(tree.mesh());
  std::vector<Ray> rays;
  std::vector<Sphere> spheres;
  Random r(5);
  for (int i = 0; i < 2000; ++i) {
    rays.push_back(Ray{random_point_near(r, box, 1.0), r.unit_vector()});
    spheres.push_back(Sphere{random_point_near(r, box), 0.1});
  }
  std::vector<long long> expected(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const auto hit = ray_closest_hit(tree, rays[i]);
    expected[i] = (hit ? hit->facet : -1) * 100000LL + (long long)query_overlap(tree, spheres[i]).size();
  }
  const int thread_count = 8;
  std::vector<std::vector<long long>> got(thread_count, std::vector<long long>(rays.size()));
  std::vector<std::thread> threads;
  for (int t = 0; t < thread_count; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t k = 0; k < rays.size(); ++k) {
        const std::size_t i = (k + std::size_t(t) * 37) % rays.size();
        const auto hit = ray_closest_hit(tree, rays[i]);
        got[std::size_t(t)][i] = (hit ? hit->facet : -1) * 100000LL + (long long)query_overlap(tree, spheres[i]).size();
      }
    });
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < thread_count; ++t) EXPECT_EQ(got[std::size_t(t)], expected) << "thread " << t;
}

}  // namespace
}  // namespace boxtree
