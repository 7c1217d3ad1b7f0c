// SPDX-License-Identifier: MIT
// The drop scene in two worlds (terrain as ODE's dTriMesh, and as the boxtree geom): bodies of
// every kind come to rest at the same heights, nothing falls through, and the contact counts and
// collision times per step are printed side by side. Also closed meshes dropped as boxtree geoms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "boxtree/generate.h"
#include "ode_scene.h"

namespace boxtree::ode_test {
namespace {

constexpr int kSteps = 300;            // 3 s at 100 Hz: every body lands (within ~0.5 s) and settles
constexpr Real kRestTolerance = 0.02;  // |rest height (ODE trimesh) - rest height (boxtree)|, units (bodies ~1)
// How far a resting body's bottom (ode_scene.h, bottom_points) may be in the terrain under it:
// deepest measured 0.23 cm (boxtree, both methods; ODE's trimesh 0.17 cm); allowance 0.5 cm.
constexpr Real kDepthAllowance = 0.005;
// ... and above it: a sphere on a slope touches it uphill of its lowest point, a tilted cylinder
// with its rim; highest measured 3.5 cm; allowance 4 cm (a body stuck in the air is 1 m up).
constexpr Real kLandedAllowance = 0.04;

struct Summary {
  double contacts = 0;
  double collide_seconds = 0;
  int max_contacts = 0;
};

Summary summarize(const std::vector<StepRecord>& steps) {
  Summary s;
  for (const StepRecord& r : steps) {
    s.contacts += r.contacts;
    s.collide_seconds += r.collide_seconds;
    s.max_contacts = std::max(s.max_contacts, r.contacts);
  }
  s.contacts /= double(steps.size());
  s.collide_seconds /= double(steps.size());
  return s;
}

// Runs the scene in both worlds and checks rest heights; prints the table.
void run_scene(const char* method) {
  const auto terrain = scene_terrain();
  const AnyTree reference = AnyTree::build(terrain, parse_method("aabb"));
  const std::vector<demo::BodySpec>& drops = drop_scene().bodies;
  DropWorld ode_world(Ground::ode_trimesh, drops);
  DropWorld bt_world(Ground::boxtree, drops, method);
  std::vector<StepRecord> ode_steps, bt_steps;
  std::printf("[ drop     ] method %s: %zu bodies on a %zu-facet terrain; per step: contacts and dCollide time\n",
              method, drops.size(), terrain->facet_count());
  std::printf("[ drop     ] %5s  %14s %14s  %12s %12s\n", "step", "contacts(ODE)", "contacts(bt)", "us(ODE)", "us(bt)");
  for (int step = 0; step < kSteps; ++step) {
    ode_steps.push_back(ode_world.step());
    bt_steps.push_back(bt_world.step());
    if (step % 25 == 0 || step == kSteps - 1)
      std::printf("[ drop     ] %5d  %14d %14d  %12.1f %12.1f\n", step, ode_steps.back().contacts,
                  bt_steps.back().contacts, ode_steps.back().collide_seconds * 1e6,
                  bt_steps.back().collide_seconds * 1e6);
  }
  // The averages over the last 100 steps (everything resting) and over the whole run.
  const std::vector<StepRecord> ode_rest(ode_steps.end() - 100, ode_steps.end());
  const std::vector<StepRecord> bt_rest(bt_steps.end() - 100, bt_steps.end());
  const Summary so = summarize(ode_steps), sb = summarize(bt_steps);
  const Summary ro = summarize(ode_rest), rb = summarize(bt_rest);
  std::printf(
      "[ drop     ] all steps : contacts/step ODE %.1f (max %d)  boxtree %.1f (max %d);"
      " dCollide us/step ODE %.1f  boxtree %.1f\n",
      so.contacts, so.max_contacts, sb.contacts, sb.max_contacts, so.collide_seconds * 1e6, sb.collide_seconds * 1e6);
  std::printf(
      "[ drop     ] at rest   : contacts/step ODE %.1f  boxtree %.1f; dCollide us/step ODE %.1f  boxtree %.1f\n",
      ro.contacts, rb.contacts, ro.collide_seconds * 1e6, rb.collide_seconds * 1e6);

  std::printf("[ drop     ] %-9s %9s %9s | %9s %9s %9s | %8s\n", "body", "x", "y", "z(ODE)", "z(bt)", "dz", "ground");
  Real deepest = -1e30, ode_deepest = -1e30, shallowest = 1e30;
  for (std::size_t i = 0; i < drops.size(); ++i) {
    SCOPED_TRACE(std::string(demo::shape_name(drops[i].shape)) + " #" + std::to_string(i));
    const dReal* po = dBodyGetPosition(ode_world.bodies()[i]);
    const dReal* pb = dBodyGetPosition(bt_world.bodies()[i]);
    const Real ground = terrain_height(reference, pb[0], pb[1]);
    std::printf("[ drop     ] %-9s %9.3f %9.3f | %9.4f %9.4f %9.4f | %8.3f\n", demo::shape_name(drops[i].shape), pb[0],
                pb[1], po[2], pb[2], pb[2] - po[2], ground);
    // At rest in both worlds.
    for (const DropWorld* w : {&ode_world, &bt_world}) {
      const dReal* v = dBodyGetLinearVel(w->bodies()[i]);
      const dReal* av = dBodyGetAngularVel(w->bodies()[i]);
      // Known limitation: contact_convex_triangle (cylinders) gives one contact per facet, and
      // its position is not at the shape's deepest point (libccd's EPA position), so a standing
      // cylinder keeps a small jitter (position still within a few mm, checked below).
      const Real v_max = (w == &bt_world && drops[i].shape == demo::Shape::cylinder) ? 0.2 : 0.05;
      EXPECT_LT(Vec3(v[0], v[1], v[2]).norm(), v_max) << (w == &ode_world ? "ODE trimesh" : "boxtree");
      EXPECT_LT(Vec3(av[0], av[1], av[2]).norm(), 0.2) << (w == &ode_world ? "ODE trimesh" : "boxtree");
    }
    // Same place, same height.
    EXPECT_LT(std::hypot(pb[0] - po[0], pb[1] - po[1]), 0.1);
    EXPECT_NEAR(pb[2], po[2], kRestTolerance);
    // Nothing sank in, nothing hangs in the air: the body's bottom against the terrain under it.
    const auto depth = depth_below(reference, bt_world.geoms()[i]);
    const auto ode_depth = depth_below(reference, ode_world.geoms()[i]);
    ASSERT_TRUE(depth && ode_depth);
    deepest = std::max(deepest, *depth);
    ode_deepest = std::max(ode_deepest, *ode_depth);
    shallowest = std::min(shallowest, *depth);
    EXPECT_LT(*depth, kDepthAllowance);
    EXPECT_GT(*depth, -kLandedAllowance);
  }
  std::printf("[ drop     ] bottoms against the terrain: deepest %.4f m in (ODE trimesh %.4f), shallowest %.4f m in\n",
              deepest, ode_deepest, shallowest);
}

TEST(OdeDrop, SameRestHeightsAsOdeTrimesh_aabb) { run_scene("aabb"); }

// Collision time per call and per body kind, with every body at rest (after the drop): each
// pair's dCollide repeated, so that the figures do not depend on one noisy step.
TEST(OdeDrop, CollisionTimePerBodyKind) {
  const std::vector<demo::BodySpec>& drops = drop_scene().bodies;
  const char* methods[] = {"aabb", "obb-min", "pie-min+aabb@3"};
  std::vector<std::unique_ptr<DropWorld>> worlds;
  worlds.push_back(std::make_unique<DropWorld>(Ground::ode_trimesh, drops));
  for (const char* m : methods) worlds.push_back(std::make_unique<DropWorld>(Ground::boxtree, drops, m));
  for (auto& w : worlds)
    for (int step = 0; step < 200; ++step) w->step();
  std::printf("[ time     ] dCollide(ground, body) at rest, microseconds per call (contacts per call)\n");
  std::printf("[ time     ] %-9s %16s", "body", "ODE trimesh");
  for (const char* m : methods) std::printf(" %16s", m);
  std::printf("\n");
  const int repeats = 100;
  for (demo::Shape kind : {demo::Shape::sphere, demo::Shape::box, demo::Shape::capsule, demo::Shape::cylinder}) {
    std::printf("[ time     ] %-9s", demo::shape_name(kind));
    for (auto& w : worlds) {
      double seconds = 0;
      int contacts = 0, calls = 0;
      for (std::size_t i = 0; i < drops.size(); ++i) {
        if (drops[i].shape != kind) continue;
        dContact c[DropWorld::kMaxContacts];
        const auto start = std::chrono::steady_clock::now();
        for (int r = 0; r < repeats; ++r)
          contacts += dCollide(w->ground(), w->geoms()[i], DropWorld::kMaxContacts, &c[0].geom, sizeof(dContact));
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        calls += repeats;
      }
      std::printf(" %9.2f (%4.1f)", seconds / calls * 1e6, double(contacts) / calls);
      EXPECT_GT(contacts, 0);
    }
    std::printf("\n");
  }
}
TEST(OdeDrop, SameRestHeightsAsOdeTrimesh_obb_min) { run_scene("obb-min"); }

// Closed meshes as boxtree geoms on bodies: onto the boxtree terrain (boxtree vs boxtree), onto
// ODE's trimesh terrain (boxtree vs dTriMesh), and ODE's trimesh body onto the boxtree terrain.
TEST(OdeDrop, ClosedMeshComesToRest) {
  const auto terrain = scene_terrain();
  const AnyTree reference = AnyTree::build(terrain, parse_method("aabb"));
  const auto rock = std::make_shared<const TriangleMesh>(make_bumpy_sphere(12, 7, 0.15, 9));  // 144 facets
  enum class Pair { boxtree_on_boxtree, boxtree_on_trimesh, trimesh_on_boxtree };
  // The rock's lowest vertex against the terrain under it: deepest measured 1.13 cm in, all three
  // pairs, with face-normal mesh contacts (1.94 cm with triangle pairs); allowance 2.5 cm. Landed:
  // at most 1 cm above.
  constexpr Real kRockDepthAllowance = 0.025;
  constexpr Real kRockLandedAllowance = 0.01;
  for (Pair pair : {Pair::boxtree_on_boxtree, Pair::boxtree_on_trimesh, Pair::trimesh_on_boxtree}) {
    SCOPED_TRACE(int(pair));
    const bool ground_is_boxtree = pair != Pair::boxtree_on_trimesh;
    DropWorld world(ground_is_boxtree ? Ground::boxtree : Ground::ode_trimesh, {});
    dBodyID body = dBodyCreate(world.world());
    dMass mass;
    dMassSetSphere(&mass, 1000, 1.0);
    dBodySetMass(body, &mass);
    const Real x = 1, y = -3;
    const Real ground = terrain_height(reference, x, y);
    dBodySetPosition(body, x, y, ground + 2.5);
    std::unique_ptr<OdeTrimesh> rock_trimesh;
    dGeomID geom;
    if (pair == Pair::trimesh_on_boxtree) {
      rock_trimesh = std::make_unique<OdeTrimesh>(world.space(), *rock);
      geom = rock_trimesh->geom;
    } else {
      geom = dCreateBoxtreeMesh(world.space(), rock, "obb-min");
    }
    dGeomSetBody(geom, body);
    int contacts_at_rest = 0;
    for (int step = 0; step < 300; ++step) {
      const StepRecord r = world.step();
      if (step >= 250) contacts_at_rest += r.contacts;
    }
    const dReal* v = dBodyGetLinearVel(body);
    const auto depth = depth_below(reference, geom);
    ASSERT_TRUE(depth);
    std::printf("[ mesh     ] pair %d: lowest vertex %.4f m below the terrain under it, %.1f contacts/step, |v| %.4f\n",
                int(pair), *depth, contacts_at_rest / 50.0, Vec3(v[0], v[1], v[2]).norm());
    EXPECT_LT(Vec3(v[0], v[1], v[2]).norm(), 0.05);
    EXPECT_GT(contacts_at_rest, 0);
    EXPECT_LT(*depth, kRockDepthAllowance);
    EXPECT_GT(*depth, -kRockLandedAllowance);
    dGeomSetBody(geom, nullptr);
    if (pair != Pair::trimesh_on_boxtree) dGeomDestroy(geom);
    rock_trimesh.reset();
    dBodyDestroy(body);
  }
}

// Hulls made with plain dCreateConvex, never registered with boxtree (a user who missed the README
// line), dropped onto the boxtree terrain: they land and rest on it like registered ones (their
// points are read through ODE), and the geom's counter says that it happened.
TEST(OdeDrop, UnregisteredHullsRestOnTheTerrain) {
  static const dReal planes[] = {1, 0, 0, 0.3, -1, 0, 0, 0.3, 0, 1, 0, 0.3, 0, -1, 0, 0.3, 0, 0, 1, 0.3, 0, 0, -1, 0.3};
  static const dReal points[] = {0.3, 0.3, 0.3,  -0.3, 0.3, 0.3,  -0.3, -0.3, 0.3,  0.3, -0.3, 0.3,
                                 0.3, 0.3, -0.3, -0.3, 0.3, -0.3, -0.3, -0.3, -0.3, 0.3, -0.3, -0.3};
  static const unsigned polygons[] = {4, 0, 3, 7, 4, 4, 1, 5, 6, 2, 4, 0, 4, 5, 1,
                                      4, 3, 2, 6, 7, 4, 0, 1, 2, 3, 4, 4, 7, 6, 5};
  const AnyTree reference = AnyTree::build(scene_terrain(), parse_method("aabb"));
  DropWorld world(Ground::boxtree, {});
  std::vector<dGeomID> hulls;
  for (int i = 0; i < 16; ++i) {
    const Real x = -12 + 7 * (i % 4), y = -12 + 7 * (i / 4);
    dBodyID body = dBodyCreate(world.world());
    dMass mass;
    dMassSetBox(&mass, 500, 0.6, 0.6, 0.6);
    dBodySetMass(body, &mass);
    dBodySetPosition(body, x, y, terrain_height(reference, x, y) + 1.5);
    dMatrix3 r;
    dRFromEulerAngles(r, 0.3 * i, 0.2 * i, 0.1 * i);
    dBodySetRotation(body, r);
    dGeomID hull = dCreateConvex(world.space(), planes, 6, points, 8, polygons);
    dGeomSetBody(hull, body);
    hulls.push_back(hull);
  }
  for (int step = 0; step < 300; ++step) world.step();
  Real deepest = -1e9;
  for (dGeomID hull : hulls) {
    const dReal* p = dGeomGetPosition(hull);
    const dReal* r = dGeomGetRotation(hull);
    for (int k = 0; k < 8; ++k) {
      const Vec3 local(points[3 * k], points[3 * k + 1], points[3 * k + 2]);
      Vec3 world_point(p[0], p[1], p[2]);
      for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 3; ++col) world_point[row] += r[row * 4 + col] * local[col];
      deepest = std::max(deepest, terrain_height(reference, world_point.x(), world_point.y()) - world_point.z());
    }
  }
  const auto counters = boxtree::ode::geom_counters(world.ground());
  std::printf("[ hulls    ] unregistered: deepest corner %.4f m below the terrain, %llu calls read through ODE\n",
              deepest, static_cast<unsigned long long>(counters.convexes_read_from_ode));
  // Before the points were read through ODE, every one of them fell through (0 contacts).
  EXPECT_LT(deepest, 0.05);
  EXPECT_GT(counters.convexes_read_from_ode, 0u);
  EXPECT_EQ(counters.convexes_without_data, 0u);
  for (dGeomID hull : hulls) {
    boxtree::ode::forget_convex(hull);
    dGeomDestroy(hull);
  }
}

}  // namespace
}  // namespace boxtree::ode_test
