// SPDX-License-Identifier: MIT
// Threads (issue 9): a built tree is immutable and its queries are const (tree.h), so 8 threads
// querying one shared tree must get exactly the single-threaded answers. Every query kind is run
// (closest/any/all ray hits, ray candidates, overlap with each shape in both facet-test modes,
// planes, stabbing, tree vs tree) for several hierarchy methods; builds and mesh loading running
// concurrently must give the single-threaded trees and meshes. Its own executable, so that CI can
// run it under ThreadSanitizer (BOXTREE_TSAN) without building the rest of the suite.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <thread>
#include <vector>

#include "boxtree/any_tree.h"
#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/io.h"
#include "boxtree/method.h"
#include "support/checks.h"
#include "support/files.h"
#include "support/meshes.h"
#include "support/random.h"

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

constexpr int kThreads = 8;

// Runs job(thread) on kThreads threads released together (so that they overlap as much as possible).
template <class Job>
void run_concurrently(Job job) {
  std::atomic<int> ready{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      ready.fetch_add(1);
      while (ready.load() < kThreads) std::this_thread::yield();
      job(t);
    });
  }
  for (std::thread& th : threads) th.join();
}

// Every answer to the queries of input `i`, as raw 64-bit words (doubles by their bits), so
// that equality means bit-identical results.
struct Inputs {
  std::vector<Ray> rays;
  std::vector<Aabb> boxes;
  std::vector<Obb> obbs;
  std::vector<Sphere> spheres;
  std::vector<Capsule> capsules;
  std::vector<Plane> planes;
  std::vector<RigidTransform> motions;
  std::size_t size() const { return rays.size(); }
};

Inputs make_inputs(const TriangleMesh& mesh, int count) {
  const Aabb box = mesh_bounds(mesh);
  const Real size = box.extent().norm();
  Random r(77);
  Inputs in;
  for (int i = 0; i < count; ++i) {
    const Vec3 c = random_point_near(r, box);
    const Real s = size * r.uniform(0.01, 0.15);
    in.rays.push_back(Ray{random_point_near(r, box, 0.5), r.unit_vector()});
    in.boxes.push_back(Aabb::from_points(c, c + r.uniform_vec3(-s, s)));
    in.obbs.push_back(Obb{c, random_rotation(r), r.uniform_vec3(0, s)});
    in.spheres.push_back(Sphere{c, s});
    in.capsules.push_back(Capsule{c, c + r.unit_vector() * s, 0.3 * s});
    in.planes.push_back(Plane{r.unit_vector(), r.unit_vector().dot(c)});
    in.motions.push_back(RigidTransform{random_rotation(r), r.uniform_vec3(-0.3 * size, 0.3 * size)});
  }
  return in;
}

void put(std::vector<std::uint64_t>& out, Real x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  out.push_back(bits);
}

template <class V>
std::vector<std::uint64_t> answers(const Tree<V>& tree, const Tree<V>& other, const Inputs& in, std::size_t i) {
  std::vector<std::uint64_t> out;
  const auto add_hit = [&](const std::optional<RayHit>& h) {
    out.push_back(h ? h->facet : ~0ull);
    if (h) {
      put(out, h->t);
      put(out, h->u);
      put(out, h->v);
    }
  };
  add_hit(ray_closest_hit(tree, in.rays[i]));
  add_hit(ray_any_hit(tree, in.rays[i]));
  for (const RayHit& h : ray_all_hits(tree, in.rays[i])) add_hit(h);
  ray_candidates(tree, in.rays[i], [&](FacetId f, Real t_max) {
    out.push_back(f);
    return t_max;
  });
  const auto add_facets = [&](const std::vector<FacetId>& facets) {
    out.push_back(facets.size());
    out.insert(out.end(), facets.begin(), facets.end());
  };
  for (FacetTest test : {FacetTest::exact_triangle, FacetTest::leaf_volume}) {
    add_facets(query_overlap(tree, in.boxes[i], nullptr, test));
    add_facets(query_overlap(tree, in.obbs[i], nullptr, test));
    add_facets(query_overlap(tree, in.spheres[i], nullptr, test));
    add_facets(query_overlap(tree, in.capsules[i], nullptr, test));
  }
  add_facets(query_plane(tree, in.planes[i]));
  out.push_back(stabbing_count(tree, in.spheres[i].center));
  if (i % 4 != 0) return out;  // tree vs tree (the costliest) for every fourth input
  QueryStats stats;
  for (const FacetPair& p : collide(tree, other, in.motions[i], &stats)) {
    out.push_back(p.a);
    out.push_back(p.b);
  }
  out.push_back(stats.nodes_visited);
  out.push_back(stats.volume_tests);
  out.push_back(stats.leaf_tests);
  return out;
}

TEST(Threads, EightThreadsOnOneTreeGiveTheSingleThreadedAnswers) {
  const TriangleMesh mesh = make_bumpy_sphere(20, 10, 0.25, 8);
  const TriangleMesh other_mesh = make_bumpy_sphere(8, 4, 0.3, 9);
  const Inputs in = make_inputs(mesh, scaled(40));
  for (const char* method : {"aabb", "obb-all", "pie-min+aabb@3"}) {
    SCOPED_TRACE(method);
    with_method(parse_method(method), [&](auto tag) {
      using V = typename decltype(tag)::type;
      const Tree<V> tree = build_for_test<V>(mesh);
      const Tree<V> other = build_for_test<V>(other_mesh);
      std::vector<std::vector<std::uint64_t>> expected(in.size());
      for (std::size_t i = 0; i < in.size(); ++i) expected[i] = answers(tree, other, in, i);
      // The reference itself is right: a sample against brute force.
      for (std::size_t i = 0; i < in.size(); i += 8) {
        EXPECT_EQ(violations(query_overlap(tree, in.spheres[i]), brute_overlap(mesh, in.spheres[i])), "");
        EXPECT_EQ(violations(collide(tree, other, in.motions[i]), brute_collide(mesh, other_mesh, in.motions[i])), "");
      }
      std::vector<std::vector<std::vector<std::uint64_t>>> got(kThreads,
                                                               std::vector<std::vector<std::uint64_t>>(in.size()));
      run_concurrently([&](int t) {
        // Each thread walks the inputs from a different start, so that different queries overlap.
        for (std::size_t k = 0; k < in.size(); ++k) {
          const std::size_t i = (k + std::size_t(t) * in.size() / kThreads) % in.size();
          got[std::size_t(t)][i] = answers(tree, other, in, i);
        }
      });
      for (int t = 0; t < kThreads; ++t) {
        std::size_t differing = 0;
        for (std::size_t i = 0; i < in.size(); ++i) differing += got[std::size_t(t)][i] != expected[i];
        EXPECT_EQ(differing, 0u) << "thread " << t;
      }
    });
  }
}

// The engines' handle: copies of one AnyTree share the tree; each thread holds its own copy.
TEST(Threads, AnyTreeCopiesShareOneTreeSafely) {
  const auto mesh = std::make_shared<const TriangleMesh>(make_terrain(24, 24, 3, 40, 4));
  const AnyTree shared = AnyTree::build(mesh, parse_method("obb-min"));
  const Inputs in = make_inputs(*mesh, scaled(100));
  std::vector<std::vector<FacetId>> expected(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    shared.query_overlap(in.capsules[i], [&](FacetId f) {
      expected[i].push_back(f);
      return true;
    });
  }
  std::vector<std::vector<std::vector<FacetId>>> got(kThreads, std::vector<std::vector<FacetId>>(in.size()));
  run_concurrently([&](int t) {
    const AnyTree mine = shared;  // copies and destroys the shared handle concurrently too
    for (std::size_t i = 0; i < in.size(); ++i) {
      mine.query_overlap(in.capsules[i], [&](FacetId f) {
        got[std::size_t(t)][i].push_back(f);
        return true;
      });
    }
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(got[std::size_t(t)], expected) << "thread " << t;
}

// Builds share no hidden state: 8 concurrent builds of one shared mesh give the
// single-threaded tree, node for node.
TEST(Threads, ConcurrentBuildsGiveTheSameTree) {
  const auto mesh = std::make_shared<const TriangleMesh>(make_bumpy_sphere(16, 8, 0.2, 5));
  for (const char* method : {"aabb", "obb-min", "pie-max-general"}) {
    SCOPED_TRACE(method);
    with_method(parse_method(method), [&](auto tag) {
      using V = typename decltype(tag)::type;
      const Tree<V> expected = build_for_test<V>(*mesh);
      std::vector<Tree<V>> trees(kThreads);
      run_concurrently([&](int t) { trees[std::size_t(t)] = build_tree<V>(mesh, test_settings<V>()); });
      for (const Tree<V>& tree : trees) {
        ASSERT_EQ(tree.node_count(), expected.node_count());
        std::size_t differing = 0;
        for (NodeIndex n = 0; n < tree.node_count(); ++n) {
          differing +=
              tree.is_leaf(n) != expected.is_leaf(n) ||
              (tree.is_leaf(n) ? tree.facet(n) != expected.facet(n) : tree.first_child(n) != expected.first_child(n)) ||
              surface_area(tree.volume(n)) != surface_area(expected.volume(n)) ||
              center(tree.volume(n)) != center(expected.volume(n));
        }
        EXPECT_EQ(differing, 0u);
      }
    });
  }
}

// Loading from many threads at once (OBJ through tinyobjloader, STL/OFF through Assimp, whose
// logger is process-global) gives the single-threaded meshes.
TEST(Threads, ConcurrentLoadsGiveTheSameMeshes) {
  const TriangleMesh mesh = make_bumpy_sphere(12, 6, 0.2, 2);
  const std::string obj = (scratch_dir("threads") / "mesh.obj").string();
  save_obj(mesh, obj);
  std::string off = "OFF\n" + std::to_string(mesh.vertices.size()) + " " + std::to_string(mesh.facet_count()) + " 0\n";
  for (const Vec3& v : mesh.vertices)
    off += std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + "\n";
  for (const Triangle& t : mesh.triangles)
    off += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  const std::string off_path = write_bytes(scratch_dir("threads") / "mesh.off", off);
  const std::string bad_path =
      write_bytes(scratch_dir("threads") / "bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  const TriangleMesh expected_obj = load_mesh(obj);
  const TriangleMesh expected_off = load_mesh(off_path);
  std::vector<int> mismatches(kThreads, 0), errors(kThreads, 0);
  run_concurrently([&](int t) {
    for (int k = 0; k < scaled(10); ++k) {
      const TriangleMesh a = load_mesh(obj);
      const TriangleMesh b = load_mesh(off_path);
      mismatches[std::size_t(t)] += a.vertices != expected_obj.vertices || a.triangles != expected_obj.triangles;
      mismatches[std::size_t(t)] += b.vertices != expected_off.vertices || b.triangles != expected_off.triangles;
      try {
        load_mesh(bad_path);
      } catch (const Error&) {
        ++errors[std::size_t(t)];
      }
    }
  });
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_EQ(mismatches[std::size_t(t)], 0) << "thread " << t;
    EXPECT_EQ(errors[std::size_t(t)], scaled(10)) << "thread " << t << ": a bad file loaded";
  }
}

}  // namespace
}  // namespace boxtree
