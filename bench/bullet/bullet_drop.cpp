// SPDX-License-Identifier: MIT
// Bullet drop scene: N mixed bodies fall onto a meshed terrain; the same scene runs with
// Bullet's btBvhTriangleMeshShape and with BoxtreeMeshShape (Bullet's convex-concave path fed by
// processAllTriangles, and the boxtree collision algorithm), in one process, one after the other.
// Reports per-step collision time (btCollisionWorld::performDiscreteCollisionDetection: AABB
// update, broadphase, midphase and narrowphase), whole-step time, contact points per step and
// triangles handed to the narrowphase per step, with ratios to Bullet's own shape.
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>

#include <CLI/CLI.hpp>
#include <algorithm>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "boxtree/bullet/algorithms.h"
#include "boxtree/bullet/mesh_shape.h"
#include "boxtree/generate.h"

namespace {

using Clock = std::chrono::steady_clock;

// Times collision detection inside each step (the virtual Bullet calls once per substep).
class TimedWorld : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;
  double collision_seconds = 0;
  void performDiscreteCollisionDetection() override {
    const auto t0 = Clock::now();
    btDiscreteDynamicsWorld::performDiscreteCollisionDetection();
    collision_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
};

// Counts triangles that Bullet's own convex-concave path hands to GJK, through the profile
// zone it opens per triangle (Debian's Bullet has no profiler, but the zone hooks are live).
std::uint64_t g_bullet_triangles = 0;
void enter_zone(const char* name) {
  if (std::strcmp(name, "btConvexTriangleCallback::processTriangle") == 0) ++g_bullet_triangles;
}
void leave_zone() {}

enum class Midphase { bullet_bvh, boxtree_process_all, boxtree_algorithm };
const char* name(Midphase m) {
  switch (m) {
    case Midphase::bullet_bvh:
      return "bullet btBvhTriangleMeshShape";
    case Midphase::boxtree_process_all:
      return "boxtree via processAllTriangles";
    default:
      return "boxtree algorithm";
  }
}

struct Result {
  double collision_ms_per_step = 0, step_ms = 0, contacts_per_step = 0, triangles_per_step = 0;
  int below_terrain = 0;
};

Result run(Midphase midphase, const boxtree::TriangleMesh& terrain, const std::string& method, int bodies, int steps,
           std::uint64_t seed) {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  TimedWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, 0, -9.81f));
  if (midphase != Midphase::bullet_bvh) {
    boxtree::bullet::AlgorithmSettings settings;
    settings.convexAlgorithm = midphase == Midphase::boxtree_algorithm;
    boxtree::bullet::registerBoxtreeAlgorithms(&dispatcher, settings);
  }
  // Bullet's own shape reads the mesh through an interface; both get the same btScalar vertices.
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  for (const auto& v : terrain.vertices)
    for (int k = 0; k < 3; ++k) vertices.push_back(btScalar(v[k]));
  for (const auto& t : terrain.triangles)
    for (auto v : t) indices.push_back(int(v));
  btTriangleIndexVertexArray array(int(terrain.triangles.size()), indices.data(), 3 * sizeof(int),
                                   int(terrain.vertices.size()), vertices.data(), 3 * sizeof(btScalar));
  std::unique_ptr<btCollisionShape> ground;
  const boxtree::bullet::BoxtreeMeshShape* boxtree_shape = nullptr;
  if (midphase == Midphase::bullet_bvh) {
    ground = std::make_unique<btBvhTriangleMeshShape>(&array, true);
  } else {
    auto s = std::make_unique<boxtree::bullet::BoxtreeMeshShape>(array, method);
    boxtree_shape = s.get();
    ground = std::move(s);
  }
  btRigidBody ground_body(0, nullptr, ground.get());
  world.addRigidBody(&ground_body);

  // The tests' and benchmarks' one generator (generate.h's splitmix64): the same scene with every
  // standard library.
  boxtree::Random rng(seed);
  const auto size = [&rng] { return float(rng.uniform(0.3, 0.8)); };
  const auto unit = [&rng] { return float(rng.uniform()); };
  // Several draws never share one call: the order of a call's arguments is unspecified (gcc
  // evaluates them last first, clang first first). They are drawn one per statement (in the order
  // gcc gave the former one-call forms, last argument first), the same on both compilers.
  const auto size_vector = [&](float offset) {
    const float z = size() + offset;
    const float y = size() + offset;
    const float x = size() + offset;
    return btVector3(x, y, z);
  };
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> rigid;
  boxtree::Vec3 lo = terrain.vertices.front(), hi = lo;
  for (const auto& v : terrain.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  for (int i = 0; i < bodies; ++i) {
    switch (i % 5) {
      case 0:
        shapes.push_back(std::make_unique<btSphereShape>(size()));
        break;
      case 1:
        shapes.push_back(std::make_unique<btBoxShape>(size_vector(0)));
        break;
      case 2: {
        const float height = size() * 1.5f;  // before the radius: see above
        shapes.push_back(std::make_unique<btCapsuleShapeZ>(size() * 0.7f, height));
        break;
      }
      case 3:
        shapes.push_back(std::make_unique<btCylinderShapeZ>(size_vector(0)));
        break;
      default: {
        auto hull = std::make_unique<btConvexHullShape>();
        for (int k = 0; k < 12; ++k) hull->addPoint(size_vector(-0.55f), false);
        hull->recalcLocalAabb();
        shapes.push_back(std::move(hull));
      }
    }
    btVector3 inertia;
    shapes.back()->calculateLocalInertia(1, inertia);
    const btScalar pz = btScalar(20 + 10 * unit());  // z first: see above
    const btScalar py = btScalar(lo.y() + (hi.y() - lo.y()) * (0.1 + 0.8 * unit()));
    const btScalar px = btScalar(lo.x() + (hi.x() - lo.x()) * (0.1 + 0.8 * unit()));
    const btVector3 p(px, py, pz);
    btRigidBody::btRigidBodyConstructionInfo info(1, nullptr, shapes.back().get(), inertia);
    info.m_startWorldTransform.setOrigin(p);
    rigid.push_back(std::make_unique<btRigidBody>(info));
    rigid.back()->setRollingFriction(0.05f);
    rigid.back()->setDamping(0.05f, 0.3f);
    world.addRigidBody(rigid.back().get());
  }

  g_bullet_triangles = 0;
  if (boxtree_shape) boxtree_shape->resetCounters();
  double contacts = 0;
  const auto t0 = Clock::now();
  for (int s = 0; s < steps; ++s) {
    world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m)
      contacts += dispatcher.getManifoldByIndexInternal(m)->getNumContacts();
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  Result r;
  r.collision_ms_per_step = 1000 * world.collision_seconds / steps;
  r.step_ms = 1000 * seconds / steps;
  r.contacts_per_step = contacts / steps;
  std::uint64_t triangles = g_bullet_triangles;
  if (boxtree_shape) triangles += boxtree_shape->counters().narrowphase_triangles;
  r.triangles_per_step = double(triangles) / steps;
  for (auto& b : rigid) {
    if (b->getCenterOfMassPosition().z() < -1) ++r.below_terrain;
    world.removeRigidBody(b.get());
  }
  world.removeRigidBody(&ground_body);
  return r;
}

// Mesh vs mesh: small closed meshes ("rocks") dropped on the terrain. Bullet's way is GImpact
// (btGImpactMeshShape rocks on a btBvhTriangleMeshShape terrain); boxtree's is BoxtreeMeshShape
// for both, with the mesh-mesh algorithm.
struct RockResult {
  double collision_ms_per_step = 0, contacts_per_step = 0, final_speed = 0;
  int below_terrain = 0;
};

RockResult run_rocks(bool boxtree, const boxtree::TriangleMesh& terrain, const std::string& method, int rocks,
                     int steps, std::uint64_t seed,
                     boxtree::MeshContactPolicy policy = boxtree::bullet::AlgorithmSettings{}.meshContacts) {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  TimedWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, 0, -9.81f));
  if (boxtree) {
    boxtree::bullet::AlgorithmSettings settings;
    settings.meshContacts = policy;
    boxtree::bullet::registerBoxtreeAlgorithms(&dispatcher, settings);
  } else {
    btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher);
  }
  struct Arrays {
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    explicit Arrays(const boxtree::TriangleMesh& m) {
      for (const auto& v : m.vertices)
        for (int k = 0; k < 3; ++k) vertices.push_back(btScalar(v[k]));
      for (const auto& t : m.triangles)
        for (auto v : t) indices.push_back(int(v));
      array = std::make_unique<btTriangleIndexVertexArray>(int(m.triangles.size()), indices.data(),
                                                           3 * int(sizeof(int)), int(m.vertices.size()),
                                                           vertices.data(), 3 * int(sizeof(btScalar)));
    }
  };
  Arrays ground_arrays(terrain);
  std::unique_ptr<btCollisionShape> ground;
  if (boxtree) {
    ground = std::make_unique<boxtree::bullet::BoxtreeMeshShape>(*ground_arrays.array, method);
  } else {
    ground = std::make_unique<btBvhTriangleMeshShape>(ground_arrays.array.get(), true);
  }
  btRigidBody ground_body(0, nullptr, ground.get());
  world.addRigidBody(&ground_body);

  std::vector<std::unique_ptr<Arrays>> rock_arrays;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  boxtree::Random rng(seed);  // generate.h's splitmix64, as above
  const auto unit = [&rng] { return float(rng.uniform()); };
  boxtree::Vec3 lo = terrain.vertices.front(), hi = lo;
  for (const auto& v : terrain.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  for (int i = 0; i < rocks; ++i) {
    auto mesh = boxtree::make_bumpy_sphere(10, 6, 0.3, seed + std::uint64_t(i));
    rock_arrays.push_back(std::make_unique<Arrays>(mesh));
    if (boxtree) {
      shapes.push_back(std::make_unique<boxtree::bullet::BoxtreeMeshShape>(*rock_arrays.back()->array, method));
    } else {
      auto gimpact = std::make_unique<btGImpactMeshShape>(rock_arrays.back()->array.get());
      gimpact->updateBound();
      shapes.push_back(std::move(gimpact));
    }
    btVector3 inertia;
    shapes.back()->calculateLocalInertia(2, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(2, nullptr, shapes.back().get(), inertia);
    // z first, then y, then x: gcc's order for the former btVector3 of three draws.
    const btScalar z = btScalar(hi.z() + 3 + 3 * unit());
    const btScalar y = btScalar(lo.y() + (hi.y() - lo.y()) * (0.3 + 0.4 * unit()));
    const btScalar x = btScalar(lo.x() + (hi.x() - lo.x()) * (0.3 + 0.4 * unit()));
    info.m_startWorldTransform.setOrigin(btVector3(x, y, z));
    bodies.push_back(std::make_unique<btRigidBody>(info));
    bodies.back()->setRollingFriction(0.1f);
    world.addRigidBody(bodies.back().get());
  }
  double contacts = 0;
  for (int s = 0; s < steps; ++s) {
    world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    for (int m = 0; m < dispatcher.getNumManifolds(); ++m)
      contacts += dispatcher.getManifoldByIndexInternal(m)->getNumContacts();
  }
  RockResult r;
  r.collision_ms_per_step = 1000 * world.collision_seconds / steps;
  r.contacts_per_step = contacts / steps;
  for (auto& b : bodies) {
    r.final_speed = std::max(r.final_speed, double(b->getLinearVelocity().length()));
    if (b->getCenterOfMassPosition().z() < lo.z() - 1) ++r.below_terrain;
    world.removeRigidBody(b.get());
  }
  world.removeRigidBody(&ground_body);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Bullet drop scene: Bullet's BVH vs boxtree, per-step collision time and contacts"};
  int bodies = 500, cells = 256, steps = 300;
  std::uint64_t seed = 1;
  std::string method = "aabb";
  app.add_option("--bodies", bodies, "bodies dropped")->check(CLI::Range(1, 100000));
  app.add_option("--cells", cells, "terrain cells per side (2 facets per cell)")->check(CLI::Range(2, 4096));
  app.add_option("--steps", steps, "steps of 1/60 s")->check(CLI::Range(1, 100000));
  app.add_option("--method", method, "boxtree hierarchy method");
  app.add_option("--seed", seed, "random seed");
  int rocks = 20;
  app.add_option("--rocks", rocks, "closed meshes dropped for the mesh-vs-mesh scene (0: skip)")
      ->check(CLI::Range(0, 10000));
  std::string mesh_contacts;
  app.add_option("--mesh-contacts", mesh_contacts, "boxtree's mesh-vs-mesh contacts: triangle-pairs or face-normals")
      ->check(CLI::IsMember({"triangle-pairs", "face-normals"}));
  CLI11_PARSE(app, argc, argv);

  btSetCustomEnterProfileZoneFunc(enter_zone);
  btSetCustomLeaveProfileZoneFunc(leave_zone);
  const auto terrain = boxtree::make_terrain(cells, cells, seed, 200, 20);
  std::printf("terrain %zu facets, %d bodies, %d steps, method %s (Bullet %s precision)\n", terrain.facet_count(),
              bodies, steps, method.c_str(), sizeof(btScalar) == 8 ? "double" : "single");
  std::printf("%-34s %12s %10s %10s %14s %8s\n", "midphase", "collide ms", "step ms", "contacts", "tris to narrow",
              "fell");
  Result base;
  for (Midphase m : {Midphase::bullet_bvh, Midphase::boxtree_process_all, Midphase::boxtree_algorithm}) {
    const Result r = run(m, terrain, method, bodies, steps, seed);
    if (m == Midphase::bullet_bvh) base = r;
    std::printf("%-34s %12.3f %10.3f %10.1f %14.1f %8d\n", name(m), r.collision_ms_per_step, r.step_ms,
                r.contacts_per_step, r.triangles_per_step, r.below_terrain);
    if (m != Midphase::bullet_bvh) {
      std::printf("%-34s %11.2fx %9.2fx %9.2fx %13.2fx\n", "  ratio to bullet",
                  r.collision_ms_per_step / base.collision_ms_per_step, r.step_ms / base.step_ms,
                  r.contacts_per_step / base.contacts_per_step, r.triangles_per_step / base.triangles_per_step);
    }
  }
  if (rocks > 0) {
    const auto small = boxtree::make_terrain(64, 64, seed, 40, 3);
    std::printf("\nmesh vs mesh: %d rocks (%zu facets each) on a %zu-facet terrain, %d steps\n", rocks,
                boxtree::make_bumpy_sphere(10, 6, 0.3, 0).facet_count(), small.facet_count(), steps);
    std::printf("%-34s %12s %10s %16s %8s\n", "pair", "collide ms", "contacts", "max final speed", "fell");
    const RockResult g = run_rocks(false, small, method, rocks, steps, seed);
    boxtree::MeshContactPolicy policy = boxtree::bullet::AlgorithmSettings{}.meshContacts;
    if (!mesh_contacts.empty())
      policy = mesh_contacts == "face-normals" ? boxtree::MeshContactPolicy::face_normals
                                               : boxtree::MeshContactPolicy::triangle_pairs;
    const RockResult b = run_rocks(true, small, method, rocks, steps, seed, policy);
    std::printf("%-34s %12.3f %10.1f %16.3f %8d\n", "bullet GImpact rocks on bvh", g.collision_ms_per_step,
                g.contacts_per_step, g.final_speed, g.below_terrain);
    std::printf("%-34s %12.3f %10.1f %16.3f %8d\n", "boxtree rocks on boxtree", b.collision_ms_per_step,
                b.contacts_per_step, b.final_speed, b.below_terrain);
    std::printf("%-34s %11.2fx %9.2fx\n", "  ratio to GImpact", b.collision_ms_per_step / g.collision_ms_per_step,
                b.contacts_per_step / g.contacts_per_step);
  }
  return 0;
}
