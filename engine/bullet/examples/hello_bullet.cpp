// SPDX-License-Identifier: MIT
// hello_bullet: a terrain from plain arrays, a few bodies dropped on it, boxtree as the terrain's
// midphase. Build against the installed package:
//   find_package(boxtree 0.2 CONFIG REQUIRED COMPONENTS bullet)
//   target_link_libraries(hello_bullet PRIVATE boxtree::bullet)
//! [includes]
#include <boxtree/bullet/algorithms.h>
#include <boxtree/bullet/mesh_shape.h>
//! [includes]
#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

int main() {
  // A 20 m x 20 m rolling terrain, 16 x 16 cells, two triangles per cell, counter-clockwise seen from above (+z).
  const int n = 16;
  const btScalar cell = 20.0 / n;
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const btScalar x = i * cell - 10, y = j * cell - 10;
      vertices.insert(vertices.end(), {x, y, btScalar(0.5 * std::sin(0.4 * x) * std::cos(0.3 * y))});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int v = j * (n + 1) + i;
      indices.insert(indices.end(), {v, v + 1, v + n + 2, v, v + n + 2, v + n + 1});
    }
  btTriangleIndexVertexArray meshInterface(int(indices.size() / 3), indices.data(), 3 * sizeof(int),
                                           int(vertices.size() / 3), vertices.data(), 3 * sizeof(btScalar));

  //! [world]
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  //! [register]
  boxtree::bullet::registerBoxtreeAlgorithms(&dispatcher);  // once, before bodies are added
  //! [register]
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, 0, -9.81));
  //! [world]

  //! [swap]
  // The swap: was `new btBvhTriangleMeshShape(&meshInterface, true)`. The arrays are copied.
  auto terrain = std::make_unique<boxtree::bullet::BoxtreeMeshShape>(&meshInterface, true);
  btRigidBody ground(0, nullptr, terrain.get());
  world.addRigidBody(&ground);
  //! [swap]

  btSphereShape sphere(0.5);
  btBoxShape box(btVector3(0.4, 0.4, 0.4));
  btCapsuleShapeZ capsule(0.3, 0.8);
  btCollisionShape* shapes[] = {&sphere, &box, &capsule};
  std::vector<std::unique_ptr<btDefaultMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  for (int k = 0; k < 6; ++k) {
    btCollisionShape* shape = shapes[k % 3];
    btVector3 inertia;
    shape->calculateLocalInertia(1, inertia);
    states.push_back(std::make_unique<btDefaultMotionState>(
        btTransform(btQuaternion::getIdentity(), btVector3(-5 + 2 * k, 0.5 * k - 1, 3 + k))));
    bodies.push_back(std::make_unique<btRigidBody>(1, states.back().get(), shape, inertia));
    world.addRigidBody(bodies.back().get());
  }

  for (int step = 0; step < 240; ++step) world.stepSimulation(1.0 / 60, 0);

  // Every body should have landed: its centre above the terrain under it, no longer falling.
  int landed = 0;
  for (const auto& body : bodies) {
    const btVector3 c = body->getWorldTransform().getOrigin();
    const btScalar height = c.z() - btScalar(0.5 * std::sin(0.4 * c.x()) * std::cos(0.3 * c.y()));
    const bool ok = height > 0 && std::abs(body->getLinearVelocity().z()) < 0.5;
    landed += ok;
    std::printf("%-8s at (%6.2f %6.2f %6.2f), centre %.3f m above the terrain%s\n",
                body->getCollisionShape()->getName(), c.x(), c.y(), c.z(), height, ok ? "" : "  <- has not landed");
  }
  std::printf("hello_bullet: %d of %zu bodies landed on the %d-facet boxtree terrain (%s)\n", landed, bodies.size(),
              int(indices.size() / 3), sizeof(btScalar) == 8 ? "double-precision Bullet" : "single-precision Bullet");
  for (auto& body : bodies) world.removeRigidBody(body.get());
  world.removeRigidBody(&ground);
  return landed == int(bodies.size()) ? 0 : 1;
}
