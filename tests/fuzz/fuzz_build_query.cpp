// SPDX-License-Identifier: MIT
// Fuzz target: arbitrary floats as a mesh, built with every hierarchy method, queried against
// brute force. Layout of the input: byte 0 picks the method, byte 1 the topology (bit 0: a strip,
// facets (i, i+1, i+2), sharing edges; else separate triangles (3i, 3i+1, 3i+2)); then the
// float32 coordinates of up to 64 vertices; the last 16 floats (if any) are the query: a ray
// origin and direction, a sphere radius, a box, and a rotation quaternion with a translation
// for tree vs tree. A mesh with a NaN or infinite coordinate must be refused with
// boxtree::Error; any other mesh must give a valid tree. Its answers must equal brute force once
// the coordinates are snapped to a grid of 2^-20 of the largest one: the exact triangle tests
// resolve features down to ~1e-15 of the coordinates only (tests/reliability/README.md, "Known
// limits"), and raw floats mix 1e38 with subnormals.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/method.h"
#include "boxtree/stats.h"
#include "fuzz/fuzz_common.h"
#include "support/brute_force.h"

namespace {

using namespace boxtree;

// The oracle's check (brute_force.h): must <= reported <= may, else abort saying what broke it.
#define FUZZ_CHECK_ORACLE(got, expected, what)                                      \
  do {                                                                              \
    const std::string broken = test::violations(got, expected);                     \
    FUZZ_CHECK(broken.empty(), "%s against brute force: %s", what, broken.c_str()); \
  } while (0)

const char* const kMethods[] = {"aabb",    "obb-all",         "obb-max",         "obb-min",        "pie-max",
                                "pie-min", "pie-max-general", "pie-min-general", "pie-min+aabb@2", "obb-min+aabb@1"};

template <class V>
void check_tree(const TriangleMesh& mesh, const BuildSettings& settings, const double* q, bool have_query) {
  const Tree<V> tree = build_tree<V>(mesh, settings);
  const std::string problem = validate_tree(tree, 1e-9);
  FUZZ_CHECK(problem.empty(), "invalid tree: %s", problem.c_str());
  FUZZ_CHECK(tree.node_count() == 2 * mesh.facet_count() - 1, "node count");
  if (!have_query) return;
  Ray ray{Vec3(q[0], q[1], q[2]), Vec3(q[3], q[4], q[5])};
  const auto hit = ray_closest_hit(tree, ray);
  const auto expected = test::brute_ray_closest_hit(mesh, ray);
  FUZZ_CHECK(hit.has_value() == expected.has_value(), "ray hit %d vs brute force %d", int(hit.has_value()),
             int(expected.has_value()));
  if (hit) FUZZ_CHECK(hit->facet == expected->facet && hit->t == expected->t, "ray closest hit differs");
  FUZZ_CHECK(ray_all_hits(tree, ray).size() == test::brute_ray_all_hits(mesh, ray).size(), "ray all hits differ");
  const Sphere sphere{ray.origin, std::abs(double(q[6]))};
  FUZZ_CHECK_ORACLE(query_overlap(tree, sphere), test::brute_overlap(mesh, sphere), "sphere overlap");
  const Aabb box = Aabb::from_points(ray.origin, Vec3(q[7], q[8], q[9]));
  FUZZ_CHECK_ORACLE(query_overlap(tree, box), test::brute_overlap(mesh, box), "box overlap");
  const Capsule capsule{ray.origin, Vec3(q[7], q[8], q[9]), std::abs(double(q[6]))};
  FUZZ_CHECK_ORACLE(query_overlap(tree, capsule), test::brute_overlap(mesh, capsule), "capsule overlap");
  const Plane plane{ray.direction, double(q[6])};
  FUZZ_CHECK_ORACLE(query_plane(tree, plane), test::brute_plane(mesh, plane), "plane query");
  Eigen::Quaterniond rotation(q[10], q[11], q[12], q[13]);
  if (std::isfinite(rotation.norm()) && rotation.norm() > 1e-3) {
    // The unit quaternion's components snapped to multiples of 2^-20 too, so that the rotation has
    // no entries like 1e-69 that would mix scales again.
    rotation.normalize();
    rotation.coeffs() =
        rotation.coeffs().unaryExpr([](double c) { return std::nearbyint(std::ldexp(c, 20)) / 1048576.0; });
    if (rotation.norm() == 0) rotation = Eigen::Quaterniond::Identity();
    const RigidTransform a_from_b{rotation.normalized().toRotationMatrix(), Vec3(q[14], q[15], q[9])};
    if (a_from_b.translation.allFinite()) {
      const Obb obb{ray.origin, a_from_b.rotation, Vec3(q[7], q[8], q[9]).cwiseAbs()};
      FUZZ_CHECK_ORACLE(query_overlap(tree, obb), test::brute_overlap(mesh, obb), "obb overlap");
      FUZZ_CHECK_ORACLE(collide(tree, tree, a_from_b), test::brute_collide(mesh, mesh, a_from_b), "collide");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2 + 9 * sizeof(float)) return 0;
  const Method method = parse_method(kMethods[data[0] % 10]);
  const bool strip = data[1] & 1;
  std::vector<float> floats((size - 2) / sizeof(float));
  std::memcpy(floats.data(), data + 2, floats.size() * sizeof(float));
  const bool have_query = floats.size() >= 9 + 16;
  const std::size_t coordinate_count = floats.size() - (have_query ? 16 : 0);
  TriangleMesh mesh;
  for (std::size_t i = 0; i + 3 <= coordinate_count && mesh.vertices.size() < 64; i += 3)
    mesh.vertices.emplace_back(floats[i], floats[i + 1], floats[i + 2]);
  const VertexId n = VertexId(mesh.vertices.size());
  if (strip) {
    for (VertexId i = 0; i + 2 < n; ++i) mesh.triangles.push_back({i, i + 1, i + 2});
  } else {
    for (VertexId i = 0; i + 2 < n; i += 3) mesh.triangles.push_back({i, i + 1, i + 2});
  }
  bool finite = true;  // over the vertices facets use (an unused NaN vertex is legal)
  for (const Triangle& t : mesh.triangles)
    for (VertexId v : t) finite = finite && mesh.vertices[v].allFinite();
  std::vector<double> query(16, 0.0);
  if (have_query) std::copy(floats.end() - 16, floats.end(), query.begin());
  // The raw mesh: a valid tree, or refused if (and only if) a coordinate is not finite.
  try {
    with_method(method, [&](auto tag) {
      check_tree<typename decltype(tag)::type>(mesh, settings_for(method), query.data(), false);
    });
    FUZZ_CHECK(finite, "a mesh with a non-finite coordinate was accepted");
  } catch (const Error& e) {
    FUZZ_CHECK(!finite, "a finite mesh was refused: %s", e.what());
    return 0;
  }
  if (!have_query) return 0;
  // Non-finite query values are left to tests/test_query.cpp (QueryOverlap.BadShapesReportNothing):
  // below, the answers must equal brute force on snapped coordinates.
  for (int i = 0; i < 16; ++i)
    if (!std::isfinite(query[i])) return 0;
  // Snapped to the grid (the quaternion, q[10..13], is normalized and left as it is).
  double largest = 0;
  for (Vec3& v : mesh.vertices) {
    if (!v.allFinite()) v = Vec3::Zero();  // unused ones only (see above)
    largest = std::max(largest, v.cwiseAbs().maxCoeff());
  }
  for (int i = 0; i < 16; ++i)
    if (std::isfinite(query[i]) && (i < 10 || i > 13)) largest = std::max(largest, std::abs(query[i]));
  if (!(largest > 0)) return 0;
  const double unit = std::ldexp(1.0, std::ilogb(largest) - 20);
  const auto snap = [&](double x) { return std::isfinite(x) ? std::nearbyint(x / unit) * unit : x; };
  for (Vec3& v : mesh.vertices) v = v.unaryExpr(snap);
  for (int i = 0; i < 16; ++i)
    if (i < 10 || i > 13) query[i] = snap(query[i]);
  with_method(method, [&](auto tag) {
    check_tree<typename decltype(tag)::type>(mesh, settings_for(method), query.data(), true);
  });
  return 0;
}
