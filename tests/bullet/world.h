// SPDX-License-Identifier: MIT
#pragma once
// A small Bullet world for the adapter tests: the same scene can be built twice, once with
// Bullet's own mesh shape and once with BoxtreeMeshShape, and stepped side by side.
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <vector>

#include "boxtree/active_edges.h"
#include "boxtree/bullet/algorithms.h"
#include "boxtree/bullet/mesh_shape.h"
#include "boxtree/generate.h"
#include "boxtree/query.h"

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

// Terrain height under (x, y): the closest hit of a vertical ray on a tree of the terrain;
// nullopt off the terrain.
inline std::optional<Real> terrain_height_at(const AnyTree& terrain, Real x, Real y) {
  const auto hit = terrain.ray_closest_hit(Ray{Vec3(x, y, 1000), Vec3(0, 0, -1)});
  if (!hit) return std::nullopt;
  return 1000 - hit->t;
}

// The points of a body that rest on the ground, in the world: the lowest point of a sphere and of
// each capsule cap, the corners of a box, 16 points around each rim of a cylinder, the vertices of
// a hull (less its margin, which Bullet's hull carries outside them) or of a boxtree mesh. Their
// lowest is the body's lowest point, and on a slope the others reach the ground first.
inline std::vector<Vec3> bottom_points(const btCollisionObject& body) {
  const btTransform& pose = body.getWorldTransform();
  const btCollisionShape* shape = body.getCollisionShape();
  const Vec3 center = to_vec3(pose.getOrigin());
  const Vec3 down(0, 0, -1);
  std::vector<Vec3> points;
  switch (shape->getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
      points.push_back(center + down * Real(static_cast<const btSphereShape*>(shape)->getRadius()));
      break;
    case BOX_SHAPE_PROXYTYPE: {
      const btVector3 h = static_cast<const btBoxShape*>(shape)->getHalfExtentsWithMargin();
      for (int k = 0; k < 8; ++k)
        points.push_back(
            to_vec3(pose(btVector3(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z()))));
      break;
    }
    case CAPSULE_SHAPE_PROXYTYPE: {
      const auto* capsule = static_cast<const btCapsuleShape*>(shape);
      btVector3 axis(0, 0, 0);
      axis[capsule->getUpAxis()] = capsule->getHalfHeight();
      for (const btVector3& end : {axis, -axis})
        points.push_back(to_vec3(pose(end)) + down * Real(capsule->getRadius()));
      break;
    }
    case CYLINDER_SHAPE_PROXYTYPE: {
      const auto* cylinder = static_cast<const btCylinderShape*>(shape);
      const int up = cylinder->getUpAxis();
      const btVector3 h = cylinder->getHalfExtentsWithMargin();
      for (int k = 0; k < 32; ++k) {
        const btScalar angle = btScalar(k % 16) * SIMD_2_PI / 16;
        btVector3 local(0, 0, 0);
        local[up] = k < 16 ? h[up] : -h[up];
        local[(up + 1) % 3] = cylinder->getRadius() * btCos(angle);
        local[(up + 2) % 3] = cylinder->getRadius() * btSin(angle);
        points.push_back(to_vec3(pose(local)));
      }
      break;
    }
    case CONVEX_HULL_SHAPE_PROXYTYPE: {
      const auto* hull = static_cast<const btConvexHullShape*>(shape);
      for (int i = 0; i < hull->getNumPoints(); ++i)
        points.push_back(to_vec3(pose(hull->getScaledPoint(i))) + down * Real(hull->getMargin()));
      break;
    }
    case FAST_CONCAVE_MESH_PROXYTYPE: {
      const auto* mesh = static_cast<const BoxtreeMeshShape*>(shape);
      const btVector3 scaling = mesh->getLocalScaling();
      for (const Vec3& v : mesh->mesh().vertices)
        points.push_back(to_vec3(pose(btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())) * scaling)));
      break;
    }
    default:
      points.push_back(center);
  }
  return points;
}

// How deep a body is in the ground: the largest (terrain height under a bottom point - the
// point's height) over its bottom_points with terrain under them; negative when it is clear of
// the ground, nullopt when no point is over the terrain.
inline std::optional<Real> depth_below(const AnyTree& terrain, const btCollisionObject& body) {
  std::optional<Real> depth;
  for (const Vec3& p : bottom_points(body)) {
    if (const auto ground = terrain_height_at(terrain, p.x(), p.y()))
      depth = std::max(depth.value_or(-1e30), *ground - p.z());
  }
  return depth;
}

}  // namespace boxtree::bullet::test
