// SPDX-License-Identifier: MIT
// Convex-vs-mesh temporal coherence (collider.h's ConvexPairCache): over long random sequences of
// calls, in which inputs repeat, change a little or change kind, mesh or request, every call with
// the cache gives the contacts of a call without it bit for bit, and the cache answers exactly
// the calls whose input equals the last one (a hull's from its third equal call on). A hull
// edited in place under the same address, a mesh swapped at the same pose and invalid input are
// collided again.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <vector>

#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/generate.h"
#include "support/random.h"

namespace boxtree {
namespace {

using test::Random;

bool same_bits(const std::vector<ContactPoint>& a, const std::vector<ContactPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const ContactPoint &x = a[i], &y = b[i];
    const Real xs[7] = {x.position.x(), x.position.y(), x.position.z(), x.normal.x(),
                        x.normal.y(),   x.normal.z(),   x.depth};
    const Real ys[7] = {y.position.x(), y.position.y(), y.position.z(), y.normal.x(),
                        y.normal.y(),   y.normal.z(),   y.depth};
    if (std::memcmp(xs, ys, sizeof xs) != 0 || x.facet != y.facet || x.other_facet != y.other_facet) return false;
  }
  return true;
}

const std::vector<std::vector<int>> kCubeFaces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                  {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

std::vector<Vec3> cube_corners(Real half) {
  std::vector<Vec3> corners = {Vec3(-1, -1, -1), Vec3(1, -1, -1), Vec3(1, 1, -1), Vec3(-1, 1, -1),
                               Vec3(-1, -1, 1),  Vec3(1, -1, 1),  Vec3(1, 1, 1),  Vec3(-1, 1, 1)};
  for (Vec3& p : corners) p *= half;
  return corners;
}

// One call's input: a shape kind, its placement and size, a request, a mesh.
struct Input {
  int kind = 0;  // sphere, box, capsule, cylinder, polyhedron, points
  int mesh = 0;
  Vec3 center = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
  Real size = 1;
  ContactRequest request;
};
constexpr int kKinds = 6;

TEST(ConvexPairCache, EveryCallGivesTheContactsOfAFreshCall) {
  const std::vector<std::shared_ptr<const CollisionMesh>> meshes = {
      CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(24, 24, 3, 12, 1.5)), parse_method("aabb")),
      CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(24, 24, 3, 12, 1.5)), parse_method("aabb")),
      CollisionMesh::build(std::make_shared<TriangleMesh>(make_bumpy_sphere(24, 12, 2, 5)), parse_method("obb-min"))};
  // The hulls stay put (their address is part of the input); each kind's pair has its own cache.
  const ConvexPolyhedron cube = make_convex_polyhedron(cube_corners(1), kCubeFaces);
  const std::vector<Vec3> corners = cube_corners(1);
  Random random(7);
  const auto random_input = [&](Input in) {
    in.kind = random.integer(0, kKinds - 1);
    in.mesh = random.integer(0, int(meshes.size()) - 1);
    const Aabb& bounds = meshes[std::size_t(in.mesh)]->bounds();
    in.center = bounds.center() + bounds.extent().cwiseProduct(random.uniform_vec3(-0.45, 0.45));
    in.rotation = random.rotation();
    in.size = random.uniform(0.3, 1.5);
    in.request.margin = random.chance(0.5) ? 0.05 : 0;
    in.request.two_sided = random.chance(0.3);
    in.request.max_contacts = std::size_t(random.integer(1, 8));
    in.request.merge_distance = random.chance(0.5) ? 0.01 : 0;
    in.request.early_stop = random.chance(0.1);
    return in;
  };
  const auto collide = [&](const Input& in, ContactResult& result, ConvexPairCache* cache) {
    const CollisionMesh& mesh = *meshes[std::size_t(in.mesh)];
    const Real s = in.size;
    const RigidTransform place{in.rotation, in.center};
    switch (in.kind) {
      case 0:
        return collide_convex(mesh, Sphere{in.center, s}, in.request, result, cache);
      case 1:
        return collide_convex(mesh, Obb{in.center, in.rotation, Vec3(s, 0.7 * s, 0.4 * s)}, in.request, result, cache);
      case 2:
        return collide_convex(mesh,
                              Capsule{in.center - in.rotation.col(0) * s, in.center + in.rotation.col(0) * s, s / 2},
                              in.request, result, cache);
      case 3:
        return collide_convex(mesh,
                              Cylinder{in.center - in.rotation.col(2) * s, in.center + in.rotation.col(2) * s, 0.6 * s},
                              in.request, result, cache);
      case 4:
        return collide_convex(mesh, PlacedPolyhedron{cube, place, 0.1 * s}, in.request, result, cache);
      default:
        return collide_convex(mesh, PlacedPoints{corners, place}, in.request, result, cache);
    }
  };

  std::vector<ConvexPairCache> caches(4);  // pairs of bodies, each with its own sequence
  std::vector<Input> last(caches.size());
  std::vector<int> equal_calls(caches.size(), 0);  // calls in a row with the same input so far
  std::vector<bool> called(caches.size(), false);
  for (std::size_t c = 0; c < caches.size(); ++c) last[c] = random_input(Input{});
  std::size_t reused = 0, contacts = 0, calls = 0;
  for (int step = 0; step < test::scaled(4000); ++step) {
    const std::size_t c = std::size_t(random.integer(0, int(caches.size()) - 1));
    Input in = last[c];
    const Real what = random.uniform();
    if (what < 0.45) {
      // the same input: a body at rest
    } else if (what < 0.65) {
      in.center.z() += random.uniform(-1e-9, 1e-9);  // a body that creeps
    } else if (what < 0.72) {
      in.request.margin += 1e-12;  // the request changes
    } else if (what < 0.77) {
      in.mesh = (in.mesh + 1) % 2;  // another mesh with the same facets, at the same pose
    } else {
      in = random_input(in);
    }
    SCOPED_TRACE(testing::Message() << "call " << step << " pair " << c << " kind " << in.kind);
    const bool same =
        called[c] && std::memcmp(&in.center, &last[c].center, sizeof in.center) == 0 &&
        std::memcmp(&in.rotation, &last[c].rotation, sizeof in.rotation) == 0 && in.size == last[c].size &&
        in.kind == last[c].kind && in.mesh == last[c].mesh && in.request.margin == last[c].request.margin &&
        in.request.two_sided == last[c].request.two_sided && in.request.max_contacts == last[c].request.max_contacts &&
        in.request.merge_distance == last[c].request.merge_distance &&
        in.request.early_stop == last[c].request.early_stop;
    equal_calls[c] = same ? equal_calls[c] + 1 : 0;
    ContactResult fresh, cached;
    collide(in, fresh, nullptr);
    collide(in, cached, &caches[c]);
    ASSERT_TRUE(same_bits(cached.contacts, fresh.contacts));
    // Answered only for the last input, and at the latest from its third call in a row (a
    // hull, whose arrays are copied on the third, from its fourth).
    const bool hull = in.kind >= 4;
    if (cached.counts.reused) {
      ASSERT_TRUE(same) << "equal calls " << equal_calls[c];
    }
    if (equal_calls[c] >= (hull ? 3 : 2)) {
      ASSERT_TRUE(cached.counts.reused) << "equal calls " << equal_calls[c];
    }
    ASSERT_FALSE(fresh.counts.reused);
    if (cached.counts.reused) {
      EXPECT_EQ(cached.counts.candidates, 0u);
      EXPECT_EQ(cached.counts.found, 0u);
      EXPECT_EQ(cached.counts.two_sided_fallback, fresh.counts.two_sided_fallback);
      ++reused;
    } else {
      EXPECT_EQ(cached.counts.candidates, fresh.counts.candidates);
      EXPECT_EQ(cached.counts.found, fresh.counts.found);
      EXPECT_EQ(cached.counts.merged, fresh.counts.merged);
      EXPECT_EQ(cached.counts.dropped, fresh.counts.dropped);
    }
    // Memory: the input's bytes and the last contacts.
    EXPECT_LE(caches[c].memory_bytes(), 8192u + 8 * sizeof(ContactPoint) * 2);
    contacts += fresh.contacts.size();
    ++calls;
    last[c] = in;
    called[c] = true;
  }
  EXPECT_GT(reused, std::size_t(test::scaled(4000) / 8));
  EXPECT_GT(contacts, std::size_t(test::scaled(4000)));  // the calls do make contacts
  std::printf("[ convex cache] %zu calls, %zu answered from the cache, %zu contacts\n", calls, reused, contacts);
}

// A hull changed in place (same address, same placement) is collided again: its arrays are part
// of the input.
TEST(ConvexPairCache, HullEditedInPlaceIsCollidedAgain) {
  const auto mesh =
      CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(8, 8, 3, 4, 0.2)), parse_method("aabb"));
  ConvexPolyhedron hull = make_convex_polyhedron(cube_corners(0.5), kCubeFaces);
  std::vector<Vec3> points = cube_corners(0.5);
  const Vec3 at = mesh->bounds().center() + Vec3(0, 0, 0.05);
  const RigidTransform place{Mat3::Identity(), at};
  ContactRequest request;
  request.max_contacts = 8;
  ConvexPairCache polyhedron_cache, points_cache;
  ContactResult result;
  for (int call = 0; call < 4; ++call) {
    collide_convex(*mesh, PlacedPolyhedron{hull, place, 0}, request, result, &polyhedron_cache);
    collide_convex(*mesh, PlacedPoints{points, place}, request, result, &points_cache);
  }
  ASSERT_TRUE(result.counts.reused);
  ASSERT_FALSE(result.contacts.empty());
  // Grown by half: the same address and placement, other numbers.
  hull = make_convex_polyhedron(cube_corners(0.75), kCubeFaces);
  for (Vec3& p : points) p *= 1.5;
  ContactResult fresh, cached;
  collide_convex(*mesh, PlacedPolyhedron{hull, place, 0}, request, fresh);
  collide_convex(*mesh, PlacedPolyhedron{hull, place, 0}, request, cached, &polyhedron_cache);
  EXPECT_FALSE(cached.counts.reused);
  EXPECT_TRUE(same_bits(cached.contacts, fresh.contacts));
  fresh.clear();
  collide_convex(*mesh, PlacedPoints{points, place}, request, fresh);
  collide_convex(*mesh, PlacedPoints{points, place}, request, cached, &points_cache);
  EXPECT_FALSE(cached.counts.reused);
  EXPECT_TRUE(same_bits(cached.contacts, fresh.contacts));
}

// Invalid input clears the cache and is reported as without it; the call after collides.
TEST(ConvexPairCache, InvalidInputIsNotKept) {
  const auto mesh =
      CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(8, 8, 3, 4, 0.2)), parse_method("aabb"));
  const Sphere sphere{mesh->bounds().center(), 0.5};
  ContactRequest request;
  ConvexPairCache cache;
  ContactResult result;
  for (int call = 0; call < 3; ++call) collide_convex(*mesh, sphere, request, result, &cache);
  ASSERT_TRUE(result.counts.reused);
  collide_convex(*mesh, Sphere{sphere.center, -1}, request, result, &cache);
  EXPECT_TRUE(result.counts.invalid_input);
  EXPECT_FALSE(result.counts.reused);
  EXPECT_TRUE(result.contacts.empty());
  collide_convex(*mesh, sphere, request, result, &cache);
  EXPECT_FALSE(result.counts.reused);
  collide_convex(*mesh, sphere, request, result, &cache);
  EXPECT_FALSE(result.counts.reused);
  collide_convex(*mesh, sphere, request, result, &cache);
  EXPECT_TRUE(result.counts.reused);
  cache.clear();
  collide_convex(*mesh, sphere, request, result, &cache);
  EXPECT_FALSE(result.counts.reused);
}

}  // namespace
}  // namespace boxtree
