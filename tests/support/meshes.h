// SPDX-License-Identifier: MIT
#pragma once
// Test meshes: procedural ones (always there) and the real ones in ../shared/meshes. Tests that
// need the real ones skip with a message when they are absent, except in CI (environment
// CI=true), where the meshes are part of the suite and their absence fails the test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "boxtree/generate.h"
#include "boxtree/io.h"

namespace boxtree::test {

// The folder of the real meshes: the build's (BOXTREE_SHARED_MESHES), or the environment's
// BOXTREE_SHARED_MESHES if set (tests/CMakeLists.txt points it at a missing folder to check the
// CI rule below).
inline std::string shared_mesh_dir() {
  const char* dir = std::getenv("BOXTREE_SHARED_MESHES");
  return dir != nullptr && *dir != '\0' ? std::string(dir) : std::string(BOXTREE_SHARED_MESHES);
}

inline bool shared_meshes_available() { return std::filesystem::exists(shared_mesh_dir() + "/stanford_bunny.obj"); }

// Every shared mesh, by file name.
inline std::vector<std::string> shared_mesh_names() {
  return {"stanford_bunny.obj",
          "stanford_bunny_res2.obj",
          "stanford_bunny_res3.obj",
          "stanford_bunny_res4.obj",
          "bunny_libigl_closed.obj",
          "ode_bunny.obj",
          "stanford_armadillo_86k.obj",
          "stanford_dragon_res3.obj",
          "utah_teapot.obj",
          "suzanne.obj",
          "spot.obj",
          "env.obj",
          "rob.obj",
          "bullet_diff_ring.obj",
          "bullet_kiva_pod_lowres.obj",
          "bullet_leoTest1.obj"};
}

inline TriangleMesh load_shared_mesh(const std::string& name) { return load_mesh(shared_mesh_dir() + "/" + name); }

// True in CI (CI=true, as GitHub Actions and most CI services set it).
inline bool running_in_ci() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

// Why a test cannot use `path`, in the words both macros below print.
inline std::string missing_shared_message(const std::string& path) {
  return "real meshes not found: " + path + (running_in_ci() ? " (CI=true: they are required)" : ": skipped");
}

// Skips the test if `path` (a shared mesh or the folder) is missing; fails it in CI.
#define BOXTREE_REQUIRE_SHARED_PATH(path)                                                                             \
  do {                                                                                                                \
    const std::string boxtree_required_path = (path);                                                                 \
    if (!std::filesystem::exists(boxtree_required_path)) {                                                            \
      if (::boxtree::test::running_in_ci()) FAIL() << ::boxtree::test::missing_shared_message(boxtree_required_path); \
      GTEST_SKIP() << ::boxtree::test::missing_shared_message(boxtree_required_path);                                 \
    }                                                                                                                 \
  } while (false)

#define BOXTREE_REQUIRE_SHARED_MESHES() \
  BOXTREE_REQUIRE_SHARED_PATH(::boxtree::test::shared_mesh_dir() + "/stanford_bunny.obj")

// For tests that add the real meshes to procedural ones when they are there: whether they are,
// with a test failure in CI when they are not.
inline bool use_shared_meshes_if_present() {
  if (shared_meshes_available()) return true;
  if (running_in_ci()) ADD_FAILURE() << missing_shared_message(shared_mesh_dir() + "/stanford_bunny.obj");
  return false;
}

// Multiplies test sizes (env BOXTREE_TEST_SCALE, default 1) for longer local runs.
inline double test_scale() {
  const char* s = std::getenv("BOXTREE_TEST_SCALE");
  return s ? std::max(0.01, std::atof(s)) : 1.0;
}

// A closed cone over a regular polygon: every mantle facet shares the apex (paper, Section 5),
// and the base is a fan around its centre.
inline TriangleMesh make_cone(int sides) {
  TriangleMesh mesh;
  const double pi = std::acos(-1.0);
  mesh.vertices.push_back(Vec3(0, 0, 1));
  for (int i = 0; i < sides; ++i)
    mesh.vertices.push_back(Vec3(std::cos(2 * pi * i / sides), std::sin(2 * pi * i / sides), 0));
  mesh.vertices.push_back(Vec3(0, 0, 0));
  const VertexId base = VertexId(sides + 1);
  for (int i = 0; i < sides; ++i) {
    mesh.triangles.push_back({0, VertexId(1 + i), VertexId(1 + (i + 1) % sides)});
    mesh.triangles.push_back({base, VertexId(1 + (i + 1) % sides), VertexId(1 + i)});
  }
  return mesh;
}

// A terrain closed into a solid: the height field on top, a flat bottom at z = -1 and four
// walls, all sharing the rim vertices (a closed mesh with sharp creases and flat regions).
inline TriangleMesh make_closed_terrain(int cells, std::uint64_t seed) {
  TriangleMesh mesh = make_terrain(cells, cells, seed, 10, 2);
  const int n = cells + 1;
  auto top = [&](int i, int j) { return VertexId(j * n + i); };
  // Rim of the top grid, counter-clockwise seen from above.
  std::vector<VertexId> rim;
  for (int i = 0; i < cells; ++i) rim.push_back(top(i, 0));
  for (int j = 0; j < cells; ++j) rim.push_back(top(cells, j));
  for (int i = cells; i > 0; --i) rim.push_back(top(i, cells));
  for (int j = cells; j > 0; --j) rim.push_back(top(0, j));
  const VertexId bottom_first = VertexId(mesh.vertices.size());
  for (VertexId v : rim) mesh.vertices.push_back(Vec3(mesh.vertices[v].x(), mesh.vertices[v].y(), -1));
  const VertexId centre = VertexId(mesh.vertices.size());
  mesh.vertices.push_back(Vec3(5, 5, -1));
  const std::size_t m = rim.size();
  for (std::size_t k = 0; k < m; ++k) {
    const VertexId a = rim[k], b = rim[(k + 1) % m];
    const VertexId a_low = VertexId(bottom_first + k), b_low = VertexId(bottom_first + (k + 1) % m);
    mesh.triangles.push_back({a, a_low, b_low});
    mesh.triangles.push_back({a, b_low, b});
    mesh.triangles.push_back({centre, b_low, a_low});
  }
  return mesh;
}

// Procedural meshes of every flavour the builder must handle, by name.
inline std::vector<std::pair<std::string, TriangleMesh>> procedural_meshes() {
  std::vector<std::pair<std::string, TriangleMesh>> meshes;
  meshes.emplace_back("sphere_16x8", make_uv_sphere(16, 8));
  meshes.emplace_back("bumpy_sphere_40x20", make_bumpy_sphere(40, 20, 0.3, 7));
  meshes.emplace_back("terrain_24x24", make_terrain(24, 24, 3));
  meshes.emplace_back("soup_1500", make_triangle_soup(1500, 11, 1.0, 0.08));
  meshes.emplace_back("cone_300", make_cone(300));
  {
    TriangleMesh one;
    one.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    one.triangles = {{0, 1, 2}};
    meshes.emplace_back("single_facet", one);
  }
  {
    // Degenerate facets only: a point, and segments.
    TriangleMesh degenerate;
    degenerate.vertices = {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(0.5, 0.5, 0.5)};
    degenerate.triangles = {{0, 0, 0}, {0, 1, 2}, {1, 2, 3}, {3, 3, 1}};
    meshes.emplace_back("all_degenerate", degenerate);
  }
  {
    // Duplicate facets and a far offset.
    TriangleMesh dup = make_uv_sphere(8, 4, 1, Vec3(1e6, -1e6, 1e6));
    const std::size_t n = dup.triangles.size();
    for (std::size_t i = 0; i < n; ++i) dup.triangles.push_back(dup.triangles[i]);
    meshes.emplace_back("duplicates_far", dup);
  }
  return meshes;
}

}  // namespace boxtree::test
