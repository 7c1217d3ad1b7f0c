// SPDX-License-Identifier: MIT
// The mesh collider (collider.h) against per-facet brute force: every facet of the mesh, the same
// narrowphase, the same edge correction and reduction, no tree. What the tree, the query volumes,
// the pipeline and the conversions add must change nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <tuple>

#include "boxtree/active_edges.h"
#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/generate.h"
#include "boxtree/geometry.h"
#include "support/brute_force.h"
#include "support/random.h"

namespace boxtree {
namespace {

using test::Random;

constexpr std::size_t kAll = 100000;  // max_contacts that keeps every contact

// Contacts in a canonical order (depth, then position, then facets), for comparing sets.
std::vector<ContactPoint> canonical(std::vector<ContactPoint> contacts) {
  std::sort(contacts.begin(), contacts.end(), [](const ContactPoint& x, const ContactPoint& y) {
    return std::make_tuple(x.depth, x.position.x(), x.position.y(), x.position.z(), x.facet, x.other_facet) <
           std::make_tuple(y.depth, y.position.x(), y.position.y(), y.position.z(), y.facet, y.other_facet);
  });
  return contacts;
}

// The same contacts. Where several facets give one contact (a shared corner, the same position
// and depth up to rounding), the merge keeps whichever it met first, and the tree walk and a facet
// loop meet them in different orders: a contact whose facet differs must lie on its own facet.
void expect_same_contacts(const std::vector<ContactPoint>& got, const std::vector<ContactPoint>& want,
                          const TriangleMesh& mesh) {
  const auto g = canonical(got), w = canonical(want);
  ASSERT_EQ(g.size(), w.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g[i].facet != w[i].facet || g[i].other_facet != w[i].other_facet) {
      const FacetId f = g[i].facet;
      ASSERT_LT(f, mesh.facet_count());
      const Vec3 on = closest_point_on_triangle(g[i].position, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
      EXPECT_LE((on - g[i].position).norm(), 1e-9) << "contact " << i << " facet " << f << " instead of " << w[i].facet;
    }
    EXPECT_NEAR(g[i].depth, w[i].depth, 1e-12);
    EXPECT_LE((g[i].position - w[i].position).norm(), 1e-12);
    EXPECT_LE((g[i].normal - w[i].normal).norm(), 1e-12);
  }
}

// The brute-force pipeline: every facet, `per_facet` with the request's options, the edge rule.
template <class PerFacet>
std::vector<ContactPoint> brute_convex(const CollisionMesh& mesh, const ContactRequest& request, PerFacet&& per_facet) {
  ContactOptions options;
  options.margin = request.margin;
  options.two_sided = request.two_sided || !mesh.consistent_winding();
  std::vector<ContactPoint> all;
  const TriangleMesh& m = mesh.mesh();
  for (FacetId f = 0; f < m.facet_count(); ++f) {
    ContactPoint out[kMaxEngineTriangleContacts];
    const int n = per_facet(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), options, out);
    for (int i = 0; i < n; ++i) {
      out[i].facet = f;
      if (request.internal_edges &&
          correct_internal_edge_contact(out[i], m.corner(f, 0), m.corner(f, 1), m.corner(f, 2),
                                        mesh.active_edges()[f]) == EdgeContact::discard)
        continue;
      all.push_back(out[i]);
    }
  }
  reduce_contacts(all, request.max_contacts, request.merge_distance);
  return all;
}

struct Scene {
  std::string name;
  std::shared_ptr<const CollisionMesh> mesh;
  Real size;  // shapes' size
};

std::vector<Scene> scenes() {
  return {
      {"bumpy_sphere",
       CollisionMesh::build(std::make_shared<TriangleMesh>(make_bumpy_sphere(24, 12, 0.2, 5)), parse_method("aabb")),
       0.3},
      {"terrain",
       CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(16, 16, 3, 16, 2)), parse_method("obb-min")),
       1.0}};
}

// A point near the mesh's surface: a random facet's random point, moved a little along its normal.
// The point of the oriented box farthest along d (a support mapping, for SupportShape).
Vec3 obb_support(const Obb& box, const Vec3& d) {
  Vec3 p = box.center;
  for (int k = 0; k < 3; ++k) p += box.axes.col(k) * (d.dot(box.axes.col(k)) >= 0 ? 1 : -1) * box.half_extents[k];
  return p;
}

Vec3 near_surface(const TriangleMesh& m, Random& random, Real spread) {
  const FacetId f = FacetId(random.integer(0, int(m.facet_count()) - 1));
  Real u = random.uniform(0, 1), v = random.uniform(0, 1);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  const Vec3 p = m.corner(f, 0) + u * (m.corner(f, 1) - m.corner(f, 0)) + v * (m.corner(f, 2) - m.corner(f, 0));
  const Vec3 n = (m.corner(f, 1) - m.corner(f, 0)).cross(m.corner(f, 2) - m.corner(f, 0)).normalized();
  return p + n * random.uniform(-spread, spread);
}

TEST(Collider, ConvexShapesMatchPerFacetBruteForce) {
  Random random(41);
  const std::vector<std::vector<int>> cube_faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                    {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const std::vector<Vec3> cube_points = {Vec3(-1, -1, -1), Vec3(1, -1, -1), Vec3(1, 1, -1), Vec3(-1, 1, -1),
                                         Vec3(-1, -1, 1),  Vec3(1, -1, 1),  Vec3(1, 1, 1),  Vec3(-1, 1, 1)};
  std::size_t total = 0;
  for (const Scene& scene : scenes()) {
    const CollisionMesh& mesh = *scene.mesh;
    ASSERT_TRUE(mesh.consistent_winding()) << scene.name;
    for (int trial = 0; trial < test::scaled(60); ++trial) {
      const Real s = scene.size * random.uniform(0.3, 1.0);
      const Vec3 center = near_surface(mesh.mesh(), random, s);
      const Mat3 rotation = random.rotation();
      ContactRequest request;
      request.two_sided = random.chance(0.5);
      request.margin = random.chance(0.5) ? 0.1 * s : 0;
      request.internal_edges = random.chance(0.8);
      request.max_contacts = random.chance(0.5) ? kAll : std::size_t(random.integer(1, 6));
      request.merge_distance = random.chance(0.5) ? 0 : 0.05 * s;
      SCOPED_TRACE(scene.name + " trial " + std::to_string(trial));
      ContactResult result;
      const auto check = [&](const char* kind, auto&& per_facet) {
        SCOPED_TRACE(testing::Message() << kind << " two_sided " << request.two_sided << " margin " << request.margin
                                        << " edges " << request.internal_edges << " max " << request.max_contacts
                                        << " merge " << request.merge_distance);
        const auto want = brute_convex(mesh, request, per_facet);
        if (request.max_contacts == kAll && request.merge_distance == 0) {
          expect_same_contacts(result.contacts, want, mesh.mesh());
        } else {
          // Merging and selection depend on the order among contacts of equal depth, which the
          // tree walk and the facet loop do not share: the deepest must agree, and without
          // merging the count too.
          if (request.merge_distance == 0) {
            EXPECT_EQ(result.contacts.size(), want.size());
          }
          ASSERT_EQ(result.contacts.empty(), want.empty());
          if (!want.empty()) {
            EXPECT_EQ(result.contacts[0].depth, want[0].depth);
          }
        }
        total += want.size();
        // The counts add up: everything found is kept, merged, dropped or discarded on an edge.
        EXPECT_EQ(result.counts.found,
                  result.contacts.size() + result.counts.merged + result.counts.dropped + result.counts.edge_discarded);
        EXPECT_FALSE(result.counts.invalid_input);
        result.clear();
      };
      const Sphere sphere{center, s};
      collide_convex(mesh, sphere, request, result);
      check("sphere", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_sphere_triangle(sphere, a, b, c, o, out);
      });
      const Obb box{center, rotation, Vec3(s, 0.7 * s, 0.4 * s)};
      collide_convex(mesh, box, request, result);
      check("box", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_box_triangle(box, a, b, c, o, out);
      });
      const Capsule capsule{center - rotation.col(0) * s, center + rotation.col(0) * s, 0.5 * s};
      collide_convex(mesh, capsule, request, result);
      check("capsule", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_capsule_triangle(capsule, a, b, c, o, out);
      });
      const Cylinder cylinder{center - rotation.col(2) * s, center + rotation.col(2) * s, 0.6 * s};
      collide_convex(mesh, cylinder, request, result);
      check("cylinder", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_cylinder_triangle(cylinder.p0, cylinder.p1, cylinder.radius, a, b, c, o, out);
      });
      const RigidTransform place{rotation, center};
      const Real rounding = random.chance(0.5) ? 0.1 * s : 0;
      std::vector<Vec3> cube_corners = cube_points;
      for (Vec3& p : cube_corners) p *= 0.5 * s;
      const ConvexPolyhedron small = make_convex_polyhedron(cube_corners, cube_faces);
      collide_convex(mesh, PlacedPolyhedron{small, place, rounding}, request, result);
      check("polyhedron", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        ContactOptions grown = o;
        grown.margin += rounding;
        const int n = contact_polyhedron_triangle(small, place, a, b, c, grown, out);
        for (int i = 0; i < n; ++i) out[i].depth += rounding;
        return n;
      });
      std::vector<Vec3> corners = small.vertices;
      collide_convex(mesh, PlacedPoints{corners, place}, request, result);
      std::vector<Vec3> world_corners;
      Vec3 centroid = Vec3::Zero();
      for (const Vec3& p : corners) world_corners.push_back(place.apply(p)), centroid += place.apply(p);
      centroid /= Real(corners.size());
      auto support = [&](const Vec3& d) { return support_points(world_corners, d); };
      check("points", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_convex_triangle(ConvexSupport{support, centroid, true}, a, b, c, o, out);
      });
      // A support shape: the same hull through its support mapping, with its box.
      Obb bounds{center, rotation, Vec3::Constant(0.5 * s)};
      collide_convex(mesh, SupportShape{support, centroid, bounds, true}, request, result);
      check("support", [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_convex_triangle(ConvexSupport{support, centroid, true}, a, b, c, o, out);
      });
    }
  }
  EXPECT_GT(total, 1000u);  // the scenes do make contacts
}

// The brute-force side of the per-facet tests below: facet f's `n` contacts from its routine,
// with the edge rule as run_pipeline applies it, counted into `want` and kept in `contacts`.
void keep_facet_contacts(const CollisionMesh& mesh, const ContactRequest& request, FacetId f, ContactPoint* out, int n,
                         CollisionCounts& want, std::vector<ContactPoint>& contacts) {
  const TriangleMesh& m = mesh.mesh();
  want.found += std::size_t(n);
  for (int i = 0; i < n; ++i) {
    out[i].facet = f;
    if (request.internal_edges) {
      const EdgeContact verdict =
          correct_internal_edge_contact(out[i], m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), mesh.active_edges()[f]);
      if (verdict == EdgeContact::discard) {
        ++want.edge_discarded;
        continue;
      }
      if (verdict == EdgeContact::corrected) ++want.edge_corrected;
    }
    contacts.push_back(out[i]);
  }
}

// The collider's result against the brute force's: the same counts, and the same contacts bit for
// bit unless two share a place (then the walk's order decides which the merge keeps); `compared`
// counts the contacts compared. Fatal on a count of contacts that differs.
void expect_same_as_per_facet(const ContactResult& result, const CollisionCounts& want,
                              std::vector<ContactPoint> contacts, std::size_t& compared) {
  EXPECT_EQ(result.counts.candidates, want.candidates);
  EXPECT_EQ(result.counts.found, want.found);
  EXPECT_EQ(result.counts.edge_corrected, want.edge_corrected);
  EXPECT_EQ(result.counts.edge_discarded, want.edge_discarded);
  const auto by_place = [](const ContactPoint& x, const ContactPoint& y) {
    return std::make_tuple(x.position.x(), x.position.y(), x.position.z(), x.depth) <
           std::make_tuple(y.position.x(), y.position.y(), y.position.z(), y.depth);
  };
  std::sort(contacts.begin(), contacts.end(), by_place);
  const bool shared_place = std::adjacent_find(contacts.begin(), contacts.end(), [](const auto& x, const auto& y) {
                              return x.position == y.position;
                            }) != contacts.end();
  if (shared_place) return;
  std::vector<ContactPoint> got = result.contacts;
  std::sort(got.begin(), got.end(), by_place);
  ASSERT_EQ(got.size(), contacts.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].position, contacts[i].position);
    EXPECT_EQ(got[i].normal, contacts[i].normal);
    EXPECT_EQ(got[i].depth, contacts[i].depth);
    EXPECT_EQ(got[i].facet, contacts[i].facet);
    ++compared;
  }
}

// The sphere collider makes the exact triangle test itself and hands its closest point to the
// narrowphase: its candidates are exactly the facets triangle_overlaps_sphere gives for the sphere
// grown by the margin, its counts those of contact_sphere_triangle and the edge rule on them, and
// its contacts theirs bit for bit (compared where no two share a position, so that the merge of
// exact duplicates cannot keep different ones).
TEST(Collider, SphereCandidatesAndContactsAreThePerFacetRoutinesBitForBit) {
  Random random(43);
  std::size_t compared = 0, beyond_radius = 0;
  for (const Scene& scene : scenes()) {
    const CollisionMesh& mesh = *scene.mesh;
    const TriangleMesh& m = mesh.mesh();
    for (int trial = 0; trial < test::scaled(200); ++trial) {
      const Real s = scene.size * random.uniform(0.3, 1.0);
      const Sphere sphere{near_surface(m, random, s), s};
      ContactRequest request;
      request.two_sided = random.chance(0.5);
      request.margin = random.chance(0.5) ? 0.2 * s : 0;
      request.internal_edges = random.chance(0.7);
      request.max_contacts = kAll;
      request.merge_distance = 0;
      ContactResult result;
      collide_convex(mesh, sphere, request, result);

      ContactOptions options;
      options.margin = request.margin;
      options.two_sided = request.two_sided || !mesh.consistent_winding();
      CollisionCounts want;
      std::vector<ContactPoint> contacts;
      for (FacetId f = 0; f < m.facet_count(); ++f) {
        const Vec3 &a = m.corner(f, 0), &b = m.corner(f, 1), &c = m.corner(f, 2);
        if (!triangle_overlaps_sphere(a, b, c, Sphere{sphere.center, sphere.radius + request.margin})) continue;
        ++want.candidates;
        beyond_radius += !triangle_overlaps_sphere(a, b, c, sphere);
        ContactPoint out[kMaxSphereTriangleContacts];
        const int n = contact_sphere_triangle(sphere, a, b, c, options, out);
        keep_facet_contacts(mesh, request, f, out, n, want, contacts);
      }
      SCOPED_TRACE(testing::Message() << scene.name << " trial " << trial << " two_sided " << request.two_sided
                                      << " margin " << request.margin << " edges " << request.internal_edges);
      ASSERT_NO_FATAL_FAILURE(expect_same_as_per_facet(result, want, contacts, compared));
    }
  }
  // The scenes do make contacts, and candidates only the margin reaches (the counts scale with the
  // trials: a third of them under the sanitizers, BOXTREE_TEST_SCALE).
  EXPECT_GT(compared, std::size_t(test::scaled(500)));
  EXPECT_GT(beyond_radius, std::size_t(test::scaled(20)));
}

// The capsule collider makes triangle_overlaps_capsule's test itself and hands the closest pairs
// it computes to the narrowphase: its candidates are exactly the facets triangle_overlaps_capsule
// gives for the capsule grown by the margin, its counts those of contact_capsule_triangle and the
// edge rule on them, and its contacts theirs bit for bit (compared where no two share a position,
// as for spheres above). Capsules lie along their facet in part of the trials (the face contacts
// at both ends), pierce it in others, and are points in a few. A third mesh adds facets with
// collinear corners, a repeated corner or a needle's width among a triangle soup (the leaf test's
// flat branch).
TEST(Collider, CapsuleCandidatesAndContactsAreThePerFacetRoutinesBitForBit) {
  Random random(44);
  constexpr int kSoup = 300;
  auto soup = std::make_shared<TriangleMesh>(make_triangle_soup(kSoup, 9, 4, 1.5));
  for (int i = 0; i < 150; ++i) {
    const Vec3 a = random.point(-4, 4);
    const Vec3 d = random.point(-1, 1);
    const Vec3 off = random.unit_vector();
    const Vec3 b = i % 3 == 1 ? a : Vec3(a + d);
    const Vec3 c = i % 3 == 0 ? Vec3(a + 2.5 * d) : i % 3 == 1 ? Vec3(a + d) : Vec3(a + d + 1e-9 * off);
    const VertexId base = VertexId(soup->vertices.size());
    soup->vertices.insert(soup->vertices.end(), {a, b, c});
    soup->triangles.push_back({base, base + 1, base + 2});
  }
  std::vector<Scene> meshes = scenes();
  meshes.push_back({"degenerate_soup", CollisionMesh::build(soup, parse_method("aabb")), 0.5});
  std::size_t compared = 0, beyond_radius = 0, pierced = 0, degenerate = 0;
  for (const Scene& scene : meshes) {
    const CollisionMesh& mesh = *scene.mesh;
    const TriangleMesh& m = mesh.mesh();
    for (int trial = 0; trial < test::scaled(300); ++trial) {
      const FacetId f0 = FacetId(random.integer(0, int(m.facet_count()) - 1));
      Real u = random.uniform(0, 1);
      Real v = random.uniform(0, 1);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      const Vec3 n = (m.corner(f0, 1) - m.corner(f0, 0)).cross(m.corner(f0, 2) - m.corner(f0, 0)).normalized();
      const Real s = scene.size * random.uniform(0.3, 1.0);
      const Real lift = random.uniform(-s, s);
      const Vec3 center = m.corner(f0, 0) + u * (m.corner(f0, 1) - m.corner(f0, 0)) +
                          v * (m.corner(f0, 2) - m.corner(f0, 0)) + n * lift;
      Vec3 axis = random.unit_vector();
      if (random.chance(0.4)) axis = (axis - n.dot(axis) * n).normalized();  // along the facet
      const Real half = random.chance(0.1) ? 0 : s * random.uniform(0.2, 1.5);
      const Capsule capsule{center - half * axis, center + half * axis, 0.5 * s * random.uniform(0.3, 1.0)};
      ContactRequest request;
      request.two_sided = random.chance(0.5);
      request.margin = random.chance(0.5) ? 0.2 * s : 0;
      request.internal_edges = random.chance(0.7);
      request.max_contacts = kAll;
      request.merge_distance = 0;
      ContactResult result;
      collide_convex(mesh, capsule, request, result);

      ContactOptions options;
      options.margin = request.margin;
      options.two_sided = request.two_sided || !mesh.consistent_winding();
      const Capsule grown{capsule.p0, capsule.p1, capsule.radius + request.margin};
      CollisionCounts want;
      std::vector<ContactPoint> contacts;
      for (FacetId f = 0; f < m.facet_count(); ++f) {
        const Vec3 &a = m.corner(f, 0), &b = m.corner(f, 1), &c = m.corner(f, 2);
        if (!triangle_overlaps_capsule(a, b, c, grown)) continue;
        ++want.candidates;
        beyond_radius += !triangle_overlaps_capsule(a, b, c, capsule);
        pierced += segment_triangle_distance_squared(capsule.p0, capsule.p1, a, b, c) == 0;
        degenerate += scene.name == "degenerate_soup" && f >= FacetId(kSoup);
        ContactPoint out[kMaxCapsuleTriangleContacts];
        const int k = contact_capsule_triangle(capsule, a, b, c, options, out);
        keep_facet_contacts(mesh, request, f, out, k, want, contacts);
      }
      SCOPED_TRACE(testing::Message() << scene.name << " trial " << trial << " two_sided " << request.two_sided
                                      << " margin " << request.margin << " edges " << request.internal_edges);
      ASSERT_NO_FATAL_FAILURE(expect_same_as_per_facet(result, want, contacts, compared));
    }
  }
  // The scenes do make contacts, candidates only the margin reaches, cores through facets and
  // candidates among the degenerate facets (the counts scale with the trials: a third of them under
  // the sanitizers, BOXTREE_TEST_SCALE).
  EXPECT_GT(compared, std::size_t(test::scaled(1000)));
  EXPECT_GT(beyond_radius, std::size_t(test::scaled(300)));
  EXPECT_GT(pierced, std::size_t(test::scaled(100)));
  EXPECT_GT(degenerate, std::size_t(test::scaled(30)));
}

// An engine's own narrowphase (here the core's box routine, two-sided as the collider asks):
// on one-sided facets no contact ever pushes the shape out through a facet's back, and where the
// engine's normal is already in front the contacts are the engine's.
TEST(Collider, EngineNarrowphaseOnOneSidedFacetsPushesOutThroughTheFront) {
  Random random(7);
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(12, 12, 2, 12, 2)), Method{});
  std::size_t turned = 0, contacts = 0;
  for (int trial = 0; trial < test::scaled(200); ++trial) {
    const Obb box{near_surface(mesh->mesh(), random, 0.6), random.rotation(), Vec3(0.5, 0.4, 0.3)};
    auto support = [&box](const Vec3& d) { return obb_support(box, d); };
    auto engine = [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
      EXPECT_TRUE(o.two_sided);
      const int n = contact_box_triangle(box, a, b, c, o, out);
      for (int i = 0; i < n; ++i) turned += out[i].normal.dot((b - a).cross(c - a)) < 0;
      return n;
    };
    ContactRequest request;
    request.max_contacts = kAll;
    ContactResult result;
    collide_convex(*mesh, SupportShape{support, box.center, box, true}, engine, request, result);
    for (const ContactPoint& c : result.contacts) {
      const TriangleMesh& m = mesh->mesh();
      const Vec3 front =
          (m.corner(c.facet, 1) - m.corner(c.facet, 0)).cross(m.corner(c.facet, 2) - m.corner(c.facet, 0));
      EXPECT_GE(c.normal.dot(front.normalized()), -1e-9);
      ++contacts;
    }
  }
  EXPECT_GT(contacts, 100u);
  EXPECT_GT(turned, 0u);  // the engine did push some out through a back
}

// An engine narrowphase that reports farther than the request's margin (Bullet's GJK adds its
// manifold's breaking distance to the reach it is given): those contacts do not come back, and
// they take no place of a nearer one in the reduction. The same box through the engine path with
// and without such far contacts added gives the same contacts.
TEST(Collider, EngineContactsBeyondTheMarginDoNotComeBack) {
  Random random(11);
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(12, 12, 2, 12, 2)), Method{});
  std::size_t contacts = 0;
  for (int trial = 0; trial < test::scaled(200); ++trial) {
    const Obb box{near_surface(mesh->mesh(), random, 0.3), random.rotation(), Vec3(0.5, 0.4, 0.3)};
    auto support = [&box](const Vec3& d) { return obb_support(box, d); };
    ContactRequest request;
    request.margin = 0.05;
    request.two_sided = random.chance(0.5);
    request.max_contacts = 4;
    const auto engine = [&](bool far) {
      return [&box, far](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        int n = contact_box_triangle(box, a, b, c, o, out);
        if (far && n < kMaxEngineTriangleContacts) {
          // Beyond the margin, at the triangle's far corner (a wide spread the reduction would like).
          ContactPoint extra = n > 0 ? out[0] : ContactPoint{};
          extra.position = c;
          extra.depth = -o.margin - 0.01;
          if (n == 0) extra.normal = (b - a).cross(c - a).normalized();
          out[n++] = extra;
        }
        return n;
      };
    };
    ContactResult with_far, without;
    collide_convex(*mesh, SupportShape{support, box.center, box, true}, engine(true), request, with_far);
    collide_convex(*mesh, SupportShape{support, box.center, box, true}, engine(false), request, without);
    ASSERT_EQ(with_far.contacts.size(), without.contacts.size()) << "trial " << trial;
    for (std::size_t i = 0; i < without.contacts.size(); ++i) {
      EXPECT_EQ(with_far.contacts[i].position, without.contacts[i].position);
      EXPECT_EQ(with_far.contacts[i].depth, without.contacts[i].depth);
      EXPECT_GE(with_far.contacts[i].depth, -request.margin);
    }
    contacts += without.contacts.size();
  }
  EXPECT_GT(contacts, 100u);
}

// The facets that the collider proves out of reach before an engine's narrowphase (along the
// facet's normal, and along the direction from the shape's box to the facet) give no contact:
// with margins as wide as the shapes, so that many facets lie near the reach, every contact the
// narrowphase makes on any facet within the margin comes back, as from the same routine run on
// every facet.
TEST(Collider, EngineNarrowphaseSeesEveryFacetWithinTheMargin) {
  Random random(29);
  std::size_t near_the_reach = 0;
  for (const Scene& scene : scenes()) {
    const CollisionMesh& mesh = *scene.mesh;
    for (int trial = 0; trial < test::scaled(150); ++trial) {
      const Real s = scene.size * random.uniform(0.3, 1.0);
      const Obb box{near_surface(mesh.mesh(), random, s), random.rotation(), Vec3(0.5, 0.4, 0.3) * s};
      auto support = [&box](const Vec3& d) { return obb_support(box, d); };
      const auto per_facet = [&box](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o,
                                    ContactPoint* out) { return contact_box_triangle(box, a, b, c, o, out); };
      ContactRequest request;
      request.two_sided = true;  // the engine path's own options: the same routine on both sides
      request.margin = random.uniform(0.2, 1.0) * s;
      request.internal_edges = random.chance(0.5);
      request.max_contacts = kAll;
      ContactResult result;
      collide_convex(mesh, SupportShape{support, box.center, box, true}, per_facet, request, result);
      const auto want = brute_convex(mesh, request, per_facet);
      SCOPED_TRACE(testing::Message() << scene.name << " trial " << trial << " margin " << request.margin);
      ASSERT_NO_FATAL_FAILURE(expect_same_contacts(result.contacts, want, mesh.mesh()));
      for (const ContactPoint& c : want) near_the_reach += c.depth < -0.8 * request.margin;
    }
  }
  EXPECT_GT(near_the_reach, std::size_t(test::scaled(200)));
}

// The reduction keeps the deepest contact and says what went; early_stop stops at the count.
TEST(Collider, ReductionKeepsTheDeepestAndCountsWhatWent) {
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(8, 8, 1, 8, 0)), Method{});
  const Obb box{Vec3(4.1, 3.9, 0.4), Eigen::AngleAxisd(0.3, Vec3(0.2, 1, 0.1).normalized()).toRotationMatrix(),
                Vec3(2, 1.5, 0.5)};
  ContactRequest all;
  all.max_contacts = kAll;
  ContactResult full;
  collide_convex(*mesh, box, all, full);
  ASSERT_GT(full.contacts.size(), 8u);
  ContactRequest four = all;
  four.max_contacts = 4;
  four.merge_distance = 0.05;
  ContactResult reduced;
  collide_convex(*mesh, box, four, reduced);
  ASSERT_EQ(reduced.contacts.size(), 4u);
  EXPECT_EQ(reduced.contacts[0].depth, full.contacts[0].depth);  // deepest first, and kept
  EXPECT_GT(reduced.counts.dropped, 0u);
  EXPECT_EQ(reduced.counts.found, 4 + reduced.counts.merged + reduced.counts.dropped + reduced.counts.edge_discarded);

  ContactRequest early = four;
  early.early_stop = true;
  ContactResult first;
  collide_convex(*mesh, box, early, first);
  EXPECT_EQ(first.contacts.size(), 4u);
  EXPECT_LT(first.counts.candidates, full.counts.candidates);  // the walk stopped early
}

// Internal edges (moved from the Bullet suite): a box resting across the seams of a flat grid gets
// the face normal only; without the correction it gets tilted edge normals.
TEST(Collider, FlatGridSeamsGiveTheFaceNormal) {
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(8, 8, 1, 8, 0)), Method{});
  for (const bool edges : {true, false}) {
    ContactRequest request;
    request.internal_edges = edges;
    request.max_contacts = kAll;
    std::size_t tilted = 0, total = 0;
    for (int i = 0; i < 20; ++i) {
      // A box whose bottom edge lies across a seam, tipped so that the edge touches first.
      const Obb box{Vec3(1 + 0.31 * i, 2, 0.28),
                    Eigen::AngleAxisd(0.15 * (i % 5 + 1), Vec3(1, 0.3 * (i % 3), 0).normalized()).toRotationMatrix(),
                    Vec3(0.5, 0.5, 0.25)};
      ContactResult result;
      collide_convex(*mesh, box, request, result);
      for (const ContactPoint& c : result.contacts) tilted += c.normal.dot(Vec3::UnitZ()) < 1 - 1e-9, ++total;
    }
    EXPECT_GT(total, 20u);
    if (edges) {
      EXPECT_EQ(tilted, 0u);
    } else {
      EXPECT_GT(tilted, 0u);
    }
  }
}

// CollisionMesh::active_edges: on a flat grid only the border is active; on a coarse UV sphere
// (convex, its quads between two rings planar) exactly the diagonals inside the quads are inactive.
// Checked against a reference that finds each edge's neighbour and compares the two facets' planes.
TEST(Collider, ActiveEdgesOfAFlatGridAreOnlyItsBorder) {
  const auto count_active = [](const std::vector<std::uint8_t>& edges) {
    int n = 0;
    for (auto a : edges) n += ((a >> 0) & 1) + ((a >> 1) & 1) + ((a >> 2) & 1);
    return n;
  };
  const auto floor = CollisionMesh::build(std::make_shared<TriangleMesh>(make_terrain(4, 4, 1, 4, 0)), Method{});
  ASSERT_EQ(floor->active_edges().size(), floor->mesh().facet_count());
  EXPECT_EQ(count_active(floor->active_edges()), 16);  // the 4 x 4 border edges

  const auto sphere = CollisionMesh::build(std::make_shared<TriangleMesh>(make_uv_sphere(8, 6, 1)), Method{});
  const TriangleMesh& m = sphere->mesh();
  const std::vector<std::uint8_t>& active = sphere->active_edges();
  ASSERT_EQ(active.size(), m.facet_count());
  const auto unit_normal = [&](FacetId f) {
    return (m.corner(f, 1) - m.corner(f, 0)).cross(m.corner(f, 2) - m.corner(f, 0)).normalized();
  };
  int coplanar_edges = 0;
  for (FacetId f = 0; f < m.facet_count(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const VertexId u = m.triangles[f][k], v = m.triangles[f][(k + 1) % 3];
      FacetId neighbour = f;  // the neighbour across edge (u, v) runs it the other way
      for (FacetId g = 0; g < m.facet_count(); ++g)
        for (int j = 0; j < 3; ++j)
          if (g != f && m.triangles[g][j] == v && m.triangles[g][(j + 1) % 3] == u) neighbour = g;
      ASSERT_NE(neighbour, f) << "facet " << f << " edge " << k << ": the sphere is closed";
      const bool coplanar = unit_normal(f).dot(unit_normal(neighbour)) > 1 - 1e-9;
      coplanar_edges += coplanar;
      EXPECT_EQ(((active[f] >> k) & 1) == 0, coplanar) << "facet " << f << " edge " << k;
    }
  }
  // 4 bands of 8 planar quads, one diagonal each, seen from both of its facets.
  EXPECT_EQ(coplanar_edges, 2 * 4 * 8);
  EXPECT_EQ(3 * int(m.facet_count()) - count_active(active), 2 * 4 * 8);
}

// A mesh with facets wound both ways has no fronts: one-sided requests fall back to two-sided,
// say so, and give the two-sided contacts.
TEST(Collider, InconsistentWindingFallsBackToTwoSided) {
  auto flipped = std::make_shared<TriangleMesh>(make_uv_sphere(16, 8, 1));
  for (std::size_t f = 0; f < flipped->triangles.size(); f += 3)
    std::swap(flipped->triangles[f][1], flipped->triangles[f][2]);
  const auto mesh = CollisionMesh::build(flipped, Method{});
  EXPECT_FALSE(mesh->consistent_winding());
  EXPECT_GT(mesh->inconsistent_edges(), 0u);
  const auto good = CollisionMesh::build(std::make_shared<TriangleMesh>(make_uv_sphere(16, 8, 1)), Method{});
  EXPECT_TRUE(good->consistent_winding());
  EXPECT_EQ(good->inconsistent_edges(), 0u);

  const Sphere inside{Vec3(0, 0, 0.8), 0.3};  // inside the sphere, touching it from behind
  ContactRequest one_sided, two_sided;
  two_sided.two_sided = true;
  ContactResult a, b, c;
  collide_convex(*mesh, inside, one_sided, a);
  collide_convex(*mesh, inside, two_sided, b);
  EXPECT_TRUE(a.counts.two_sided_fallback);
  EXPECT_FALSE(b.counts.two_sided_fallback);
  ASSERT_FALSE(a.contacts.empty());
  expect_same_contacts(a.contacts, b.contacts, mesh->mesh());
  // The well-wound sphere pushes the same ball out through its front: outward, deep.
  collide_convex(*good, inside, one_sided, c);
  EXPECT_FALSE(c.counts.two_sided_fallback);
  ASSERT_FALSE(c.contacts.empty());
  EXPECT_GT(c.contacts[0].normal.z(), 0.9);
  EXPECT_GT(c.contacts[0].depth, 0.4);
}

// Scaled meshes (non-uniform, mirroring) give the contacts of the mesh scaled beforehand (corners
// 1 and 2 swapped where the scale mirrors), for convex shapes and mesh pairs.
TEST(Collider, ScaledMeshGivesThePreScaledMeshsContacts) {
  const auto source = std::make_shared<TriangleMesh>(make_bumpy_sphere(16, 8, 0.2, 3));
  const auto base = CollisionMesh::build(source, parse_method("aabb"));
  const auto rock = CollisionMesh::build(std::make_shared<TriangleMesh>(make_uv_sphere(10, 6, 0.6)), Method{});
  Random random(3);
  for (const Vec3& scale : {Vec3(2, 1, 0.5), Vec3(-1.5, 1, 1), Vec3(1, -1, -1), Vec3(-1, -2, -0.5)}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale.transpose());
    const auto scaled = base->scaled(scale);
    EXPECT_EQ(scaled->mirrored(), scale.prod() < 0);
    EXPECT_EQ(base->scaled(scale), scaled);  // one scaled mesh per scale while alive
    auto copy = std::make_shared<TriangleMesh>(*source);
    for (Vec3& v : copy->vertices) v = v.cwiseProduct(scale);
    if (scale.prod() < 0)
      for (Triangle& t : copy->triangles) std::swap(t[1], t[2]);
    const auto pre = CollisionMesh::build(copy, parse_method("aabb"));
    EXPECT_TRUE(scaled->consistent_winding());
    EXPECT_EQ(scaled->active_edges(), pre->active_edges());
    std::size_t contacts = 0;
    for (int trial = 0; trial < test::scaled(40); ++trial) {
      const Vec3 center = near_surface(pre->mesh(), random, 0.3);
      ContactRequest request;
      request.max_contacts = kAll;
      ContactResult got, want;
      const Obb box{center, random.rotation(), Vec3(0.3, 0.2, 0.1)};
      collide_convex(*scaled, box, request, got);
      collide_convex(*pre, box, request, want);
      expect_same_contacts(got.contacts, want.contacts, pre->mesh());
      contacts += want.contacts.size();
      // One-sided fronts face out of the mirrored mesh too: every normal points away from the
      // centre for a box outside the surface.
      const RigidTransform pose{random.rotation(), center * 1.1};
      MeshContactRequest pair;
      pair.max_contacts = kAll;
      got.clear();
      want.clear();
      collide_meshes(*scaled, *rock, pose, pair, got);
      collide_meshes(*pre, *rock, pose, pair, want);
      expect_same_contacts(got.contacts, want.contacts, pre->mesh());
      contacts += want.contacts.size();
    }
    EXPECT_GT(contacts, 50u);
  }
  EXPECT_EQ(base->scaled(Vec3::Ones()), base);
}

// Mesh pairs: every facet pair of brute force, through both policies, and meshes of different
// methods collide as meshes of one method do (no error, the same contacts).
TEST(Collider, MeshPairsMatchBruteForceAndMixMethods) {
  const auto torus_mesh = std::make_shared<TriangleMesh>(make_torus(1, 0.3, 16, 8));
  const auto ground_mesh = std::make_shared<TriangleMesh>(make_terrain(10, 10, 4, 6, 1));
  Random random(5);
  std::size_t contacts = 0;
  int ambiguous_poses = 0;
  for (const char* method : {"aabb", "obb-min", "pie-min", "obb-min+aabb@3"}) {
    SCOPED_TRACE(method);
    const auto torus = CollisionMesh::build(torus_mesh, parse_method(method));
    const auto ground_same = CollisionMesh::build(ground_mesh, parse_method(method));
    const auto ground_aabb = CollisionMesh::build(ground_mesh, Method{});
    for (int trial = 0; trial < test::scaled(15); ++trial) {
      const RigidTransform pose{random.rotation(), near_surface(*ground_mesh, random, 0.3)};
      // The contacts are built from brute force's pairs, so a pose with a pair within rounding
      // of touching (in `may` only: reporting it or not are both right) is left out.
      const test::Expected<FacetPair> pairs = test::brute_collide(*ground_mesh, *torus_mesh, pose);
      if (pairs.must != pairs.may) {
        ++ambiguous_poses;
        continue;
      }
      for (const MeshContactPolicy policy : {MeshContactPolicy::triangle_pairs, MeshContactPolicy::face_normals}) {
        MeshContactRequest request;
        request.policy = policy;
        request.max_contacts = kAll;
        request.static_mesh = StaticMesh::mesh;
        request.internal_edges = random.chance(0.5);
        ContactResult same, mixed;
        collide_meshes(*ground_same, *torus, pose, request, same);
        collide_meshes(*ground_aabb, *torus, pose, request, mixed);  // aabb ground, `method` torus
        expect_same_contacts(mixed.contacts, same.contacts, *ground_mesh);
        // Brute force: every intersecting facet pair, the same per-pair routine.
        std::vector<ContactPoint> want;
        ContactOptions options;
        const bool faces = policy == MeshContactPolicy::face_normals;
        for (const FacetPair& p : pairs.must) {
          ContactPoint out[8];
          const TriangleMesh& g = *ground_mesh;
          const TriangleMesh& t = *torus_mesh;
          const Vec3 a0 = pose.apply(t.corner(p.b, 0)), a1 = pose.apply(t.corner(p.b, 1)),
                     a2 = pose.apply(t.corner(p.b, 2));
          const int n = faces ? contact_triangle_faces(a0, a1, a2, g.corner(p.a, 0), g.corner(p.a, 1), g.corner(p.a, 2),
                                                       options, out, FixedSurface::b)
                              : contact_triangle_triangle(a0, a1, a2, g.corner(p.a, 0), g.corner(p.a, 1),
                                                          g.corner(p.a, 2), options, out);
          for (int i = 0; i < n; ++i) {
            out[i].facet = p.a;
            out[i].other_facet = p.b;
            want.push_back(out[i]);
          }
        }
        // Face normals are never edge-corrected; the least-penetration contacts are compared
        // where the request has no edge rule, and by count (before the rule) where it has.
        if (faces || !request.internal_edges) {
          reduce_contacts(want, kAll, 0);
          expect_same_contacts(same.contacts, want, *ground_mesh);
        } else {
          EXPECT_EQ(same.counts.found, want.size());
        }
        contacts += want.size();
      }
    }
  }
  EXPECT_GT(contacts, 200u);
  EXPECT_LE(ambiguous_poses, 2);
}

// Shapes made from one built tree share one CollisionMesh: a second instance adds no per-facet
// memory (the same object), and the shared mesh lives as long as any holder.
TEST(Collider, ShapesOfOneTreeShareOneCollisionMesh) {
  const AnyTree tree = AnyTree::build(std::make_shared<TriangleMesh>(make_terrain(32, 32, 1)), Method{});
  const auto first = CollisionMesh::of(tree);
  const AnyTree copy = tree;
  const auto second = CollisionMesh::of(copy);
  EXPECT_EQ(first.get(), second.get());
  EXPECT_GT(first->memory_bytes(), first->mesh().facet_count());  // per-facet data, held once
  const AnyTree other = AnyTree::build(tree.shared_mesh(), Method{});
  EXPECT_NE(CollisionMesh::of(other).get(), first.get());  // another built tree: its own
}

// Bad input at the collider: nothing, said so, never a throw.
TEST(Collider, InvalidShapesAndPosesGiveNothing) {
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_uv_sphere(8, 4, 1)), Method{});
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  ContactRequest request;
  ContactResult result;
  collide_convex(*mesh, Sphere{Vec3(0, 0, 1), -0.5}, request, result);
  EXPECT_TRUE(result.counts.invalid_input);
  EXPECT_TRUE(result.contacts.empty());
  result.clear();
  collide_convex(*mesh, Obb{Vec3(nan, 0, 1), Mat3::Identity(), Vec3::Ones()}, request, result);
  EXPECT_TRUE(result.counts.invalid_input);
  result.clear();
  MeshContactRequest pair;
  collide_meshes(*mesh, *mesh, RigidTransform{Mat3::Identity(), Vec3(nan, 0, 0)}, pair, result);
  EXPECT_TRUE(result.counts.invalid_input);
  result.clear();
  // A rotation off by 1e-6 (single-precision engines) is taken as the nearest rotation.
  Mat3 sloppy = Eigen::AngleAxisd(0.4, Vec3::UnitZ()).toRotationMatrix();
  sloppy(0, 0) += 1e-6;
  EXPECT_NO_THROW(collide_meshes(*mesh, *mesh, RigidTransform{sloppy, Vec3(0.5, 0, 0)}, pair, result));
  EXPECT_FALSE(result.counts.invalid_input);
  EXPECT_FALSE(result.contacts.empty());
  result.clear();
  request.margin = -1;
  collide_convex(*mesh, Sphere{Vec3(0, 0, 1), 0.5}, request, result);
  EXPECT_TRUE(result.counts.invalid_input);
}

// ray_hits: every hit of brute force, nearest first; closest_only the first of them; first_only
// one of them; culling keeps the front-facing ones.
TEST(Collider, RayHitsAreBruteForcesHits) {
  const auto mesh = CollisionMesh::build(std::make_shared<TriangleMesh>(make_bumpy_sphere(24, 12, 0.2, 5)), Method{});
  Random random(9);
  std::size_t total = 0;
  for (int trial = 0; trial < test::scaled(200); ++trial) {
    // From outside towards the middle, some ending inside the mesh.
    const Vec3 from = random.unit_vector() * 3;
    const Ray ray{from, (random.point(-0.5, 0.5) - from).normalized(), 0, random.uniform(1.5, 6)};
    const auto want = test::brute_ray_all_hits(mesh->mesh(), ray);
    std::vector<FacetHit> all, closest, first, front;
    ray_hits(*mesh, ray, {}, all);
    ASSERT_EQ(all.size(), want.size()) << "trial " << trial;
    for (std::size_t i = 0; i < all.size(); ++i) EXPECT_NEAR(all[i].t, want[i].t, 1e-12);
    for (std::size_t i = 1; i < all.size(); ++i) EXPECT_LE(all[i - 1].t, all[i].t);
    RayHitsRequest request;
    request.closest_only = true;
    ray_hits(*mesh, ray, request, closest);
    request = {};
    request.first_only = true;
    ray_hits(*mesh, ray, request, first);
    request = {};
    request.cull_back_faces = true;
    ray_hits(*mesh, ray, request, front);
    ASSERT_EQ(closest.size(), std::min<std::size_t>(all.size(), 1));
    ASSERT_EQ(first.size(), std::min<std::size_t>(all.size(), 1));
    if (!all.empty()) {
      EXPECT_EQ(closest[0].t, all[0].t);
      EXPECT_TRUE(std::any_of(all.begin(), all.end(), [&](const FacetHit& h) { return h.facet == first[0].facet; }));
    }
    std::size_t entering = 0;
    for (const FacetHit& h : all) {
      const TriangleMesh& m = mesh->mesh();
      entering += (m.corner(h.facet, 1) - m.corner(h.facet, 0))
                      .cross(m.corner(h.facet, 2) - m.corner(h.facet, 0))
                      .dot(ray.direction) < 0;
    }
    EXPECT_EQ(front.size(), entering);
    total += all.size();
  }
  std::printf("%zu hits of %d rays\n", total, test::scaled(200));
  // Enough hits to check: 269 with gcc (BOXTREE_TEST_SCALE 1), 91 with clang (0.34); the bound
  // scales with the ray count (before, 100 whatever the scale).
  EXPECT_GT(total, std::size_t(test::scaled(100)));
}

}  // namespace
}  // namespace boxtree
