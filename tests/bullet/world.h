// SPDX-License-Identifier: MIT
#pragma once
// A small Bullet world for the adapter tests: the same scene can be built twice, once with
// Bullet's own mesh shape and once with BoxtreeMeshShape, and stepped side by side.
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

#include "boxtree/active_edges.h"
#include "boxtree/bullet/algorithms.h"
#include "boxtree/bullet/mesh_shape.h"
#include "boxtree/generate.h"

namespace boxtree::bullet::test {

inline Vec3 to_vec3(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
// Bullet's rotation, re-orthonormalized (single precision is orthonormal to ~1e-7 only).
inline Mat3 to_mat_test(const btMatrix3x3& m) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
  return Eigen::Quaternion<Real>(r).normalized().toRotationMatrix();
}

// A mesh as Bullet sees it: btScalar vertices and int indices, owned here.
struct BulletMesh {
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;

  explicit BulletMesh(const TriangleMesh& mesh) {
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(btScalar(v[k]));
    for (const Triangle& t : mesh.triangles)
      for (VertexId v : t) indices.push_back(int(v));
    array = std::make_unique<btTriangleIndexVertexArray>(int(mesh.triangles.size()), indices.data(),
                                                         3 * int(sizeof(int)), int(mesh.vertices.size()),
                                                         vertices.data(), 3 * int(sizeof(btScalar)));
  }
  // The mesh with Bullet's (possibly float) coordinates, for brute-force references.
  TriangleMesh as_boxtree() const {
    TriangleMesh m;
    for (std::size_t i = 0; i < vertices.size(); i += 3)
      m.vertices.push_back({vertices[i], vertices[i + 1], vertices[i + 2]});
    for (std::size_t i = 0; i < indices.size(); i += 3)
      m.triangles.push_back({VertexId(indices[i]), VertexId(indices[i + 1]), VertexId(indices[i + 2])});
    return m;
  }
};

struct World {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;

  explicit World(bool boxtree_algorithms, const AlgorithmSettings& settings = {}) {
    world.setGravity(btVector3(0, 0, -9.81f));
    if (boxtree_algorithms) registerBoxtreeAlgorithms(&dispatcher, settings);
  }
  ~World() {
    for (auto& b : bodies) world.removeRigidBody(b.get());
  }
  btRigidBody* add(std::unique_ptr<btCollisionShape> shape, btScalar mass, const btVector3& position,
                   const btQuaternion& rotation = btQuaternion::getIdentity()) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    motion_states.push_back(std::make_unique<btDefaultMotionState>(btTransform(rotation, position)));
    btRigidBody::btRigidBodyConstructionInfo info(mass, motion_states.back().get(), shape.get(), inertia);
    bodies.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(shape));
    world.addRigidBody(bodies.back().get());
    return bodies.back().get();
  }
  // Contact points in all manifolds now.
  int contact_points() {
    int n = 0;
    for (int i = 0; i < dispatcher.getNumManifolds(); ++i)
      n += dispatcher.getManifoldByIndexInternal(i)->getNumContacts();
    return n;
  }
};

}  // namespace boxtree::bullet::test
