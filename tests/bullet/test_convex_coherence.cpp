// SPDX-License-Identifier: MIT
// Convex-vs-mesh temporal coherence in Bullet (AlgorithmSettings::convexCoherence,
// ConvexPairCache). Bullet collides a pair only while one of its objects is active, and wakes
// whatever touches an active kinematic object, so a pair keeps its input from step to step when a
// kinematic body held still touches a static mesh (a filter mask that lets kinematic and static
// objects meet). Kinematic spheres, boxes, capsules, cylinders and hulls with faces rest in a
// static boxtree terrain, some held still, some moving: the contact manifolds are bit for bit
// those without the pair state, the still ones are answered from it, the moving ones never.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>

#include "bullet/world.h"
#include "support/traces.h"

namespace boxtree::bullet::test {
namespace {

struct KinematicRun {
  std::vector<btScalar> trace;  // every manifold's points after each step
  BoxtreeMeshShape::Counters counters;
};

KinematicRun run_kinematic(bool coherence, int steps) {
  AlgorithmSettings settings;
  settings.convexCoherence = coherence;
  settings.hullFaces = true;
  World world(true, settings);
  auto terrain_shape =
      std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(make_terrain(16, 16, 3, 6, 0.3)), "aabb");
  const BoxtreeMeshShape* terrain = terrain_shape.get();
  world.add(std::move(terrain_shape), 0, btVector3(-3, -3, 0));
  std::vector<btRigidBody*> moving;
  for (int k = 0; k < 10; ++k) {
    std::unique_ptr<btCollisionShape> shape;
    switch (k % 5) {
      case 0:
        shape = std::make_unique<btSphereShape>(btScalar(0.2));
        break;
      case 1:
        shape = std::make_unique<btBoxShape>(btVector3(btScalar(0.25), btScalar(0.2), btScalar(0.15)));
        break;
      case 2:
        shape = std::make_unique<btCapsuleShapeZ>(btScalar(0.12), btScalar(0.3));
        break;
      case 3:
        shape = std::make_unique<btCylinderShapeZ>(btVector3(btScalar(0.2), btScalar(0.2), btScalar(0.15)));
        break;
      default: {
        auto hull = std::make_unique<btConvexHullShape>();
        for (int i = 0; i < 8; ++i)
          hull->addPoint(btVector3(i & 1 ? 0.2f : -0.2f, i & 2 ? 0.15f : -0.15f, i & 4 ? 0.1f : -0.1f));
        hull->initializePolyhedralFeatures();
        shape = std::move(hull);
      }
    }
    // Sunk a little into the terrain (heights within 0.3 of 0): every body touches it.
    const btScalar x = btScalar(-1.6 + 0.8 * (k % 5)), y = btScalar(-0.6 + 1.2 * (k / 5));
    btRigidBody* b = world.add(std::move(shape), 0, btVector3(x, y, btScalar(0.1)),
                               btQuaternion(btVector3(1, 2, 3).normalized(), btScalar(0.3 * k)));
    b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    b->setActivationState(DISABLE_DEACTIVATION);
    world.world.removeRigidBody(b);
    world.world.addRigidBody(b, btBroadphaseProxy::KinematicFilter, btBroadphaseProxy::AllFilter);
    if (k >= 5) moving.push_back(b);
  }
  KinematicRun run;
  for (int i = 0; i < steps; ++i) {
    for (btRigidBody* b : moving) {
      btTransform t;
      b->getMotionState()->getWorldTransform(t);
      t.setOrigin(t.getOrigin() + btVector3(btScalar(0.002), btScalar(0.001), 0));
      b->getMotionState()->setWorldTransform(t);
    }
    world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    for (int m = 0; m < world.dispatcher.getNumManifolds(); ++m) {
      const btPersistentManifold* manifold = world.dispatcher.getManifoldByIndexInternal(m);
      run.trace.push_back(btScalar(manifold->getNumContacts()));
      for (int c = 0; c < manifold->getNumContacts(); ++c) {
        const btManifoldPoint& p = manifold->getContactPoint(c);
        for (int a = 0; a < 3; ++a) run.trace.push_back(p.m_positionWorldOnB[a]);
        for (int a = 0; a < 3; ++a) run.trace.push_back(p.m_normalWorldOnB[a]);
        run.trace.push_back(p.m_distance1);
      }
    }
  }
  run.counters = terrain->counters();
  return run;
}

TEST(BulletConvexCoherence, KinematicBodiesHeldStillAreAnsweredFromTheirPairState) {
  const int steps = 120;
  const KinematicRun with = run_kinematic(true, steps);
  const KinematicRun without = run_kinematic(false, steps);
  ASSERT_EQ(with.trace.size(), without.trace.size());
  ASSERT_EQ(std::memcmp(with.trace.data(), without.trace.data(), with.trace.size() * sizeof(btScalar)), 0);
  EXPECT_GT(with.trace.size(), std::size_t(steps) * 10 * 7);  // the bodies do touch the terrain
  EXPECT_EQ(without.counters.reused_calls, 0u);
  // The five still bodies from their third step on; the moving ones never.
  EXPECT_GE(with.counters.reused_calls, 5u * (steps - 3));
  EXPECT_LE(with.counters.reused_calls, 5u * steps);
  EXPECT_LT(with.counters.narrowphase_triangles, without.counters.narrowphase_triangles);
  std::printf("[ convex coherence] %llu calls reused; narrowphase triangles %llu with, %llu without\n",
              static_cast<unsigned long long>(with.counters.reused_calls),
              static_cast<unsigned long long>(with.counters.narrowphase_triangles),
              static_cast<unsigned long long>(without.counters.narrowphase_triangles));
}

}  // namespace
}  // namespace boxtree::bullet::test
