// SPDX-License-Identifier: MIT
// The demo's scene library (demos/src/scene.h): the default scene is pinned by a fingerprint of
// make_scene's whole output (the demo's images and bench/sim/drop_bench's committed rows depend on
// it), and the scene options give what they say.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "hull.h"
#include "scene.h"

namespace {

// FNV-1a over the bytes of every number make_scene produced: terrain vertices and triangles, and
// every field of every body (its mesh included).
class Fingerprint {
 public:
  void add_bytes(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash_ = (hash_ ^ bytes[i]) * 0x100000001B3ULL;
  }
  void add(double value) { add_bytes(&value, sizeof value); }
  void add(std::uint64_t value) { add_bytes(&value, sizeof value); }
  void add(const demo::Vec3& v) { add(v.x()), add(v.y()), add(v.z()); }
  void add(const demo::TriangleMesh& mesh) {
    add(std::uint64_t(mesh.vertices.size()));
    for (const demo::Vec3& v : mesh.vertices) add(v);
    add(std::uint64_t(mesh.triangles.size()));
    for (const auto& t : mesh.triangles)
      for (auto v : t) add(std::uint64_t(v));
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xCBF29CE484222325ULL;
};

std::uint64_t fingerprint(const demo::Scene& scene) {
  Fingerprint f;
  f.add(*scene.terrain);
  f.add(std::uint64_t(scene.bodies.size()));
  for (const demo::BodySpec& b : scene.bodies) {
    f.add(std::uint64_t(b.shape));
    f.add(b.radius);
    f.add(b.half_extents);
    f.add(b.half_length);
    if (b.mesh) f.add(*b.mesh);
    f.add(b.mass);
    f.add(b.position);
    f.add(b.orientation.coeffs().x()), f.add(b.orientation.coeffs().y());
    f.add(b.orientation.coeffs().z()), f.add(b.orientation.coeffs().w());
    f.add(b.colour);
  }
  return f.value();
}

std::string hex(std::uint64_t value) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(value));
  return text;
}

TEST(Scene, DefaultScenesUnchanged) {
  // The demo's defaults (128 cells, 300 bodies) and drop_bench's 256^2 / 500 bodies, seed 1.
  // The same on every compiler: scene.cpp draws one random number per statement (in the order
  // gcc evaluated its former one-call draws, which these values were pinned with).
  demo::TerrainOptions demo_terrain;
  EXPECT_EQ(hex(fingerprint(demo::make_scene(demo_terrain, 300, 1))), "0xa13e40a2606556c6");
  demo::TerrainOptions bench_terrain;
  bench_terrain.cells = 256;
  EXPECT_EQ(hex(fingerprint(demo::make_scene(bench_terrain, 500, 1))), "0x6e8655f35a65ea7a");
}

demo::SceneOptions small_scene(demo::BodyMix mix, int bodies = 60) {
  demo::SceneOptions options;
  options.terrain.cells = 16;
  options.bodies = bodies;
  options.mix = mix;
  return options;
}

// Closed (every edge used once in each direction) and convex (every vertex on or behind every
// facet's plane), facets outward.
void expect_closed_convex(const demo::TriangleMesh& mesh) {
  std::set<std::pair<boxtree::VertexId, boxtree::VertexId>> edges;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(edges.insert({t[k], t[(k + 1) % 3]}).second);
  for (const auto& [a, b] : edges) EXPECT_TRUE(edges.count({b, a})) << a << "-" << b;
  for (std::size_t f = 0; f < mesh.facet_count(); ++f) {
    const demo::Vec3 a = mesh.corner(boxtree::FacetId(f), 0), b = mesh.corner(boxtree::FacetId(f), 1),
                     c = mesh.corner(boxtree::FacetId(f), 2);
    const demo::Vec3 n = (b - a).cross(c - a);
    // The origin well inside (ODE's convexes need it inside): at least a tenth of the mesh's size.
    EXPECT_LT(n.dot(-a), -0.1 * n.norm() * mesh.vertices.front().norm()) << "facet " << f << " faces the origin";
    for (const demo::Vec3& v : mesh.vertices) EXPECT_LE(n.dot(v - a), 1e-12 * n.norm()) << "facet " << f;
  }
}

TEST(Scene, SingleKindMixesHoldOneShape) {
  const std::pair<demo::BodyMix, demo::Shape> kinds[] = {
      {demo::BodyMix::sphere, demo::Shape::sphere},   {demo::BodyMix::box, demo::Shape::box},
      {demo::BodyMix::capsule, demo::Shape::capsule}, {demo::BodyMix::cylinder, demo::Shape::cylinder},
      {demo::BodyMix::hull8, demo::Shape::convex},    {demo::BodyMix::hull64, demo::Shape::convex},
      {demo::BodyMix::mesh, demo::Shape::mesh}};
  for (const auto& [mix, shape] : kinds) {
    const demo::Scene scene = demo::make_scene(small_scene(mix), 3);
    ASSERT_EQ(scene.bodies.size(), 60u) << demo::body_mix_name(mix);
    for (const demo::BodySpec& b : scene.bodies) EXPECT_EQ(b.shape, shape) << demo::body_mix_name(mix);
  }
}

TEST(Scene, HullsHaveTheirPointCount) {
  const std::pair<demo::BodyMix, std::size_t> hulls[] = {
      {demo::BodyMix::hull8, 8}, {demo::BodyMix::hull16, 16}, {demo::BodyMix::hull32, 32}, {demo::BodyMix::hull64, 64}};
  for (const auto& [mix, points] : hulls)
    for (const demo::BodySpec& b : demo::make_scene(small_scene(mix, 200), 5).bodies) {
      ASSERT_TRUE(b.mesh);
      EXPECT_EQ(b.mesh->vertices.size(), points);
      EXPECT_EQ(b.mesh->facet_count(), 2 * points - 4);  // a triangulated polyhedron (Euler)
      expect_closed_convex(*b.mesh);
    }
}

TEST(Scene, ConvexHullDropsInnerPoints) {
  std::vector<demo::Vec3> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.1, 0.1, 0.1}, {1, 1, 1}};
  const demo::TriangleMesh hull = demo::convex_hull(points);
  EXPECT_EQ(hull.vertices.size(), 5u);
  EXPECT_EQ(hull.facet_count(), 6u);
  EXPECT_THROW(demo::convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}), boxtree::Error);
}

TEST(Scene, MixedWithoutMeshesHasEveryOtherKind) {
  std::map<demo::Shape, int> count;
  for (const demo::BodySpec& b : demo::make_scene(small_scene(demo::BodyMix::mixed_without_meshes, 300), 1).bodies)
    ++count[b.shape];
  EXPECT_EQ(count.count(demo::Shape::mesh), 0u);
  for (demo::Shape shape :
       {demo::Shape::sphere, demo::Shape::box, demo::Shape::capsule, demo::Shape::cylinder, demo::Shape::convex})
    EXPECT_GT(count[shape], 20) << demo::shape_name(shape);
}

TEST(Scene, TerrainKinds) {
  for (demo::TerrainKind kind : {demo::TerrainKind::bowl, demo::TerrainKind::rough, demo::TerrainKind::flat}) {
    demo::SceneOptions options = small_scene(demo::BodyMix::sphere, 10);
    options.terrain.kind = kind;
    const demo::Scene scene = demo::make_scene(options, 2);
    EXPECT_EQ(scene.terrain->facet_count(), 2u * 16 * 16);
    EXPECT_DOUBLE_EQ(scene.bounds_max.x() - scene.bounds_min.x(), 40);
    const double height = scene.bounds_max.z() - scene.bounds_min.z();
    if (kind == demo::TerrainKind::flat) {
      EXPECT_EQ(height, 0);
    } else if (kind == demo::TerrainKind::rough) {
      EXPECT_GT(height, 0.5);  // the noise, 4 m at most
      EXPECT_LT(height, 4);
    } else {
      EXPECT_GT(height, 7);  // the rim: 7 m
    }
    for (const demo::BodySpec& b : scene.bodies) {
      EXPECT_TRUE(demo::over_terrain(scene, b.position));
      const auto depth = demo::depth_below_terrain(*scene.probe, b, {b.position, b.orientation});
      ASSERT_TRUE(depth);
      EXPECT_LT(*depth, -0.3) << "bodies start above the ground";
    }
    EXPECT_FALSE(demo::over_terrain(scene, {21, 0, 0}));
  }
}

TEST(Scene, TerrainWidthAndNoiseHeight) {
  demo::SceneOptions options = small_scene(demo::BodyMix::sphere, 10);
  options.terrain.kind = demo::TerrainKind::rough;
  options.terrain.width = 50;
  options.terrain.noise_height = 6;
  const demo::Scene scene = demo::make_scene(options, 4);
  EXPECT_DOUBLE_EQ(scene.bounds_min.x(), -25);
  EXPECT_DOUBLE_EQ(scene.bounds_max.y(), 25);
  const double height = scene.bounds_max.z() - scene.bounds_min.z();
  EXPECT_GT(height, 4);  // more than the default noise's 4 m at most
  EXPECT_LE(height, 6);
  // The same heights as boxtree::make_terrain's, moved to the origin.
  const demo::TriangleMesh plain = boxtree::make_terrain(16, 16, 4, 50, 6);
  ASSERT_EQ(plain.vertices.size(), scene.terrain->vertices.size());
  for (std::size_t v = 0; v < plain.vertices.size(); ++v)
    EXPECT_EQ(scene.terrain->vertices[v], plain.vertices[v] - demo::Vec3(25, 25, 0)) << v;
}

TEST(Scene, PrimitivesInTurnOnAGridLayout) {
  demo::SceneOptions options = small_scene(demo::BodyMix::primitives_in_turn, 16);
  options.terrain.kind = demo::TerrainKind::rough;
  options.layout.spacing = 8;
  options.layout.max_width = 24;
  options.layout.clearance = 1;
  options.layout.jitter = 0;
  options.layout.random_orientation = false;
  options.body_density = 1000;
  const demo::Scene scene = demo::make_scene(options, 7);
  ASSERT_EQ(scene.bodies.size(), 16u);
  const demo::Shape in_turn[] = {demo::Shape::sphere, demo::Shape::box, demo::Shape::capsule, demo::Shape::cylinder};
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    SCOPED_TRACE(i);
    const demo::BodySpec& b = scene.bodies[i];
    EXPECT_EQ(b.shape, in_turn[i % 4]);
    // One column each, 8 m apart, centred: x and y in -12, -4, 4, 12.
    EXPECT_DOUBLE_EQ(b.position.x(), -12 + 8.0 * double(i % 4));
    EXPECT_DOUBLE_EQ(b.position.y(), -12 + 8.0 * double(i / 4));
    const auto depth = demo::depth_below_terrain(*scene.probe, b, {b.position, b.orientation});
    ASSERT_TRUE(depth);
    EXPECT_LT(*depth, -0.3) << "bodies start above the ground";
    const double capsule_tilt = b.shape == demo::Shape::capsule ? std::acos(-1.0) / 2 : 0.0;
    EXPECT_NEAR(Eigen::AngleAxis<double>(b.orientation).angle(), capsule_tilt, 1e-12);
  }
  const demo::BodySpec &sphere = scene.bodies[0], &box = scene.bodies[1], &capsule = scene.bodies[2],
                       &cylinder = scene.bodies[3];
  EXPECT_EQ(sphere.radius, 0.5);
  EXPECT_EQ(box.half_extents, demo::Vec3(0.5, 0.4, 0.3));
  EXPECT_EQ(capsule.radius, 0.3);
  EXPECT_EQ(capsule.half_length, 0.5);
  EXPECT_EQ(cylinder.radius, 0.4);
  EXPECT_EQ(cylinder.half_length, 0.3);
  EXPECT_NEAR(box.mass, 1000 * 1.0 * 0.8 * 0.6, 1e-9);
  // The capsule lies along x.
  EXPECT_NEAR(std::abs((capsule.orientation * demo::Vec3::UnitZ()).x()), 1, 1e-12);
  // The same bodies on another seed; only the terrain under them (and so their heights) changes.
  const demo::Scene other = demo::make_scene(options, 8);
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    EXPECT_EQ(other.bodies[i].radius, scene.bodies[i].radius);
    EXPECT_EQ(other.bodies[i].half_extents, scene.bodies[i].half_extents);
    EXPECT_EQ(other.bodies[i].position.head<2>(), scene.bodies[i].position.head<2>());
  }
  demo::BodyMix parsed = demo::BodyMix::mixed;
  EXPECT_TRUE(demo::parse_body_mix("primitives-in-turn", &parsed));
  EXPECT_EQ(parsed, demo::BodyMix::primitives_in_turn);
}

}  // namespace
