// SPDX-License-Identifier: MIT
// The scene in Bullet: the terrain as a static triangle-mesh shape, the bodies as Bullet's
// convex primitives and, for the small meshes, dynamic triangle-mesh shapes.
//   builtin: btBvhTriangleMeshShape (terrain) and btGImpactMeshShape (dynamic meshes; Bullet's
//            only moving concave shape), with GImpact's algorithm registered.
//   boxtree: boxtree::bullet::BoxtreeMeshShape for both, with the adapter's algorithms.
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <map>
#include <string>

#include "boxtree/error.h"
#include "sim.h"

#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
#include "boxtree/bullet/algorithms.h"
#include "boxtree/bullet/mesh_shape.h"
#endif

namespace demo {

bool have_bullet_adapter() { return BOXTREE_DEMO_HAVE_BULLET_ADAPTER + 0 != 0; }

namespace {

btVector3 bt(const Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }

// Times collision detection inside each step: the world's one virtual entry for it.
class TimedWorld : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;
  void performDiscreteCollisionDetection() override {
    const auto start = std::chrono::steady_clock::now();
    btDiscreteDynamicsWorld::performDiscreteCollisionDetection();
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  double seconds = 0;
};

// Bullet's own convex-vs-mesh path opens a profile zone per triangle it hands to the narrowphase;
// Debian's Bullet has no profiler, but the zone hooks are live, so counting the zones counts the
// triangles. The hooks are global: one counter for all builtin simulations of the process.
std::atomic<std::uint64_t> g_builtin_triangles{0};
void enter_zone(const char* name) {
  if (std::strcmp(name, "btConvexTriangleCallback::processTriangle") == 0) ++g_builtin_triangles;
}
void leave_zone() {}

// Times each pair's collision (Bullet's default near callback: the pair's algorithm, midphase and
// narrowphase) by the kind of pair, as ODE's near callback does (sim.h, collision_breakdown). The
// same few loads and two clock reads per pair for both midphases.
class TimedDispatcher : public btCollisionDispatcher {
 public:
  // Kinds: a body's Shape (its pair with the terrain), kBodyBody for two bodies.
  static constexpr int kBodyBody = int(Shape::mesh) + 1, kPairKinds = kBodyBody + 1;

  TimedDispatcher(btCollisionConfiguration* configuration, bool boxtree)
      : btCollisionDispatcher(configuration), boxtree_(boxtree) {
    setNearCallback(&TimedDispatcher::timed_near_callback);
  }
  // Bodies carry their Shape in the user index; the terrain is told apart by its address.
  void set_terrain(const btCollisionObject* terrain) { terrain_ = terrain; }
  const Simulation::PairKindTime& time(int kind) const { return time_[kind]; }

 private:
  static void timed_near_callback(btBroadphasePair& pair, btCollisionDispatcher& dispatcher,
                                  const btDispatcherInfo& info) {
    auto& self = static_cast<TimedDispatcher&>(dispatcher);
    const auto* a = static_cast<const btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    const auto* b = static_cast<const btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    const int kind = a == self.terrain_ ? b->getUserIndex() : b == self.terrain_ ? a->getUserIndex() : kBodyBody;
    const std::uint64_t triangles_before = self.pair_triangles(a, b);
    const auto start = std::chrono::steady_clock::now();
    btCollisionDispatcher::defaultNearCallback(pair, dispatcher, info);
    Simulation::PairKindTime& time = self.time_[kind >= 0 && kind < kPairKinds ? kind : kBodyBody];
    time.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++time.calls;
    time.triangles += self.pair_triangles(a, b) - triangles_before;
    if (pair.m_algorithm) {
      self.manifolds_.resize(0);
      pair.m_algorithm->getAllContactManifolds(self.manifolds_);
      for (int i = 0; i < self.manifolds_.size(); ++i)
        time.contacts += std::uint64_t(self.manifolds_[i]->getNumContacts());
    }
  }

  // The narrowphase triangles counted so far for the meshes of the pair (as narrowphase_triangles()).
  std::uint64_t pair_triangles(const btCollisionObject* a, const btCollisionObject* b) const {
    if (!boxtree_) return g_builtin_triangles.load(std::memory_order_relaxed);
    std::uint64_t total = 0;
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    for (const btCollisionObject* object : {a, b})
      if (object->getCollisionShape()->getShapeType() == FAST_CONCAVE_MESH_PROXYTYPE)
        total += static_cast<const boxtree::bullet::BoxtreeMeshShape*>(object->getCollisionShape())
                     ->counters()
                     .narrowphase_triangles;
#else
    (void)a, (void)b;
#endif
    return total;
  }

  bool boxtree_;
  const btCollisionObject* terrain_ = nullptr;
  Simulation::PairKindTime time_[kPairKinds];
  btManifoldArray manifolds_;
};

// A triangle mesh as Bullet's striding interface; owns the arrays it points into.
struct BulletMeshData {
  explicit BulletMeshData(const TriangleMesh& mesh) {
    vertices.reserve(3 * mesh.vertices.size());
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(btScalar(v[k]));
    indices.reserve(3 * mesh.facet_count());
    for (const auto& t : mesh.triangles)
      for (auto v : t) indices.push_back(int(v));
    array = std::make_unique<btTriangleIndexVertexArray>(int(mesh.facet_count()), indices.data(), 3 * int(sizeof(int)),
                                                         int(mesh.vertices.size()), vertices.data(),
                                                         3 * int(sizeof(btScalar)));
  }
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;
};

class BulletSimulation final : public Simulation {
 public:
  BulletSimulation(const Scene& scene, const SimOptions& options) : boxtree_(options.boxtree_midphase) {
#if !BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    if (boxtree_) throw boxtree::Error("the Bullet adapter (boxtree::bullet) was not built; use --midphase builtin");
#endif
    if (!boxtree_) {
      btSetCustomEnterProfileZoneFunc(enter_zone);
      btSetCustomLeaveProfileZoneFunc(leave_zone);
      builtin_triangles_at_start_ = g_builtin_triangles.load();
    }
    btDefaultCollisionConstructionInfo info;
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    // The adapter's algorithms may be larger than Bullet's default pool element.
    if (boxtree_)
      info.m_customCollisionAlgorithmMaxElementSize =
          std::max(info.m_customCollisionAlgorithmMaxElementSize, boxtree::bullet::boxtreeAlgorithmMaxSize());
#endif
    configuration_ = std::make_unique<btDefaultCollisionConfiguration>(info);
    dispatcher_ = std::make_unique<TimedDispatcher>(configuration_.get(), boxtree_);
    // Before any body exists: Bullet caches an algorithm per overlapping pair.
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    if (boxtree_) {
      boxtree::bullet::AlgorithmSettings settings;
      if (!options.mesh_contacts.empty())
        settings.meshContacts = options.mesh_contacts == "face-normals" ? boxtree::MeshContactPolicy::face_normals
                                                                        : boxtree::MeshContactPolicy::triangle_pairs;
      settings.meshCoherence = options.mesh_coherence;
      settings.convexCoherence = options.convex_coherence;
      settings.hullFaces = options.hull_faces;
      boxtree::bullet::registerBoxtreeAlgorithms(dispatcher_.get(), settings);
    }
#endif
    if (!boxtree_) btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher_.get());
    broadphase_ = std::make_unique<btDbvtBroadphase>();
    solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
    world_ = std::make_unique<TimedWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(), configuration_.get());
    world_->setGravity(btVector3(0, 0, btScalar(-9.81)));

    // The terrain.
    btCollisionShape* terrain_shape = nullptr;
    if (boxtree_) {
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
      auto* shape = new boxtree::bullet::BoxtreeMeshShape(scene.terrain, options.method);
      // A terrain has a front: a body pressed past a facet's plane by the pile above it is pushed
      // back up, not through (two-sided, such a body falls through: see mesh_shape.h).
      shape->setTwoSided(false);
      terrain_shape = own(shape);
#endif
    } else {
      mesh_data_.push_back(std::make_unique<BulletMeshData>(*scene.terrain));
      terrain_shape = own(new btBvhTriangleMeshShape(mesh_data_.back()->array.get(), true));
    }
    btRigidBody::btRigidBodyConstructionInfo terrain_info(0, nullptr, terrain_shape);
    terrain_info.m_friction = 0.8;
    terrain_ = std::make_unique<btRigidBody>(terrain_info);
    dispatcher_->set_terrain(terrain_.get());
    world_->addRigidBody(terrain_.get());

    for (const BodySpec& spec : scene.bodies) {
      btCollisionShape* shape = nullptr;
      switch (spec.shape) {
        case Shape::sphere:
          shape = own(new btSphereShape(btScalar(spec.radius)));
          break;
        case Shape::box:
          shape = own(new btBoxShape(bt(spec.half_extents)));
          break;
        case Shape::capsule:
          shape = own(new btCapsuleShapeZ(btScalar(spec.radius), btScalar(2 * spec.half_length)));
          break;
        case Shape::cylinder:
          shape = own(new btCylinderShapeZ(
              btVector3(btScalar(spec.radius), btScalar(spec.radius), btScalar(spec.half_length))));
          break;
        case Shape::convex: {
          auto* hull = new btConvexHullShape();
          for (const Vec3& v : spec.mesh->vertices) hull->addPoint(bt(v), false);
          hull->recalcLocalAabb();
          if (boxtree_ && options.hull_faces) hull->initializePolyhedralFeatures();
          shape = own(hull);
          break;
        }
        case Shape::mesh:
          if (boxtree_) {
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
            shape = own(new boxtree::bullet::BoxtreeMeshShape(spec.mesh, options.method));
#endif
          } else {
            mesh_data_.push_back(std::make_unique<BulletMeshData>(*spec.mesh));
            auto* gimpact = new btGImpactMeshShape(mesh_data_.back()->array.get());
            gimpact->updateBound();
            shape = own(gimpact);
          }
          break;
      }
      btVector3 inertia(0, 0, 0);
      shape->calculateLocalInertia(btScalar(spec.mass), inertia);
      btTransform start;
      start.setOrigin(bt(spec.position));
      start.setRotation(btQuaternion(btScalar(spec.orientation.x()), btScalar(spec.orientation.y()),
                                     btScalar(spec.orientation.z()), btScalar(spec.orientation.w())));
      btRigidBody::btRigidBodyConstructionInfo body_info(btScalar(spec.mass), nullptr, shape, inertia);
      body_info.m_startWorldTransform = start;
      body_info.m_friction = 0.6;
      body_info.m_restitution = 0.1;
      // Round things would roll across the whole bowl without it.
      body_info.m_rollingFriction = 0.02;
      body_info.m_spinningFriction = 0.02;
      bodies_.push_back(std::make_unique<btRigidBody>(body_info));
      bodies_.back()->setUserIndex(int(spec.shape));  // the pair kind (TimedDispatcher, replays)
      if (!options.sleeping) bodies_.back()->setActivationState(DISABLE_DEACTIVATION);
      world_->addRigidBody(bodies_.back().get());
    }
  }

  ~BulletSimulation() override {
    for (auto& body : bodies_) world_->removeRigidBody(body.get());
    world_->removeRigidBody(terrain_.get());
  }

  void step(Real dt) override {
    world_->stepSimulation(btScalar(dt), 1, btScalar(dt));
    contacts_ = 0;
    for (int i = 0; i < dispatcher_->getNumManifolds(); ++i)
      contacts_ += dispatcher_->getManifoldByIndexInternal(i)->getNumContacts();
  }

  std::vector<Pose> poses() const override {
    std::vector<Pose> out;
    out.reserve(bodies_.size());
    for (const auto& body : bodies_) {
      const btTransform& t = body->getWorldTransform();
      const btQuaternion q = t.getRotation();
      out.push_back({Vec3(t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z()), Quat(q.w(), q.x(), q.y(), q.z())});
    }
    return out;
  }

  bool set_poses(const std::vector<Pose>& poses) override {
    if (poses.size() != bodies_.size()) return false;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      btTransform t;
      t.setOrigin(bt(poses[i].position));
      const Quat& q = poses[i].orientation;
      t.setRotation(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())));
      bodies_[i]->setWorldTransform(t);
      bodies_[i]->setInterpolationWorldTransform(t);
      bodies_[i]->setLinearVelocity(btVector3(0, 0, 0));
      bodies_[i]->setAngularVelocity(btVector3(0, 0, 0));
      bodies_[i]->activate(true);
    }
    // Bounds, broadphase pairs and each pair's algorithm for the new poses (not counted as
    // collision time of the simulation).
    const double seconds = world_->seconds;
    world_->performDiscreteCollisionDetection();
    world_->seconds = seconds;
    return true;
  }

  // Every broadphase pair of the terrain or a mesh body with another body, collided `repeats`
  // times by the pair's own algorithm (as btCollisionDispatcher::defaultNearCallback does), kinds
  // "terrain-<shape>" and "mesh-<shape>".
  std::vector<PairKindTime> replay_terrain_pairs(int repeats, const Shape* only) override {
    struct Pair {
      btBroadphasePair* pair;
      std::string kind;
    };
    std::vector<Pair> pairs;
    btOverlappingPairCache* cache = broadphase_->getOverlappingPairCache();
    btBroadphasePairArray& array = cache->getOverlappingPairArray();
    for (int i = 0; i < array.size(); ++i) {
      btBroadphasePair& pair = array[i];
      if (!pair.m_algorithm) continue;
      const auto* a = static_cast<const btCollisionObject*>(pair.m_pProxy0->m_clientObject);
      const auto* b = static_cast<const btCollisionObject*>(pair.m_pProxy1->m_clientObject);
      // 0: the terrain, 1: a body (its Shape in the user index), -1: anything else.
      const auto kind_of = [&](const btCollisionObject* o, Shape* shape) {
        if (o == terrain_.get()) return 0;
        const int index = o->getUserIndex();
        if (index < 0 || index > int(Shape::mesh)) return -1;
        *shape = Shape(index);
        return 1;
      };
      Shape sa{}, sb{};
      const int ka = kind_of(a, &sa), kb = kind_of(b, &sb);
      if (ka < 0 || kb < 0) continue;
      std::string kind;
      if (ka == 0 || kb == 0) {
        const Shape other = ka == 0 ? sb : sa;
        if (only && other != *only) continue;
        kind = std::string("terrain-") + shape_name(other);
      } else if (sa == Shape::mesh || sb == Shape::mesh) {
        const Shape other = sa == Shape::mesh ? sb : sa;
        if (only && other != *only) continue;
        kind = std::string("mesh-") + shape_name(other);
      } else {
        continue;
      }
      pairs.push_back({&pair, kind});
    }
    std::map<std::string, PairKindTime> kinds;
    btDispatcherInfo& info = world_->getDispatchInfo();
    btManifoldArray manifolds;
    for (int r = 0; r < repeats; ++r) {
      for (const Pair& p : pairs) {
        const auto* a = static_cast<const btCollisionObject*>(p.pair->m_pProxy0->m_clientObject);
        const auto* b = static_cast<const btCollisionObject*>(p.pair->m_pProxy1->m_clientObject);
        const btCollisionObjectWrapper wa(nullptr, a->getCollisionShape(), a, a->getWorldTransform(), -1, -1);
        const btCollisionObjectWrapper wb(nullptr, b->getCollisionShape(), b, b->getWorldTransform(), -1, -1);
        btManifoldResult result(&wa, &wb);
        const std::uint64_t triangles = narrowphase_triangles();
        const auto start = std::chrono::steady_clock::now();
        p.pair->m_algorithm->processCollision(&wa, &wb, info, &result);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        PairKindTime& t = kinds[p.kind];
        t.kind = p.kind;
        t.seconds += seconds;
        ++t.calls;
        t.triangles += narrowphase_triangles() - triangles;
        manifolds.resize(0);
        p.pair->m_algorithm->getAllContactManifolds(manifolds);
        for (int m = 0; m < manifolds.size(); ++m) t.contacts += std::uint64_t(manifolds[m]->getNumContacts());
      }
    }
    std::vector<PairKindTime> out;
    for (auto& [kind, t] : kinds) out.push_back(t);
    return out;
  }

  int contacts() const override { return contacts_; }
  double collision_seconds() const override { return world_->seconds; }
  std::uint64_t narrowphase_triangles() const override {
    if (!boxtree_) return g_builtin_triangles.load() - builtin_triangles_at_start_;
    std::uint64_t total = 0;
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    if (mesh_shapes_.empty())
      for (const auto& shape : shapes_)
        if (const auto* mesh = dynamic_cast<const boxtree::bullet::BoxtreeMeshShape*>(shape.get()))
          mesh_shapes_.push_back(mesh);
    for (const auto* mesh : mesh_shapes_) total += mesh->counters().narrowphase_triangles;
#endif
    return total;
  }
  std::uint64_t mesh_volume_tests() const override {
    std::uint64_t total = 0;
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
    if (boxtree_) {
      narrowphase_triangles();  // fills mesh_shapes_
      for (const auto* mesh : mesh_shapes_) total += mesh->counters().mesh_volume_tests;
    }
#endif
    return total;
  }
  std::vector<PairKindTime> collision_breakdown() const override {
    std::vector<PairKindTime> out;
    for (int k = 0; k < TimedDispatcher::kPairKinds; ++k) {
      PairKindTime t = dispatcher_->time(k);
      if (t.calls == 0) continue;
      t.kind = k == TimedDispatcher::kBodyBody ? "body-body" : std::string("terrain-") + shape_name(Shape(k));
      out.push_back(t);
    }
    return out;
  }
  std::string midphase_description() const override {
    return boxtree_ ? "boxtree::bullet::BoxtreeMeshShape (terrain and meshes)"
                    : "btBvhTriangleMeshShape (terrain), btGImpactMeshShape (meshes)";
  }

 private:
  btCollisionShape* own(btCollisionShape* shape) {
    shapes_.emplace_back(shape);
    return shape;
  }

  bool boxtree_;
  // Declared in construction order; destroyed in reverse (bodies before shapes before the world).
  std::unique_ptr<btDefaultCollisionConfiguration> configuration_;
  std::unique_ptr<TimedDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<TimedWorld> world_;
  std::vector<std::unique_ptr<BulletMeshData>> mesh_data_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::unique_ptr<btRigidBody> terrain_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
#if BOXTREE_DEMO_HAVE_BULLET_ADAPTER
  // The boxtree mesh shapes among shapes_ (filled on first use; shapes_ is complete by then).
  mutable std::vector<const boxtree::bullet::BoxtreeMeshShape*> mesh_shapes_;
#endif
  int contacts_ = 0;
  std::uint64_t builtin_triangles_at_start_ = 0;
};

}  // namespace

std::unique_ptr<Simulation> make_bullet_simulation(const Scene& scene, const SimOptions& options) {
  return std::make_unique<BulletSimulation>(scene, options);
}

}  // namespace demo
