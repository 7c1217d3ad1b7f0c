// contact_triangle_faces: mesh-vs-mesh contacts along face normals.
#include <gtest/gtest.h>

#include "boxtree/contact.h"
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
  const Vec3 c[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
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
