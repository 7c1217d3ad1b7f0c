// SPDX-License-Identifier: MIT
#pragma once
// The drop scene, built twice: the scene library's terrain (demos/src/scene.h) as ODE's own
// dTriMesh in one world and as the boxtree geom in another, the same bodies dropped onto both.
// Shared by the scene tests and the timing report (test_drop.cpp).
#include <ode/ode.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "boxtree/generate.h"
#include "boxtree/ode/boxtree_geom.h"
#include "scene.h"

namespace boxtree::ode_test {

// The scene library's rough terrain of 40 x 40 cells (3200 facets), 40 m across and centred on
// the origin, heights within about 0..4 m: slopes gentle enough that the bodies stay where they
// land (with the rolling friction below). On it, 16 bodies of BodyMix::primitives_in_turn (four
// of each kind), one per column of a 4 x 4 grid 8 m apart, unrotated (the capsules lying), 1 m
// above the highest ground within 0.7 m of their column; density 1000 kg/m^3.
inline demo::SceneOptions drop_scene_options() {
  demo::SceneOptions options;
  options.terrain.cells = 40;
  options.terrain.kind = demo::TerrainKind::rough;
  options.bodies = 16;
  options.mix = demo::BodyMix::primitives_in_turn;
  options.layout.spacing = 8;
  options.layout.max_width = 24;
  options.layout.clearance = 1;
  options.layout.ground_reach = 0.7;
  options.layout.jitter = 0;
  options.layout.random_orientation = false;
  options.body_density = 1000;
  return options;
}
inline const demo::Scene& drop_scene() {
  static const demo::Scene scene = demo::make_scene(drop_scene_options(), 7);
  return scene;
}
inline std::shared_ptr<const TriangleMesh> scene_terrain() { return drop_scene().terrain; }

// ODE's own trimesh over the same vertices (double precision arrays; OPCODE keeps floats inside).
// The arrays must outlive the data object, since ODE does not copy them.
struct OdeTrimesh {
  std::vector<dReal> vertices;
  std::vector<dTriIndex> indices;
  dTriMeshDataID data = nullptr;
  dGeomID geom = nullptr;

  OdeTrimesh(dSpaceID space, const TriangleMesh& mesh) {
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(v[k]);
    for (const Triangle& t : mesh.triangles)
      for (VertexId v : t) indices.push_back(dTriIndex(v));
    data = dGeomTriMeshDataCreate();
    dGeomTriMeshDataBuildDouble(data, vertices.data(), 3 * int(sizeof(dReal)), int(mesh.vertices.size()),
                                indices.data(), int(indices.size()), 3 * int(sizeof(dTriIndex)));
    // ODE's convex-vs-trimesh needs the face angles (it aborts without them).
    dGeomTriMeshDataPreprocess2(data, 1U << dTRIDATAPREPROCESS_BUILD_FACE_ANGLES, nullptr);
    geom = dCreateTriMesh(space, data, nullptr, nullptr, nullptr);
  }
  ~OdeTrimesh() {
    if (geom) dGeomDestroy(geom);
    if (data) dGeomTriMeshDataDestroy(data);
  }
  OdeTrimesh(const OdeTrimesh&) = delete;
  OdeTrimesh& operator=(const OdeTrimesh&) = delete;
};

// Per step: contacts made and the time spent inside dCollide (the collision work proper; the
// space's broadphase is the same in both worlds).
struct StepRecord {
  int contacts = 0;
  int pairs = 0;
  double collide_seconds = 0;
};

// Every body's position and rotation (ODE's 3 and 12 numbers), appended to a trace: one step of
// the coherence tests' traces (support/traces.h).
inline void append_body_states(const std::vector<dBodyID>& bodies, std::vector<dReal>& trace) {
  for (dBodyID b : bodies) {
    const dReal* p = dBodyGetPosition(b);
    const dReal* r = dBodyGetRotation(b);
    trace.insert(trace.end(), p, p + 3);
    trace.insert(trace.end(), r, r + 12);
  }
}

enum class Ground { ode_trimesh, boxtree };

class DropWorld {
 public:
  static constexpr int kMaxContacts = 16;  // asked per pair, like a typical near callback

  // The drop scene's terrain, and `bodies` (spheres, boxes, capsules and cylinders) on it.
  DropWorld(Ground ground, const std::vector<demo::BodySpec>& bodies, const char* method = "aabb")
      : ground_kind_(ground) {
    // Refused before anything of ODE's exists, so that a refusal leaks nothing.
    for (const demo::BodySpec& spec : bodies)
      if (!is_primitive(spec.shape))
        throw std::invalid_argument(std::string("DropWorld: no ") + demo::shape_name(spec.shape) + " bodies");
    world_ = dWorldCreate();
    space_ = dHashSpaceCreate(nullptr);
    joints_ = dJointGroupCreate(0);
    dWorldSetGravity(world_, 0, 0, -9.81);
    dWorldSetQuickStepNumIterations(world_, 30);
    dWorldSetContactSurfaceLayer(world_, 0.001);
    dWorldSetContactMaxCorrectingVel(world_, 2.0);
    dWorldSetAngularDamping(world_, 0.01);
    const auto terrain = scene_terrain();
    if (ground == Ground::boxtree) {
      ground_ = dCreateBoxtreeMesh(space_, terrain, method);
    } else {
      ode_ground_ = std::make_unique<OdeTrimesh>(space_, *terrain);
      ground_ = ode_ground_->geom;
    }
    for (const demo::BodySpec& spec : bodies) add_body(spec);
  }
  ~DropWorld() {
    for (dGeomID g : geoms_) dGeomDestroy(g);
    if (ground_kind_ == Ground::boxtree) dGeomDestroy(ground_);
    ode_ground_.reset();
    dJointGroupDestroy(joints_);
    dSpaceDestroy(space_);
    dWorldDestroy(world_);
  }
  DropWorld(const DropWorld&) = delete;
  DropWorld& operator=(const DropWorld&) = delete;

  StepRecord step(dReal dt = 0.01) {
    record_ = {};
    dSpaceCollide(space_, this, &DropWorld::near_callback);
    dWorldQuickStep(world_, dt);
    dJointGroupEmpty(joints_);
    return record_;
  }

  const std::vector<dBodyID>& bodies() const { return bodies_; }
  const std::vector<dGeomID>& geoms() const { return geoms_; }
  dGeomID ground() const { return ground_; }
  dSpaceID space() const { return space_; }
  dWorldID world() const { return world_; }

 private:
  static void near_callback(void* self_ptr, dGeomID a, dGeomID b) {
    auto* self = static_cast<DropWorld*>(self_ptr);
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
    dContact contacts[kMaxContacts];
    const auto start = std::chrono::steady_clock::now();
    const int n = dCollide(a, b, kMaxContacts, &contacts[0].geom, sizeof(dContact));
    self->record_.collide_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (n > 0) ++self->record_.pairs;
    self->record_.contacts += n;
    for (int i = 0; i < n; ++i) {
      dContact& c = contacts[i];
      c.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactRolling;
      c.surface.mu = 1.0;
      c.surface.soft_erp = 0.4;
      c.surface.soft_cfm = 1e-5;
      // Rolling friction: without it a sphere on any slope rolls forever, and the two worlds
      // would be compared at different places rather than at rest.
      c.surface.rho = 0.3;
      c.surface.rho2 = 0.3;
      c.surface.rhoN = 0.05;
      dJointID j = dJointCreateContact(self->world_, self->joints_, &c);
      dJointAttach(j, ba, bb);
    }
  }

  // The shapes add_body makes (any other is refused before the world exists, not dropped).
  static bool is_primitive(demo::Shape shape) {
    return shape == demo::Shape::sphere || shape == demo::Shape::box || shape == demo::Shape::capsule ||
           shape == demo::Shape::cylinder;
  }

  void add_body(const demo::BodySpec& spec) {
    dMass mass;
    dGeomID geom = nullptr;
    const Real m = spec.mass, r = spec.radius, length = 2 * spec.half_length;
    const Vec3 sides = 2 * spec.half_extents;
    switch (spec.shape) {
      case demo::Shape::sphere:
        geom = dCreateSphere(space_, r);
        dMassSetSphereTotal(&mass, m, r);
        break;
      case demo::Shape::box:
        geom = dCreateBox(space_, sides.x(), sides.y(), sides.z());
        dMassSetBoxTotal(&mass, m, sides.x(), sides.y(), sides.z());
        break;
      case demo::Shape::capsule:
        geom = dCreateCapsule(space_, r, length);
        dMassSetCapsuleTotal(&mass, m, 3, r, length);
        break;
      case demo::Shape::cylinder:
        geom = dCreateCylinder(space_, r, length);
        dMassSetCylinderTotal(&mass, m, 3, r, length);
        break;
      default:  // not is_primitive: refused by the constructor
        return;
    }
    dBodyID body = dBodyCreate(world_);
    dBodySetMass(body, &mass);
    dBodySetPosition(body, spec.position.x(), spec.position.y(), spec.position.z());
    const dQuaternion q = {spec.orientation.w(), spec.orientation.x(), spec.orientation.y(), spec.orientation.z()};
    dBodySetQuaternion(body, q);
    dGeomSetBody(geom, body);
    bodies_.push_back(body);
    geoms_.push_back(geom);
  }

  Ground ground_kind_;
  dWorldID world_ = nullptr;
  dSpaceID space_ = nullptr;
  dJointGroupID joints_ = nullptr;
  dGeomID ground_ = nullptr;
  std::unique_ptr<OdeTrimesh> ode_ground_;
  std::vector<dBodyID> bodies_;
  std::vector<dGeomID> geoms_;
  StepRecord record_;
};

// Terrain height under (x, y): the closest hit of a vertical ray on the boxtree of the terrain.
inline Real terrain_height(const AnyTree& tree, Real x, Real y) {
  const auto hit = tree.ray_closest_hit(Ray{Vec3(x, y, 1000), Vec3(0, 0, -1)});
  return hit ? 1000 - hit->t : -1e9;
}

// Terrain height under (x, y), nullopt off the terrain.
inline std::optional<Real> terrain_height_at(const AnyTree& tree, Real x, Real y) {
  const auto hit = tree.ray_closest_hit(Ray{Vec3(x, y, 1000), Vec3(0, 0, -1)});
  if (!hit) return std::nullopt;
  return 1000 - hit->t;
}

// The points of a geom that rest on the ground, in the world: the lowest point of a sphere and of
// each capsule cap, the corners of a box, 16 points around each rim of a cylinder, the vertices
// of a boxtree geom or an ODE trimesh. Their lowest is the geom's lowest point, and on a slope
// the others reach the ground first.
inline std::vector<Vec3> bottom_points(dGeomID g) {
  const dReal* p = dGeomGetPosition(g);
  const dReal* r = dGeomGetRotation(g);  // 3 rows of 4
  const Vec3 center(p[0], p[1], p[2]);
  const auto world = [&](const Vec3& local) {
    Vec3 w;
    for (int row = 0; row < 3; ++row)
      w[row] = r[4 * row] * local.x() + r[4 * row + 1] * local.y() + r[4 * row + 2] * local.z() + p[row];
    return w;
  };
  const Vec3 down(0, 0, -1);
  std::vector<Vec3> points;
  switch (dGeomGetClass(g)) {
    case dSphereClass:
      points.push_back(center + down * dGeomSphereGetRadius(g));
      break;
    case dBoxClass: {
      dVector3 l;
      dGeomBoxGetLengths(g, l);
      for (int k = 0; k < 8; ++k)
        points.push_back(world(0.5 * Vec3(k & 1 ? l[0] : -l[0], k & 2 ? l[1] : -l[1], k & 4 ? l[2] : -l[2])));
      break;
    }
    case dCapsuleClass: {
      dReal radius, length;
      dGeomCapsuleGetParams(g, &radius, &length);
      for (Real end : {-0.5, 0.5}) points.push_back(world(Vec3(0, 0, end * length)) + down * radius);
      break;
    }
    case dCylinderClass: {
      dReal radius, length;
      dGeomCylinderGetParams(g, &radius, &length);
      for (int k = 0; k < 32; ++k) {
        const Real angle = (k % 16) * M_PI / 8;
        points.push_back(
            world(Vec3(radius * std::cos(angle), radius * std::sin(angle), (k < 16 ? 0.5 : -0.5) * length)));
      }
      break;
    }
    case dTriMeshClass:
      for (int i = 0; i < dGeomTriMeshGetTriangleCount(g); ++i) {
        dVector3 v[3];
        dGeomTriMeshGetTriangle(g, i, &v[0], &v[1], &v[2]);
        for (const dVector3& c : v) points.emplace_back(c[0], c[1], c[2]);
      }
      break;
    default:
      if (const AnyTree* tree = boxtree::ode::geom_tree(g)) {
        for (const Vec3& v : tree->mesh().vertices) points.push_back(world(v));
      } else {
        points.push_back(center);
      }
  }
  return points;
}

// How deep a geom is in the ground: the largest (terrain height under a bottom point - the
// point's height) over its bottom_points with terrain under them; negative when it is clear of
// the ground, nullopt when no point is over the terrain.
inline std::optional<Real> depth_below(const AnyTree& terrain, dGeomID g) {
  std::optional<Real> depth;
  for (const Vec3& p : bottom_points(g)) {
    if (const auto ground = terrain_height_at(terrain, p.x(), p.y()))
      depth = std::max(depth.value_or(-1e30), *ground - p.z());
  }
  return depth;
}

}  // namespace boxtree::ode_test
