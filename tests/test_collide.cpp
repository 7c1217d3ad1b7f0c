// SPDX-License-Identifier: MIT
// Tree vs tree against all-pairs brute force, under random rigid motions.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/geometry.h"
#include "boxtree/packed_tree.h"
#include "boxtree/volume/aabb.h"
#include "support/brute_force.h"
#include "support/checks.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

RigidTransform random_motion(Random& r, double translation) {
  // z, y, x, then w: gcc's order for the former Quaterniond(w, x, y, z) of four draws (see tests/support/random.h).
  const Real z = r.uniform(-1, 1);
  const Real y = r.uniform(-1, 1);
  const Real x = r.uniform(-1, 1);
  const Real w = r.uniform(-1, 1);
  Eigen::Quaterniond q(w, x, y, z);
  q.normalize();
  RigidTransform t;
  t.rotation = q.toRotationMatrix();
  t.translation = r.uniform_vec3(-translation, translation);
  return t;
}

void check_pair(const TriangleMesh& mesh_a, const TriangleMesh& mesh_b, int poses, double translation,
                const std::string& name, std::size_t* total_pairs = nullptr) {
  const Tree<Aabb> a = build_tree<Aabb>(mesh_a);
  const Tree<Aabb> b = build_tree<Aabb>(mesh_b);
  Random r(99);
  std::size_t sum = 0;
  for (int i = 0; i < poses; ++i) {
    const RigidTransform a_from_b = i == 0 ? RigidTransform::identity() : random_motion(r, translation);
    QueryStats stats;
    const std::vector<FacetPair> got = collide(a, b, a_from_b, &stats);
    const test::Expected<FacetPair> expected = test::brute_collide(mesh_a, mesh_b, a_from_b);
    ASSERT_EQ(test::violations(got, expected), "") << name << " pose " << i;
    EXPECT_EQ(stats.leaf_tests >= got.size(), true);
    sum += got.size();

    CollideSettings first;
    first.stop_at_first = true;
    const std::vector<FacetPair> one = collide(a, b, a_from_b, nullptr, first);
    EXPECT_EQ(one.size(), got.empty() ? 0u : 1u) << name;
    if (!one.empty()) {
      EXPECT_TRUE(std::binary_search(expected.may.begin(), expected.may.end(), one.front()));
    }
  }
  if (total_pairs) *total_pairs = sum;
}

TEST(Collide, MatchesBruteForceOnProceduralMeshes) {
  std::size_t pairs = 0;
  check_pair(make_bumpy_sphere(30, 15, 0.2, 1), make_bumpy_sphere(24, 12, 0.3, 2), 20, 0.8, "bumpy spheres", &pairs);
  EXPECT_GT(pairs, 0u);
  check_pair(make_triangle_soup(800, 3, 1, 0.15), make_triangle_soup(600, 4, 1, 0.15), 10, 0.3, "soups", &pairs);
  EXPECT_GT(pairs, 0u);
  check_pair(make_terrain(20, 20, 1, 10, 3), make_uv_sphere(16, 8, 2, Vec3(5, 5, 1)), 10, 2, "terrain vs sphere");
  check_pair(test::make_cone(100), make_uv_sphere(12, 6, 0.5), 10, 0.5, "cone vs sphere");
}

// The same mesh against itself at the identity: every facet touches itself and its neighbours,
// the densest touching/coplanar case there is. At the identity brute force gives the exact answer
// (must == may), which triangles_intersect promises: its coordinates are not dyadic, and before its
// signs were exact it missed 580 of these 3370 pairs.
TEST(Collide, SelfContactIsExact) {
  const TriangleMesh mesh = make_terrain(12, 12, 2, 10, 2);
  const Tree<Aabb> tree = build_tree<Aabb>(mesh);
  const std::vector<FacetPair> got = collide(tree, tree, RigidTransform::identity());
  const test::Expected<FacetPair> expected = test::brute_collide(mesh, mesh, RigidTransform::identity());
  EXPECT_EQ(test::violations(got, expected), "");
  for (FacetId f = 0; f < mesh.facet_count(); ++f)
    EXPECT_TRUE(std::binary_search(got.begin(), got.end(), FacetPair{f, f}));
}

// The pairs for which triangles_intersect, on a's corners and on b's corners moved by a_from_b
// (the very doubles that collide tests), says the facets meet: exactly what collide reports.
std::vector<FacetPair> meeting_pairs(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b) {
  std::vector<Vec3> moved(b.vertices.size());
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = a_from_b.apply(b.vertices[i]);
  std::vector<FacetPair> out;
  for (FacetId fa = 0; fa < a.facet_count(); ++fa) {
    for (FacetId fb = 0; fb < b.facet_count(); ++fb) {
      const auto& t = b.triangles[fb];
      if (triangles_intersect(a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2), moved[t[0]], moved[t[1]], moved[t[2]]))
        out.push_back({fa, fb});
    }
  }
  return out;
}

// The walks keep the facets they meet prepared for the leaf test (b's corners moved, bounding
// boxes, planes: query_internal.h's FacetPairTest) and reuse them for later pairs; that must
// change no answer. A mesh against itself moved by a few ulps or turned by ~1e-10, also 1e4 from
// the origin: nearly every leaf pair touches or nearly so and goes to the exact stage on a reused
// plane. A small body on a larger terrain takes the packed tree's other path (the facets gathered
// in the body's root box, each against the body's tree).
TEST(Collide, LeafPairsAreTrianglesIntersectOnTheMovedCorners) {
  test::Random r(77);
  std::size_t pairs = 0;
  const auto check = [&](const TriangleMesh& mesh_a, const TriangleMesh& mesh_b, const RigidTransform& a_from_b,
                         const std::string& name) {
    const std::vector<FacetPair> expected = meeting_pairs(mesh_a, mesh_b, a_from_b);
    const Tree<Aabb> a = build_tree<Aabb>(mesh_a);
    const Tree<Aabb> b = build_tree<Aabb>(mesh_b);
    EXPECT_EQ(collide(a, b, a_from_b), expected) << name << ": Tree<Aabb>";
    EXPECT_EQ(collide(PackedAabbTree(a), PackedAabbTree(b), a_from_b), expected) << name << ": PackedAabbTree";
    pairs += expected.size();
  };
  for (const Real offset : {0.0, 1e4}) {
    TriangleMesh mesh = make_terrain(12, 12, 2, 10, 2);
    for (Vec3& v : mesh.vertices) v += Vec3(offset, -offset, offset);
    const std::string name = "terrain at " + std::to_string(offset);
    check(mesh, mesh, RigidTransform::identity(), name + ", identity");
    for (int pose = 0; pose < 6; ++pose) {
      RigidTransform shifted = RigidTransform::identity();
      const Real ulps = r.uniform(-8, 8);
      shifted.translation = r.unit_vector() * (ulps * std::numeric_limits<Real>::epsilon() * (offset + 10));
      check(mesh, mesh, shifted, name + ", shifted " + std::to_string(pose));
      RigidTransform turned = RigidTransform::identity();
      const Real angle = r.uniform(-1e-10, 1e-10);
      turned.rotation = Eigen::AngleAxisd(angle, r.unit_vector()).toRotationMatrix();
      check(mesh, mesh, turned, name + ", turned " + std::to_string(pose));
    }
  }
  TriangleMesh body = make_uv_sphere(16, 8, 0.6);
  const TriangleMesh terrain = make_terrain(24, 24, 3, 24, 2);
  for (int pose = 0; pose < 6; ++pose) {
    RigidTransform t;
    t.rotation = random_rotation(r);
    const Vec3& anchor = terrain.vertices[r.next() % terrain.vertices.size()];
    t.translation = anchor + Vec3(0, 0, r.uniform(0, 0.5));
    check(terrain, body, t, "body on terrain " + std::to_string(pose));
    check(body, terrain, t.inverse(), "terrain on body " + std::to_string(pose));
  }
  EXPECT_GT(pairs, 1000u);
}

TEST(Collide, ConcentricSpheresNoPairs) {
  const TriangleMesh inner = make_uv_sphere(40, 20, 1.0);
  const TriangleMesh outer = make_uv_sphere(40, 20, 1.05);
  QueryStats stats;
  EXPECT_TRUE(collide(build_tree<Aabb>(inner), build_tree<Aabb>(outer), RigidTransform::identity(), &stats).empty());
  EXPECT_GT(stats.volume_tests, 100u);  // close surfaces force many box tests (paper, Table 1)
}

TEST(Collide, MatchesBruteForceOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  std::size_t pairs = 0;
  check_pair(test::load_shared_mesh("env.obj"), test::load_shared_mesh("rob.obj"), 12, 1500, "env vs rob", &pairs);
  EXPECT_GT(pairs, 0u);
  check_pair(test::load_shared_mesh("ode_bunny.obj"), test::load_shared_mesh("ode_bunny.obj"), 8, 0.5, "bunny vs bunny",
             &pairs);
  EXPECT_GT(pairs, 0u);
}

TEST(Collide, RejectsNonRigidTransform) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_uv_sphere(8, 4));
  RigidTransform scaled;
  scaled.rotation = Mat3::Identity() * 2;
  EXPECT_THROW(collide(tree, tree, scaled), Error);
  RigidTransform mirrored;
  mirrored.rotation = Mat3::Identity();
  mirrored.rotation(2, 2) = -1;
  EXPECT_THROW(collide(tree, tree, mirrored), Error);
  RigidTransform nan_shift;
  nan_shift.translation.x() = std::nan("");
  EXPECT_THROW(collide(tree, tree, nan_shift), Error);
}

}  // namespace
}  // namespace boxtree
