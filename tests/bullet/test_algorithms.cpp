// SPDX-License-Identifier: MIT
// The collision algorithms: bodies dropped on a terrain in two worlds (Bullet's own mesh shape,
// and BoxtreeMeshShape with the convex-vs-boxtree algorithm), mesh vs mesh, internal edges.
#include <gtest/gtest.h>

#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <LinearMath/btPoolAllocator.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "boxtree/collide.h"
#include "boxtree/geometry.h"
#include "scene.h"
#include "world.h"

namespace boxtree::bullet::test {
namespace {

// Terrain height under (x, y) by a vertical ray against the core tree (brute force would do too).
Real terrain_height(const AnyTree& tree, Real x, Real y) {
  Ray ray{Vec3(x, y, 1000), Vec3(0, 0, -1)};
  const auto hit = tree.ray_closest_hit(ray);
  return hit ? 1000 - hit->t : -1e30;
}

// A btVector3 of three draws in [lo, hi), z first, then y, then x (see tests/support/random.h).
btVector3 draw_vector(Random& rng, Real lo, Real hi) {
  const btScalar z = btScalar(rng.uniform(lo, hi));
  const btScalar y = btScalar(rng.uniform(lo, hi));
  const btScalar x = btScalar(rng.uniform(lo, hi));
  return btVector3(x, y, z);
}

// Bullet's shape for a scene body (demos/src/scene.h) with the terrain's z up: spheres, boxes,
// capsules, cylinders, and hulls with faces (initializePolyhedralFeatures: Bullet's hull-hull pairs
// use its clipping; boxtree keeps GJK for hulls unless AlgorithmSettings::hullFaces, the test below).
std::unique_ptr<btCollisionShape> make_body_shape(const demo::BodySpec& body) {
  const auto bt = [](const Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); };
  switch (body.shape) {
    case demo::Shape::sphere:
      return std::make_unique<btSphereShape>(btScalar(body.radius));
    case demo::Shape::box:
      return std::make_unique<btBoxShape>(bt(body.half_extents));
    case demo::Shape::capsule:
      return std::make_unique<btCapsuleShapeZ>(btScalar(body.radius), btScalar(2 * body.half_length));
    case demo::Shape::cylinder:
      return std::make_unique<btCylinderShapeZ>(bt(Vec3(body.radius, body.radius, body.half_length)));
    case demo::Shape::convex: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vec3& v : body.mesh->vertices) hull->addPoint(bt(v), false);
      hull->recalcLocalAabb();
      hull->initializePolyhedralFeatures();
      return hull;
    }
    case demo::Shape::mesh:
      break;
  }
  ADD_FAILURE() << "no Bullet shape here for " << demo::shape_name(body.shape) << " bodies";
  return std::make_unique<btSphereShape>(btScalar(body.half_extents.minCoeff()));
}

// The scene library's rough terrain, 50 m across with noise up to 6 m, `cells` per side, and
// `count` bodies of its mix without meshes (spheres, boxes, capsules, cylinders, hulls), one per
// column of a grid 5 m apart (the library's drop height).
demo::Scene drop_scene(int cells, int count, std::uint64_t seed) {
  demo::SceneOptions options;
  options.terrain.cells = cells;
  options.terrain.kind = demo::TerrainKind::rough;
  options.terrain.width = 50;
  options.terrain.noise_height = 6;
  options.bodies = count;
  options.mix = demo::BodyMix::mixed_without_meshes;
  options.layout.spacing = 5;
  options.layout.max_width = 30;
  return demo::make_scene(options, seed);
}

// A drop scene in one world: its terrain as Bullet's own mesh shape or as BoxtreeMeshShape, its
// bodies with some rolling resistance.
struct DropScene {
  World world;
  BulletMesh mesh;
  const BoxtreeMeshShape* shape = nullptr;
  std::vector<btRigidBody*> bodies;
  std::vector<int> contacts_per_step;

  DropScene(bool boxtree, const demo::Scene& scene, const AlgorithmSettings& settings = {},
            const std::string& method = "aabb")
      : world(boxtree, settings), mesh(*scene.terrain) {
    if (boxtree) {
      auto s = std::make_unique<BoxtreeMeshShape>(*mesh.array, method);
      shape = s.get();
      world.add(std::move(s), 0, btVector3(0, 0, 0));
    } else {
      world.add(std::make_unique<btBvhTriangleMeshShape>(mesh.array.get(), true), 0, btVector3(0, 0, 0));
    }
    for (const demo::BodySpec& spec : scene.bodies) {
      const btVector3 p(btScalar(spec.position.x()), btScalar(spec.position.y()), btScalar(spec.position.z()));
      const btQuaternion q(btScalar(spec.orientation.x()), btScalar(spec.orientation.y()),
                           btScalar(spec.orientation.z()), btScalar(spec.orientation.w()));
      btRigidBody* body = world.add(make_body_shape(spec), btScalar(spec.mass), p, q);
      // Some rolling resistance, so that spheres and cylinders settle in the hollows instead of
      // rolling for ever: the comparison is about resting contact.
      body->setRollingFriction(btScalar(0.05));
      body->setSpinningFriction(btScalar(0.05));
      body->setDamping(btScalar(0.05), btScalar(0.3));
      bodies.push_back(body);
    }
  }
  void run(int steps) {
    for (int i = 0; i < steps; ++i) {
      world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
      contacts_per_step.push_back(world.contact_points());
    }
  }
  double mean_contacts(int from) const {
    double sum = 0;
    for (std::size_t i = std::size_t(from); i < contacts_per_step.size(); ++i) sum += contacts_per_step[i];
    return sum / double(contacts_per_step.size() - std::size_t(from));
  }
};

// Measured on this scene (drop_scene(32, 40, 4) since issue 24's shared scene library; before,
// 40 bodies of the test's own sizes scattered over the terrain and dropped from 8 to 20 m) in CI's
// two passes: gcc -O2 with single-precision Bullet, clang -O1 + ASan with double precision. Bodies
// at rest (below 0.5 m/s): the deepest 2.1 cm into the terrain with gcc, 1.8 cm with clang (both
// Bullet's own; boxtree with GJK 1.2 and 1.2, boxtree analytic 0.05 and 0.1) -> allowance 3 cm (the
// former scene: 1.9 and 2.3 cm). Bodies still moving (rolling down slopes) after 6 s: 7, 6 and 5
// of 40 (Bullet's own, boxtree analytic, boxtree GJK) with gcc, 5, 5 and 4 with clang -> 8 (the
// former scene: at most 9 -> 10). A rolling body's momentary penetration is not a resting depth
// (with clang and an earlier scene, a cylinder rolling at 0.8 m/s was 15.1 cm in on the boxtree
// GJK path), so a moving body is only required to have its centre above the terrain. Contact
// points at rest, against Bullet's own count (143.1 per step with gcc, 135.5 with clang): boxtree
// analytic 0.8% fewer and equal, boxtree GJK 0.3% more and 1.5% fewer -> 5% (the former scene: at
// most 17.0%, with clang, where Bullet's own count fell to 121.8 in double precision -> 18%).
constexpr Real kDropDepthAllowance = 0.03;
constexpr int kDropMovingAllowance = 8;
constexpr double kDropContactRatioAllowance = 0.05;
// Bodies that left the terrain over its edge: none with either compiler (the former scene: one
// sphere of Bullet's own world with both, and with clang one capsule of the all-GJK world) -> 1.
constexpr int kDropOffAllowance = 1;

TEST(BulletAlgorithms, DropSceneRestsLikeBulletsOwnShape) {
  const int count = 40, steps = 360;
  const demo::Scene scene = drop_scene(32, count, 4);
  const AnyTree reference =
      AnyTree::build(std::make_shared<TriangleMesh>(BulletMesh(*scene.terrain).as_boxtree()), Method{});
  DropScene bullet(false, scene);
  DropScene analytic(true, scene);
  AlgorithmSettings gjk_only;
  gjk_only.analyticContacts = false;
  DropScene gjk(true, scene, gjk_only, "obb-min");
  bullet.run(steps);
  analytic.run(steps);
  gjk.run(steps);
  const char* names[] = {"bullet", "boxtree analytic", "boxtree gjk"};
  int which = 0;
  for (const DropScene* world : {&bullet, &analytic, &gjk}) {
    SCOPED_TRACE(names[which++]);
    int moving = 0, off = 0;
    Real deepest = -1e30, deepest_moving = -1e30;
    for (std::size_t i = 0; i < world->bodies.size(); ++i) {
      const btRigidBody& body = *world->bodies[i];
      const auto depth = depth_below(reference, body);
      if (!depth) {
        // Rolled off the terrain's edge (an open sheet), not through it.
        const btVector3 at = body.getWorldTransform().getOrigin();
        std::printf("%s: body %d (%s, %.2f m/s) left the terrain at (%.2f, %.2f, %.2f)\n", names[which - 1], int(i),
                    body.getCollisionShape()->getName(), double(body.getLinearVelocity().length()), double(at.x()),
                    double(at.y()), double(at.z()));
        ++off;
        continue;
      }
      const bool is_moving = body.getLinearVelocity().length() > 0.5f;
      moving += is_moving;
      const std::string what = "body " + std::to_string(i) + " (" + body.getCollisionShape()->getName() + ", " +
                               std::to_string(body.getLinearVelocity().length()) + " m/s)";
      if (is_moving) {
        deepest_moving = std::max(deepest_moving, *depth);
        const Vec3 c = to_vec3(body.getWorldTransform().getOrigin());
        const auto ground = terrain_height_at(reference, c.x(), c.y());
        ASSERT_TRUE(ground) << what << " is off the terrain";
        EXPECT_GT(c.z(), *ground) << what << " has its centre below the terrain";
      } else {
        deepest = std::max(deepest, *depth);
        EXPECT_LT(*depth, kDropDepthAllowance) << what << " rests in the ground";
      }
    }
    std::printf(
        "%s: deepest resting body %.4f m into the terrain, deepest moving one %.4f m; %d of %d bodies still "
        "moving\n",
        names[which - 1], deepest, deepest_moving, moving, count);
    EXPECT_LE(moving, kDropMovingAllowance);
    EXPECT_LE(off, kDropOffAllowance) << "bodies rolled off the terrain";
  }
  const double at_rest_bullet = bullet.mean_contacts(steps - 60);
  const double at_rest_analytic = analytic.mean_contacts(steps - 60);
  const double at_rest_gjk = gjk.mean_contacts(steps - 60);
  std::printf("contact points per step at rest (%d bodies): bullet bvh %.1f, boxtree analytic %.1f, boxtree gjk %.1f\n",
              count, at_rest_bullet, at_rest_analytic, at_rest_gjk);
  // Each body has one manifold of at most 4 points either way; the analytic routines find the
  // same supports, GJK the same as Bullet.
  EXPECT_NEAR(at_rest_analytic / at_rest_bullet, 1.0, kDropContactRatioAllowance);
  EXPECT_NEAR(at_rest_gjk / at_rest_bullet, 1.0, kDropContactRatioAllowance);
}

// A hull with faces (initializePolyhedralFeatures) against the terrain, at fixed poses that
// touch or cut into it: the separating-axis path's deepest contact against Bullet's own
// per-triangle GJK/EPA (analyticContacts off: what it did before, and does without faces), one
// collision pass each. Two-sided facets: one-sided, GJK's contacts pushing out through a facet's
// back are turned to its front at the depth below the facet's plane (collider.h), deeper than the
// separating axes' least lift that clears the triangle where the hull overhangs its edge.
TEST(BulletAlgorithms, HullWithFacesAgreesWithGjkOnTheDeepestContact) {
  const TriangleMesh terrain = make_terrain(24, 24, 5, 12, 1.5);
  Random rng(23);
  const auto xy = [&rng] { return btScalar(rng.uniform(3, 9)); };
  const auto unit = [&rng] { return btScalar(rng.uniform(-1, 1)); };
  int compared = 0, more_points = 0;
  std::vector<Real> differences;  // |deepest contact, face path - GJK|, per pose compared
  for (int trial = 0; trial < 60; ++trial) {
    auto make_hull = [&](Random r) {
      auto hull = std::make_unique<btConvexHullShape>();
      for (int i = 0; i < 10 + trial % 10; ++i) hull->addPoint(draw_vector(r, -0.5, 0.5) * 0.8f, false);
      hull->recalcLocalAabb();
      hull->initializePolyhedralFeatures();
      return hull;
    };
    const Random shape_seed(rng.next());
    const btScalar at_y = xy();  // y first: see tests/support/random.h
    const btVector3 at(xy(), at_y, 0);
    // The angle first, then the axis z, y, x: see tests/support/random.h.
    const btScalar turn_angle = btScalar(rng.uniform(0, 6.28));
    const btScalar axis_z = unit() + 0.01f;
    const btScalar axis_y = unit();
    const btQuaternion turn(btVector3(unit(), axis_y, axis_z).normalized(), turn_angle);
    const btScalar sink = btScalar(0.02 + 0.08 * (trial % 5) / 4.0);  // 2 to 10 cm into the ground
    float deepest[2] = {0, 0};
    int points[2] = {0, 0};
    for (int mode = 0; mode < 2; ++mode) {
      AlgorithmSettings settings;
      settings.analyticContacts = mode == 0;
      settings.hullFaces = mode == 0;
      World world(true, settings);
      auto ground = std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(terrain), "aabb");
      ground->setTwoSided(true);
      const BoxtreeMeshShape* ground_shape = ground.get();
      world.add(std::move(ground), 0, btVector3(0, 0, 0));
      auto hull = make_hull(shape_seed);
      // Lowered until its lowest point (with the margin) is `sink` below the terrain under its centre.
      const btScalar lowest =
          quatRotate(turn, hull->localGetSupportingVertex(quatRotate(turn.inverse(), btVector3(0, 0, -1)))).z();
      const btScalar z = btScalar(terrain_height(ground_shape->tree(), at.x(), at.y())) - lowest - sink;
      world.add(std::move(hull), 1, btVector3(at.x(), at.y(), z), turn);
      world.world.performDiscreteCollisionDetection();
      for (int m = 0; m < world.dispatcher.getNumManifolds(); ++m) {
        const btPersistentManifold* manifold = world.dispatcher.getManifoldByIndexInternal(m);
        points[mode] += manifold->getNumContacts();
        for (int k = 0; k < manifold->getNumContacts(); ++k)
          deepest[mode] = std::min(deepest[mode], float(manifold->getContactPoint(k).getDistance()));
      }
    }
    if (points[1] == 0) continue;  // GJK found nothing (the hull's lowest corner sits over no facet's reach)
    ++compared;
    more_points += points[0] > points[1];
    const Real difference = Real(deepest[0]) - Real(deepest[1]);  // < 0: the face path deeper
    differences.push_back(std::abs(difference));
    // The separating axes are exact (core hull + margin, test_convex_polyhedron's brute force) and
    // EPA on floats comes from inside: on the three poses that differ most below, before the
    // internal edges, the core's separating axes and its own GJK/EPA found the same deepest
    // contact to 0.7 mm (EPA up to 3.5 mm shallower on single facets; gcc). Where the internal edges
    // turn a contact to the face normal, its depth is projected onto that normal (active_edges.h),
    // so a corrected depth follows the normal it came with; where several axes nearly tie, the two
    // paths take different ones. Measured, gcc and clang alike: 48 of 54 poses within 0.1 mm; the
    // GJK path deeper by up to 6.5 mm (trial 19), the face path by up to 34.0 mm (trial 46) ->
    // 1 cm and 4 cm (before, with the tests' former std::mt19937 draws: up to ~4 mm and ~11 mm ->
    // 2 mm and 1.5 cm).
    EXPECT_LE(deepest[0], deepest[1] + 1e-2) << "trial " << trial;
    EXPECT_GE(deepest[0], deepest[1] - 4e-2)
        << "trial " << trial << ": separating axes " << points[0] << " points, GJK " << points[1];
  }
  std::printf("%d poses compared; the face path gave more manifold points than GJK on %d\n", compared, more_points);
  EXPECT_GT(compared, 45);
  // A wrong frame, or a margin counted twice or not at all, would move every pose by the 4 cm
  // margin or more; the edge corrections above move a few. The median difference: 0.02 mm with
  // gcc, 0.03 mm with clang -> 1 mm.
  ASSERT_FALSE(differences.empty());
  std::nth_element(differences.begin(), differences.begin() + std::ptrdiff_t(differences.size() / 2),
                   differences.end());
  const Real median = differences[differences.size() / 2];
  std::printf("median |deepest(face path) - deepest(GJK)| %.5f m\n", double(median));
  EXPECT_LT(median, 1e-3);
  EXPECT_GE(more_points, 5);  // patches: several points from one pass where a face rests on facets
}

TEST(BulletAlgorithms, TightVolumesSendFewerTrianglesToTheNarrowphase) {
  const demo::Scene scene = drop_scene(64, 30, 8);
  DropScene with_algorithm(true, scene);
  AlgorithmSettings bullet_path;
  bullet_path.convexAlgorithm = false;
  DropScene without(true, scene, bullet_path);
  with_algorithm.run(120);
  without.run(120);
  // Without the algorithm, Bullet's convex-concave path asks processAllTriangles with each body's
  // box and runs its narrowphase on every triangle returned; with it, processAllTriangles is
  // never called for contacts and only triangles meeting the body's own volume get a contact
  // routine.
  EXPECT_EQ(with_algorithm.shape->counters().queries, 0u);
  const auto tight = with_algorithm.shape->counters().narrowphase_triangles;
  const auto by_box = without.shape->counters().triangles;
  std::printf("triangles to the narrowphase over 120 steps: %llu with the body's volume, %llu with its box\n",
              static_cast<unsigned long long>(tight), static_cast<unsigned long long>(by_box));
  EXPECT_GT(tight, 0u);
  EXPECT_LT(double(tight), 0.7 * double(by_box));
}

TEST(BulletAlgorithms, MeshOnMeshComesToRest) {
  World world(true);
  const TriangleMesh terrain = make_terrain(24, 24, 2, 30, 0.4);
  auto ground = std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(terrain), "obb-min");
  const BoxtreeMeshShape* ground_shape = ground.get();
  world.add(std::move(ground), 0, btVector3(0, 0, 0));
  auto rock =
      std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(make_bumpy_sphere(10, 6, 0.3, 5)), "obb-min");
  rock->setMargin(btScalar(0.02));
  btRigidBody* body = world.add(std::move(rock), 2, btVector3(15, 15, 4));
  body->setRollingFriction(btScalar(0.1));
  int steps_with_contacts = 0;
  for (int i = 0; i < 400; ++i) {
    world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    if (world.contact_points() > 0) ++steps_with_contacts;
  }
  const auto depth = depth_below(ground_shape->tree(), *body);
  ASSERT_TRUE(depth);
  std::printf("rock on the terrain: lowest vertex %.3g m below the terrain under it\n", *depth);
  // Measured: 2.6 um in (single precision; 1.3 um double): mesh pairs touch only where triangles
  // cross. Allowed: 2 mm in, 1 cm above.
  EXPECT_LT(*depth, 0.002);
  EXPECT_GT(*depth, -0.01);
  EXPECT_LT(body->getLinearVelocity().length(), 0.2f);
  EXPECT_GT(steps_with_contacts, 200);

  // The manifold's points come from the facet pairs the core's tree-vs-tree query finds: each
  // point lies on the facet its index names (the mesh's facet on body B), and at rest the
  // meshes are in contact by both accounts.
  const auto* rock_shape = static_cast<const BoxtreeMeshShape*>(body->getCollisionShape());
  ASSERT_EQ(world.dispatcher.getNumManifolds(), 1);
  const btPersistentManifold* m = world.dispatcher.getManifoldByIndexInternal(0);
  ASSERT_GT(m->getNumContacts(), 0);
  const bool rock_is_b = m->getBody1() == body;
  const BoxtreeMeshShape* b_shape = rock_is_b ? rock_shape : ground_shape;
  const btTransform b_pose = m->getBody1()->getWorldTransform();
  for (int k = 0; k < m->getNumContacts(); ++k) {
    const btManifoldPoint& pt = m->getContactPoint(k);
    btVector3 tri[3];
    b_shape->scaledTriangle(b_shape->partToFacet(pt.m_partId1, pt.m_index1), tri);
    const Vec3 local = to_vec3(b_pose.invXform(pt.m_positionWorldOnB));
    const Vec3 closest = closest_point_on_triangle(local, to_vec3(tri[0]), to_vec3(tri[1]), to_vec3(tri[2]));
    EXPECT_LT((closest - local).norm(), 1e-4) << "point " << k;
  }
  const btTransform pose = body->getWorldTransform();
  RigidTransform ground_from_rock{to_mat_test(pose.getBasis()), to_vec3(pose.getOrigin())};
  // Touching within the contact margin: the rock moved down by the margins meets the ground.
  ground_from_rock.translation.z() -= 0.05;
  const auto pairs = collide(*ground_shape->tree().get<ObbMin>(), *rock_shape->tree().get<ObbMin>(), ground_from_rock);
  EXPECT_FALSE(pairs.empty());
}

// Tori under heavy boxes on a terrain of cells finer than their facets: pressed in past the
// middle of the tube, the upward faces of a torus cross the ground, and taking their normals
// (the larger faces) pulled tori through it (7 of 10 under 200 kg in the drop scene's terrain,
// before the terrain's faces resolved such pairs: contact.h's FixedSurface). Returns how deep
// each torus's lowest vertex ends below the terrain under it (nullopt: no terrain under it).
std::vector<std::optional<Real>> tori_under_boxes(btScalar box_mass) {
  World world(true);
  const TriangleMesh terrain = make_terrain(80, 80, 3, 4, 0.3);  // 5 cm cells
  auto ground = std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(terrain), "aabb");
  const BoxtreeMeshShape* ground_shape = ground.get();
  world.add(std::move(ground), 0, btVector3(0, 0, 0));
  const auto torus = std::make_shared<TriangleMesh>(make_torus(0.21, 0.09, 18, 8));  // 8 cm facets, 17 kg
  std::vector<btRigidBody*> tori;
  for (int k = 0; k < 9; ++k) {
    const btScalar x = btScalar(0.7 + 1.3 * (k % 3)), y = btScalar(0.7 + 1.3 * (k / 3));
    const btScalar z = btScalar(terrain_height(ground_shape->tree(), x, y));
    tori.push_back(world.add(std::make_unique<BoxtreeMeshShape>(torus, "aabb"), 17, btVector3(x, y, z + 0.4f)));
    world.add(std::make_unique<btBoxShape>(btVector3(0.4f, 0.4f, 0.1f)), box_mass, btVector3(x, y, z + 0.8f));
  }
  for (int i = 0; i < 300; ++i) world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
  std::vector<std::optional<Real>> depths;
  for (const btRigidBody* t : tori) depths.push_back(depth_below(ground_shape->tree(), *t));
  return depths;
}

// Deepest measured at the end under 100 kg: 0.9 cm (single-precision Bullet; 0.8 double; during
// the landing up to 9 cm for a step or two); allowance 1.2 cm.
constexpr Real kToriDepthAllowance = 0.012;

TEST(BulletAlgorithms, MeshBodyUnderLoadDoesNotSinkThroughAFineTerrain) {
  const auto depths = tori_under_boxes(100);  // 6 times the torus's mass
  Real deepest = -1e30;
  for (std::size_t k = 0; k < depths.size(); ++k) {
    ASSERT_TRUE(depths[k]) << "torus " << k << " is off the terrain";
    deepest = std::max(deepest, *depths[k]);
    EXPECT_LT(*depths[k], kToriDepthAllowance) << "torus " << k;
  }
  std::printf("tori under 100 kg boxes: deepest vertex %.4f m below the terrain under it\n", deepest);
}

// Known defect, disabled so that it is seen (gtest lists disabled tests) without failing the suite:
// under 400 kg (24 times the torus's mass) some of the 9 tori are pushed through the terrain and
// fall (measured: 2 with single-precision Bullet, 3 with double; 1 with one torus mesh per body
// instead of a shared one), and those left rest within a centimetre. Bullet's own shapes do worse here (GImpact tori on
// btBvhTriangleMeshShape: all 9 fall through, already under 50 kg): the contacts of a mesh pair
// exist only while triangles intersect, and the solver does not stop a 400 kg box driving a 17 kg
// body through in one or two steps. Run with --gtest_also_run_disabled_tests.
TEST(BulletAlgorithms, DISABLED_MeshBodyUnderHeavyLoadDoesNotSinkThroughAFineTerrain) {
  const auto depths = tori_under_boxes(400);
  for (std::size_t k = 0; k < depths.size(); ++k) {
    if (!depths[k]) {
      ADD_FAILURE() << "torus " << k << " went through the terrain and fell off beneath it";
      continue;
    }
    EXPECT_LT(*depths[k], kToriDepthAllowance) << "torus " << k;
  }
}

// A flat floor of many triangles: a box pushed across it (no friction) must slide without hopping
// or spinning at the shared edges. Bullet's own shape, without its internal-edge utility, is run
// alongside as the reference for what bumping looks like.
struct Slide {
  float max_up = 0, max_spin = 0, final_x = 0;
};
Slide slide_box(int mode) {  // 0: boxtree analytic, 1: boxtree with Bullet's GJK, 2: Bullet's BVH
  AlgorithmSettings settings;
  settings.analyticContacts = mode == 0;
  World world(mode != 2, settings);
  static const TriangleMesh floor = make_terrain(40, 40, 1, 40, 0);
  static const BulletMesh bullet_floor(floor);
  if (mode == 2) {
    world.add(std::make_unique<btBvhTriangleMeshShape>(bullet_floor.array.get(), true), 0, btVector3(0, 0, 0));
  } else {
    world.add(std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(floor), "aabb"), 0, btVector3(0, 0, 0));
  }
  btRigidBody* box =
      world.add(std::make_unique<btBoxShape>(btVector3(0.5f, 0.5f, 0.25f)), 1, btVector3(5, 5.3f, 0.26f));
  box->setFriction(0.0f);
  for (int i = 0; i < 30; ++i) world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
  box->setLinearVelocity(btVector3(6, 3.5f, 0));
  box->setActivationState(DISABLE_DEACTIVATION);
  Slide s;
  for (int i = 0; i < 240; ++i) {
    world.world.stepSimulation(btScalar(1.0 / 60), 1, btScalar(1.0 / 60));
    s.max_up = std::max(s.max_up, float(box->getLinearVelocity().z()));
    s.max_spin = std::max(s.max_spin, float(box->getAngularVelocity().length()));
  }
  s.final_x = float(box->getCenterOfMassPosition().x());
  return s;
}

TEST(BulletAlgorithms, SlidingBoxDoesNotBumpOnInternalEdges) {
  const Slide analytic = slide_box(0), gjk = slide_box(1), bullet = slide_box(2);
  std::printf(
      "sliding box, max upward speed / max spin: boxtree analytic %.3f / %.3f, boxtree gjk %.3f / %.3f, "
      "bullet bvh %.3f / %.3f\n",
      analytic.max_up, analytic.max_spin, gjk.max_up, gjk.max_spin, bullet.max_up, bullet.max_spin);
  for (const Slide& s : {analytic, gjk}) {
    EXPECT_GT(s.final_x, 25.0f);  // slid over ~20 cells, ~60 shared edges
    EXPECT_LT(s.max_up, 0.2f);    // m/s; Bullet's own shape reaches about 2
    EXPECT_LT(s.max_spin, 1.0f);  // rad/s; Bullet's own shape reaches about 5
  }
  EXPECT_LT(analytic.max_up, 0.1f);
  EXPECT_LT(analytic.max_spin, 0.5f);
  EXPECT_GT(bullet.max_up, 5 * analytic.max_up);  // the scene does provoke bumps
}

// AlgorithmSettings::analyticContacts: a box 1 cm into one large facet gets its four bottom
// corners from one collision pass with the core's box routine, one point from Bullet's GJK/EPA.
TEST(BulletAlgorithms, AnalyticContactsGiveTheBoxFaceInOnePass) {
  const TriangleMesh floor = make_terrain(1, 1, 1, 40, 0);  // two facets, 40 m square, z = 0
  for (const bool analytic : {true, false}) {
    SCOPED_TRACE(analytic ? "analytic" : "gjk");
    AlgorithmSettings settings;
    settings.analyticContacts = analytic;
    World world(true, settings);
    auto ground = std::make_unique<BoxtreeMeshShape>(std::make_shared<TriangleMesh>(floor));
    const BoxtreeMeshShape* ground_shape = ground.get();
    world.add(std::move(ground), 0, btVector3(0, 0, 0));
    // Over the middle of the facet below the diagonal, 11 m from its other edges.
    world.add(std::make_unique<btBoxShape>(btVector3(0.5f, 0.5f, 0.25f)), 1, btVector3(28, 12, 0.24f));
    world.world.performDiscreteCollisionDetection();
    EXPECT_EQ(world.contact_points(), analytic ? 4 : 1);
    EXPECT_EQ(ground_shape->counters().narrowphase_triangles, 1u);
  }
}

// AlgorithmSettings::meshMeshAlgorithm: without it, Bullet has nothing for a boxtree mesh against
// a boxtree mesh (its empty algorithm): a rock sunk into the ground gets no contact, while a
// sphere beside it still does (the convex algorithm is registered on its own).
TEST(BulletAlgorithms, MeshMeshAlgorithmCanBeLeftOut) {
  const auto floor = std::make_shared<TriangleMesh>(make_terrain(8, 8, 1, 16, 0));
  const auto rock = std::make_shared<TriangleMesh>(make_uv_sphere(12, 8, 1));
  for (const bool mesh_mesh : {true, false}) {
    SCOPED_TRACE(mesh_mesh ? "with" : "without");
    AlgorithmSettings settings;
    settings.meshMeshAlgorithm = mesh_mesh;
    World world(true, settings);
    world.add(std::make_unique<BoxtreeMeshShape>(floor), 0, btVector3(0, 0, 0));
    btRigidBody* rock_body = world.add(std::make_unique<BoxtreeMeshShape>(rock), 1, btVector3(4, 4, 0.9f));
    btRigidBody* sphere_body = world.add(std::make_unique<btSphereShape>(0.5f), 1, btVector3(12, 12, 0.49f));
    world.world.performDiscreteCollisionDetection();
    int rock_points = 0, sphere_points = 0;
    for (int i = 0; i < world.dispatcher.getNumManifolds(); ++i) {
      const btPersistentManifold* m = world.dispatcher.getManifoldByIndexInternal(i);
      if (m->getBody0() == rock_body || m->getBody1() == rock_body) rock_points += m->getNumContacts();
      if (m->getBody0() == sphere_body || m->getBody1() == sphere_body) sphere_points += m->getNumContacts();
    }
    if (mesh_mesh) {
      EXPECT_GT(rock_points, 0);
    } else {
      EXPECT_EQ(rock_points, 0);
    }
    EXPECT_GT(sphere_points, 0);
  }
}

// boxtreeAlgorithmMaxSize is at least an algorithm object (Bullet's base plus the manifold
// pointer), and registration refuses a pool one pointer smaller and accepts one of that size.
// (One pointer, not one byte: btPoolAllocator threads its free list through the elements, so an
// element size that is not a multiple of a pointer is itself undefined behaviour, which UBSan
// reports in the pool's constructor.)
TEST(BulletAlgorithms, RegistrationChecksThePoolSize) {
  EXPECT_GT(boxtreeAlgorithmMaxSize(), int(sizeof(btActivatingCollisionAlgorithm)));
  ASSERT_EQ(boxtreeAlgorithmMaxSize() % int(sizeof(void*)), 0);
  for (const int element_size : {boxtreeAlgorithmMaxSize() - int(sizeof(void*)), boxtreeAlgorithmMaxSize()}) {
    btPoolAllocator pool(element_size, 64);
    btDefaultCollisionConstructionInfo info;
    info.m_collisionAlgorithmPool = &pool;  // the configuration uses it, and does not own it
    btDefaultCollisionConfiguration config(info);
    btCollisionDispatcher dispatcher(&config);
    if (element_size < boxtreeAlgorithmMaxSize()) {
      EXPECT_THROW(registerBoxtreeAlgorithms(&dispatcher), Error);
    } else {
      EXPECT_NO_THROW(registerBoxtreeAlgorithms(&dispatcher));
    }
  }
  EXPECT_THROW(registerBoxtreeAlgorithms(nullptr), Error);
}

}  // namespace
}  // namespace boxtree::bullet::test
