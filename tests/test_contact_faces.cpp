// SPDX-License-Identifier: MIT
// contact_triangle_faces: mesh-vs-mesh contacts along face normals (and make_torus, the mesh
// its deep-overlap case is about).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include "boxtree/contact.h"
#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/geometry.h"

namespace boxtree {
namespace {

TEST(ContactFaces, SmallTriangleThroughALargeFaceGetsTheLargeFacesNormal) {
  // b: a large floor triangle (normal +z); a: a small steep triangle poking 0.1 below it.
  const Vec3 b0(-5, -5, 0), b1(5, -5, 0), b2(0, 5, 0);
  const Vec3 a0(0, 0, -0.1), a1(0.3, 0, 0.4), a2(0, 0.3, 0.4);
  ContactPoint out[kMaxTriangleFaceContacts];
  const int n = contact_triangle_faces(a0, a1, a2, b0, b1, b2, {}, out);
  ASSERT_GE(n, 1);
  Real deepest = 0;
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(out[i].normal.z(), 1, 1e-12);
    EXPECT_NEAR(out[i].position.z(), 0, 1e-12);  // on b
    deepest = std::max(deepest, out[i].depth);
  }
  EXPECT_NEAR(deepest, 0.1, 1e-12);
}

TEST(ContactFaces, CubeSinkingIntoAGridIsPushedUpNotSideways) {
  // A closed cube of half size 0.5, turned 0.3 rad about z, sunk 0.05 into a flat grid of unit
  // cells: the contacts of the intersecting facet pairs are no deeper than the cube sank, and
  // most point up (a wall facet against a cell it barely reaches may push sideways, but by no
  // more than the sinking: per pair the shallower face wins between faces of similar size).
  const TriangleMesh floor = make_terrain(6, 6, 1, 6, 0);
  const Mat3 r = Eigen::AngleAxis<Real>(0.3, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 center(3.2, 3.1, 0.45);
  // The cube's 12 facets, wound outward.
  const Vec3 c[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                     {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  const int faces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                            {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  auto corner = [&](int i) { return Vec3(center + r * (c[i] * 0.5)); };
  ContactOptions options;
  options.margin = 0.01;
  int total = 0, up = 0;
  for (const auto& f : faces) {
    for (FacetId g = 0; g < floor.facet_count(); ++g) {
      if (!triangles_intersect(corner(f[0]), corner(f[1]), corner(f[2]), floor.corner(g, 0), floor.corner(g, 1),
                               floor.corner(g, 2)))
        continue;
      ContactPoint out[kMaxTriangleFaceContacts];
      const int n = contact_triangle_faces(corner(f[0]), corner(f[1]), corner(f[2]), floor.corner(g, 0),
                                           floor.corner(g, 1), floor.corner(g, 2), options, out);
      for (int i = 0; i < n; ++i) {
        EXPECT_LE(out[i].depth, 0.05 + 1e-9) << "facet " << g;
        up += out[i].normal.z() > 0.99;
        ++total;
      }
    }
  }
  EXPECT_GT(total, 4);
  EXPECT_GT(up, 3 * total / 4);
}

// The push on a torus whose tube has sunk past its middle into a fine flat grid: the sum of
// depth x normal over the contacts of every intersecting facet pair, as a force on the torus.
// `torus_is_a`: the torus is triangle a (normals point towards it) or b (they point away).
Vec3 push_on_sunk_torus(bool torus_is_a, FixedSurface fixed, int* same_facing_pairs) {
  const TriangleMesh floor = make_terrain(24, 24, 1, 1.2, 0);       // 5 cm cells, z = 0
  TriangleMesh torus = make_torus(0.21, 0.09, 18, 8);               // 8 cm facets: twice a cell's area
  for (Vec3& v : torus.vertices) v += Vec3(0.6, 0.6, 0.09 - 0.12);  // tube 0.18 thick, 0.12 under
  Vec3 push = Vec3::Zero();
  *same_facing_pairs = 0;
  for (FacetId t = 0; t < torus.facet_count(); ++t) {
    for (FacetId g = 0; g < floor.facet_count(); ++g) {
      const Vec3 t0 = torus.corner(t, 0), t1 = torus.corner(t, 1), t2 = torus.corner(t, 2);
      const Vec3 g0 = floor.corner(g, 0), g1 = floor.corner(g, 1), g2 = floor.corner(g, 2);
      if (!triangles_intersect(t0, t1, t2, g0, g1, g2)) continue;
      *same_facing_pairs += (t1 - t0).cross(t2 - t0).z() > 0;
      ContactPoint out[kMaxTriangleFaceContacts];
      const int n = torus_is_a ? contact_triangle_faces(t0, t1, t2, g0, g1, g2, {}, out, fixed)
                               : contact_triangle_faces(g0, g1, g2, t0, t1, t2, {}, out, fixed);
      for (int i = 0; i < n; ++i) push += (torus_is_a ? 1 : -1) * out[i].depth * out[i].normal;
    }
  }
  return push;
}

TEST(ContactFaces, DeepOverlapIsResolvedThroughTheFixedSurface) {
  // Past its middle the tube crosses the floor with faces pointing up, like the floor's; the
  // larger face's normal (the torus's, when neither is fixed) would push it down, further in.
  // With the floor fixed, the same-facing pairs take the floor's normal: the torus goes up.
  for (const bool torus_is_a : {true, false}) {
    SCOPED_TRACE(torus_is_a ? "torus is a" : "torus is b");
    int same_facing = 0;
    const Vec3 free = push_on_sunk_torus(torus_is_a, FixedSurface::neither, &same_facing);
    const Vec3 fixed = push_on_sunk_torus(torus_is_a, torus_is_a ? FixedSurface::b : FixedSurface::a, &same_facing);
    std::printf("push on the sunk torus: %.4f with neither fixed, %.4f with the floor fixed (%d same-facing pairs)\n",
                free.z(), fixed.z(), same_facing);
    EXPECT_GT(same_facing, 50);
    EXPECT_GT(fixed.z(), 0);
    // Only same-facing pairs change: with the torus fixed instead (a static torus, a moving floor)
    // the floor is pushed the other way round, down, out of the torus's tube past its middle.
    const Vec3 torus_fixed =
        push_on_sunk_torus(torus_is_a, torus_is_a ? FixedSurface::a : FixedSurface::b, &same_facing);
    EXPECT_LT(torus_fixed.z(), 0);
  }
}

TEST(GenerateTorus, ClosedWoundOutwardWithThePolygonalTorusVolume) {
  const Real major = 0.7, minor = 0.3;
  const TriangleMesh torus = make_torus(major, minor, 18, 8);
  EXPECT_EQ(torus.facet_count(), 2u * 18 * 8);
  // Closed and consistently wound: every directed edge once, and its reverse once.
  std::map<std::pair<VertexId, VertexId>, int> edges;
  for (const Triangle& t : torus.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1u);
  }
  // Outward: positive volume, a little under the smooth torus's 2 pi^2 R r^2 (an octagon's
  // area is 0.90 of its circle's, 18 segments shorten the path to 0.98 of the circle).
  Real volume = 0;
  for (FacetId f = 0; f < torus.facet_count(); ++f)
    volume += torus.corner(f, 0).dot(torus.corner(f, 1).cross(torus.corner(f, 2))) / 6;
  const Real smooth = 2 * std::acos(Real(-1)) * std::acos(Real(-1)) * major * minor * minor;
  EXPECT_GT(volume, 0.85 * smooth);
  EXPECT_LT(volume, 0.92 * smooth);
  EXPECT_THROW(make_torus(0.3, 0.3, 18, 8), Error);
  EXPECT_THROW(make_torus(0.7, 0.3, 2, 8), Error);
  EXPECT_THROW(make_torus(0.7, std::nan(""), 18, 8), Error);
}

TEST(ContactFaces, ApartBeyondTheMarginOrDegenerateGivesNothing) {
  ContactPoint out[kMaxTriangleFaceContacts];
  const Vec3 b0(0, 0, 0), b1(1, 0, 0), b2(0, 1, 0);
  ContactOptions options;
  options.margin = 0.1;
  EXPECT_EQ(contact_triangle_faces({0.2, 0.2, 0.2}, {0.4, 0.2, 0.3}, {0.2, 0.4, 0.3}, b0, b1, b2, options, out), 0);
  EXPECT_GT(contact_triangle_faces({0.2, 0.2, 0.05}, {0.4, 0.2, 0.3}, {0.2, 0.4, 0.3}, b0, b1, b2, options, out), 0);
  EXPECT_EQ(contact_triangle_faces({0.2, 0.2, 0}, {0.4, 0.2, 0}, {0.6, 0.2, 0}, b0, b1, b2, options, out), 0);
}

}  // namespace
}  // namespace boxtree
