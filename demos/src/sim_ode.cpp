// SPDX-License-Identifier: MIT
// The scene in ODE: the terrain as a static triangle mesh, the bodies as ODE's primitives,
// convexes and, for the small meshes, triangle meshes attached to bodies.
//   builtin: dCreateTriMesh (OPCODE) for the terrain and the meshes.
//   boxtree: dCreateBoxtreeMesh (boxtree::ode) for both; convexes are registered with the
//            adapter, which needs their points.
#include <ode/ode.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <unordered_map>

#include "boxtree/error.h"
#include "sim.h"

#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
#include "boxtree/ode/boxtree_geom.h"
#endif

namespace demo {

bool have_ode_adapter() { return BOXTREE_DEMO_HAVE_ODE_ADAPTER + 0 != 0; }

namespace {

constexpr int kContactBuffer = 64;  // the largest SimOptions::max_contacts_per_pair

// Arrays ODE keeps pointers into (trimesh data, convex planes and polygons).
struct OdeMeshData {
  std::vector<dReal> vertices;
  std::vector<dTriIndex> indices;
  dTriMeshDataID data = nullptr;
  ~OdeMeshData() {
    if (data) dGeomTriMeshDataDestroy(data);
  }
};

struct OdeConvexData {
  std::vector<dReal> planes, points;
  std::vector<unsigned> polygons;
};

class OdeSimulation final : public Simulation {
 public:
  OdeSimulation(const Scene& scene, const SimOptions& options)
      : boxtree_(options.boxtree_midphase),
        max_contacts_(options.max_contacts_per_pair),
        mesh_contacts_(options.mesh_contacts),
        mesh_coherence_(options.mesh_coherence),
        convex_coherence_(options.convex_coherence) {
    if (max_contacts_ < 1 || max_contacts_ > kContactBuffer)
      throw boxtree::Error("max_contacts_per_pair must be 1 to " + std::to_string(kContactBuffer));
#if !BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_) throw boxtree::Error("the ODE adapter (boxtree::ode) was not built; use --midphase builtin");
#endif
    dInitODE2(0);
    dAllocateODEDataForThread(dAllocateMaskAll);
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_) dBoxtreeInit();  // after dInitODE2, which clears the collider table
#endif
    // Quickstep shuffles its constraint rows with ODE's global random generator.
    dRandSetSeed(static_cast<unsigned long>(options.seed));
    world_ = dWorldCreate();
    dWorldSetGravity(world_, 0, 0, -9.81);
    dWorldSetQuickStepNumIterations(world_, 30);
    dWorldSetCFM(world_, 1e-5);
    dWorldSetERP(world_, 0.2);
    dWorldSetContactMaxCorrectingVel(world_, 3);
    dWorldSetContactSurfaceLayer(world_, 0.002);
    dWorldSetAngularDamping(world_, 0.02);  // round things would roll across the whole bowl
    dWorldSetAutoDisableFlag(world_, options.sleeping ? 1 : 0);
    space_ = dHashSpaceCreate(nullptr);
    dHashSpaceSetLevels(space_, -2, 4);
    contacts_group_ = dJointGroupCreate(0);

    terrain_ = create_mesh_geom(scene.terrain, options.method);
    for (const BodySpec& spec : scene.bodies) {
      dBodyID body = dBodyCreate(world_);
      dMass mass;
      dGeomID geom = nullptr;
      const dReal m = spec.mass;
      switch (spec.shape) {
        case Shape::sphere:
          geom = dCreateSphere(space_, spec.radius);
          dMassSetSphereTotal(&mass, m, spec.radius);
          break;
        case Shape::box:
          geom = dCreateBox(space_, 2 * spec.half_extents.x(), 2 * spec.half_extents.y(), 2 * spec.half_extents.z());
          dMassSetBoxTotal(&mass, m, 2 * spec.half_extents.x(), 2 * spec.half_extents.y(), 2 * spec.half_extents.z());
          break;
        case Shape::capsule:
          geom = dCreateCapsule(space_, spec.radius, 2 * spec.half_length);
          dMassSetCapsuleTotal(&mass, m, 3, spec.radius, 2 * spec.half_length);
          break;
        case Shape::cylinder:
          geom = dCreateCylinder(space_, spec.radius, 2 * spec.half_length);
          dMassSetCylinderTotal(&mass, m, 3, spec.radius, 2 * spec.half_length);
          break;
        case Shape::convex:
          geom = create_convex(*spec.mesh);
          // The mass model of the hull's bounding box: close enough for a demo.
          dMassSetBoxTotal(&mass, m, 2 * spec.half_extents.x(), 2 * spec.half_extents.y(), 2 * spec.half_extents.z());
          break;
        case Shape::mesh:
          geom = create_mesh_geom(spec.mesh, options.method);
          dMassSetBoxTotal(&mass, m, 2 * spec.half_extents.x(), 2 * spec.half_extents.y(), 2 * spec.half_extents.z());
          break;
      }
      shape_of_[geom] = spec.shape;
      dBodySetMass(body, &mass);
      dGeomSetBody(geom, body);
      dBodySetPosition(body, spec.position.x(), spec.position.y(), spec.position.z());
      const dQuaternion q = {spec.orientation.w(), spec.orientation.x(), spec.orientation.y(), spec.orientation.z()};
      dBodySetQuaternion(body, q);
      bodies_.push_back(body);
    }
  }

  ~OdeSimulation() override {
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    for (dGeomID convex : convex_geoms_) boxtree::ode::forget_convex(convex);
    for (auto& data : mesh_data_)
      if (data->data) boxtree::ode::forget_trimesh_data(data->data);
#endif
    dJointGroupDestroy(contacts_group_);
    dSpaceDestroy(space_);  // destroys its geoms (cleanup mode is on by default)
    dWorldDestroy(world_);
    mesh_data_.clear();
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_) dBoxtreeClose();
#endif
    dCloseODE();
  }

  void step(Real dt) override {
    contacts_ = 0;
    const auto start = std::chrono::steady_clock::now();
    dSpaceCollide(space_, this, &OdeSimulation::near_callback);
    collision_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    dWorldQuickStep(world_, dt);
    dJointGroupEmpty(contacts_group_);
  }

  std::vector<Pose> poses() const override {
    std::vector<Pose> out;
    out.reserve(bodies_.size());
    for (dBodyID body : bodies_) {
      const dReal* p = dBodyGetPosition(body);
      const dReal* q = dBodyGetQuaternion(body);
      out.push_back({Vec3(p[0], p[1], p[2]), Quat(q[0], q[1], q[2], q[3]).normalized()});
    }
    return out;
  }

  int contacts() const override { return contacts_; }
  double collision_seconds() const override { return collision_seconds_; }
  std::uint64_t narrowphase_triangles() const override {
    std::uint64_t total = builtin_triangles_;
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_)
      for (dGeomID geom : mesh_geoms_) total += boxtree::ode::geom_counters(geom).candidate_facets;
#endif
    return total;
  }
  PairState pair_state() const override {
    PairState state;
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_) {
      const boxtree::ode::ConvexPairCacheInfo convex = boxtree::ode::convex_pair_cache_info();
      const boxtree::ode::MeshPairCacheInfo mesh = boxtree::ode::mesh_pair_cache_info();
      state.pairs = convex.pairs + mesh.pairs;
      state.bytes = convex.bytes + mesh.bytes;
    }
#endif
    return state;
  }
  std::uint64_t mesh_volume_tests() const override {
    std::uint64_t total = 0;
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    if (boxtree_)
      for (dGeomID geom : mesh_geoms_) total += boxtree::ode::geom_counters(geom).mesh_volume_tests;
#endif
    return total;
  }
  std::vector<PairKindTime> collision_breakdown() const override {
    std::vector<PairKindTime> out;
    for (int k = 0; k < kPairKinds; ++k) {
      if (pair_time_[k].calls == 0) continue;
      PairKindTime t = pair_time_[k];
      t.kind = k == kBodyBody ? "body-body" : std::string("terrain-") + shape_name(Shape(k));
      out.push_back(t);
    }
    return out;
  }
  bool set_poses(const std::vector<Pose>& poses) override {
    if (poses.size() != bodies_.size()) return false;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Pose& pose = poses[i];
      dBodySetPosition(bodies_[i], pose.position.x(), pose.position.y(), pose.position.z());
      const dQuaternion q = {pose.orientation.w(), pose.orientation.x(), pose.orientation.y(), pose.orientation.z()};
      dBodySetQuaternion(bodies_[i], q);
      dBodySetLinearVel(bodies_[i], 0, 0, 0);
      dBodySetAngularVel(bodies_[i], 0, 0, 0);
    }
    dReal box[6];
    for (const auto& entry : shape_of_) dGeomGetAABB(entry.first, box);  // recomputed for the moved geoms
    return true;
  }
  std::vector<PairKindTime> replay_terrain_pairs(int repeats, const Shape* only) override {
    PairKindTime saved[kPairKinds];
    std::copy(std::begin(pair_time_), std::end(pair_time_), std::begin(saved));
    std::fill(std::begin(pair_time_), std::end(pair_time_), PairKindTime{});
    for (int r = 0; r < repeats; ++r)
      for (const auto& [geom, shape] : shape_of_)
        if (!only || shape == *only) timed_collide(terrain_, geom);
    std::vector<PairKindTime> out = collision_breakdown();
    std::copy(std::begin(saved), std::end(saved), std::begin(pair_time_));
    return out;
  }
  std::string midphase_description() const override {
    return boxtree_ ? "dCreateBoxtreeMesh (terrain and meshes)" : "dCreateTriMesh, OPCODE (terrain and meshes)";
  }

 private:
  // OPCODE's per-triangle callback: called for every triangle it hands to a collider; 1 = keep it.
  static int count_triangle(dGeomID mesh, dGeomID, int) {
    ++static_cast<OdeSimulation*>(dGeomGetData(mesh))->builtin_triangles_;
    return 1;
  }

  dGeomID create_mesh_geom(const std::shared_ptr<const TriangleMesh>& mesh, const std::string& method) {
    if (boxtree_) {
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
      dGeomID geom = dCreateBoxtreeMesh(space_, mesh, method.c_str());
      boxtree::ode::GeomSettings settings = boxtree::ode::geom_settings(geom);
      if (!mesh_contacts_.empty())
        settings.mesh_contacts = mesh_contacts_ == "face-normals" ? boxtree::MeshContactPolicy::face_normals
                                                                  : boxtree::MeshContactPolicy::triangle_pairs;
      settings.mesh_coherence = mesh_coherence_;
      settings.convex_coherence = convex_coherence_;
      boxtree::ode::set_geom_settings(geom, settings);
      mesh_geoms_.push_back(geom);
      return geom;
#endif
    }
    (void)method;
    auto data = std::make_unique<OdeMeshData>();
    for (const Vec3& v : mesh->vertices)
      for (int k = 0; k < 3; ++k) data->vertices.push_back(v[k]);
    for (const auto& t : mesh->triangles)
      for (auto v : t) data->indices.push_back(dTriIndex(v));
    data->data = dGeomTriMeshDataCreate();
    dGeomTriMeshDataBuildDouble(data->data, data->vertices.data(), 3 * sizeof(dReal), int(mesh->vertices.size()),
                                data->indices.data(), int(data->indices.size()), 3 * sizeof(dTriIndex));
    // ODE's convex-vs-trimesh collider needs the face angles (it aborts without them).
    dGeomTriMeshDataPreprocess2(data->data, 1U << dTRIDATAPREPROCESS_BUILD_FACE_ANGLES, nullptr);
    dGeomID geom = dCreateTriMesh(space_, data->data, &OdeSimulation::count_triangle, nullptr, nullptr);
    dGeomSetData(geom, this);
    mesh_geoms_.push_back(geom);
    mesh_data_.push_back(std::move(data));
    return geom;
  }

  dGeomID create_convex(const TriangleMesh& hull) {
    auto data = std::make_unique<OdeConvexData>();
    for (const Vec3& v : hull.vertices)
      for (int k = 0; k < 3; ++k) data->points.push_back(v[k]);
    for (std::size_t f = 0; f < hull.facet_count(); ++f) {
      const auto& t = hull.triangles[f];
      const Vec3 n = (hull.corner(boxtree::FacetId(f), 1) - hull.corner(boxtree::FacetId(f), 0))
                         .cross(hull.corner(boxtree::FacetId(f), 2) - hull.corner(boxtree::FacetId(f), 0))
                         .normalized();
      data->planes.insert(data->planes.end(), {n.x(), n.y(), n.z(), n.dot(hull.corner(boxtree::FacetId(f), 0))});
      data->polygons.insert(data->polygons.end(), {3u, t[0], t[1], t[2]});
    }
    const unsigned planes = unsigned(hull.facet_count()), points = unsigned(hull.vertices.size());
    dGeomID geom = nullptr;
    if (boxtree_) {
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
      // The adapter keeps its own copy of the points and faces (ODE has no getter for them).
      geom = boxtree::ode::create_convex(space_, data->planes.data(), planes, data->points.data(), points,
                                         data->polygons.data());
      convex_geoms_.push_back(geom);
#endif
    } else {
      geom = dCreateConvex(space_, data->planes.data(), planes, data->points.data(), points, data->polygons.data());
    }
    convex_data_.push_back(std::move(data));
    return geom;
  }

  static void near_callback(void* self, dGeomID a, dGeomID b) { static_cast<OdeSimulation*>(self)->collide_pair(a, b); }

  void collide_pair(dGeomID a, dGeomID b) {
    dBodyID body_a = dGeomGetBody(a), body_b = dGeomGetBody(b);
    if (!body_a && !body_b) return;
    dContact contact[kContactBuffer];
    const int n = timed_collide(a, b, contact);
    for (int i = 0; i < n; ++i) {
      contact[i].surface.mode = dContactApprox1 | dContactRolling;
      contact[i].surface.mu = 0.6;
      contact[i].surface.rho = 0.002;  // rolling friction
      contact[i].surface.rho2 = 0;
      contact[i].surface.rhoN = 0;
      dJointID joint = dJointCreateContact(world_, contacts_group_, &contact[i]);
      dJointAttach(joint, body_a, body_b);
    }
    contacts_ += n;
  }

  // dCollide(a, b), its time, contacts and triangles added to pair_time_.
  int timed_collide(dGeomID a, dGeomID b, dContact* contact = nullptr) {
    dContact scratch[kContactBuffer];
    if (!contact) contact = scratch;
    const std::uint64_t triangles_before = pair_triangles(a, b);
    const auto start = std::chrono::steady_clock::now();
    const int n = dCollide(a, b, max_contacts_, &contact[0].geom, sizeof(dContact));
    PairKindTime& time = pair_time_[pair_kind(a, b)];
    time.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++time.calls;
    time.contacts += std::uint64_t(n);
    time.triangles += pair_triangles(a, b) - triangles_before;
    return n;
  }

  // The index into pair_time_: the body's shape for a pair with the terrain, else kBodyBody.
  static constexpr int kBodyBody = int(Shape::mesh) + 1, kPairKinds = kBodyBody + 1;
  int pair_kind(dGeomID a, dGeomID b) const {
    if (a != terrain_ && b != terrain_) return kBodyBody;
    const auto it = shape_of_.find(a == terrain_ ? b : a);
    return it == shape_of_.end() ? kBodyBody : int(it->second);
  }

  // The narrowphase triangles counted so far for the meshes of the pair (a, b).
  std::uint64_t pair_triangles(dGeomID a, dGeomID b) const {
    if (!boxtree_) return builtin_triangles_;
    std::uint64_t total = 0;
#if BOXTREE_DEMO_HAVE_ODE_ADAPTER
    for (dGeomID g : {a, b}) {
      const auto it = shape_of_.find(g);
      if (g == terrain_ || (it != shape_of_.end() && it->second == Shape::mesh))
        total += boxtree::ode::geom_counters(g).candidate_facets;
    }
#else
    (void)a, (void)b;
#endif
    return total;
  }

  bool boxtree_;
  int max_contacts_;
  std::string mesh_contacts_;                    // SimOptions::mesh_contacts
  bool mesh_coherence_ = false;                  // SimOptions::mesh_coherence
  bool convex_coherence_ = true;                 // SimOptions::convex_coherence
  std::unordered_map<dGeomID, Shape> shape_of_;  // every body's geom
  PairKindTime pair_time_[kPairKinds];
  dWorldID world_ = nullptr;
  dSpaceID space_ = nullptr;
  dJointGroupID contacts_group_ = nullptr;
  dGeomID terrain_ = nullptr;
  std::vector<dBodyID> bodies_;
  std::vector<std::unique_ptr<OdeMeshData>> mesh_data_;
  std::vector<std::unique_ptr<OdeConvexData>> convex_data_;
  std::vector<dGeomID> convex_geoms_;
  int contacts_ = 0;
  double collision_seconds_ = 0;
  std::vector<dGeomID> mesh_geoms_;      // terrain and mesh bodies
  std::uint64_t builtin_triangles_ = 0;  // counted by count_triangle (builtin only)
};

}  // namespace

std::unique_ptr<Simulation> make_ode_simulation(const Scene& scene, const SimOptions& options) {
  return std::make_unique<OdeSimulation>(scene, options);
}

}  // namespace demo
