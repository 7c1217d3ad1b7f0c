// SPDX-License-Identifier: MIT
// Mesh-vs-mesh temporal coherence in ODE (GeomSettings::mesh_coherence): a pile of mesh bodies
// on a mesh terrain steps bit for bit the same with the per-pair fronts as without; the pair
// registry evicts pairs unseen for a few steps and every pair of a destroyed geom, and stays
// within its bounds.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "boxtree/generate.h"
#include "boxtree/ode/boxtree_geom.h"
#include "ode_scene.h"
#include "support/traces.h"

namespace boxtree::ode_test {
namespace {

struct Pile {
  dWorldID world = dWorldCreate();
  dSpaceID space = dHashSpaceCreate(nullptr);
  dJointGroupID contacts = dJointGroupCreate(0);
  std::vector<dGeomID> geoms;
  std::vector<dBodyID> bodies;

  explicit Pile(bool coherence) {
    dWorldSetGravity(world, 0, 0, -9.81);
    const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(16, 16, 3, 6, 0.5));
    const auto rock = std::make_shared<const TriangleMesh>(make_bumpy_sphere(12, 8, 0.2, 5));
    const auto torus = std::make_shared<const TriangleMesh>(make_torus(0.35, 0.12, 16, 8));
    ode::GeomSettings settings;
    settings.mesh_coherence = coherence;
    geoms.push_back(dCreateBoxtreeMesh(space, terrain, "aabb"));
    dGeomSetPosition(geoms.back(), -3, -3, 0);
    ode::set_geom_settings(geoms.back(), settings);
    for (int k = 0; k < 12; ++k) {
      dGeomID g = dCreateBoxtreeMesh(space, k % 2 ? torus : rock, "aabb");
      ode::set_geom_settings(g, settings);
      dBodyID b = dBodyCreate(world);
      dMass mass;
      dMassSetSphereTotal(&mass, 1, 0.4);
      dBodySetMass(b, &mass);
      dBodySetPosition(b, 0.9 * (k % 3), 0.9 * ((k / 3) % 2), 1.5 + 0.9 * (k / 6) + 0.05 * k);
      dBodySetAutoDisableFlag(b, 0);  // resting pairs keep colliding
      dGeomSetBody(g, b);
      geoms.push_back(g);
      bodies.push_back(b);
    }
  }
  ~Pile() {
    for (dGeomID g : geoms) dGeomDestroy(g);
    dJointGroupDestroy(contacts);
    dSpaceDestroy(space);
    dWorldDestroy(world);
  }

  static void near(void* data, dGeomID o1, dGeomID o2) {
    Pile& pile = *static_cast<Pile*>(data);
    dContact contact[8];
    const int n = dCollide(o1, o2, 8, &contact[0].geom, sizeof(dContact));
    for (int i = 0; i < n; ++i) {
      contact[i].surface.mode = dContactApprox1;
      contact[i].surface.mu = 0.8;
      dJointID j = dJointCreateContact(pile.world, pile.contacts, &contact[i]);
      dJointAttach(j, dGeomGetBody(o1), dGeomGetBody(o2));
    }
  }

  // Every body's position and rotation after each step.
  std::vector<dReal> run(int steps) {
    dRandSetSeed(1);
    std::vector<dReal> trace;
    for (int i = 0; i < steps; ++i) {
      dSpaceCollide(space, this, &near);
      dWorldQuickStep(world, 1.0 / 60);
      dJointGroupEmpty(contacts);
      append_body_states(bodies, trace);
    }
    return trace;
  }

  std::uint64_t volume_tests() const {
    std::uint64_t n = 0;
    for (dGeomID g : geoms) n += ode::geom_counters(g).mesh_volume_tests;
    return n;
  }
};

TEST(OdeCoherence, MeshPileStepsBitIdenticallyWithAndWithoutFronts) {
  const int steps = 240;
  ode::clear_mesh_pair_caches();
  std::vector<dReal> with, without;
  std::uint64_t tests_with = 0, tests_without = 0;
  {
    Pile pile(true);
    with = pile.run(steps);
    tests_with = pile.volume_tests();
    const ode::MeshPairCacheInfo info = ode::mesh_pair_cache_info();
    EXPECT_GT(info.pairs, 0u);
    EXPECT_GE(info.steps, std::uint64_t(steps - 1));
    // Memory per pair: the front's cap (two buffers of 8,192 records of 24 bytes) and the call's facet pairs.
    EXPECT_LE(info.largest_front, CollideFront::kDefaultMaxRecords);
    EXPECT_LE(info.bytes, info.pairs * (2 * CollideFront::kDefaultMaxRecords * sizeof(CollideFront::Record) + 65536));
    std::printf("[ coherence] %zu pairs kept, %zu bytes, largest front %zu records, %llu evicted\n", info.pairs,
                info.bytes, info.largest_front, static_cast<unsigned long long>(info.evicted));
  }
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 0u);  // every geom destroyed: every entry gone
  {
    Pile pile(false);
    without = pile.run(steps);
    tests_without = pile.volume_tests();
    EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 0u);  // off: nothing kept
  }
  ASSERT_NO_FATAL_FAILURE(boxtree::test::expect_same_bits_every_step(with, without, steps));
  const std::size_t per_step = with.size() / std::size_t(steps);
  EXPECT_NE(with.front(), with[with.size() - per_step]);
  EXPECT_GT(tests_without, 0u);
  EXPECT_LT(tests_with, tests_without);
  std::printf("[ coherence] mesh-vs-mesh volume tests over %d steps: %llu with fronts, %llu fresh\n", steps,
              static_cast<unsigned long long>(tests_with), static_cast<unsigned long long>(tests_without));
}

// Entries age out when their pair is no longer collided, and go with a destroyed geom.
TEST(OdeCoherence, PairEntriesEvictedUnseenAndOnDestroy) {
  ode::clear_mesh_pair_caches();
  const auto rock = std::make_shared<const TriangleMesh>(make_bumpy_sphere(12, 8, 0.2, 5));
  dGeomID a = dCreateBoxtreeMesh(nullptr, rock, "aabb");
  dGeomID b = dCreateBoxtreeMesh(nullptr, rock, "aabb");
  dGeomID c = dCreateBoxtreeMesh(nullptr, rock, "aabb");
  dGeomID d = dCreateBoxtreeMesh(nullptr, rock, "aabb");
  ode::GeomSettings settings;
  settings.mesh_coherence = true;  // off by default
  for (dGeomID g : {a, b, c, d}) ode::set_geom_settings(g, settings);
  dGeomSetPosition(b, 1.5, 0, 0);
  dGeomSetPosition(c, 10, 0, 0);
  dGeomSetPosition(d, 11.5, 0, 0);
  dContactGeom out[4];
  const auto collide = [&](dGeomID x, dGeomID y) { return dCollide(x, y, 4, out, sizeof(dContactGeom)); };
  for (int step = 0; step < 3; ++step) {
    EXPECT_GT(collide(a, b), 0);
    EXPECT_GT(collide(c, d), 0);
  }
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 2u);
  const std::uint64_t evicted_before = ode::mesh_pair_cache_info().evicted;
  // (a, b) apart in the broadphase from now on: only (c, d) is collided, once per step.
  for (int step = 0; step < 5; ++step) collide(c, d);
  ode::MeshPairCacheInfo info = ode::mesh_pair_cache_info();
  EXPECT_EQ(info.pairs, 1u);
  EXPECT_EQ(info.evicted - evicted_before, 1u);
  // The reverse order is a pair of its own (the front is of the ordered pair).
  collide(d, c);
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 2u);
  dGeomDestroy(c);
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 0u);
  EXPECT_GT(collide(a, b), 0);
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 1u);
  dGeomDestroy(b);
  EXPECT_EQ(ode::mesh_pair_cache_info().pairs, 0u);
  dGeomDestroy(a);
  dGeomDestroy(d);
}

}  // namespace
}  // namespace boxtree::ode_test
