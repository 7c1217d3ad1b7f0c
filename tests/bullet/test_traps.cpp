// SPDX-License-Identifier: MIT
// The configurations that used to lose bodies or throw inside stepSimulation, each in a world:
// mesh pairs of different methods, scaled and mirrored mesh bodies, scaled terrains under convex
// bodies, a boxtree shape inside a compound, and the adapter's contacts against the collider's.
#include <gtest/gtest.h>

#include <cstdio>

#include "boxtree/collider.h"
#include "support/random.h"
#include "world.h"

namespace boxtree::bullet::test {
namespace {

using Random = boxtree::test::Random;
btVector3 bt_point(const Vec3& p) { return btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())); }

// The lowest vertex of a boxtree mesh body against the terrain under it (positive: in it).
Real mesh_depth(const btRigidBody& body, const AnyTree& terrain) {
  const auto& shape = static_cast<const BoxtreeMeshShape&>(*body.getCollisionShape());
  Real deepest = -1e30;
  const TriangleMesh& m = shape.mesh();
  for (const Vec3& v : m.vertices) {
    const btVector3 scaled = btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())) * shape.getLocalScaling();
    const Vec3 p = to_vec3(body.getWorldTransform()(scaled));
    const auto ground = terrain_height_at(terrain, p.x(), p.y());
    if (ground) deepest = std::max(deepest, *ground - p.z());
  }
  return deepest;
}

struct Drop {
  Real depth = 0;
  Real speed = 0;
  int contacts = 0;
};

// A rock (a closed bumpy sphere, `rock_method`, scaled by `scale`) dropped on a terrain
// (`terrain_method`), stepped `steps` times.
Drop drop_rock(const char* terrain_method, const char* rock_method, const btVector3& scale, int steps = 300) {
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(16, 16, 3, 16, 1));
  const AnyTree reference = AnyTree::build(terrain, Method{});
  World world(true);
  world.add(std::make_unique<BoxtreeMeshShape>(terrain, terrain_method), 0, btVector3(0, 0, 0));
  auto rock = std::make_unique<BoxtreeMeshShape>(
      std::make_shared<const TriangleMesh>(make_bumpy_sphere(12, 7, 0.15, 9)), rock_method);
  rock->setLocalScaling(scale);
  const Real ground = *terrain_height_at(reference, 8, 8);
  btRigidBody* body = world.add(std::move(rock), 1, btVector3(8, 8, btScalar(ground + 2)));
  Drop d;
  for (int i = 0; i < steps; ++i) {
    world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    if (i >= steps - 30) d.contacts += world.contact_points();
  }
  d.depth = mesh_depth(*body, reference);
  d.speed = Real(body->getLinearVelocity().length());
  return d;
}

// Two meshes built with different methods: stepSimulation threw boxtree::Error from the mesh-mesh
// algorithm; the collider walks them with a tree of one method, built once.
TEST(BulletTraps, MixedMethodMeshPairComesToRest) {
  for (const auto& [terrain, rock] : {std::pair{"aabb", "obb-min"}, std::pair{"pie-min", "aabb"}}) {
    SCOPED_TRACE(std::string(terrain) + " terrain, " + rock + " rock");
    Drop d;
    ASSERT_NO_THROW(d = drop_rock(terrain, rock, btVector3(1, 1, 1)));
    std::printf("mixed methods %s / %s: lowest vertex %.4f m in, |v| %.4f, %d contacts over 30 steps\n", terrain, rock,
                d.depth, d.speed, d.contacts);
    EXPECT_GT(d.contacts, 0);
    EXPECT_LT(d.speed, 0.05);
    // Same allowance as the rock of the drop-scene suite (its worst measured 2.6 um in).
    EXPECT_LT(d.depth, 0.025);
    EXPECT_GT(d.depth, -0.01);
  }
}

// A dynamic mesh with non-unit local scaling (non-uniform, mirrored) fell straight through a
// boxtree terrain (the pair got no contacts); now it rests on it.
TEST(BulletTraps, ScaledMeshBodiesRestOnTheTerrain) {
  for (const btVector3& scale : {btVector3(2, 1, 0.5), btVector3(-1.5, 1, 1), btVector3(1, -1, -1)}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale.x() << " " << scale.y() << " " << scale.z());
    const Drop d = drop_rock("aabb", "aabb", scale);
    std::printf("scaled rock (%g, %g, %g): lowest vertex %.4f m in, |v| %.4f, %d contacts over 30 steps\n",
                double(scale.x()), double(scale.y()), double(scale.z()), d.depth, d.speed, d.contacts);
    EXPECT_GT(d.contacts, 0);
    EXPECT_LT(d.speed, 0.05);
    EXPECT_LT(d.depth, 0.025);
    EXPECT_GT(d.depth, -0.01);
  }
}

// Manifold points of one collision pass (world positions on body B, depths), sorted.
std::vector<std::pair<Vec3, Real>> manifold_points(World& world) {
  world.world.performDiscreteCollisionDetection();
  std::vector<std::pair<Vec3, Real>> points;
  for (int i = 0; i < world.dispatcher.getNumManifolds(); ++i) {
    const btPersistentManifold* m = world.dispatcher.getManifoldByIndexInternal(i);
    for (int k = 0; k < m->getNumContacts(); ++k)
      points.emplace_back(to_vec3(m->getContactPoint(k).getPositionWorldOnB()),
                          Real(m->getContactPoint(k).getDistance()));
  }
  std::sort(points.begin(), points.end(), [](const auto& x, const auto& y) {
    return std::make_tuple(x.second, x.first.x(), x.first.y()) < std::make_tuple(y.second, y.first.x(), y.first.y());
  });
  return points;
}

void expect_same_points(const std::vector<std::pair<Vec3, Real>>& got, const std::vector<std::pair<Vec3, Real>>& want,
                        Real tolerance) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_LT((got[i].first - want[i].first).norm(), tolerance) << "point " << i;
    EXPECT_NEAR(got[i].second, want[i].second, tolerance) << "point " << i;
  }
}

// A mesh scaled by setLocalScaling collides like the mesh scaled beforehand (corners 1 and 2
// swapped where the scale mirrors, so that the fronts stay outside): mesh pairs and convex pairs
// alike, the scaled terrain's convex pairs on the analytic path (not Bullet's GJK).
TEST(BulletTraps, ScaledPairsGiveThePreScaledMeshsContacts) {
  const TriangleMesh rock = make_bumpy_sphere(12, 7, 0.15, 9);
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(12, 12, 3, 12, 1));
  for (const Vec3& scale : {Vec3(2, 1, 0.5), Vec3(-1.5, 1, 1), Vec3(1, -1, -1)}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale.transpose());
    auto prescaled = std::make_shared<TriangleMesh>(rock);
    for (Vec3& v : prescaled->vertices) v = v.cwiseProduct(scale);
    if (scale.prod() < 0)
      for (Triangle& t : prescaled->triangles) std::swap(t[1], t[2]);
    const btQuaternion turn(btVector3(0.3f, 1, 0.2f).normalized(), 0.7f);
    std::vector<std::pair<Vec3, Real>> points[2];
    for (int pre = 0; pre < 2; ++pre) {
      World world(true);
      world.add(std::make_unique<BoxtreeMeshShape>(terrain), 0, btVector3(0, 0, 0));
      std::unique_ptr<BoxtreeMeshShape> body;
      if (pre) {
        body = std::make_unique<BoxtreeMeshShape>(prescaled);
      } else {
        body = std::make_unique<BoxtreeMeshShape>(std::make_shared<const TriangleMesh>(rock));
        body->setLocalScaling(btVector3(btScalar(scale.x()), btScalar(scale.y()), btScalar(scale.z())));
      }
      world.add(std::move(body), 1, btVector3(6, 6, 1.2f), turn);
      points[pre] = manifold_points(world);
    }
    EXPECT_FALSE(points[1].empty());
    expect_same_points(points[0], points[1], 1e-5);

    // The terrain scaled under a box: the same contacts as the pre-scaled terrain, analytic.
    auto terrain_prescaled = std::make_shared<TriangleMesh>(*terrain);
    for (Vec3& v : terrain_prescaled->vertices) v = v.cwiseProduct(scale);
    if (scale.prod() < 0)
      for (Triangle& t : terrain_prescaled->triangles) std::swap(t[1], t[2]);
    // A box where the scaled terrain is: under its surface's image, from whichever side faces up.
    const Vec3 spot = Vec3(6, 6, 0).cwiseProduct(scale);
    const AnyTree scaled_tree = AnyTree::build(terrain_prescaled, Method{});
    const auto up = scaled_tree.ray_closest_hit(Ray{Vec3(spot.x(), spot.y(), 100), Vec3(0, 0, -1)});
    ASSERT_TRUE(up);
    const btScalar surface = btScalar(100 - up->t);
    for (int pre = 0; pre < 2; ++pre) {
      AlgorithmSettings settings;
      World world(true, settings);
      std::unique_ptr<BoxtreeMeshShape> ground;
      if (pre) {
        ground = std::make_unique<BoxtreeMeshShape>(terrain_prescaled);
      } else {
        ground = std::make_unique<BoxtreeMeshShape>(terrain);
        ground->setLocalScaling(btVector3(btScalar(scale.x()), btScalar(scale.y()), btScalar(scale.z())));
      }
      ground->setTwoSided(true);  // a terrain flipped upside down by the scale is seen from its back
      world.add(std::move(ground), 0, btVector3(0, 0, 0));
      world.add(std::make_unique<btBoxShape>(btVector3(0.5f, 0.4f, 0.3f)), 1,
                btVector3(btScalar(spot.x()), btScalar(spot.y()), surface + 0.25f), turn);
      points[pre] = manifold_points(world);
    }
    EXPECT_GE(points[1].size(), 2u);  // the analytic box path: a patch, not GJK's one point per triangle
    expect_same_points(points[0], points[1], 1e-5);
  }
}

// A boxtree shape as the child of a static btCompoundShape collides like the same shape at the
// same place at the top level.
TEST(BulletTraps, CompoundChildCollidesLikeTopLevel) {
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(12, 12, 3, 12, 1));
  const btTransform child(btQuaternion(btVector3(0, 0, 1), 0.4f), btVector3(2, -1, 0.5f));
  std::vector<std::pair<Vec3, Real>> points[2];
  for (int compound = 0; compound < 2; ++compound) {
    World world(true);
    if (compound) {
      auto shape = std::make_unique<btCompoundShape>();
      world.shapes.push_back(std::make_unique<BoxtreeMeshShape>(terrain));
      shape->addChildShape(child, world.shapes.back().get());
      world.add(std::move(shape), 0, btVector3(0, 0, 0));
    } else {
      world.add(std::make_unique<BoxtreeMeshShape>(terrain), 0, child.getOrigin(), child.getRotation());
    }
    const AnyTree reference = AnyTree::build(terrain, Method{});
    for (int i = 0; i < 6; ++i) {
      const Vec3 local(2 + 1.5 * i, 3 + i, 0);
      const Vec3 at = to_vec3(child(btVector3(btScalar(local.x()), btScalar(local.y()), 0)));
      const btScalar z = btScalar(child.getOrigin().z() + *terrain_height_at(reference, local.x(), local.y()));
      if (i % 2)
        world.add(std::make_unique<btSphereShape>(0.4f), 1, btVector3(btScalar(at.x()), btScalar(at.y()), z + 0.35f));
      else
        world.add(std::make_unique<btBoxShape>(btVector3(0.4f, 0.3f, 0.2f)), 1,
                  btVector3(btScalar(at.x()), btScalar(at.y()), z + 0.15f));
    }
    points[compound] = manifold_points(world);
  }
  EXPECT_GE(points[0].size(), 6u);
  expect_same_points(points[1], points[0], 1e-5);
}

// The adapter's manifold points are the collider's contacts on the same input, converted.
TEST(BulletTraps, AdapterContactsAreTheCollidersContacts) {
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(12, 12, 3, 12, 1));
  World world(true);
  auto ground = std::make_unique<BoxtreeMeshShape>(terrain);
  const BoxtreeMeshShape* shape = ground.get();
  const btTransform ground_pose(btQuaternion(btVector3(0, 0, 1), 0.3f), btVector3(1, 2, 0.5f));
  world.add(std::move(ground), 0, ground_pose.getOrigin(), ground_pose.getRotation());
  const btTransform box_pose(btQuaternion(btVector3(1, 0.2f, 0).normalized(), 0.5f), btVector3(5, 7, 1.4f));
  const btVector3 half(0.6f, 0.4f, 0.3f);
  world.add(std::make_unique<btBoxShape>(half), 1, box_pose.getOrigin(), box_pose.getRotation());
  const auto got = manifold_points(world);
  ASSERT_FALSE(got.empty());
  const btPersistentManifold* manifold = world.dispatcher.getManifoldByIndexInternal(0);
  // The same request as the algorithm's, the box in the mesh's frame.
  ContactRequest request;
  request.margin = Real(manifold->getContactBreakingThreshold()) + Real(shape->getMargin());
  request.max_contacts = 4;
  request.merge_distance = Real(manifold->getContactBreakingThreshold());
  const btTransform in_mesh = ground_pose.inverseTimes(box_pose);
  const auto* box = static_cast<const btBoxShape*>(world.bodies.back()->getCollisionShape());
  ContactResult result;
  collide_convex(
      shape->collisionMesh(),
      Obb{to_vec3(in_mesh.getOrigin()), to_mat_test(in_mesh.getBasis()), to_vec3(box->getHalfExtentsWithMargin())},
      request, result);
  std::vector<std::pair<Vec3, Real>> want;
  for (const ContactPoint& c : result.contacts)
    want.emplace_back(
        to_vec3(ground_pose(btVector3(btScalar(c.position.x()), btScalar(c.position.y()), btScalar(c.position.z())))),
        -(c.depth + Real(shape->getMargin())));
  std::sort(want.begin(), want.end(), [](const auto& x, const auto& y) {
    return std::make_tuple(x.second, x.first.x(), x.first.y()) < std::make_tuple(y.second, y.first.x(), y.first.y());
  });
  expect_same_points(got, want, 1e-5);
}

// Hulls on Bullet's GJK path get the manifold points Bullet's own mesh shape gives at the same
// poses (hulls settled on Bullet's own shape, then one collision pass in a fresh world of each).
// The collider used to hand the manifold contacts beyond its breaking distance (Bullet's GJK was
// given the breaking distance twice), which took the places of nearer ones in the reduction and
// were then thrown away: 0.94 points per hull against Bullet's 3.14 on the drop scene's terrain
// (pair_replay --engine bullet --only convex).
TEST(BulletTraps, HullsGetTheManifoldPointsOfBulletsOwnShape) {
  const TriangleMesh terrain = make_terrain(16, 16, 3, 10, 0.4);
  BulletMesh bullet_mesh(terrain);
  const auto make_hull = [](int k) {
    auto hull = std::make_unique<btConvexHullShape>();
    Random random(std::uint64_t(100 + k));
    for (int i = 0; i < 16; ++i) hull->addPoint(bt_point(random.point(-0.3, 0.3)), false);
    hull->recalcLocalAabb();
    return hull;
  };
  constexpr int kHulls = 16;
  std::vector<btTransform> poses;
  {
    World settling(false);
    settling.add(std::make_unique<btBvhTriangleMeshShape>(bullet_mesh.array.get(), true), 0, btVector3(0, 0, 0));
    for (int k = 0; k < kHulls; ++k)
      settling.add(make_hull(k), 1, btVector3(1.5f + 2 * float(k % 4), 1.5f + 2 * float(k / 4), 1.0f),
                   btQuaternion(btVector3(0.2f, 0.3f, 1).normalized(), 0.3f * float(k)));
    for (int step = 0; step < 200; ++step) settling.world.stepSimulation(1.f / 60, 1, 1.f / 60);
    for (std::size_t i = 1; i < settling.bodies.size(); ++i) poses.push_back(settling.bodies[i]->getWorldTransform());
  }
  int points[2] = {0, 0};
  for (const bool boxtree : {false, true}) {
    World world(boxtree);
    if (boxtree)
      world.add(std::make_unique<BoxtreeMeshShape>(*bullet_mesh.array), 0, btVector3(0, 0, 0));
    else
      world.add(std::make_unique<btBvhTriangleMeshShape>(bullet_mesh.array.get(), true), 0, btVector3(0, 0, 0));
    for (int k = 0; k < kHulls; ++k)
      world.add(make_hull(k), 1, poses[std::size_t(k)].getOrigin(), poses[std::size_t(k)].getRotation());
    world.world.performDiscreteCollisionDetection();
    points[boxtree] = world.contact_points();
  }
  std::printf("manifold points of %d settled hulls, one pass: Bullet's own shape %d, boxtree %d\n", kHulls, points[0],
              points[1]);
  EXPECT_GE(points[0], 2 * kHulls) << "the hulls rest on Bullet's own shape";
  EXPECT_GE(points[1], points[0] * 9 / 10) << "Bullet's own shape: " << points[0] << " points, boxtree: " << points[1];
}

// A mesh whose facets are wound both ways has no front: its shapes collide two-sided, and one line
// on stderr says so, once per mesh.
TEST(BulletTraps, InconsistentWindingIsTwoSidedAndSaidOnce) {
  auto flipped = std::make_shared<TriangleMesh>(make_uv_sphere(16, 8, 1));
  for (std::size_t f = 0; f < flipped->triangles.size(); f += 3)
    std::swap(flipped->triangles[f][1], flipped->triangles[f][2]);
  const AnyTree tree = AnyTree::build(flipped, Method{});
  testing::internal::CaptureStderr();
  const BoxtreeMeshShape first(tree), second(tree);
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("wound the same way"), std::string::npos) << said;
  EXPECT_EQ(said.find("wound the same way"), said.rfind("wound the same way")) << "said more than once: " << said;
  EXPECT_FALSE(first.collisionMesh().consistent_winding());
  // A well-wound mesh says nothing.
  testing::internal::CaptureStderr();
  const BoxtreeMeshShape good(std::make_shared<const TriangleMesh>(make_uv_sphere(16, 8, 1)));
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace boxtree::bullet::test
