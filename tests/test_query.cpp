// SPDX-License-Identifier: MIT
// Every single-tree query against brute force, on procedural and real meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <thread>

#include <Eigen/Geometry>

#include "boxtree/any_tree.h"
#include "boxtree/build.h"
#include "boxtree/detail/volume_kinds.h"
#include "boxtree/method.h"
#include "boxtree/packed_prism_tree.h"
#include "boxtree/packed_tree.h"
#include "boxtree/query.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "support/brute_force.h"
#include "support/checks.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

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

// ---- Invalid query shapes (shapes.h: they match nothing), through every tree form ----

// A tree form as the same few functions: the facets (sorted) an overlap query reports in either
// FacetTest mode, and those a plane query reports (null where the form has no plane query).
struct TreeForm {
  std::string name;
  std::function<std::vector<FacetId>(const Aabb&, FacetTest)> aabb;
  std::function<std::vector<FacetId>(const Obb&, FacetTest)> obb;
  std::function<std::vector<FacetId>(const Sphere&, FacetTest)> sphere;
  std::function<std::vector<FacetId>(const Capsule&, FacetTest)> capsule;
  std::function<std::vector<FacetId>(const Plane&)> plane;

  std::vector<FacetId> overlap(const Aabb& s, FacetTest t) const { return aabb(s, t); }
  std::vector<FacetId> overlap(const Obb& s, FacetTest t) const { return obb(s, t); }
  std::vector<FacetId> overlap(const Sphere& s, FacetTest t) const { return sphere(s, t); }
  std::vector<FacetId> overlap(const Capsule& s, FacetTest t) const { return capsule(s, t); }
};

// Tree<V>, PackedAabbTree, PackedPrismTree: the free functions of query.h.
template <class T>
TreeForm form_of(std::string name, T tree) {
  auto held = std::make_shared<const T>(std::move(tree));
  const auto overlap = [held](const auto& shape, FacetTest test) { return query_overlap(*held, shape, nullptr, test); };
  TreeForm form{std::move(name), overlap, overlap, overlap, overlap, nullptr};
  if constexpr (!std::is_same_v<T, PackedAabbTree>) {
    form.plane = [held](const Plane& plane) { return query_plane(*held, plane); };
  }
  return form;
}

TreeForm form_of(std::string name, AnyTree tree) {
  auto held = std::make_shared<const AnyTree>(std::move(tree));
  const auto overlap = [held](const auto& shape, FacetTest test) {
    std::vector<FacetId> facets;
    held->query_overlap(
        shape,
        [&](FacetId f) {
          facets.push_back(f);
          return true;
        },
        nullptr, test);
    std::sort(facets.begin(), facets.end());
    return facets;
  };
  return {std::move(name), overlap, overlap, overlap, overlap, nullptr};
}

// The exact tree of every volume kind (hybrids included), both packed forms, and AnyTree for
// every method name, with and without -tight and +aabb@2.
std::vector<TreeForm> every_tree_form(const TriangleMesh& mesh) {
  std::vector<TreeForm> forms;
#define BOXTREE_EXACT_FORM(V) forms.push_back(form_of("Tree<" #V ">", build_for_test<V>(mesh)));
  BOXTREE_FOR_EACH_VOLUME(BOXTREE_EXACT_FORM)
#undef BOXTREE_EXACT_FORM
  forms.push_back(form_of("PackedAabbTree", PackedAabbTree(build_tree<Aabb>(mesh))));
  forms.push_back(form_of("PackedPrismTree of PieMax", PackedPrismTree(build_tree<PieMax>(mesh))));
  forms.push_back(form_of("PackedPrismTree of PieMin", PackedPrismTree(build_tree<PieMin>(mesh))));
  forms.push_back(form_of("PackedPrismTree of PieMaxGeneral", PackedPrismTree(build_tree<PieMaxGeneral>(mesh))));
  forms.push_back(form_of("PackedPrismTree of PieMinGeneral", PackedPrismTree(build_tree<PieMinGeneral>(mesh))));
  const auto shared = std::make_shared<const TriangleMesh>(mesh);
  for (const std::string& base : method_names()) {
    std::vector<std::string> names{base};
    if (base != "aabb") names.insert(names.end(), {base + "-tight", base + "+aabb@2"});
    for (const std::string& name : names)
      forms.push_back(form_of("AnyTree " + name, AnyTree::build(shared, parse_method(name))));
  }
  forms.push_back(form_of("AnyTree of an exact Tree<Aabb>", AnyTree(build_tree<Aabb>(mesh), parse_method("aabb"))));
  return forms;
}

template <class Shape>
void expect_nothing(const std::vector<TreeForm>& forms, const Shape& shape, const std::string& what) {
  for (const TreeForm& form : forms) {
    for (FacetTest test : {FacetTest::exact_triangle, FacetTest::leaf_volume, FacetTest::none}) {
      const std::vector<FacetId> got = form.overlap(shape, test);
      EXPECT_TRUE(got.empty()) << form.name << ", " << what << " (facet test " << int(test) << "): " << got.size()
                               << " facets";
    }
  }
}

// A valid shape: brute force's facets, of which some must be reported (else an invalid twin at the
// same place would prove nothing), a superset of the reported ones in leaf-volume mode, and a
// superset of those without a facet test.
template <class Shape>
void expect_brute_force(const std::vector<TreeForm>& forms, const TriangleMesh& mesh, const Shape& shape,
                        const std::string& what, Real tolerance = kTolerance) {
  const Expected<FacetId> expected = brute_overlap(mesh, shape, tolerance);
  ASSERT_FALSE(expected.must.empty()) << what << " must reach the mesh";
  for (const TreeForm& form : forms) {
    const std::vector<FacetId> got = form.overlap(shape, FacetTest::exact_triangle);
    EXPECT_EQ(violations(got, expected), "") << form.name << ", " << what;
    const std::vector<FacetId> leaves = form.overlap(shape, FacetTest::leaf_volume);
    EXPECT_TRUE(std::includes(leaves.begin(), leaves.end(), got.begin(), got.end()))
        << form.name << ", " << what << " (leaf volumes)";
    const std::vector<FacetId> reached = form.overlap(shape, FacetTest::none);
    EXPECT_TRUE(std::includes(reached.begin(), reached.end(), leaves.begin(), leaves.end()))
        << form.name << ", " << what << " (no facet test)";
  }
}

// Every invalid shape is placed where a form that read it as valid (a negative radius as its
// magnitude, an inverted box as its swapped corners) would report facets, beside its valid twin,
// which every form must report as brute force does.
TEST(QueryOverlap, BadShapesReportNothing) {
  // The unit sphere: its north pole (0, 0, 1) is a vertex, exactly 2 from (0, 0, 3).
  const TriangleMesh mesh = make_uv_sphere(16, 8);
  ASSERT_EQ(mesh.vertices.front(), Vec3(0, 0, 1));
  const std::vector<TreeForm> forms = every_tree_form(mesh);
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  const Vec3 above(0, 0, 3);
  const Mat3 turned = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();

  for (const Real r : {Real(2), Real(-2)}) {
    const std::string what = "|r| touching the pole, r = " + std::to_string(r);
    const Sphere touching{above, r};
    const Capsule touching_capsule{above, Vec3(0, 0, 5), r};
    const Sphere crossing{Vec3(0, 0, 0.5), r / 2};
    const Capsule crossing_capsule{Vec3(-3, 0, 0.2), Vec3(3, 0, 0.2), r / 20};
    if (r > 0) {
      // Touching is exact here (the pole and both centres are small integers, the distances
      // come out exact), so brute force's exact answer, tolerance 0, is the one to give.
      expect_brute_force(forms, mesh, touching, "sphere, " + what, 0);
      expect_brute_force(forms, mesh, touching_capsule, "capsule, " + what, 0);
      expect_brute_force(forms, mesh, crossing, "sphere across the surface");
      expect_brute_force(forms, mesh, crossing_capsule, "capsule across the surface");
    } else {
      expect_nothing(forms, touching, "sphere, " + what);
      expect_nothing(forms, touching_capsule, "capsule, " + what);
      expect_nothing(forms, crossing, "sphere across the surface, negative radius");
      expect_nothing(forms, crossing_capsule, "capsule across the surface, negative radius");
    }
  }
  for (const Real r : {nan, -inf}) {
    expect_nothing(forms, Sphere{above, r}, "sphere of radius " + std::to_string(r));
    expect_nothing(forms, Capsule{above, Vec3(0, 0, 5), r}, "capsule of radius " + std::to_string(r));
  }
  // An infinite radius is valid: all of space.
  EXPECT_EQ(brute_overlap(mesh, Sphere{above, inf}).must.size(), mesh.facet_count());
  expect_brute_force(forms, mesh, Sphere{above, inf}, "sphere of infinite radius");
  expect_brute_force(forms, mesh, Capsule{above, Vec3(0, 0, 5), inf}, "capsule of infinite radius");
  for (const Vec3& bad : {Vec3(nan, 0, 0), Vec3(0, 0, inf)}) {
    expect_nothing(forms, Sphere{bad, 5}, "sphere with a non-finite centre");
    expect_nothing(forms, Capsule{bad, Vec3::Zero(), 5}, "capsule with a non-finite end");
    expect_nothing(forms, Capsule{Vec3::Zero(), bad, 5}, "capsule with a non-finite end");
  }

  // Boxes: an inverted box is not its swapped corners.
  for (const Real size : {Real(2), Real(0.1)}) {
    const Vec3 low = Vec3(0, 0, 1) - Vec3::Constant(size), high = Vec3(0, 0, 1) + Vec3::Constant(size);
    expect_brute_force(forms, mesh, Aabb{low, high}, "box of size " + std::to_string(size));
    expect_nothing(forms, Aabb{high, low}, "inverted box of size " + std::to_string(size));
    expect_brute_force(forms, mesh, Obb{Vec3(0, 0, 1), turned, Vec3::Constant(size)},
                       "oriented box of size " + std::to_string(size));
    expect_nothing(forms, Obb{Vec3(0, 0, 1), turned, Vec3(size, -size, size)}, "oriented box, a negative extent");
  }
  expect_nothing(forms, Aabb::empty(), "Aabb::empty()");
  expect_nothing(forms, Aabb{Vec3(-2, nan, -2), Vec3::Constant(2)}, "box with a NaN corner");
  expect_nothing(forms, Aabb{Vec3::Constant(-2), Vec3(2, 2, nan)}, "box with a NaN corner");
  expect_nothing(forms, Obb{Vec3::Zero(), turned, Vec3(nan, 2, 2)}, "oriented box, a NaN extent");
  expect_nothing(forms, Obb{Vec3::Zero(), turned, Vec3(inf, 2, 2)}, "oriented box, an infinite extent");
  expect_nothing(forms, Obb{Vec3(nan, 0, 0), turned, Vec3::Constant(2)}, "oriented box, a NaN centre");
  Mat3 nan_axes = turned;
  nan_axes(1, 2) = nan;
  expect_nothing(forms, Obb{Vec3::Zero(), nan_axes, Vec3::Constant(2)}, "oriented box, a NaN axis");
  // Infinite sides are valid (all of space, a half-space, a quadrant column).
  const Aabb everything{Vec3::Constant(-inf), Vec3::Constant(inf)};
  EXPECT_EQ(brute_overlap(mesh, everything).must.size(), mesh.facet_count());
  expect_brute_force(forms, mesh, everything, "all of space");
  expect_brute_force(forms, mesh, Aabb{Vec3::Constant(-inf), Vec3(0, inf, inf)}, "half-space x <= 0");
  expect_brute_force(forms, mesh, Aabb{Vec3(0.3, 0.3, -inf), Vec3(inf, inf, inf)}, "quadrant column");

  // Planes: a zero normal (every point satisfies 0 . x == 0) and non-finite ones.
  const Plane equator{Vec3::UnitZ(), 0};
  for (const TreeForm& form : forms) {
    if (!form.plane) continue;
    EXPECT_EQ(violations(form.plane(equator), brute_plane(mesh, equator)), "") << form.name;
    EXPECT_FALSE(form.plane(equator).empty()) << form.name;  // its corners on the equator are 6e-17 off
    for (const Plane& bad : {Plane{Vec3::Zero(), 0}, Plane{Vec3(nan, 0, 1), 0}, Plane{Vec3(0, 0, inf), 0},
                             Plane{Vec3::UnitZ(), nan}, Plane{Vec3::UnitZ(), inf}})
      EXPECT_TRUE(form.plane(bad).empty())
          << form.name << ", plane (" << bad.normal.transpose() << ", " << bad.offset << ")";
  }
  EXPECT_FALSE(brute_plane(mesh, equator).may.empty());

  const Tree<Aabb> tree = build_tree<Aabb>(mesh);
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
  if (test::use_shared_meshes_if_present())
    meshes.emplace_back("bunny", test::load_shared_mesh("stanford_bunny_res2.obj"));
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
      EXPECT_EQ(test::violations(query_plane(tree, plane, &stats), test::brute_plane(mesh, plane)), "")
          << name << " plane " << i;
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
      if (i % 2) {
        const int k = int(r.next() % 3);  // the corner first: see tests/support/random.h
        p = mesh.corner(FacetId(r.next() % mesh.facet_count()), k);
      }
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
