// Every single-tree query against brute force, on procedural and real meshes.
#include <gtest/gtest.h>

#include <thread>

#include <Eigen/Geometry>

#include "boxtree/build.h"
#include "boxtree/query.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "support/brute_force.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

using test::brute_overlap;

Aabb mesh_bounds(const TriangleMesh& m) {
  Aabb box;
  for (const Triangle& t : m.triangles)
    for (VertexId v : t) box.expand(m.vertices[v]);
  return box;
}

Vec3 random_point_near(Random& r, const Aabb& box, double margin = 0.2) {
  const Vec3 e = box.extent().cwiseMax(Vec3::Constant(1e-3));
  Vec3 p;
  for (int i = 0; i < 3; ++i) p[i] = r.uniform(box.min[i] - margin * e[i], box.max[i] + margin * e[i]);
  return p;
}

Mat3 random_rotation(Random& r) {
  Eigen::Quaterniond q(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1));
  q.normalize();
  return q.toRotationMatrix();
}

void check_rays(const Tree<Aabb>& tree, int count, std::uint64_t seed, const std::string& name) {
  const TriangleMesh& mesh = tree.mesh();
  const Aabb box = mesh_bounds(mesh);
  Random r(seed);
  int hits = 0;
  for (int i = 0; i < count; ++i) {
    Ray ray;
    ray.origin = random_point_near(r, box, 0.5);
    // Aim at a random facet's interior half the time so that many rays hit.
    if (i % 2 == 0) {
      const FacetId f = FacetId(r.next() % mesh.facet_count());
      const double u = r.uniform(), v = r.uniform() * (1 - u);
      const Vec3 target = (1 - u - v) * mesh.corner(f, 0) + u * mesh.corner(f, 1) + v * mesh.corner(f, 2);
      ray.direction = (target - ray.origin) * r.uniform(0.1, 3);
    } else {
      ray.direction = r.unit_vector() * r.uniform(0.1, 10);
    }
    if (ray.direction.isZero(0)) continue;
    if (i % 5 == 0) ray.t_max = r.uniform(0.2, 2);  // segments
    const auto expected = test::brute_ray_all_hits(mesh, ray);
    QueryStats stats;
    const auto closest = ray_closest_hit(tree, ray, &stats);
    ASSERT_EQ(closest.has_value(), !expected.empty()) << name << " ray " << i;
    if (closest) {
      ++hits;
      EXPECT_EQ(closest->facet, expected.front().facet) << name << " ray " << i;
      EXPECT_EQ(closest->t, expected.front().t) << name << " ray " << i;
      EXPECT_EQ(closest->u, expected.front().u);
      EXPECT_EQ(closest->v, expected.front().v);
      EXPECT_GE(stats.leaf_tests, 1u);
    }
    const auto all = ray_all_hits(tree, ray);
    ASSERT_EQ(all.size(), expected.size()) << name << " ray " << i;
    for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k].facet, expected[k].facet);
    const auto any = ray_any_hit(tree, ray);
    ASSERT_EQ(any.has_value(), !expected.empty());
    if (any) {
      EXPECT_TRUE(std::any_of(expected.begin(), expected.end(),
                              [&](const RayHit& h) { return h.facet == any->facet && h.t == any->t; }));
    }
  }
  if (compute_mesh_stats(mesh).degenerate_facets < mesh.facet_count()) {
    EXPECT_GT(hits, count / 4) << name << ": the test must exercise hits";
  } else {
    EXPECT_EQ(hits, 0) << name << ": degenerate facets are never hit";
  }
}

TEST(QueryRay, MatchesBruteForceOnProceduralMeshes) {
  for (const auto& [name, mesh] : test::procedural_meshes()) check_rays(build_tree<Aabb>(mesh), 300, 1, name);
}

TEST(QueryRay, MatchesBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"stanford_bunny_res3.obj", "bunny_libigl_closed.obj", "env.obj", "rob.obj", "suzanne.obj",
                           "bullet_kiva_pod_lowres.obj", "bullet_leoTest1.obj"})
    check_rays(build_tree<Aabb>(test::load_shared_mesh(name)), 150, 2, name);
}

// Watertightness: a ray aimed exactly at a shared vertex or at a point on a shared edge of a
// closed mesh, along a line through an interior point, must hit. (Such a line cannot merely
// graze the surface: it passes through the interior. Rays from outside aimed at a silhouette
// edge may legitimately miss, so they are not used.) Checked for rays starting at the interior
// point and for rays starting outside, beyond the target.
void check_watertight(const TriangleMesh& mesh, const Vec3& inside, const std::string& name, int count) {
  const Tree<Aabb> tree = build_tree<Aabb>(mesh);
  Random r(17);
  int misses = 0, brute_misses = 0;
  for (int i = 0; i < count; ++i) {
    const Triangle& t = mesh.triangles[r.next() % mesh.facet_count()];
    const int k = int(r.next() % 3);
    const Vec3& p = mesh.vertices[t[k]];
    const Vec3& q = mesh.vertices[t[(k + 1) % 3]];
    const Vec3 target = i % 2 ? p : Vec3(p + (q - p) * r.uniform());  // a vertex, or a point on an edge
    Ray from_inside;
    from_inside.origin = inside;
    from_inside.direction = target - inside;
    Ray from_outside;
    from_outside.origin = target + (target - inside) * r.uniform(0.01, 3);
    from_outside.direction = inside - from_outside.origin;
    for (const Ray& ray : {from_inside, from_outside}) {
      misses += !ray_closest_hit(tree, ray).has_value();
      brute_misses += !test::brute_ray_closest_hit(mesh, ray).has_value();
    }
  }
  EXPECT_EQ(brute_misses, 0) << name << ": the ray-triangle test leaks";
  EXPECT_EQ(misses, 0) << name << ": the tree culls hits";
}

// A point inside a closed mesh: just behind a facet, on the side where a generic ray crosses
// the surface an odd number of times (agreed on by several directions).
Vec3 inside_point(const TriangleMesh& mesh) {
  Random r(8);
  for (FacetId f = 0; f < mesh.facet_count(); f += 7) {
    const Vec3 a = mesh.corner(f, 0), b = mesh.corner(f, 1), c = mesh.corner(f, 2);
    const Vec3 n = (b - a).cross(c - a);
    if (n.norm() == 0) continue;
    const double step = 1e-3 * std::sqrt(n.norm());
    for (double sign : {-1.0, 1.0}) {
      const Vec3 p = (a + b + c) / 3 + sign * step * n.normalized();
      int odd = 0;
      for (int k = 0; k < 5; ++k) odd += test::brute_ray_all_hits(mesh, Ray{p, r.unit_vector()}).size() % 2;
      if (odd == 5) return p;
    }
  }
  ADD_FAILURE() << "no inside point found";
  return Vec3::Zero();
}

TEST(QueryRay, WatertightThroughSharedEdgesAndVertices) {
  check_watertight(make_uv_sphere(40, 20), Vec3::Zero(), "sphere", 4000);
  check_watertight(make_bumpy_sphere(30, 15, 0.1, 3), Vec3::Zero(), "bumpy_sphere", 4000);
  check_watertight(test::make_cone(64), Vec3(0, 0, 0.3), "cone", 2000);
  const TriangleMesh terrain_box = test::make_closed_terrain(12, 5);
  check_watertight(terrain_box, inside_point(terrain_box), "closed terrain", 2000);
}

TEST(QueryRay, WatertightOnRealClosedMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const char* name : {"ode_bunny.obj", "bunny_libigl_closed.obj", "spot.obj"}) {
    const TriangleMesh mesh = test::load_shared_mesh(name);
    check_watertight(mesh, inside_point(mesh), name, 2000);
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

template <class Shape>
void expect_overlap_matches(const Tree<Aabb>& tree, const Shape& shape, const std::string& what) {
  QueryStats stats;
  const std::vector<FacetId> got = query_overlap(tree, shape, &stats);
  EXPECT_EQ(got, brute_overlap(tree.mesh(), shape)) << what;
  EXPECT_LE(stats.volume_tests, 2 * tree.node_count());
  // Leaf-volume mode: the facets whose leaf boxes overlap the shape.
  std::vector<FacetId> expected_leaf;
  const TriangleMesh& m = tree.mesh();
  for (FacetId f = 0; f < m.facet_count(); ++f)
    if (overlaps(Aabb::from_triangle(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2)), shape)) expected_leaf.push_back(f);
  EXPECT_EQ(query_overlap(tree, shape, nullptr, FacetTest::leaf_volume), expected_leaf) << what << " (leaf volumes)";
}

void check_overlaps(const Tree<Aabb>& tree, int count, const std::string& name) {
  const Aabb box = mesh_bounds(tree.mesh());
  const double size = box.extent().norm();
  Random r(23);
  std::size_t reported = 0;
  for (int i = 0; i < count; ++i) {
    const Vec3 c = random_point_near(r, box);
    const double s = size * r.uniform(0.001, 0.2);
    const Aabb query = Aabb::from_points(c, c + r.uniform_vec3(-s, s));
    expect_overlap_matches(tree, query, name + " aabb");
    Obb obb{c, random_rotation(r), r.uniform_vec3(0, s)};
    if (i % 7 == 0) obb.half_extents[i % 3] = 0;  // flat boxes too
    expect_overlap_matches(tree, obb, name + " obb");
    expect_overlap_matches(tree, Sphere{c, s}, name + " sphere");
    expect_overlap_matches(tree, Capsule{c, c + r.unit_vector() * s * 2, s * 0.3}, name + " capsule");
    reported += query_overlap(tree, Sphere{c, s}).size();
  }
  EXPECT_GT(reported, 0u) << name << ": the test must exercise overlaps";
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
