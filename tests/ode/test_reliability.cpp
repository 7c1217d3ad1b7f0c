// SPDX-License-Identifier: MIT
// Reliability of the ODE adapter (issue 9): bad input to dCreateBoxtreeMesh is refused with one
// clear line before any ODE object is made; a terrain full of duplicate, zero-area and sliver
// facets gives no NaN and lets no body through; the same scene stepped twice gives bit-identical
// positions and rotations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "ode_scene.h"
#include "support/odd_meshes.h"

namespace boxtree::ode_test {
namespace {

struct Space {
  dSpaceID id = dSimpleSpaceCreate(nullptr);
  ~Space() { dSpaceDestroy(id); }
};

// `create` must throw boxtree::Error with one line containing `expected`, and add no geom.
template <class Create>
void expect_refused(const char* name, const char* expected, Create create) {
  SCOPED_TRACE(name);
  Space space;
  try {
    create(space.id);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_EQ(dSpaceGetNumGeoms(space.id), 0);
}

TEST(OdeReliability, BadInputIsRefusedWithOneClearLine) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> v = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::vector<dTriIndex> i = {0, 1, 2};
  const int stride = 3 * sizeof(double), tri = 3 * sizeof(dTriIndex);
  expect_refused("null vertices", "bad vertex/index arrays", [&](dSpaceID s) {
    dCreateBoxtreeMesh(s, static_cast<const double*>(nullptr), stride, 3, i.data(), 3, tri);
  });
  expect_refused("null indices", "bad vertex/index arrays",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), stride, 3, nullptr, 3, tri); });
  expect_refused("negative vertex count", "bad vertex/index arrays",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), stride, -3, i.data(), 3, tri); });
  expect_refused("index count not a multiple of 3", "bad vertex/index arrays",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), stride, 3, i.data(), 2, tri); });
  expect_refused("vertex stride below 3 coordinates", "bad vertex/index arrays",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), 2 * int(sizeof(double)), 3, i.data(), 3, tri); });
  std::vector<dTriIndex> high = {0, 1, 3};
  expect_refused("index beyond the vertex count", "out of range",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), stride, 3, high.data(), 3, tri); });
  std::vector<double> with_nan = v;
  with_nan[4] = nan;
  expect_refused("NaN coordinate", "non-finite",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, with_nan.data(), stride, 3, i.data(), 3, tri); });
  std::vector<float> huge = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  huge[3] = std::numeric_limits<float>::infinity();
  expect_refused("infinite float coordinate", "non-finite",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, huge.data(), 3 * int(sizeof(float)), 3, i.data(), 3, tri); });
  expect_refused("unknown method", "no-such-method",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, v.data(), stride, 3, i.data(), 3, tri, "no-such-method"); });
  expect_refused("null mesh", "no mesh",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, std::shared_ptr<const TriangleMesh>(), "aabb"); });
  expect_refused("empty mesh", "no facets",
                 [&](dSpaceID s) { dCreateBoxtreeMesh(s, std::make_shared<const TriangleMesh>(), "aabb"); });
  expect_refused("empty tree", "empty", [&](dSpaceID s) { dCreateBoxtreeMesh(s, AnyTree()); });
}

// Spheres, boxes, capsules and cylinders dropped on the odd terrain (boxtree geom).
class OddWorld {
 public:
  explicit OddWorld(std::shared_ptr<const TriangleMesh> terrain) : terrain_(std::move(terrain)) {
    world_ = dWorldCreate();
    space_ = dHashSpaceCreate(nullptr);
    joints_ = dJointGroupCreate(0);
    dWorldSetGravity(world_, 0, 0, -9.81);
    dWorldSetQuickStepNumIterations(world_, 20);
    dWorldSetContactSurfaceLayer(world_, 0.001);
    dWorldSetContactMaxCorrectingVel(world_, 2.0);
    ground_ = dCreateBoxtreeMesh(space_, terrain_, "pie-min");
    for (int k = 0; k < 32; ++k) {
      dBodyID body = dBodyCreate(world_);
      dMass mass;
      dGeomID geom = nullptr;
      switch (k % 4) {
        case 0:
          geom = dCreateSphere(space_, 0.5);
          dMassSetSphere(&mass, 1000, 0.5);
          break;
        case 1:
          geom = dCreateBox(space_, 1.0, 0.8, 0.6);
          dMassSetBox(&mass, 1000, 1.0, 0.8, 0.6);
          break;
        case 2:
          geom = dCreateCapsule(space_, 0.3, 0.8);
          dMassSetCapsule(&mass, 1000, 3, 0.3, 0.8);
          break;
        default:
          geom = dCreateCylinder(space_, 0.4, 0.6);
          dMassSetCylinder(&mass, 1000, 3, 0.4, 0.6);
          break;
      }
      dBodySetMass(body, &mass);
      dBodySetPosition(body, 4 + 4 * (k % 6), 4 + 4 * ((k / 6) % 6), 8 + 2 * (k / 36));
      dMatrix3 r;
      dRFromAxisAndAngle(r, 1, 1, 0, 0.3 * k);
      dBodySetRotation(body, r);
      dGeomSetBody(geom, body);
      bodies_.push_back(body);
    }
  }
  ~OddWorld() {
    dJointGroupDestroy(joints_);
    dSpaceDestroy(space_);  // and the geoms in it
    dWorldDestroy(world_);
  }
  OddWorld(const OddWorld&) = delete;
  OddWorld& operator=(const OddWorld&) = delete;

  void run(int steps) {
    for (int s = 0; s < steps; ++s) {
      dSpaceCollide(space_, this, &OddWorld::near_callback);
      dWorldQuickStep(world_, 0.01);
      dJointGroupEmpty(joints_);
    }
  }
  const std::vector<dBodyID>& bodies() const { return bodies_; }

 private:
  static void near_callback(void* self_ptr, dGeomID a, dGeomID b) {
    auto* self = static_cast<OddWorld*>(self_ptr);
    dContact contacts[16];
    const int n = dCollide(a, b, 16, &contacts[0].geom, sizeof(dContact));
    for (int k = 0; k < n; ++k) {
      dContact& c = contacts[k];
      c.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactRolling;
      c.surface.mu = 1.0;
      c.surface.soft_erp = 0.4;
      c.surface.soft_cfm = 1e-5;
      c.surface.rho = c.surface.rho2 = 0.3;
      c.surface.rhoN = 0.05;
      dJointAttach(dJointCreateContact(self->world_, self->joints_, &c), dGeomGetBody(a), dGeomGetBody(b));
    }
  }

  std::shared_ptr<const TriangleMesh> terrain_;
  dWorldID world_ = nullptr;
  dSpaceID space_ = nullptr;
  dJointGroupID joints_ = nullptr;
  dGeomID ground_ = nullptr;
  std::vector<dBodyID> bodies_;
};

// The bodies' bottoms against the odd terrain under them: deepest measured 0.23 cm; allowance 0.5 cm.
constexpr Real kOddDepthAllowance = 0.005;

TEST(OdeReliability, OddTerrainGivesNoNanAndNoFallThrough) {
  const auto terrain = std::make_shared<const TriangleMesh>(boxtree::test::make_odd_terrain(28, 3, 28, 3));
  const AnyTree reference = AnyTree::build(terrain, Method{});
  OddWorld world(terrain);
  world.run(300);
  int non_finite = 0, off = 0;
  Real deepest = -1e30;
  for (std::size_t k = 0; k < world.bodies().size(); ++k) {
    const dReal* p = dBodyGetPosition(world.bodies()[k]);
    const dReal* q = dBodyGetQuaternion(world.bodies()[k]);
    if (!std::isfinite(p[0] + p[1] + p[2]) || !std::isfinite(q[0] + q[1] + q[2] + q[3])) {
      ++non_finite;
      continue;
    }
    const auto depth = depth_below(reference, dBodyGetFirstGeom(world.bodies()[k]));
    if (!depth) {
      ++off;  // rolled off the terrain's edge (an open sheet), not through it
      continue;
    }
    deepest = std::max(deepest, *depth);
    EXPECT_LT(*depth, kOddDepthAllowance) << "body " << k << " is in the ground";
  }
  std::printf("[ odd      ] deepest body %.4f m below the terrain, %d off it\n", deepest, off);
  EXPECT_EQ(non_finite, 0);
  EXPECT_EQ(off, 0) << "measured: all 32 stay on the terrain";
}

// dWorldQuickStep shuffles its constraints with ODE's global random generator, so each run
// starts from the same seed (as the demo does) and the two runs are not interleaved.
std::vector<dReal> run_and_record(const std::shared_ptr<const TriangleMesh>& terrain) {
  dRandSetSeed(1);
  OddWorld world(terrain);
  std::vector<dReal> states;
  for (int round = 0; round < 4; ++round) {
    world.run(50);
    for (dBodyID body : world.bodies()) {
      const dReal* p = dBodyGetPosition(body);
      const dReal* q = dBodyGetQuaternion(body);
      states.insert(states.end(), {p[0], p[1], p[2], q[0], q[1], q[2], q[3]});
    }
  }
  return states;
}

TEST(OdeReliability, SameSceneTwiceGivesBitIdenticalStates) {
  const auto terrain = std::make_shared<const TriangleMesh>(boxtree::test::make_odd_terrain(20, 5, 28, 3));
  const std::vector<dReal> a = run_and_record(terrain);
  const std::vector<dReal> b = run_and_record(terrain);
  ASSERT_EQ(a.size(), b.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differing += std::memcmp(&a[i], &b[i], sizeof(dReal)) != 0;
  EXPECT_EQ(differing, 0u) << "of " << a.size() << " values (32 bodies x 4 checkpoints x 7)";
}

}  // namespace
}  // namespace boxtree::ode_test
