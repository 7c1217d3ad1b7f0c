// SPDX-License-Identifier: MIT
// Temporal coherence (collide_front.h, collider.h's MeshPairCache): tree vs tree from the last
// call's front reports exactly the facet pairs of a fresh descent, and collide_meshes with a cache
// gives bit for bit the contacts it gives without one, over motion sequences with resting, moving,
// separating and returning bodies; the front stays under its cap.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "boxtree/collide_front.h"
#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/generate.h"
#include "support/meshes.h"
#include "support/random.h"

namespace boxtree {
namespace {

using test::Random;

// A pose sequence of b in a's frame: phases of rest (the same pose, or a jitter of 1e-6), slow
// drift and turn, fast motion, a jump far away (the pair disappears) and a jump back into a's
// surface (it reappears). One draw per statement.
class Motion {
 public:
  // `reach`: how far from a's centre b's centre comes back to (b then overlaps a's surface).
  Motion(Random& random, const Aabb& a_bounds, Real reach) : random_(random), bounds_(a_bounds), reach_(reach) {
    reset_near();
  }

  const RigidTransform& pose() const { return pose_; }

  void step() {
    if (--left_ <= 0) {
      const int kind = random_.integer(0, 5);
      phase_ = kind;
      left_ = random_.integer(3, 12);
      if (kind == 4) reset_far();
      if (kind == 5) reset_near();
    }
    const Real size = bounds_.extent().norm();
    switch (phase_) {
      case 0:  // at rest
        return;
      case 1:  // resting with a jitter, as a settled body in an engine
        move(size * 1e-6, 1e-6);
        return;
      case 2:  // slow
        move(size * 0.004, 0.01);
        return;
      default:  // fast, or after a jump
        move(size * 0.05, 0.1);
        return;
    }
  }

 private:
  void move(Real reach, Real angle) {
    const Vec3 shift = random_.point(-reach, reach);
    const Vec3 axis = random_.unit_vector();
    const Real turn = random_.uniform(-angle, angle);
    pose_.translation += shift;
    pose_.rotation = (Eigen::AngleAxis<Real>(turn, axis).toRotationMatrix() * pose_.rotation).eval();
    // Keep it a rotation to 1e-9 (collide checks 1e-6; drift over thousands of steps adds up).
    pose_.rotation = Eigen::Quaternion<Real>(pose_.rotation).normalized().toRotationMatrix();
  }
  void reset_near() {
    const Vec3 direction = random_.unit_vector();
    const Real distance = random_.uniform(0.7, 1) * reach_;
    pose_.rotation = random_.rotation();
    pose_.translation = bounds_.center() + direction * distance;
  }
  void reset_far() { pose_.translation = bounds_.center() + Vec3(3, 0, 0) * bounds_.extent().norm(); }

  Random& random_;
  Aabb bounds_;
  Real reach_;
  RigidTransform pose_;
  int phase_ = 2, left_ = 8;
};

std::vector<FacetPair> sorted(std::vector<FacetPair> pairs) {
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

struct MeshPair {
  const char* name;
  std::shared_ptr<const CollisionMesh> a, b;
};

// Generated meshes always; real ones from ../shared/meshes when present.
std::vector<MeshPair> mesh_pairs() {
  const auto build = [](TriangleMesh mesh) {
    return CollisionMesh::build(std::make_shared<const TriangleMesh>(std::move(mesh)), Method{});
  };
  std::vector<MeshPair> pairs;
  const auto torus = build(make_torus(1, 0.35, 24, 12));
  const auto rock = build(make_bumpy_sphere(20, 12, 0.15, 7));
  pairs.push_back({"torus-rock", torus, rock});
  pairs.push_back({"rock-rock", rock, rock});
  pairs.push_back({"terrain-rock", build(make_terrain(24, 24, 3, 6, 1)), rock});
  if (test::use_shared_meshes_if_present()) {
    // Both scaled to a diameter of 2 about the origin (the bunny is 0.2 across, the cow 2).
    const auto unit = [](TriangleMesh mesh) {
      Aabb box = Aabb::empty();
      for (const Vec3& v : mesh.vertices) box.expand(v);
      const Vec3 center = box.center();
      const Real scale = 2 / box.extent().norm();
      for (Vec3& v : mesh.vertices) v = (v - center) * scale;
      return mesh;
    };
    const auto bunny = build(unit(test::load_shared_mesh("bunny_libigl_closed.obj")));
    const auto spot = build(unit(test::load_shared_mesh("spot.obj")));
    pairs.push_back({"bunny-spot", bunny, spot});
    pairs.push_back({"spot-spot", spot, spot});
  }
  return pairs;
}

// How far from a's centre b's centre comes back to: well inside both bounding spheres.
Real reach_of(const MeshPair& meshes) {
  return 0.3 * (meshes.a->bounds().extent().norm() + meshes.b->bounds().extent().norm());
}

TEST(CollideFront, SameFacetPairsAsAFreshDescentOverMotionSequences) {
  Random random(11);
  std::size_t pairs_seen = 0, kept = 0, kept_whole = 0, pulled = 0, descended = 0;
  for (const MeshPair& meshes : mesh_pairs()) {
    SCOPED_TRACE(meshes.name);
    ASSERT_NE(meshes.a->tree().packed(), nullptr);
    ASSERT_NE(meshes.b->tree().packed(), nullptr);
    const PackedAabbTree& a = *meshes.a->tree().packed();
    const PackedAabbTree& b = *meshes.b->tree().packed();
    Motion motion(random, meshes.a->bounds(), reach_of(meshes));
    CollideFront front;
    std::size_t fresh_tests = 0, front_tests = 0, largest = 0, overflows = 0;
    for (int step = 0; step < test::scaled(300); ++step) {
      motion.step();
      QueryStats fresh_stats, front_stats;
      const std::vector<FacetPair> want = collide(a, b, motion.pose(), &fresh_stats);
      std::vector<FacetPair> got;
      collide(
          a, b, motion.pose(), front,
          [&](const FacetPair& p) {
            got.push_back(p);
            return true;
          },
          &front_stats);
      ASSERT_EQ(sorted(got), want) << "step " << step;
      // Each facet pair once.
      EXPECT_EQ(std::adjacent_find(want.begin(), want.end()), want.end());
      pairs_seen += want.size();
      kept += front.last_call().kept_apart;
      kept_whole += front.last_call().kept_whole;
      pulled += front.last_call().pulled_up;
      descended += front.last_call().descended;
      fresh_tests += fresh_stats.volume_tests;
      front_tests += front_stats.volume_tests;
      largest = std::max(largest, front.size());
      EXPECT_LE(front.size(), front.max_records());
      EXPECT_LE(front.memory_bytes(), 2 * front.max_records() * sizeof(CollideFront::Record));
      overflows += front.last_call().overflowed;
    }
    std::cout << "[          ] " << meshes.name << ": volume tests with the front " << front_tests << ", fresh "
              << fresh_tests << ", largest front " << largest << " records, " << overflows << " overflows\n";
  }
  // The sequences exercised every branch: contact, resting pairs kept (one by one and as whole
  // subtrees), descents and pull-ups.
  EXPECT_GT(pairs_seen, 500u);
  EXPECT_GT(kept, 0u);
  EXPECT_GT(kept_whole, 0u);
  EXPECT_GT(pulled, 0u);
  EXPECT_GT(descended, 0u);
}

// Bodies that separate: the front is pulled back up to the root pair.
TEST(CollideFront, PulledBackUpAsBodiesSeparate) {
  const auto rock =
      CollisionMesh::build(std::make_shared<const TriangleMesh>(make_bumpy_sphere(20, 12, 0.15, 7)), Method{});
  const PackedAabbTree& tree = *rock->tree().packed();
  CollideFront front;
  RigidTransform pose;
  pose.translation = Vec3(1.2, 0.3, 0.1);  // overlapping
  const auto count = [&] {
    std::size_t n = 0;
    collide(tree, tree, pose, front, [&](const FacetPair&) {
      ++n;
      return true;
    });
    return n;
  };
  EXPECT_GT(count(), 0u);
  const std::size_t touching = front.size();
  EXPECT_GT(touching, 10u);
  for (int step = 0; step < 200; ++step) {
    pose.translation.x() += 0.02;
    count();
  }
  EXPECT_EQ(count(), 0u);
  EXPECT_EQ(front.size(), 1u);  // the root pair, apart
  EXPECT_EQ(front.cut_size(), 1u);
  // Far apart and still: nothing is tested again.
  QueryStats stats;
  collide(
      tree, tree, pose, front, [](const FacetPair&) { return true; }, &stats);
  EXPECT_EQ(stats.volume_tests, 0u);
  EXPECT_EQ(front.last_call().kept_apart, 1u);
}

// A body that zigzags towards the other in small steps, two forward and one back: the records
// expire by the motion since they were written, so every touching pair is found as a fresh
// descent finds it, the last one included.
TEST(CollideFront, ZigzagApproachFindsWhatAFreshDescentFinds) {
  const auto rock =
      CollisionMesh::build(std::make_shared<const TriangleMesh>(make_bumpy_sphere(20, 12, 0.15, 7)), Method{});
  const PackedAabbTree& tree = *rock->tree().packed();
  RigidTransform pose;
  pose.translation = Vec3(3.0, 0.3, 0.1);  // apart
  while (collide(tree, tree, pose).empty()) pose.translation.x() -= 0.01;
  pose.translation.x() += 0.03;  // 2 to 3 hundredths short of touching
  const Real step_length = 3e-4 * tree.bounds().extent().norm();
  CollideFront front;
  std::size_t touching_calls = 0, kept = 0;
  for (int step = 0; step < 600; ++step) {
    pose.translation.x() += step % 3 == 2 ? step_length : -step_length;
    std::vector<FacetPair> got;
    collide(tree, tree, pose, front, [&](const FacetPair& p) {
      got.push_back(p);
      return true;
    });
    const std::vector<FacetPair> want = collide(tree, tree, pose);
    ASSERT_EQ(sorted(got), want) << "step " << step;
    touching_calls += !want.empty();
    kept += front.last_call().kept_apart;
  }
  EXPECT_GT(touching_calls, 100u);  // it came into contact, and went deeper
  EXPECT_GT(kept, 1000u);           // and the front kept pairs on the way
}

// Past the cap the call still reports every pair, keeps no front (nor its memory) and the next
// kFreshCallsAfterOverflow calls descend fresh; a stopping visitor drops the front too.
TEST(CollideFront, CapAndEarlyStop) {
  const auto rock =
      CollisionMesh::build(std::make_shared<const TriangleMesh>(make_bumpy_sphere(20, 12, 0.15, 7)), Method{});
  const PackedAabbTree& tree = *rock->tree().packed();
  const RigidTransform pose{Mat3::Identity(), Vec3(0.9, 0.2, 0.1)};
  const std::vector<FacetPair> want = collide(tree, tree, pose);
  ASSERT_GT(want.size(), 20u);
  CollideFront small(64);
  const auto run = [&](CollideFront& front) {
    std::vector<FacetPair> got;
    collide(tree, tree, pose, front, [&](const FacetPair& p) {
      got.push_back(p);
      return true;
    });
    return sorted(got);
  };
  EXPECT_EQ(run(small), want);
  EXPECT_TRUE(small.last_call().overflowed);
  EXPECT_TRUE(small.empty());
  EXPECT_EQ(small.memory_bytes(), 0u);
  for (int i = 0; i < CollideFront::kFreshCallsAfterOverflow; ++i) {
    EXPECT_EQ(run(small), want);
    EXPECT_TRUE(small.last_call().fresh);
    EXPECT_TRUE(small.empty());
  }
  EXPECT_EQ(run(small), want);  // tries again (and overflows again)
  EXPECT_FALSE(small.last_call().fresh);
  EXPECT_TRUE(small.last_call().overflowed);

  CollideFront front;
  EXPECT_EQ(run(front), want);
  EXPECT_FALSE(front.empty());
  int visits = 0;
  collide(tree, tree, pose, front, [&](const FacetPair&) { return ++visits < 3; });
  EXPECT_EQ(visits, 3);
  EXPECT_TRUE(front.empty());
  EXPECT_EQ(run(front), want);
}

// Bit for bit: the same contacts in the same order, the same counts.
void expect_identical(const ContactResult& got, const ContactResult& want) {
  ASSERT_EQ(got.contacts.size(), want.contacts.size());
  for (std::size_t i = 0; i < got.contacts.size(); ++i) {
    const ContactPoint& g = got.contacts[i];
    const ContactPoint& w = want.contacts[i];
    EXPECT_EQ(g.facet, w.facet) << i;
    EXPECT_EQ(g.other_facet, w.other_facet) << i;
    EXPECT_TRUE(g.position == w.position && g.normal == w.normal && g.depth == w.depth) << "contact " << i;
  }
  EXPECT_EQ(got.counts.candidates, want.counts.candidates);
  EXPECT_EQ(got.counts.found, want.counts.found);
  EXPECT_EQ(got.counts.merged, want.counts.merged);
  EXPECT_EQ(got.counts.dropped, want.counts.dropped);
  EXPECT_EQ(got.counts.edge_corrected, want.counts.edge_corrected);
  EXPECT_EQ(got.counts.edge_discarded, want.counts.edge_discarded);
}

TEST(MeshPairCache, ContactsBitIdenticalWithAndWithoutCoherence) {
  Random random(12);
  std::size_t contacts = 0;
  for (const MeshPair& meshes : mesh_pairs()) {
    SCOPED_TRACE(meshes.name);
    Motion motion(random, meshes.a->bounds(), reach_of(meshes));
    MeshPairCache cache;
    for (int step = 0; step < test::scaled(200); ++step) {
      motion.step();
      MeshContactRequest request;
      request.policy = step % 3 == 0 ? MeshContactPolicy::triangle_pairs : MeshContactPolicy::face_normals;
      request.static_mesh = StaticMesh::mesh;
      request.margin = step % 2 == 0 ? 0.0 : 0.01;
      request.merge_distance = 0.01;
      request.max_contacts = step % 5 == 0 ? 100000 : 4;
      ContactResult cached, fresh;
      collide_meshes(*meshes.a, *meshes.b, motion.pose(), request, cached, &cache);
      collide_meshes(*meshes.a, *meshes.b, motion.pose(), request, fresh);
      {
        SCOPED_TRACE(testing::Message() << "step " << step);
        expect_identical(cached, fresh);
      }
      if (HasFatalFailure()) return;
      contacts += fresh.contacts.size();
      EXPECT_LE(cache.front().size(), cache.front().max_records());
    }
  }
  EXPECT_GT(contacts, 100u);
}

// What drops or bypasses the front: early_stop, coherence off, another layout, other meshes.
TEST(MeshPairCache, FallsBackToAFreshDescent) {
  const auto rock_mesh = std::make_shared<const TriangleMesh>(make_bumpy_sphere(20, 12, 0.15, 7));
  const auto rock = CollisionMesh::build(rock_mesh, Method{});
  const auto torus = CollisionMesh::build(std::make_shared<const TriangleMesh>(make_torus(1, 0.35, 24, 12)), Method{});
  const auto rock_obb = CollisionMesh::build(rock_mesh, parse_method("obb-min"));
  const RigidTransform pose{Mat3::Identity(), Vec3(0.9, 0.2, 0.1)};
  MeshContactRequest request;
  MeshPairCache cache;
  ContactResult cached, fresh;
  const auto both = [&](const CollisionMesh& a, const CollisionMesh& b, const MeshContactRequest& r) {
    cached.clear();
    fresh.clear();
    collide_meshes(a, b, pose, r, cached, &cache);
    collide_meshes(a, b, pose, r, fresh);
    expect_identical(cached, fresh);
  };
  both(*rock, *torus, request);
  EXPECT_FALSE(cache.front().empty());
  const std::size_t records = cache.front().size();
  both(*rock, *torus, request);
  EXPECT_EQ(cache.front().last_call().records_in, records);  // started from the front
  both(*torus, *rock, request);                              // swapped: afresh
  EXPECT_EQ(cache.front().last_call().records_in, 0u);
  MeshContactRequest off = request;
  off.coherence = false;
  both(*torus, *rock, off);
  EXPECT_TRUE(cache.front().empty());
  both(*rock_obb, *torus, request);  // obb-min against aabb: both walked as obb-min trees, no front
  EXPECT_TRUE(cache.front().empty());
  both(*rock, *torus, request);
  EXPECT_FALSE(cache.front().empty());
  MeshContactRequest stop = request;
  stop.early_stop = true;
  stop.max_contacts = 1;
  both(*rock, *torus, stop);
  EXPECT_TRUE(cache.front().empty());
}

}  // namespace
}  // namespace boxtree
