// SPDX-License-Identifier: MIT
// Determinism (issue 9): the same mesh, method and settings give bit-identical trees (every
// node's links and every corner of its volume, compared by their bits) and bit-identical query
// answers, in one process and across processes (a child process of this test binary computes the
// same fingerprints: heap addresses, ASLR and allocation order differ there, so a builder that
// orders anything by pointer or by an unordered container's iteration would show). The physics
// side: tests/bullet/test_reliability.cpp and tests/ode/test_reliability.cpp step the same scene
// twice in one process; tests/demo compares whole demo runs across processes.
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/method.h"
#include "boxtree/query.h"
#include "support/checks.h"
#include "support/files.h"
#include "support/meshes.h"

extern char** environ;

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

// FNV-1a over raw bytes.
struct Fingerprint {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  void add_bytes(const void* data, std::size_t size) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  }
  void add(std::uint64_t x) { add_bytes(&x, sizeof x); }
  void add(const Vec3& v) { add_bytes(v.data(), 3 * sizeof(Real)); }
};

// Every node: leaf flag and facet or first child, and every corner of its volume.
template <class V>
std::uint64_t tree_fingerprint(const Tree<V>& tree) {
  Fingerprint f;
  f.add(tree.node_count());
  f.add(std::uint64_t(tree.height()));
  for (NodeIndex n = 0; n < tree.node_count(); ++n) {
    f.add(tree.is_leaf(n) ? (std::uint64_t(1) << 40) | tree.facet(n) : tree.first_child(n));
    const ConvexPolytope polytope = polytope_of(tree.volume(n));
    for (int k = 0; k < polytope.vertex_count; ++k) f.add(polytope.vertices[std::size_t(k)]);
  }
  return f.hash;
}

// The closest hits and the work counters of a fixed set of rays.
template <class V>
std::uint64_t query_fingerprint(const Tree<V>& tree) {
  Fingerprint f;
  Random r(3);
  const Aabb box = mesh_bounds(tree.mesh());
  for (int i = 0; i < 200; ++i) {
    QueryStats stats;
    const auto hit = ray_closest_hit(tree, Ray{random_point_near(r, box, 0.5), r.unit_vector()}, &stats);
    f.add(hit ? hit->facet : ~0ull);
    if (hit) f.add(Vec3(hit->t, hit->u, hit->v));
    f.add(stats.nodes_visited);
    f.add(stats.volume_tests);
  }
  return f.hash;
}

const char* const kMethods[] = {"aabb",    "obb-all",         "obb-max",         "obb-min",       "pie-max",
                                "pie-min", "pie-max-general", "pie-min-general", "pie-min+aabb@3"};

std::vector<std::pair<std::string, TriangleMesh>> determinism_meshes() {
  std::vector<std::pair<std::string, TriangleMesh>> meshes;
  meshes.emplace_back("bumpy_sphere", make_bumpy_sphere(24, 12, 0.3, 4));
  meshes.emplace_back("terrain", make_terrain(16, 16, 6));
  meshes.emplace_back("soup", make_triangle_soup(600, 5, 1, 0.08));
  meshes.emplace_back("cone", make_cone(100));  // ties everywhere: every mantle facet the same shape
  return meshes;
}

// "mesh method" -> "tree-hash query-hash", for every mesh and method.
std::map<std::string, std::string> all_fingerprints() {
  std::map<std::string, std::string> out;
  for (const auto& named_mesh : determinism_meshes()) {
    // Named references, not a structured binding: lambdas may capture those only from C++20.
    const std::string& name = named_mesh.first;
    const TriangleMesh& mesh = named_mesh.second;
    for (const char* method : kMethods) {
      with_method(parse_method(method), [&](auto tag) {
        using V = typename decltype(tag)::type;
        const Tree<V> tree = build_for_test<V>(mesh);
        out[name + " " + method] =
            std::to_string(tree_fingerprint(tree)) + " " + std::to_string(query_fingerprint(tree));
      });
    }
  }
  return out;
}

TEST(Determinism, RebuildsAreBitIdentical) {
  for (const auto& named_mesh : determinism_meshes()) {
    const std::string& name = named_mesh.first;
    const TriangleMesh& mesh = named_mesh.second;
    for (const char* method : kMethods) {
      with_method(parse_method(method), [&](auto tag) {
        using V = typename decltype(tag)::type;
        const Tree<V> a = build_for_test<V>(mesh);
        // The second build from a copy of the mesh at another address.
        const Tree<V> b = build_tree<V>(std::make_shared<const TriangleMesh>(mesh), test_settings<V>());
        EXPECT_EQ(tree_fingerprint(a), tree_fingerprint(b)) << name << " " << method;
        EXPECT_EQ(query_fingerprint(a), query_fingerprint(b)) << name << " " << method;
      });
    }
  }
}

// A mesh written and read back gives the same tree as the mesh itself (OBJ is exact both ways).
TEST(Determinism, SavedAndLoadedMeshGivesTheSameTree) {
  const TriangleMesh mesh = make_bumpy_sphere(30, 15, 0.3, 11);
  const std::string path = (scratch_dir("determinism") / "mesh.obj").string();
  save_obj(mesh, path);
  const TriangleMesh loaded = load_mesh(path);
  EXPECT_EQ(tree_fingerprint(build_tree<Aabb>(mesh)), tree_fingerprint(build_tree<Aabb>(loaded)));
  EXPECT_EQ(tree_fingerprint(build_tree<PieMin>(mesh)), tree_fingerprint(build_tree<PieMin>(loaded)));
}

// The fingerprints, written by a child process of this binary (see SameAcrossProcesses).
TEST(DeterminismChild, WriteFingerprints) {
  const char* out_path = std::getenv("BOXTREE_FINGERPRINT_FILE");
  if (!out_path) GTEST_SKIP() << "only run as the child process of Determinism.SameAcrossProcesses";
  std::ofstream out(out_path);
  for (const auto& [key, value] : all_fingerprints()) out << key << "=" << value << "\n";
  ASSERT_TRUE(out.good());
}

TEST(Determinism, SameAcrossProcesses) {
  const std::string file = (scratch_dir("determinism") / "child_fingerprints.txt").string();
  std::remove(file.c_str());
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
  env_strings.push_back("BOXTREE_FINGERPRINT_FILE=" + file);
  std::vector<char*> envp;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string self = "/proc/self/exe", filter = "--gtest_filter=DeterminismChild.WriteFingerprints";
  char* argv[] = {self.data(), filter.data(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, argv, envp.data()), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child status " << status;

  std::map<std::string, std::string> child;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    const std::size_t eq = line.find('=');
    if (eq != std::string::npos) child[line.substr(0, eq)] = line.substr(eq + 1);
  }
  const std::map<std::string, std::string> mine = all_fingerprints();
  EXPECT_EQ(child.size(), mine.size());
  for (const auto& [key, value] : mine) EXPECT_EQ(child[key], value) << key;
}

}  // namespace
}  // namespace boxtree
