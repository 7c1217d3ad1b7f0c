// SPDX-License-Identifier: MIT
// Mesh-vs-mesh temporal coherence in Bullet (AlgorithmSettings::meshCoherence): a pile of mesh
// bodies falling onto a mesh terrain and onto each other steps bit for bit the same with the
// per-pair fronts as with a fresh descent every step.
#include <gtest/gtest.h>

#include <cstdio>

#include "bullet/world.h"
#include "support/traces.h"

namespace boxtree::bullet::test {
namespace {

// Every body's transform after each step; `volume_tests`: the mesh-vs-mesh walks' volume tests.
std::vector<btScalar> run_pile(bool coherence, int steps, std::uint64_t* volume_tests) {
  AlgorithmSettings settings;
  settings.meshCoherence = coherence;
  World world(true, settings);
  world.world.getSolverInfo().m_numIterations = 10;
  const TriangleMesh terrain = make_terrain(16, 16, 3, 6, 0.5);
  world.add(std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(terrain), "aabb"), 0,
            btVector3(-3, -3, 0));
  const auto rock = std::make_shared<TriangleMesh>(make_bumpy_sphere(12, 8, 0.2, 5));
  const auto torus = std::make_shared<TriangleMesh>(make_torus(0.35, 0.12, 16, 8));
  std::vector<btRigidBody*> bodies;
  std::vector<const BoxtreeMeshShape*> shapes;
  for (int k = 0; k < 12; ++k) {
    const btScalar x = btScalar(0.45 * (k % 3)), y = btScalar(0.45 * ((k / 3) % 2)), z = btScalar(1 + 0.6 * (k / 6));
    auto shape = std::make_unique<BoxtreeMeshShape>(k % 2 ? torus : rock, "aabb");
    shape->setLocalScaling(btVector3(0.5f, 0.5f, 0.5f));
    shapes.push_back(shape.get());
    bodies.push_back(world.add(std::move(shape), 1, btVector3(x, y, z + btScalar(0.1 * k))));
    bodies.back()->setActivationState(DISABLE_DEACTIVATION);  // resting pairs keep colliding
  }
  std::vector<btScalar> trace;
  for (int i = 0; i < steps; ++i) {
    world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    for (const btRigidBody* b : bodies) {
      const btTransform& t = b->getWorldTransform();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) trace.push_back(t.getBasis()[r][c]);
      for (int c = 0; c < 3; ++c) trace.push_back(t.getOrigin()[c]);
    }
  }
  *volume_tests = 0;
  for (const BoxtreeMeshShape* s : shapes) *volume_tests += s->counters().mesh_volume_tests;
  return trace;
}

TEST(BulletCoherence, MeshPileStepsBitIdenticallyWithAndWithoutFronts) {
  const int steps = 240;
  std::uint64_t tests_with = 0, tests_without = 0;
  const std::vector<btScalar> with = run_pile(true, steps, &tests_with);
  const std::vector<btScalar> without = run_pile(false, steps, &tests_without);
  ASSERT_NO_FATAL_FAILURE(boxtree::test::expect_same_bits_every_step(with, without, steps));
  const std::size_t per_step = with.size() / std::size_t(steps);
  // The pile moved and settled: not a trivially static scene.
  EXPECT_NE(with.front(), with[with.size() - per_step]);
  // The fronts were used: fewer volume tests (the terrain's pairs are counted by the terrain
  // shape, which is not summed here).
  EXPECT_GT(tests_without, 0u);
  EXPECT_LT(tests_with, tests_without);
  std::printf("[ coherence] mesh-vs-mesh volume tests over %d steps: %llu with fronts, %llu fresh\n", steps,
              static_cast<unsigned long long>(tests_with), static_cast<unsigned long long>(tests_without));
}

}  // namespace
}  // namespace boxtree::bullet::test
