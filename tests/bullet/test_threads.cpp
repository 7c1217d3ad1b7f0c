// SPDX-License-Identifier: MIT
// One BoxtreeMeshShape collided from several threads at once (built and run under
// ThreadSanitizer in CI, .ci/test): Debian's Bullet is built without BT_THREADSAFE, so
// btCollisionDispatcherMt has no task scheduler to run on; instead several worlds, one per
// thread, share the shape, as the threads of a multithreaded dispatcher would.
#include <gtest/gtest.h>

#include <thread>

#include "world.h"

namespace boxtree::bullet::test {
namespace {

// Several worlds collide bodies against one shared shape from several threads at once: the
// shape's queries are const and its counters atomic (run under ThreadSanitizer in CI).
TEST(BulletThreads, OneShapeCollidedFromManyThreads) {
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(24, 24, 3, 24, 2));
  auto shared = std::make_shared<BoxtreeMeshShape>(terrain);
  const AnyTree reference = AnyTree::build(terrain, Method{});
  constexpr int kThreads = 4;
  std::vector<int> contacts(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      World world(true);
      btCollisionObject ground;
      ground.setCollisionShape(shared.get());
      world.world.addCollisionObject(&ground);
      for (int i = 0; i < 8; ++i) {
        const Real x = 3 + 2.5 * i, y = 4 + 2 * t;
        const btScalar z = btScalar(*terrain_height_at(reference, x, y));
        if (i % 2)
          world.add(std::make_unique<btSphereShape>(0.5f), 1, btVector3(btScalar(x), btScalar(y), z + 0.45f));
        else
          world.add(std::make_unique<btCylinderShapeZ>(btVector3(0.4f, 0.4f, 0.3f)), 1,
                    btVector3(btScalar(x), btScalar(y), z + 0.25f));
      }
      for (int step = 0; step < 20; ++step) {
        world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
        contacts[std::size_t(t)] += world.contact_points();
        btCollisionWorld::ClosestRayResultCallback ray(btVector3(5, 5, 50), btVector3(5, 5, -50));
        world.world.rayTest(ray.m_rayFromWorld, ray.m_rayToWorld, ray);
      }
      world.world.removeCollisionObject(&ground);
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_GT(contacts[std::size_t(t)], 0) << "thread " << t;
  const BoxtreeMeshShape::Counters c = shared->counters();
  EXPECT_EQ(c.ray_queries, std::uint64_t(kThreads * 20));
  EXPECT_GT(c.narrowphase_triangles, 0u);
}

}  // namespace
}  // namespace boxtree::bullet::test
