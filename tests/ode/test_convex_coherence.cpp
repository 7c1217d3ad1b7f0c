// SPDX-License-Identifier: MIT
// Convex-vs-mesh temporal coherence in ODE (GeomSettings::convex_coherence, ConvexPairCache): the
// drop scene's spheres, boxes, capsules and cylinders and two hulls (one with faces, one of
// points) settle on the boxtree terrain with auto-disable, and step bit for bit the same with the
// per-pair state as without, while disabled bodies' pairs are answered from it; a disabled body
// moved by hand, a changed geom setting and bodies thrown up and landing again are collided
// afresh; the registry evicts pairs unseen for a few steps and
// every pair of a destroyed geom, and stays within its bounds.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "ode_scene.h"
#include "support/traces.h"

namespace boxtree::ode_test {
namespace {

// A unit cube's corners and faces, as dCreateConvex takes them (outward planes, polygons).
struct CubeData {
  std::vector<dReal> planes = {1, 0,  0, 0.35, -1, 0, 0, 0.35, 0, 1, 0,  0.35,
                               0, -1, 0, 0.35, 0,  0, 1, 0.35, 0, 0, -1, 0.35};
  std::vector<dReal> points;
  // Corner i is at (+-0.35, +-0.35, +-0.35) by its bits (x, y, z); faces +x, -x, +y, -y, +z, -z.
  std::vector<unsigned> polygons = {4, 1, 3, 7, 5, 4, 0, 4, 6, 2, 4, 2, 6, 7, 3,
                                    4, 0, 1, 5, 4, 4, 4, 5, 7, 6, 4, 0, 2, 3, 1};
  CubeData() {
    for (int i = 0; i < 8; ++i) {
      points.push_back(i & 1 ? 0.35 : -0.35);
      points.push_back(i & 2 ? 0.35 : -0.35);
      points.push_back(i & 4 ? 0.35 : -0.35);
    }
  }
};

struct RestingScene {
  DropWorld world{Ground::boxtree, demo::make_scene(drop_scene_options(), 7).bodies};
  CubeData cube;
  std::vector<dGeomID> hulls;
  std::vector<dBodyID> bodies;

  explicit RestingScene(bool coherence) {
    ode::GeomSettings settings = ode::geom_settings(world.ground());
    settings.convex_coherence = coherence;
    ode::set_geom_settings(world.ground(), settings);
    bodies = world.bodies();
    // Two hulls of the same cube: one with its faces (the separating-axis narrowphase), one of its
    // points only (GJK/EPA).
    for (int k = 0; k < 2; ++k) {
      dGeomID g = nullptr;
      if (k == 0) {
        g = ode::create_convex(world.space(), cube.planes.data(), 6, cube.points.data(), 8, cube.polygons.data());
      } else {
        g = dCreateConvex(world.space(), cube.planes.data(), 6, cube.points.data(), 8, cube.polygons.data());
        ode::set_convex_points(g, cube.points.data(), 8);
      }
      dBodyID b = dBodyCreate(world.world());
      dMass mass;
      dMassSetBoxTotal(&mass, 300, 0.7, 0.7, 0.7);
      dBodySetMass(b, &mass);
      dBodySetPosition(b, -4 + 8 * k, 0, 6);
      dGeomSetBody(g, b);
      hulls.push_back(g);
      bodies.push_back(b);
    }
    for (dBodyID b : bodies) dBodySetAutoDisableFlag(b, 1);
  }
  ~RestingScene() {
    for (dGeomID g : hulls) {
      ode::forget_convex(g);
      dGeomDestroy(g);
    }
  }

  // Every body's position and rotation after each step. At `nudge_step` a disabled body is
  // moved by hand (it stays disabled), at `setting_step` the terrain's margin changes, and at
  // `throw_step` every other body is thrown up (its pairs go, then come back as it lands).
  std::vector<dReal> run(int steps, int nudge_step, int setting_step, int throw_step = -1) {
    dRandSetSeed(1);
    std::vector<dReal> trace;
    for (int i = 0; i < steps; ++i) {
      if (i == nudge_step) {
        for (dBodyID b : bodies) {
          if (dBodyIsEnabled(b)) continue;
          const dReal* p = dBodyGetPosition(b);
          dBodySetPosition(b, p[0] + 1e-4, p[1], p[2]);
          break;
        }
      }
      if (i == throw_step) {
        for (std::size_t k = 0; k < bodies.size(); k += 2) {
          dBodyEnable(bodies[k]);
          dBodySetLinearVel(bodies[k], 0, 0, 4);
        }
      }
      if (i == setting_step) {
        ode::GeomSettings settings = ode::geom_settings(world.ground());
        settings.margin = 0.01;
        ode::set_geom_settings(world.ground(), settings);
      }
      world.step();
      append_body_states(bodies, trace);
    }
    return trace;
  }

  int disabled() const {
    int n = 0;
    for (dBodyID b : bodies) n += dBodyIsEnabled(b) ? 0 : 1;
    return n;
  }
};

TEST(OdeConvexCoherence, RestingBodiesStepBitIdenticallyWithAndWithoutTheCache) {
  const int steps = 800, nudge = 300, setting = 400, thrown = 450;
  ode::clear_convex_pair_caches();
  std::vector<dReal> with, without;
  ode::CollisionCounters counters_with, counters_without;
  {
    RestingScene scene(true);
    with = scene.run(steps, nudge, setting, thrown);
    counters_with = ode::geom_counters(scene.world.ground());
    EXPECT_GE(scene.disabled(), int(scene.bodies.size()) / 2);  // the scene does come to rest
    const ode::ConvexPairCacheInfo info = ode::convex_pair_cache_info();
    EXPECT_GT(info.pairs, 0u);
    EXPECT_LE(info.pairs, scene.bodies.size());
    // Per pair: the input's bytes (a hull's arrays: a few KiB) and at most 16 contacts.
    EXPECT_LE(info.bytes, info.pairs * (8192 + 2 * 16 * sizeof(ContactPoint)));
    std::printf("[ convex coherence] %d of %zu bodies disabled, %zu pairs kept, %zu bytes, %llu of %llu calls reused\n",
                scene.disabled(), scene.bodies.size(), info.pairs, info.bytes,
                static_cast<unsigned long long>(counters_with.reused),
                static_cast<unsigned long long>(counters_with.calls));
  }
  EXPECT_EQ(ode::convex_pair_cache_info().pairs, 0u);  // the terrain destroyed: every entry gone
  {
    RestingScene scene(false);
    without = scene.run(steps, nudge, setting, thrown);
    counters_without = ode::geom_counters(scene.world.ground());
    EXPECT_EQ(ode::convex_pair_cache_info().pairs, 0u);  // off: nothing kept
  }
  ASSERT_NO_FATAL_FAILURE(boxtree::test::expect_same_bits_every_step(with, without, steps));
  EXPECT_EQ(counters_with.calls, counters_without.calls);
  EXPECT_EQ(counters_with.contacts, counters_without.contacts);
  EXPECT_EQ(counters_without.reused, 0u);
  // Most calls after the bodies come to rest are answered from the cache.
  EXPECT_GT(counters_with.reused, counters_with.calls / 4);
  EXPECT_LT(counters_with.candidate_facets, counters_without.candidate_facets);
}

// Entries age out once their pair is no longer looked up (a body that wakes, a geom gone), and go
// with a destroyed boxtree geom or a forgotten convex.
TEST(OdeConvexCoherence, PairEntriesEvictedUnseenAndOnDestroy) {
  ode::clear_convex_pair_caches();
  auto scene = std::make_unique<RestingScene>(true);
  scene->run(300, -1, -1);
  const std::size_t resting = ode::convex_pair_cache_info().pairs;
  ASSERT_GE(resting, 4u);
  // A forgotten convex takes its entry along.
  ode::forget_convex(scene->hulls[0]);
  EXPECT_LT(ode::convex_pair_cache_info().pairs, resting);
  // Woken bodies (thrown up) stop looking their pairs up: after a few steps only the one left
  // resting is kept.
  for (std::size_t k = 0; k + 1 < scene->bodies.size(); ++k) {
    dBodyEnable(scene->bodies[k]);
    dBodySetAutoDisableFlag(scene->bodies[k], 0);
    dBodySetLinearVel(scene->bodies[k], 0, 0, 5);
  }
  const std::uint64_t evicted_before = ode::convex_pair_cache_info().evicted;
  scene->run(3 + 3, -1, -1);  // unseen for more than 3 steps: evicted
  const ode::ConvexPairCacheInfo info = ode::convex_pair_cache_info();
  EXPECT_LE(info.pairs, 1u);
  EXPECT_GT(info.evicted, evicted_before);
  scene.reset();
  EXPECT_EQ(ode::convex_pair_cache_info().pairs, 0u);
}

}  // namespace
}  // namespace boxtree::ode_test
