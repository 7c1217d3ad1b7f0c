// SPDX-License-Identifier: MIT
// The boxtree geom's contract with ODE: registration, AABB, the contact conventions of every
// collider (checked against ODE's own trimesh on the same triangles where ODE has a collider),
// the contact array protocol (max count, skip stride, CONTACTS_UNIMPORTANT), and rays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/method.h"
#include "boxtree/ode/boxtree_geom.h"
#include "ode_scene.h"

namespace boxtree::ode_test {
namespace {

// A flat grid over [-half, half]^2 at z = 0, counter-clockwise seen from above (normal +z).
std::shared_ptr<const TriangleMesh> flat_grid(int cells, Real half) {
  auto mesh = std::make_shared<TriangleMesh>();
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      mesh->vertices.emplace_back(-half + 2 * half * i / cells, -half + 2 * half * j / cells, 0);
  auto id = [&](int i, int j) { return VertexId(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      mesh->triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh->triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

// A closed axis-aligned box mesh (outward CCW faces), 12 facets.
std::shared_ptr<const TriangleMesh> box_mesh(const Vec3& half) {
  auto mesh = std::make_shared<TriangleMesh>();
  for (int k = 0; k < 8; ++k)
    mesh->vertices.emplace_back((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                                (k & 4) ? half.z() : -half.z());
  const Triangle faces[12] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                              {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const Triangle& t : faces) mesh->triangles.push_back(t);
  return mesh;
}

Vec3 normal_of(const dContactGeom& c) { return Vec3(c.normal[0], c.normal[1], c.normal[2]); }
Vec3 pos_of(const dContactGeom& c) { return Vec3(c.pos[0], c.pos[1], c.pos[2]); }

// A geom's placement: x_world = rotation * x_geom + translation.
RigidTransform pose_of_geom(dGeomID g) {
  const dReal* p = dGeomGetPosition(g);
  const dReal* r = dGeomGetRotation(g);  // 3 rows of 4
  RigidTransform pose;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) pose.rotation(row, col) = r[row * 4 + col];
  pose.translation = Vec3(p[0], p[1], p[2]);
  return pose;
}

int collide(dGeomID a, dGeomID b, std::vector<dContactGeom>& out, int max = 32, int flags_extra = 0) {
  out.assign(std::size_t(max), dContactGeom{});
  const int n = dCollide(a, b, max | flags_extra, out.data(), sizeof(dContactGeom));
  out.resize(std::size_t(std::max(n, 0)));
  return n;
}

const dContactGeom& deepest(const std::vector<dContactGeom>& contacts) {
  return *std::max_element(contacts.begin(), contacts.end(),
                           [](const dContactGeom& x, const dContactGeom& y) { return x.depth < y.depth; });
}

// Each test owns its space and geoms.
struct Space {
  dSpaceID id = dSimpleSpaceCreate(nullptr);
  ~Space() { dSpaceDestroy(id); }  // destroys the geoms still in it (cleanup mode on by default)
};

TEST(OdeGeom, RegisteredAfterInitAndRecognised) {
  ASSERT_GE(dBoxtreeGetClass(), int(dFirstUserClass));
  EXPECT_EQ(dBoxtreeInit(), dBoxtreeGetClass());  // idempotent within one ODE session
  Space space;
  dGeomID g = dCreateBoxtreeMesh(space.id, flat_grid(4, 1), "obb-min");
  EXPECT_EQ(dGeomGetClass(g), dBoxtreeGetClass());
  EXPECT_TRUE(boxtree::ode::is_boxtree_geom(g));
  ASSERT_NE(boxtree::ode::geom_tree(g), nullptr);
  EXPECT_EQ(boxtree::ode::geom_tree(g)->facet_count(), 32u);
  EXPECT_EQ(method_name(boxtree::ode::geom_tree(g)->method()), "obb-min");
  dGeomID sphere = dCreateSphere(space.id, 1);
  EXPECT_FALSE(boxtree::ode::is_boxtree_geom(sphere));
  EXPECT_EQ(boxtree::ode::geom_tree(sphere), nullptr);
  EXPECT_THROW(dCreateBoxtreeMesh(space.id, flat_grid(2, 1), "no-such-method"), Error);
  EXPECT_THROW(dCreateBoxtreeMesh(space.id, std::make_shared<const TriangleMesh>(), "aabb"), Error);
}

TEST(OdeGeom, ArraysLikeTriMeshDataBuild) {
  const auto grid = flat_grid(3, 2);
  std::vector<double> vd;
  std::vector<float> vf;
  // Strided vertices (4 coordinates, like dVector3) and strided triangles (4 indices).
  for (const Vec3& v : grid->vertices) {
    for (int k = 0; k < 3; ++k) {
      vd.push_back(v[k]);
      vf.push_back(float(v[k]));
    }
    vd.push_back(0);
    vf.push_back(0);
  }
  std::vector<dTriIndex> indices;
  for (const Triangle& t : grid->triangles) {
    for (VertexId v : t) indices.push_back(v);
    indices.push_back(12345);
  }
  Space space;
  dGeomID gd = dCreateBoxtreeMesh(space.id, vd.data(), 4 * sizeof(double), int(grid->vertices.size()), indices.data(),
                                  int(grid->triangles.size() * 3), 4 * sizeof(dTriIndex));
  dGeomID gf = dCreateBoxtreeMesh(space.id, vf.data(), 4 * sizeof(float), int(grid->vertices.size()), indices.data(),
                                  int(grid->triangles.size() * 3), 4 * sizeof(dTriIndex), "pie-min");
  for (dGeomID g : {gd, gf}) {
    const TriangleMesh& m = boxtree::ode::geom_tree(g)->mesh();
    ASSERT_EQ(m.triangles.size(), grid->triangles.size());
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
      for (int k = 0; k < 3; ++k) EXPECT_LT((m.corner(FacetId(f), k) - grid->corner(FacetId(f), k)).norm(), 1e-6);
  }
  EXPECT_THROW(dCreateBoxtreeMesh(space.id, vd.data(), 4 * sizeof(double), 4, indices.data(), 4, 16), Error);
}

TEST(OdeGeom, AabbFollowsTheBodyPose) {
  dWorldID world = dWorldCreate();
  Space space;
  const auto mesh = std::make_shared<const TriangleMesh>(make_bumpy_sphere(16, 8, 0.3, 5));
  dGeomID g = dCreateBoxtreeMesh(space.id, mesh, "aabb");
  dBodyID body = dBodyCreate(world);
  dGeomSetBody(g, body);
  Random random(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 p = random.uniform_vec3(-50, 50);
    const Vec3 axis = random.unit_vector();
    dMatrix3 r;
    dRFromAxisAndAngle(r, axis.x(), axis.y(), axis.z(), random.uniform(-3, 3));
    dBodySetPosition(body, p.x(), p.y(), p.z());
    dBodySetRotation(body, r);
    dReal box[6];
    dGeomGetAABB(g, box);
    const dReal* rot = dGeomGetRotation(g);
    Vec3 lo = Vec3::Constant(1e30), hi = Vec3::Constant(-1e30);
    for (const Vec3& v : mesh->vertices) {
      Vec3 w;
      for (int row = 0; row < 3; ++row)
        w[row] = rot[row * 4] * v.x() + rot[row * 4 + 1] * v.y() + rot[row * 4 + 2] * v.z() + p[row];
      lo = lo.cwiseMin(w);
      hi = hi.cwiseMax(w);
    }
    // Contains every vertex; no looser than the turned local box (at most sqrt(3) wider).
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(box[2 * i], lo[i] + 1e-9);
      EXPECT_GE(box[2 * i + 1], hi[i] - 1e-9);
      EXPECT_LE(box[2 * i + 1] - box[2 * i], (hi[i] - lo[i]) * 1.8 + 1e-9);
    }
  }
  dGeomDestroy(g);
  dBodyDestroy(body);
  dWorldDestroy(world);
}

// A sphere in front of the faces: the same contact from the boxtree geom and from ODE's trimesh
// (ODE: normal = -face normal with the mesh as g1), and ODE's swap for dCollide(sphere, mesh).
TEST(OdeGeom, SphereNormalDirectionAndSidesMatchOdeTrimesh) {
  Space space;
  const auto grid = flat_grid(8, 4);
  OdeTrimesh ode_mesh(space.id, *grid);
  dGeomID mesh = dCreateBoxtreeMesh(space.id, grid, "aabb");
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  // Over the incentre of facet 2 * (4 + 4 * 8) = 72 (cell [0,1]^2, the triangle below its
  // diagonal), touching no other facet: both colliders give exactly that one contact.
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);
  std::vector<dContactGeom> ours, theirs;
  ASSERT_EQ(collide(mesh, sphere, ours), 1);
  ASSERT_EQ(collide(ode_mesh.geom, sphere, theirs), 1);
  EXPECT_EQ(ours[0].g1, mesh);
  EXPECT_EQ(ours[0].g2, sphere);
  EXPECT_EQ(ours[0].side2, -1);
  EXPECT_EQ(ours[0].side1, 72);
  EXPECT_EQ(ours[0].side1, theirs[0].side1);
  EXPECT_NEAR(ours[0].depth, 0.05, 1e-12);
  EXPECT_NEAR(ours[0].depth, theirs[0].depth, 1e-6);
  EXPECT_LT((normal_of(ours[0]) - Vec3(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((normal_of(ours[0]) - normal_of(theirs[0])).norm(), 1e-6);
  EXPECT_LT((pos_of(ours[0]) - pos_of(theirs[0])).norm(), 1e-5);
  EXPECT_EQ(ours[0].pos[3], 0);
  EXPECT_EQ(ours[0].normal[3], 0);

  // The reverse order: ODE negates the normal and swaps g and side.
  ASSERT_EQ(collide(sphere, mesh, ours), 1);
  ASSERT_EQ(collide(sphere, ode_mesh.geom, theirs), 1);
  EXPECT_EQ(ours[0].g1, sphere);
  EXPECT_EQ(ours[0].g2, mesh);
  EXPECT_EQ(ours[0].side1, -1);
  EXPECT_EQ(ours[0].side2, theirs[0].side2);
  EXPECT_LT((normal_of(ours[0]) - Vec3(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((normal_of(ours[0]) - normal_of(theirs[0])).norm(), 1e-6);

  // Exactly over a shared edge (the cell's diagonal), ODE makes one contact per facet; ours are
  // merged (same point and normal).
  dGeomSetPosition(sphere, 0.5, 0.5, 0.25);
  EXPECT_EQ(collide(ode_mesh.geom, sphere, theirs), 2);
  ASSERT_EQ(collide(mesh, sphere, ours), 1);
  EXPECT_NEAR(ours[0].depth, deepest(theirs).depth, 1e-6);

  // Overlapping several facets of the flat grid: every contact has the face normal (the flat
  // seams are internal edges: no tilted edge normals) and the deepest one matches ODE's.
  dGeomSetPosition(sphere, 0.1, 0.05, 0.2);
  ASSERT_GE(collide(mesh, sphere, ours), 1);
  ASSERT_GE(collide(ode_mesh.geom, sphere, theirs), 1);
  EXPECT_NEAR(deepest(ours).depth, 0.1, 1e-12);
  EXPECT_NEAR(deepest(ours).depth, deepest(theirs).depth, 1e-6);
  for (const dContactGeom& g : ours) EXPECT_LT((normal_of(g) - Vec3(0, 0, -1)).norm(), 1e-12);

  // Apart: nothing, and the array is untouched.
  dGeomSetPosition(sphere, 0.3, 0.15, 0.31);
  EXPECT_EQ(collide(mesh, sphere, ours), 0);
  EXPECT_EQ(collide(sphere, mesh, ours), 0);
}

// The mesh turned and moved (on a body): contacts are computed in its frame and come back in world.
TEST(OdeGeom, ContactsFollowTheMeshPose) {
  dWorldID world = dWorldCreate();
  Space space;
  const auto grid = flat_grid(6, 3);
  dGeomID mesh = dCreateBoxtreeMesh(space.id, grid, "obb-min");
  dBodyID body = dBodyCreate(world);
  dGeomSetBody(mesh, body);
  // Turn the grid so that its front faces +x, and move it.
  dMatrix3 r;
  dRFromAxisAndAngle(r, 0, 1, 0, M_PI / 2);  // z -> x
  dBodySetRotation(body, r);
  dBodySetPosition(body, 10, 20, 30);
  dGeomID sphere = dCreateSphere(space.id, 1.0);
  dGeomSetPosition(sphere, 10.75, 20.2, 29.9);
  std::vector<dContactGeom> out;
  ASSERT_GE(collide(mesh, sphere, out), 1);
  // reduce_contacts puts the deepest first.
  EXPECT_LT((normal_of(out[0]) - Vec3(-1, 0, 0)).norm(), 1e-12);
  EXPECT_NEAR(out[0].depth, 0.25, 1e-12);
  EXPECT_LT((pos_of(out[0]) - Vec3(10, 20.2, 29.9)).norm(), 1e-12);
  for (const dContactGeom& g : out) EXPECT_LT((normal_of(g) - Vec3(-1, 0, 0)).norm(), 1e-12);
  dGeomDestroy(mesh);
  dBodyDestroy(body);
  dWorldDestroy(world);
}

// Every primitive pressed into a flat grid from above: all normals -z (mesh = g1), the deepest
// depth as ODE's trimesh computes it, side1 a real facet, side2 = -1.
TEST(OdeGeom, PrimitivesAgainstFlatGridMatchOdeTrimesh) {
  Space space;
  const auto grid = flat_grid(10, 5);
  OdeTrimesh ode_mesh(space.id, *grid);
  dGeomID mesh = dCreateBoxtreeMesh(space.id, grid, "aabb");
  const Real depth = 0.05;
  dMatrix3 lying;
  dRFromAxisAndAngle(lying, 1, 0, 0, M_PI / 2);
  struct Case {
    const char* name;
    dGeomID geom;
    Real center_z;
    int min_contacts;  // resting flat: at least this many (a box face: 4)
  };
  std::vector<Case> cases;
  cases.push_back({"sphere", dCreateSphere(space.id, 0.5), 0.5 - depth, 1});
  cases.push_back({"box", dCreateBox(space.id, 1.0, 0.8, 0.6), 0.3 - depth, 4});
  dGeomID capsule = dCreateCapsule(space.id, 0.3, 1.2);
  dGeomSetRotation(capsule, lying);
  cases.push_back({"capsule", capsule, 0.3 - depth, 2});
  cases.push_back({"cylinder", dCreateCylinder(space.id, 0.4, 0.6), 0.3 - depth, 1});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    dGeomSetPosition(c.geom, 0.13, -0.21, c.center_z);
    std::vector<dContactGeom> ours, theirs;
    const int n = collide(mesh, c.geom, ours, 16);
    ASSERT_GE(n, c.min_contacts);
    ASSERT_GE(collide(ode_mesh.geom, c.geom, theirs, 16), 1);
    EXPECT_NEAR(deepest(ours).depth, depth, 1e-6);
    EXPECT_NEAR(deepest(ours).depth, deepest(theirs).depth, 1e-4);
    for (const dContactGeom& g : ours) {
      EXPECT_LT((normal_of(g) - Vec3(0, 0, -1)).norm(), 1e-6);
      EXPECT_NEAR(g.pos[2], 0, 1e-6);  // on the mesh's surface
      EXPECT_GE(g.depth, 0);
      EXPECT_EQ(g.g1, mesh);
      EXPECT_EQ(g.g2, c.geom);
      EXPECT_GE(g.side1, 0);
      EXPECT_LT(g.side1, int(grid->facet_count()));
      EXPECT_EQ(g.side2, -1);
    }
    // Lifted clear of the grid: nothing.
    dGeomSetPosition(c.geom, 0.13, -0.21, c.center_z + 2 * depth);
    EXPECT_EQ(collide(mesh, c.geom, ours), 0);
    EXPECT_EQ(collide(c.geom, mesh, ours), 0);
  }
}

// The contact array protocol: never more than asked, the stride honoured (only the dContactGeom
// part of each dContact written), CONTACTS_UNIMPORTANT gives some contacts and stops.
TEST(OdeGeom, MaxCountSkipStrideAndUnimportant) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, scene_terrain(), "aabb");
  // A big box sunk into the terrain: many candidate facets and contacts.
  dGeomID box = dCreateBox(space.id, 3, 3, 3);
  const Real ground = terrain_height(*boxtree::ode::geom_tree(mesh), 0, 0);  // the middle
  dGeomSetPosition(box, 0, 0, ground + 1.2);
  for (int max : {1, 2, 3, 4, 7, 16, 64}) {
    SCOPED_TRACE(max);
    std::vector<dContact> contacts(std::size_t(max) + 2);
    for (dContact& c : contacts) std::memset(static_cast<void*>(&c), 0xab, sizeof c);
    const int n = dCollide(mesh, box, max, &contacts[0].geom, sizeof(dContact));
    ASSERT_GE(n, 1);
    ASSERT_LE(n, max);
    for (int i = 0; i < int(contacts.size()); ++i) {
      const auto* bytes = reinterpret_cast<const unsigned char*>(&contacts[std::size_t(i)]);
      if (i < n) {
        const dContactGeom& g = contacts[std::size_t(i)].geom;
        EXPECT_EQ(g.g1, mesh);
        EXPECT_EQ(g.g2, box);
        EXPECT_GE(g.depth, 0);
        EXPECT_NEAR(normal_of(g).norm(), 1, 1e-9);
        // The surface and fdir1 parts are the caller's: untouched.
        const auto* surface = reinterpret_cast<const unsigned char*>(&contacts[std::size_t(i)].surface);
        for (std::size_t k = 0; k < sizeof(dSurfaceParameters); ++k) ASSERT_EQ(surface[k], 0xab);
        const auto* fdir = reinterpret_cast<const unsigned char*>(&contacts[std::size_t(i)].fdir1);
        for (std::size_t k = 0; k < sizeof(dVector3); ++k) ASSERT_EQ(fdir[k], 0xab);
      } else {
        for (std::size_t k = 0; k < sizeof(dContact); ++k) ASSERT_EQ(bytes[k], 0xab) << "entry " << i;
      }
    }
    // The deepest contact is always kept.
    std::vector<dContactGeom> all;
    collide(mesh, box, all, 256);
    Real best = 0;
    for (int i = 0; i < n; ++i) best = std::max(best, contacts[std::size_t(i)].geom.depth);
    EXPECT_NEAR(best, deepest(all).depth, 1e-12);
  }
  std::vector<dContactGeom> some;
  const int n = collide(mesh, box, some, 3, int(CONTACTS_UNIMPORTANT));
  EXPECT_GE(n, 1);
  EXPECT_LE(n, 3);
}

// Rays: the same closest hits as ODE's trimesh (facet, and distance within float precision:
// OPCODE stores the vertices as float).
TEST(OdeGeom, RayClosestHitsMatchOdeTrimesh) {
  Space space;
  const auto terrain = scene_terrain();
  OdeTrimesh ode_mesh(space.id, *terrain);
  dGeomID mesh = dCreateBoxtreeMesh(space.id, terrain, "obb-min");
  dGeomID ray = dCreateRay(space.id, 100);
  dGeomRaySetClosestHit(ray, 1);
  Random random(11);
  int hits = 0, facet_mismatches = 0, only_one_hits = 0;
  const int rays = 2000;
  for (int i = 0; i < rays; ++i) {
    // Around the scene's terrain (40 m across, centred on the origin).
    const Real origin_z = random.uniform(-2, 15);  // z first: see tests/support/random.h
    const Real origin_y = random.uniform(-25, 25);
    const Real origin_x = random.uniform(-25, 25);
    const Vec3 origin(origin_x, origin_y, origin_z);
    Vec3 dir = random.unit_vector();
    if (i % 2 == 0) {
      const Real target_y = random.uniform(-20, 20);  // y first: see tests/support/random.h
      const Real target_x = random.uniform(-20, 20);
      dir = (Vec3(target_x, target_y, 1) - origin).normalized();
    }
    dGeomRaySet(ray, origin.x(), origin.y(), origin.z(), dir.x(), dir.y(), dir.z());
    std::vector<dContactGeom> ours, theirs;
    const int n_ours = collide(mesh, ray, ours, 4);
    const int n_theirs = collide(ode_mesh.geom, ray, theirs, 4);
    ASSERT_LE(n_ours, 1);
    if (n_theirs != n_ours) {
      // A grazing ray through the mesh's outer boundary edge, or ending right at the surface,
      // can hit in double and miss in float (or the reverse): counted, must be rare.
      ++only_one_hits;
      continue;
    }
    if (n_theirs == 0) continue;
    ++hits;
    EXPECT_NEAR(ours[0].depth, theirs[0].depth, 1e-4 * (1 + theirs[0].depth)) << "ray " << i;
    EXPECT_LT((pos_of(ours[0]) - pos_of(theirs[0])).norm(), 1e-3) << "ray " << i;
    EXPECT_EQ(ours[0].g1, mesh);
    EXPECT_EQ(ours[0].g2, ray);
    EXPECT_EQ(ours[0].side2, -1);
    if (ours[0].side1 != theirs[0].side1) {
      ++facet_mismatches;  // a hit on a shared edge: either facet is right
    } else {
      EXPECT_LT((normal_of(ours[0]) - normal_of(theirs[0])).norm(), 1e-5) << "ray " << i;
    }
  }
  std::printf("[ rays     ] %d rays, %d hits, %d on a shared edge with a different facet, %d hit by one only\n", rays,
              hits, facet_mismatches, only_one_hits);
  EXPECT_GT(hits, rays / 3);
  EXPECT_LE(facet_mismatches, hits / 100 + 1);
  EXPECT_LE(only_one_hits, rays / 500 + 1);
}

// Ray options as dCollideRTL honours them: length, back-face culling, first contact, all hits.
TEST(OdeGeom, RayLengthCullingAndAllHits) {
  Space space;
  const auto cube = box_mesh(Vec3(1, 1, 1));
  dGeomID mesh = dCreateBoxtreeMesh(space.id, cube, "aabb");
  dGeomID ray = dCreateRay(space.id, 10);
  dGeomRaySet(ray, 0.1, 0.2, 5, 0, 0, -1);  // down through the top face (z = 1) and the bottom (z = -1)
  std::vector<dContactGeom> out;
  ASSERT_EQ(collide(mesh, ray, out, 8), 2);  // all hits, nearest first
  EXPECT_NEAR(out[0].depth, 4, 1e-12);
  EXPECT_NEAR(out[1].depth, 6, 1e-12);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, -1)).norm(), 1e-12);  // -(top face normal +z)
  EXPECT_LT((normal_of(out[1]) - Vec3(0, 0, 1)).norm(), 1e-12);   // -(bottom face normal -z), as ODE does
  EXPECT_LT((pos_of(out[0]) - Vec3(0.1, 0.2, 1)).norm(), 1e-12);
  ASSERT_EQ(collide(mesh, ray, out, 1), 1);
  EXPECT_NEAR(out[0].depth, 4, 1e-12);
  // Culling: the bottom face is seen from behind.
  dGeomRaySetBackfaceCull(ray, 1);
  ASSERT_EQ(collide(mesh, ray, out, 8), 1);
  EXPECT_NEAR(out[0].depth, 4, 1e-12);
  // From inside the cube, culling leaves nothing.
  dGeomRaySet(ray, 0.1, 0.2, 0, 0, 0, -1);
  EXPECT_EQ(collide(mesh, ray, out, 8), 0);
  dGeomRaySetBackfaceCull(ray, 0);
  ASSERT_EQ(collide(mesh, ray, out, 8), 1);
  EXPECT_NEAR(out[0].depth, 1, 1e-12);
  // Length: too short to reach.
  dGeomRaySet(ray, 0.1, 0.2, 5, 0, 0, -1);
  dGeomRaySetLength(ray, 3.9);
  EXPECT_EQ(collide(mesh, ray, out, 8), 0);
  dGeomRaySetLength(ray, 4.5);
  EXPECT_EQ(collide(mesh, ray, out, 8), 1);
  // First contact: one hit, whichever.
  dGeomRaySetLength(ray, 10);
  dGeomRaySetFirstContact(ray, 1);
  EXPECT_EQ(collide(mesh, ray, out, 8), 1);
  // Reverse order: ODE swaps, the normal becomes +face normal as for dCollide(ray, trimesh).
  dGeomRaySetFirstContact(ray, 0);
  dGeomRaySetClosestHit(ray, 1);
  ASSERT_EQ(collide(ray, mesh, out, 8), 1);
  EXPECT_EQ(out[0].g1, ray);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, 1)).norm(), 1e-12);
}

// Plane: every vertex below it, normal = plane normal (from the plane into the mesh), as
// dCollideTrimeshPlane; with a small array, the deepest vertex is kept.
TEST(OdeGeom, PlaneMatchesOdeTrimesh) {
  Space space;
  const auto cube = box_mesh(Vec3(1, 1, 1));
  OdeTrimesh ode_mesh(space.id, *cube);
  dGeomID mesh = dCreateBoxtreeMesh(space.id, cube, "obb-min");
  // Tilted plane cutting off three corners... and then parallel to a face.
  const Vec3 n = Vec3(1, 2, 3).normalized();
  dGeomID plane = dCreatePlane(space.id, n.x(), n.y(), n.z(), -0.3 * n.sum());
  std::vector<dContactGeom> ours, theirs;
  const int n_ours = collide(mesh, plane, ours, 16);
  const int n_theirs = collide(ode_mesh.geom, plane, theirs, 16);
  EXPECT_EQ(n_ours, n_theirs);
  ASSERT_GE(n_ours, 1);
  EXPECT_NEAR(deepest(ours).depth, deepest(theirs).depth, 1e-6);
  for (const dContactGeom& g : ours) {
    EXPECT_LT((normal_of(g) - n).norm(), 1e-12);
    EXPECT_EQ(g.g1, mesh);
    EXPECT_EQ(g.g2, plane);
    EXPECT_EQ(g.side2, -1);
  }
  ASSERT_EQ(collide(mesh, plane, ours, 1), 1);
  EXPECT_NEAR(ours[0].depth, deepest(theirs).depth, 1e-12);
  dGeomDestroy(plane);
  plane = dCreatePlane(space.id, 0, 0, 1, -0.5);  // z = -0.5: the four bottom corners, depth 0.5
  ASSERT_EQ(collide(mesh, plane, ours, 16), 4);
  for (const dContactGeom& g : ours) EXPECT_NEAR(g.depth, 0.5, 1e-12);
  ASSERT_EQ(collide(plane, mesh, ours, 16), 4);  // reversed: normal -z, g1 = plane
  EXPECT_LT((normal_of(ours[0]) - Vec3(0, 0, -1)).norm(), 1e-12);
  EXPECT_EQ(ours[0].g1, plane);
  dGeomDestroy(plane);
  plane = dCreatePlane(space.id, 0, 0, 1, -1.01);
  EXPECT_EQ(collide(mesh, plane, ours, 16), 0);
}

// A cube of half size 0.5 as dCreateConvex takes it: planes (n, d), points, polygons.
const dReal kCubePlanes[] = {1, 0, 0, 0.5, -1, 0, 0, 0.5, 0, 1, 0, 0.5, 0, -1, 0, 0.5, 0, 0, 1, 0.5, 0, 0, -1, 0.5};
const dReal kCubePoints[] = {0.5, 0.5, 0.5,  -0.5, 0.5, 0.5,  -0.5, -0.5, 0.5,  0.5, -0.5, 0.5,
                             0.5, 0.5, -0.5, -0.5, 0.5, -0.5, -0.5, -0.5, -0.5, 0.5, -0.5, -0.5};
const unsigned kCubePolygons[] = {4, 0, 3, 7, 4, 4, 1, 5, 6, 2, 4, 0, 4, 5, 1,
                                  4, 2, 6, 7, 3, 4, 0, 1, 2, 3, 4, 4, 7, 6, 5};

// Convex geoms need their points registered (ODE has no getter); unregistered ones give nothing.
TEST(OdeGeom, ConvexWithRegisteredPoints) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(10, 5), "aabb");
  const dReal* planes = kCubePlanes;
  const dReal* points = kCubePoints;
  const unsigned* polygons = kCubePolygons;
  dGeomID convex = boxtree::ode::create_convex(space.id, planes, 6, points, 8, polygons);
  dGeomSetPosition(convex, 0.1, 0.2, 0.45);
  std::vector<dContactGeom> out;
  // With the faces (create_convex = set_convex): the separating-axis narrowphase, whose face case
  // is a patch: the cube's bottom corners and the grid corners under it, all 0.05 deep.
  ASSERT_GE(collide(mesh, convex, out, 8), 4);
  for (const dContactGeom& g : out) {
    EXPECT_NEAR(g.depth, 0.05, 1e-9);
    EXPECT_LT((normal_of(g) - Vec3(0, 0, -1)).norm(), 1e-9);
  }
  ASSERT_GE(collide(convex, mesh, out, 8), 4);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, 1)).norm(), 1e-9);
  dGeomSetPosition(convex, 0.1, 0.2, 0.55);
  EXPECT_EQ(collide(mesh, convex, out, 8), 0);
  // Points only: GJK/EPA on their hull, one point per facet, the same depth.
  boxtree::ode::set_convex_points(convex, points, 8);
  dGeomSetPosition(convex, 0.1, 0.2, 0.45);
  ASSERT_GE(collide(mesh, convex, out, 8), 1);
  EXPECT_NEAR(deepest(out).depth, 0.05, 1e-6);
  for (const dContactGeom& g : out) EXPECT_LT((normal_of(g) - Vec3(0, 0, -1)).norm(), 1e-6);
  dGeomSetPosition(convex, 0.1, 0.2, 0.55);
  EXPECT_EQ(collide(mesh, convex, out, 8), 0);
  // Forgotten (or never registered): its points are read through ODE, GJK/EPA as above.
  boxtree::ode::forget_convex(convex);
  dGeomSetPosition(convex, 0.1, 0.2, 0.45);
  boxtree::ode::reset_geom_counters(mesh);
  ASSERT_GE(collide(mesh, convex, out, 8), 1);
  EXPECT_NEAR(deepest(out).depth, 0.05, 1e-6);
  EXPECT_EQ(boxtree::ode::geom_counters(mesh).convexes_read_from_ode, 1u);
}

// Convex data that is not a closed convex polyhedron with matching planes is refused with the
// reason; create_convex then leaves nothing in the space.
TEST(OdeGeom, ConvexWithBadFacesIsRefused) {
  Space space;
  static const dReal points[] = {0.5, 0.5, 0.5,  -0.5, 0.5, 0.5,  -0.5, -0.5, 0.5,  0.5, -0.5, 0.5,
                                 0.5, 0.5, -0.5, -0.5, 0.5, -0.5, -0.5, -0.5, -0.5, 0.5, -0.5, -0.5};
  const std::vector<dReal> planes = {1, 0,  0, 0.5, -1, 0, 0, 0.5, 0, 1, 0,  0.5,
                                     0, -1, 0, 0.5, 0,  0, 1, 0.5, 0, 0, -1, 0.5};
  const std::vector<unsigned> polygons = {4, 0, 3, 7, 4, 4, 1, 5, 6, 2, 4, 0, 4, 5, 1,
                                          4, 2, 6, 7, 3, 4, 0, 1, 2, 3, 4, 4, 7, 6, 5};
  const auto refused = [&](const std::vector<dReal>& pl, const std::vector<unsigned>& po, unsigned plane_count,
                           const std::string& reason) {
    const int before = dSpaceGetNumGeoms(space.id);
    try {
      boxtree::ode::create_convex(space.id, pl.data(), plane_count, points, 8, po.data());
      ADD_FAILURE() << "accepted; expected: " << reason;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
    EXPECT_EQ(dSpaceGetNumGeoms(space.id), before);
  };
  std::vector<dReal> moved_plane = planes;
  moved_plane[3] = 0.6;  // plane 0 off its polygon
  refused(moved_plane, polygons, 6, "plane 0 is not the outward plane of polygon 0");
  std::vector<dReal> inward = planes;
  for (int k = 4; k < 8; ++k) inward[std::size_t(k)] = -inward[std::size_t(k)];  // plane 1 turned inward
  refused(inward, polygons, 6, "plane 1");
  std::vector<unsigned> bad_index = polygons;
  bad_index[3] = 8;
  refused(planes, bad_index, 6, "polygon 0: point index 8 out of range");
  refused(planes, polygons, 5, "do not close");  // the last face left out
  std::vector<unsigned> two_corners = polygons;
  two_corners[0] = 2;
  refused(planes, two_corners, 6, "polygon 0 has 2 corners");
  // set_convex on a geom that is not a convex.
  dGeomID sphere = dCreateSphere(space.id, 1);
  EXPECT_THROW(boxtree::ode::set_convex(sphere, planes.data(), 6, points, 8, polygons.data()), Error);
}

// Mesh vs mesh: boxtree vs boxtree (same and different methods) and boxtree vs ODE's trimesh, in
// both argument orders. A cube sunk 0.05 into a flat grid: normals from the cube into the grid.
TEST(OdeGeom, MeshVersusMeshBothOrders) {
  Space space;
  const auto grid = flat_grid(8, 4);
  const auto cube = box_mesh(Vec3(0.5, 0.5, 0.5));
  dGeomID ground = dCreateBoxtreeMesh(space.id, grid, "aabb");
  dGeomID cube_same = dCreateBoxtreeMesh(space.id, cube, "aabb");
  dGeomID cube_other = dCreateBoxtreeMesh(space.id, cube, "obb-min");
  OdeTrimesh cube_ode(space.id, *cube);
  dMatrix3 r;
  dRFromAxisAndAngle(r, 0, 0, 1, 0.3);
  for (dGeomID c : {cube_same, cube_other, cube_ode.geom}) {
    dGeomSetPosition(c, 0.2, 0.1, 0.45);
    dGeomSetRotation(c, r);
  }
  for (dGeomID c : {cube_same, cube_other, cube_ode.geom}) {
    std::vector<dContactGeom> out;
    // From the cube (g2) down into the ground (g1). Where a corner of the cube just crosses a
    // grid facet, the least penetration of that one triangle pair can be sideways or even the
    // wrong way (a sliver of a side wall pushed down out of one small facet): per-pair contacts
    // know nothing of the rest of the meshes. Those must stay shallow and few.
    auto check = [&](dGeomID g1, dGeomID g2, Real down) {
      std::vector<dContactGeom> contacts;
      ASSERT_GE(collide(g1, g2, contacts, 16), 3);
      int vertical = 0;
      for (const dContactGeom& g : contacts) {
        EXPECT_EQ(g.g1, g1);
        EXPECT_EQ(g.g2, g2);
        const int ground_side = g1 == ground ? g.side1 : g.side2;
        const int cube_side = g1 == ground ? g.side2 : g.side1;
        EXPECT_GE(ground_side, 0);
        EXPECT_LT(ground_side, int(grid->facet_count()));
        EXPECT_GE(cube_side, 0);
        EXPECT_LT(cube_side, 12);
        if (normal_of(g).z() * down > 0.99) ++vertical;
        if (normal_of(g).z() * down < -0.1) {
          EXPECT_LT(g.depth, 0.02);
        }
      }
      EXPECT_GE(vertical, int(contacts.size()) * 3 / 4);
      EXPECT_NEAR(deepest(contacts).depth, 0.05, 1e-9);
      EXPECT_GT(normal_of(deepest(contacts)).z() * down, 0.99);
    };
    check(ground, c, -1);
    check(c, ground, 1);
    dGeomSetPosition(c, 0.2, 0.1, 0.55);
    EXPECT_EQ(collide(ground, c, out, 16), 0);
  }
}

// Facets are one-sided by default: a sphere whose centre is 0.1 behind a facet is pushed out
// through its front (up, depth 0.3 + 0.1); two_sided pushes it out the near way (down, 0.3 - 0.1).
TEST(OdeGeom, OneSidedByDefaultTwoSidedPushesOutTheNearSide) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(8, 4), "aabb");
  EXPECT_FALSE(boxtree::ode::geom_settings(mesh).two_sided);
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  dGeomSetPosition(sphere, 0.7071, 0.2929, -0.1);  // under the incentre of facet 72 (see above)
  std::vector<dContactGeom> out;
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  EXPECT_EQ(out[0].side1, 72);
  EXPECT_NEAR(out[0].depth, 0.4, 1e-12);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, -1)).norm(), 1e-12);  // g2 -> g1: the sphere is pushed up
  boxtree::ode::GeomSettings settings;
  settings.two_sided = true;
  boxtree::ode::set_geom_settings(mesh, settings);
  EXPECT_TRUE(boxtree::ode::geom_settings(mesh).two_sided);
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  EXPECT_NEAR(out[0].depth, 0.2, 1e-12);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, 1)).norm(), 1e-12);  // pushed down, out of the back
  // In front, both settings agree.
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  EXPECT_NEAR(out[0].depth, 0.05, 1e-12);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, -1)).norm(), 1e-12);
}

// margin: a sphere 2 cm above a facet touches nothing; with a 5 cm margin it gets a contact of
// depth 0, and the geom's AABB (so the space's pairing) grows by the margin.
TEST(OdeGeom, MarginMakesSpeculativeContacts) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(8, 4), "aabb");
  EXPECT_EQ(boxtree::ode::geom_settings(mesh).margin, 0);
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.32);
  std::vector<dContactGeom> out;
  EXPECT_EQ(collide(mesh, sphere, out), 0);
  dReal before[6], after[6];
  dGeomGetAABB(mesh, before);
  boxtree::ode::GeomSettings settings;
  settings.margin = 0.05;
  boxtree::ode::set_geom_settings(mesh, settings);
  EXPECT_EQ(boxtree::ode::geom_settings(mesh).margin, 0.05);
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  EXPECT_EQ(out[0].depth, 0);
  EXPECT_LT((normal_of(out[0]) - Vec3(0, 0, -1)).norm(), 1e-12);
  EXPECT_EQ(out[0].side1, 72);
  dGeomGetAABB(mesh, after);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(after[2 * i], before[2 * i] - 0.05, 1e-12);
    EXPECT_NEAR(after[2 * i + 1], before[2 * i + 1] + 0.05, 1e-12);
  }
  // Beyond the margin: nothing.
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.36);
  EXPECT_EQ(collide(mesh, sphere, out), 0);
  settings.margin = -0.01;
  EXPECT_THROW(boxtree::ode::set_geom_settings(mesh, settings), Error);
  settings.margin = 0;
  settings.merge_fraction = -1;
  EXPECT_THROW(boxtree::ode::set_geom_settings(mesh, settings), Error);
  EXPECT_EQ(boxtree::ode::geom_settings(mesh).margin, 0.05);  // a refused setting changes nothing
  // Only boxtree geoms have settings and counters.
  EXPECT_THROW(boxtree::ode::set_geom_settings(sphere, {}), Error);
  EXPECT_THROW(boxtree::ode::geom_settings(sphere), Error);
  EXPECT_THROW(boxtree::ode::geom_counters(sphere), Error);
  EXPECT_THROW(boxtree::ode::reset_geom_counters(sphere), Error);
}

// merge_fraction: a box face resting on a fine grid (25 cm cells) gives a patch point at every
// grid vertex and box corner under it; merged at half the box's size, far fewer remain.
TEST(OdeGeom, MergeFractionMergesNearbyContacts) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(16, 2), "aabb");
  dGeomID box = dCreateBox(space.id, 1.0, 0.8, 0.6);
  dGeomSetPosition(box, 0.13, -0.21, 0.25);
  std::vector<int> counts;
  for (const Real fraction : {0.0, 0.01, 0.5}) {
    boxtree::ode::GeomSettings settings;
    settings.merge_fraction = fraction;
    boxtree::ode::set_geom_settings(mesh, settings);
    std::vector<dContactGeom> out;
    counts.push_back(collide(mesh, box, out, 64));
    for (const dContactGeom& g : out) EXPECT_NEAR(g.depth, 0.05, 1e-9);
  }
  std::printf("[ merge    ] box on a 25 cm grid, 64 asked: %d contacts unmerged, %d at 0.01, %d at 0.5\n", counts[0],
              counts[1], counts[2]);
  // Measured: 49, 43 and 8.
  EXPECT_GE(counts[0], 40);
  EXPECT_LT(counts[1], counts[0]);
  EXPECT_LE(counts[2], 8);
}

// internal_edges: a sphere over a flat grid near a vertex touches the neighbouring facets at their
// edges; with internal_edges (the default) those contacts get the face normal, without they keep
// the tilted edge normals (up to ~29 degrees here).
TEST(OdeGeom, InternalEdgesGiveTheFaceNormal) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(10, 5), "aabb");
  EXPECT_TRUE(boxtree::ode::geom_settings(mesh).internal_edges);
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  dGeomSetPosition(sphere, 0.1, 0.05, 0.2);
  for (const bool internal_edges : {true, false}) {
    SCOPED_TRACE(internal_edges);
    boxtree::ode::GeomSettings settings;
    settings.internal_edges = internal_edges;
    boxtree::ode::set_geom_settings(mesh, settings);
    std::vector<dContactGeom> out;
    ASSERT_GE(collide(mesh, sphere, out), 1);
    Real most_tilted = 1;
    for (const dContactGeom& g : out) most_tilted = std::min(most_tilted, -normal_of(g).z());
    if (internal_edges) {
      EXPECT_GT(most_tilted, 1 - 1e-12);
    } else {
      EXPECT_LT(most_tilted, std::cos(20 * M_PI / 180));
    }
    EXPECT_NEAR(deepest(out).depth, 0.1, 1e-12);
  }
}

// geom_counters: one call per dCollide that reaches the tree, the facets the tree query returned,
// the contacts written; reset_geom_counters zeroes them.
TEST(OdeGeom, GeomCountersCountAndReset) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(8, 4), "aabb");
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  auto counters = boxtree::ode::geom_counters(mesh);
  EXPECT_EQ(counters.calls + counters.candidate_facets + counters.contacts, 0u);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);  // meets facet 72 only
  std::vector<dContactGeom> out;
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  ASSERT_EQ(collide(sphere, mesh, out), 1);
  // Neither geom has a body and nothing moved: from the third call on, the pair's last contacts
  // again, no facet tested (GeomSettings::convex_coherence).
  ASSERT_EQ(collide(mesh, sphere, out), 1);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 2);  // clear: the tree is asked, nothing found
  EXPECT_EQ(collide(mesh, sphere, out), 0);
  counters = boxtree::ode::geom_counters(mesh);
  EXPECT_EQ(counters.calls, 4u);
  EXPECT_EQ(counters.candidate_facets, 2u);
  EXPECT_EQ(counters.reused, 1u);
  EXPECT_EQ(counters.contacts, 3u);
  boxtree::ode::reset_geom_counters(mesh);
  counters = boxtree::ode::geom_counters(mesh);
  EXPECT_EQ(counters.calls, 0u);
  EXPECT_EQ(counters.candidate_facets, 0u);
  EXPECT_EQ(counters.reused, 0u);
  EXPECT_EQ(counters.contacts, 0u);
  // Without coherence every call tests its facets.
  boxtree::ode::GeomSettings settings = boxtree::ode::geom_settings(mesh);
  settings.convex_coherence = false;
  boxtree::ode::set_geom_settings(mesh, settings);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);
  for (int call = 0; call < 3; ++call) ASSERT_EQ(collide(mesh, sphere, out), 1);
  counters = boxtree::ode::geom_counters(mesh);
  EXPECT_EQ(counters.candidate_facets, 3u);
  EXPECT_EQ(counters.reused, 0u);
}

// dCreateBoxtreeMesh(space, tree): geoms share the built tree (no rebuild) and each collides in
// its own place.
TEST(OdeGeom, GeomsShareOneBuiltTree) {
  Space space;
  const auto grid = flat_grid(8, 4);
  const AnyTree tree = AnyTree::build(grid, parse_method("obb-min"));
  dGeomID a = dCreateBoxtreeMesh(space.id, tree);
  dGeomID b = dCreateBoxtreeMesh(space.id, tree);
  dGeomSetPosition(b, 10, 0, 0);
  for (dGeomID g : {a, b}) {
    ASSERT_TRUE(boxtree::ode::is_boxtree_geom(g));
    EXPECT_EQ(boxtree::ode::geom_tree(g)->get<ObbMin>(), tree.get<ObbMin>());
    EXPECT_EQ(&boxtree::ode::geom_tree(g)->mesh(), grid.get());
    EXPECT_EQ(dSpaceQuery(space.id, g), 1);
  }
  // One collision mesh (tree, edge data) for both: the second geom adds no per-facet memory.
  EXPECT_EQ(boxtree::ode::geom_collision_mesh(a), boxtree::ode::geom_collision_mesh(b));
  std::printf("[ shared   ] collision mesh of %zu facets: %zu bytes, held once by both geoms\n", grid->facet_count(),
              boxtree::ode::geom_collision_mesh(a)->memory_bytes());
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  std::vector<dContactGeom> out;
  dGeomSetPosition(sphere, 10.7071, 0.2929, 0.25);
  EXPECT_EQ(collide(a, sphere, out), 0);
  ASSERT_EQ(collide(b, sphere, out), 1);
  EXPECT_EQ(out[0].side1, 72);
  EXPECT_NEAR(out[0].depth, 0.05, 1e-12);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);
  EXPECT_EQ(collide(a, sphere, out), 1);
  EXPECT_EQ(collide(b, sphere, out), 0);
}

// The tree the adapter caches for an ODE trimesh is checked against three of its triangles only
// (the first, middle and last): after the data is changed elsewhere, the cached tree is stale
// until forget_trimesh_data drops it.
TEST(OdeGeom, ForgetTrimeshDataDropsTheCachedTree) {
  Space space;
  // The grid with its own three corners per facet, so that facets move one by one.
  const auto shared = flat_grid(8, 4);
  TriangleMesh unshared;
  for (FacetId f = 0; f < shared->facet_count(); ++f) {
    const auto base = VertexId(unshared.vertices.size());
    for (int k = 0; k < 3; ++k) unshared.vertices.push_back(shared->corner(f, k));
    unshared.triangles.push_back({base, base + 1, base + 2});
  }
  OdeTrimesh ground(space.id, unshared);
  dGeomID cube = dCreateBoxtreeMesh(space.id, box_mesh(Vec3(0.5, 0.5, 0.5)), "aabb");
  dGeomSetPosition(cube, 1.3, -2.4, 0.45);  // 5 cm into cells far from facets 0, 64 and 127
  std::vector<dContactGeom> out;
  ASSERT_GE(collide(cube, ground.geom, out, 16), 1);
  // Every other facet 1 m down, in the arrays ODE reads.
  const int count = int(unshared.facet_count());
  for (int f = 0; f < count; ++f) {
    if (f == 0 || f == count / 2 || f == count - 1) continue;
    for (int k = 0; k < 3; ++k) ground.vertices[std::size_t(9 * f + 3 * k + 2)] -= 1;
  }
  dGeomTriMeshDataUpdate(ground.data);
  EXPECT_GE(collide(cube, ground.geom, out, 16), 1);  // the stale tree still has them at z = 0
  boxtree::ode::forget_trimesh_data(ground.data);
  EXPECT_EQ(collide(cube, ground.geom, out, 16), 0);
  dGeomSetPosition(cube, 1.3, -2.4, -0.55);
  EXPECT_GE(collide(cube, ground.geom, out, 16), 1);
}

// A geom made with dCreateConvex and never registered collides all the same: its points are read
// through ODE (GJK/EPA on their hull, the same depth), the counter says so; set_convex then gives
// the face patch, set_convex_points GJK on the given points.
TEST(OdeGeom, ConvexRegistrationOfAPlainConvexGeom) {
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(10, 5), "aabb");
  const dReal* planes = kCubePlanes;
  const dReal* points = kCubePoints;
  const unsigned* polygons = kCubePolygons;
  dGeomID with_faces = dCreateConvex(space.id, planes, 6, points, 8, polygons);
  dGeomID points_only = dCreateConvex(space.id, planes, 6, points, 8, polygons);
  std::vector<dContactGeom> out;
  for (dGeomID c : {with_faces, points_only}) {
    dGeomSetPosition(c, 0.1, 0.2, 0.45);
    // Turned, so that the points come back in the convex's frame and not by luck.
    dMatrix3 r;
    dRFromAxisAndAngle(r, 0, 0, 1, 0.3);
    dGeomSetRotation(c, r);
    ASSERT_GE(collide(mesh, c, out, 8), 1);  // not registered: read through ODE
    EXPECT_NEAR(deepest(out).depth, 0.05, 1e-6);
    for (const dContactGeom& g : out) EXPECT_LT((normal_of(g) - Vec3(0, 0, -1)).norm(), 1e-6);
  }
  EXPECT_EQ(boxtree::ode::geom_counters(mesh).convexes_read_from_ode, 2u);
  EXPECT_EQ(boxtree::ode::geom_counters(mesh).convexes_without_data, 0u);
  boxtree::ode::set_convex(with_faces, planes, 6, points, 8, polygons);
  ASSERT_GE(collide(mesh, with_faces, out, 8), 4);
  for (const dContactGeom& g : out) EXPECT_NEAR(g.depth, 0.05, 1e-9);
  boxtree::ode::set_convex_points(points_only, points, 8);
  ASSERT_GE(collide(mesh, points_only, out, 8), 1);
  EXPECT_NEAR(deepest(out).depth, 0.05, 1e-6);
  EXPECT_EQ(boxtree::ode::geom_counters(mesh).convexes_read_from_ode, 2u);  // registered now
  EXPECT_THROW(boxtree::ode::set_convex_points(mesh, points, 8), Error);    // not a dConvex
  for (dGeomID c : {with_faces, points_only}) boxtree::ode::forget_convex(c);
}

// The colliders only convert: dCollide's contacts are the core collider's on the same input (the
// box in the mesh's frame, the geom's settings as the request), in the world and ODE's convention
// (normal from the box into the mesh, depth >= 0).
TEST(OdeGeom, ContactsAreTheCollidersContacts) {
  Space space;
  const auto terrain = std::make_shared<const TriangleMesh>(make_terrain(12, 12, 3, 12, 1));
  dGeomID mesh = dCreateBoxtreeMesh(space.id, terrain, "aabb");
  dMatrix3 turn;
  dRFromAxisAndAngle(turn, 0, 0, 1, 0.3);
  dGeomSetRotation(mesh, turn);
  dGeomSetPosition(mesh, 1, 2, 0.5);
  dGeomID box = dCreateBox(space.id, 1.2, 0.8, 0.6);
  dRFromAxisAndAngle(turn, 1, 0.2, 0, 0.5);
  dGeomSetRotation(box, turn);
  int compared = 0;
  for (int i = 0; i < 12; ++i) {
    dGeomSetPosition(box, 3 + 0.5 * i, 5 + 0.3 * i, 1.1 + 0.05 * (i % 4));
    std::vector<dContactGeom> got;
    const int n = collide(mesh, box, got, 8);
    // The same in the core: the box in the mesh's frame.
    const RigidTransform world_from_mesh = pose_of_geom(mesh);
    const RigidTransform world_from_box = pose_of_geom(box);
    const Mat3 r = world_from_mesh.rotation.transpose();
    const Obb in_mesh{r * (world_from_box.translation - world_from_mesh.translation), r * world_from_box.rotation,
                      Vec3(0.6, 0.4, 0.3)};
    const boxtree::ode::GeomSettings settings = boxtree::ode::geom_settings(mesh);
    ContactRequest request;
    request.margin = settings.margin;
    request.two_sided = settings.two_sided;
    request.internal_edges = settings.internal_edges;
    request.max_contacts = 8;
    request.merge_distance = settings.merge_fraction * in_mesh.half_extents.norm();
    ContactResult want;
    collide_convex(*boxtree::ode::geom_collision_mesh(mesh), in_mesh, request, want);
    ASSERT_EQ(std::size_t(n), want.contacts.size()) << "pose " << i;
    for (int k = 0; k < n; ++k) {
      const ContactPoint& c = want.contacts[std::size_t(k)];
      EXPECT_LT((pos_of(got[std::size_t(k)]) - world_from_mesh.apply(c.position)).norm(), 1e-12);
      EXPECT_LT((normal_of(got[std::size_t(k)]) + world_from_mesh.rotation * c.normal).norm(), 1e-12);
      EXPECT_NEAR(got[std::size_t(k)].depth, std::max(c.depth, 0.0), 1e-12);
      EXPECT_EQ(got[std::size_t(k)].side1, int(c.facet));
    }
    compared += n;
  }
  EXPECT_GT(compared, 12);
}

// A mesh whose facets are wound both ways has no front: its geoms collide two-sided, and ODE's
// message handler is told once per mesh.
std::vector<std::string> g_messages;
void record_message(int, const char* format, va_list args) {
  char text[1024];
  std::vsnprintf(text, sizeof text, format, args);
  g_messages.emplace_back(text);
}

TEST(OdeGeom, InconsistentWindingIsTwoSidedAndSaidOnce) {
  auto flipped = std::make_shared<TriangleMesh>(make_uv_sphere(16, 8, 1));
  for (std::size_t f = 0; f < flipped->triangles.size(); f += 3)
    std::swap(flipped->triangles[f][1], flipped->triangles[f][2]);
  const AnyTree tree = AnyTree::build(flipped, Method{});
  Space space;
  dMessageFunction* previous = dGetMessageHandler();
  g_messages.clear();
  dSetMessageHandler(&record_message);
  dGeomID a = dCreateBoxtreeMesh(space.id, tree);
  dCreateBoxtreeMesh(space.id, tree);
  dSetMessageHandler(previous);
  ASSERT_EQ(g_messages.size(), 1u);
  EXPECT_NE(g_messages[0].find("wound the same way"), std::string::npos) << g_messages[0];
  // One-sided is asked (the default), two-sided is what it gets: a ball inside the sphere touching
  // it from behind is pushed further in (towards the middle), as a two-sided facet does.
  dGeomID ball = dCreateSphere(space.id, 0.3);
  dGeomSetPosition(ball, 0, 0, 0.8);
  std::vector<dContactGeom> out;
  ASSERT_GE(collide(a, ball, out), 1);
  EXPECT_GT(normal_of(deepest(out)).z(), 0.9);  // ODE's normal: from the ball into the mesh, up
}

// ODE's registration does not survive dCloseODE: close, re-init, register again, collide.
TEST(OdeGeom, ReRegistersAfterCloseAndInit) {
  dBoxtreeClose();
  dCloseODE();
  dInitODE2(0);
  EXPECT_EQ(dBoxtreeGetClass(), -1);
  ASSERT_GE(dBoxtreeInit(), int(dFirstUserClass));
  Space space;
  dGeomID mesh = dCreateBoxtreeMesh(space.id, flat_grid(4, 2), "aabb");
  dGeomID sphere = dCreateSphere(space.id, 0.3);
  dGeomSetPosition(sphere, 0.7071, 0.2929, 0.25);
  std::vector<dContactGeom> out;
  EXPECT_EQ(collide(mesh, sphere, out), 1);
  EXPECT_EQ(collide(sphere, mesh, out), 1);
}

}  // namespace
}  // namespace boxtree::ode_test
