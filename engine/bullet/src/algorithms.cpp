// SPDX-License-Identifier: MIT
#include "boxtree/bullet/algorithms.h"

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionShapes/btConvexPolyhedron.h>
#include <BulletCollision/CollisionShapes/btPolyhedralConvexShape.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>

#include <LinearMath/btPoolAllocator.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "boxtree/active_edges.h"
#include "boxtree/bullet/mesh_shape.h"
#include "boxtree/contact.h"
#include "boxtree/convex_polyhedron.h"
#include "boxtree/error.h"
#include "convert.h"

namespace boxtree::bullet {
namespace {

// Contacts handed to the manifold per pair and step: the manifold keeps 4, and reduce_contacts
// already picks the deepest point and the largest spread, so 4 it gets. (8, letting Bullet's own
// replacement choose, cost 2% more of the drop scene's time for the same contact count.)
constexpr std::size_t kMaxContactsPerPair = 4;

const BoxtreeMeshShape& mesh_shape(const btCollisionObjectWrapper* wrap) {
  return *static_cast<const BoxtreeMeshShape*>(wrap->getCollisionShape());
}

// The hull Bullet computed for a polyhedral shape (initializePolyhedralFeatures: its corners and
// its faces, coplanar triangles merged into polygons), as the core's ConvexPolyhedron; empty if the
// core refuses it (a merged face not planar to 1e-6 of the size, say), and the shape keeps GJK.
std::unique_ptr<const ConvexPolyhedron> convert_polyhedron(const btConvexPolyhedron& source) {
  std::vector<Vec3> points;
  points.reserve(std::size_t(source.m_vertices.size()));
  for (int i = 0; i < source.m_vertices.size(); ++i) points.push_back(to_vec(source.m_vertices[i]));
  std::vector<std::vector<int>> faces(std::size_t(source.m_faces.size()));
  for (int f = 0; f < source.m_faces.size(); ++f)
    for (int k = 0; k < source.m_faces[f].m_indices.size(); ++k)
      faces[std::size_t(f)].push_back(source.m_faces[f].m_indices[k]);
  try {
    return std::make_unique<const ConvexPolyhedron>(make_convex_polyhedron(points, faces));
  } catch (const Error&) {
    return nullptr;
  }
}

// Bullet's contact convention, which the code below relies on: btManifoldResult::addContactPoint
// takes the normal and point relative to the *manifold's* body order (normal on its body 1,
// pointing to body 0; point on body 1; negative depth = penetration) and only swaps the stored
// local points when the result's wrappers come in the other order. The convex-mesh manifolds
// here are created as (convex, mesh), so contacts are always given as normal on the mesh,
// point on the mesh. Shape identifiers, in contrast, follow the result's order.
void add_contact(btManifoldResult& result, const btTransform& mesh_to_world, const ContactPoint& c, Real extra_depth) {
  result.addContactPoint(mesh_to_world.getBasis() * to_bt(c.normal), mesh_to_world(to_bt(c.position)),
                         -btScalar(c.depth + extra_depth));
}

void set_mesh_identifiers(btManifoldResult& result, bool mesh_is_result_b, int part, int index) {
  if (mesh_is_result_b) {
    result.setShapeIdentifiersA(-1, -1);
    result.setShapeIdentifiersB(part, index);
  } else {
    result.setShapeIdentifiersA(part, index);
    result.setShapeIdentifiersB(-1, -1);
  }
}

// Reports contacts of per-triangle GJK (the fallback for general convex shapes) through the
// real result, correcting normals on inactive edges on the way. The per-triangle algorithm runs
// in the order (convex, triangle), so its normals are on the triangle, pointing to the convex.
struct EdgeCorrectingResult : btManifoldResult {
  EdgeCorrectingResult(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1)
      : btManifoldResult(w0, w1) {}
  const BoxtreeMeshShape* mesh = nullptr;
  btTransform mesh_to_world;
  FacetId facet = 0;

  // One-sided meshes: the convex body (its shape and its transform in the mesh frame), to
  // measure how far it reaches behind a facet.
  const btConvexShape* convex = nullptr;
  btTransform convex_in_mesh;

  void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
    const std::uint8_t active = mesh->activeEdges()[facet];
    // The common case, a two-sided mesh and no internal edge: the contact as GJK gave it, without
    // fetching the triangle.
    if (mesh->isTwoSided() && active == 0x7)
      return btManifoldResult::addContactPoint(normalOnBInWorld, pointInWorld, depth);
    btVector3 tri[3];
    mesh->scaledTriangle(facet, tri);
    const btVector3 front_local = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    const bool back_facing = !mesh->isTwoSided() && front_local.length2() > 0 &&
                             (mesh_to_world.getBasis().transpose() * normalOnBInWorld).dot(front_local) < 0;
    if (back_facing) {
      // GJK pushes the body out through the back of the facet: push it out through the front
      // instead, by how far its deepest point along the front normal lies behind the facet's
      // plane (as the core's one-sided contacts do, ContactOptions::two_sided).
      const btVector3 front = front_local.normalized();
      const btVector3 deepest =
          convex_in_mesh(convex->localGetSupportingVertex(-(convex_in_mesh.getBasis().transpose() * front)));
      const btScalar behind = (tri[0] - deepest).dot(front);
      if (behind < 0) return;  // apart along the front normal: no contact from this side
      const btVector3 on_plane = deepest + front * behind;
      return btManifoldResult::addContactPoint(mesh_to_world.getBasis() * front, mesh_to_world(on_plane), -behind);
    }
    if (active == 0x7) return btManifoldResult::addContactPoint(normalOnBInWorld, pointInWorld, depth);
    ContactPoint c;
    c.depth = -Real(depth);
    c.normal = to_vec(mesh_to_world.getBasis().transpose() * normalOnBInWorld);
    c.position = to_vec(mesh_to_world.invXform(pointInWorld));
    switch (correct_internal_edge_contact(c, to_vec(tri[0]), to_vec(tri[1]), to_vec(tri[2]), active)) {
      case EdgeContact::keep:
        return btManifoldResult::addContactPoint(normalOnBInWorld, pointInWorld, depth);
      case EdgeContact::discard:
        return;
      case EdgeContact::corrected:
        btManifoldResult::addContactPoint(mesh_to_world.getBasis() * to_bt(c.normal), pointInWorld, -btScalar(c.depth));
    }
  }
};

// ---------------------------------------------------------------------------------------------
// Convex body vs boxtree mesh.
class ConvexMeshAlgorithm : public btActivatingCollisionAlgorithm {
 public:
  ConvexMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                      const btCollisionObjectWrapper* w1, bool swapped, const AlgorithmSettings* settings)
      : btActivatingCollisionAlgorithm(ci, w0, w1), m_swapped(swapped), m_settings(settings) {}
  ~ConvexMeshAlgorithm() override {
    if (m_manifold) m_dispatcher->releaseManifold(m_manifold);
  }

  void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                        const btDispatcherInfo& info, btManifoldResult* result) override {
    const btCollisionObjectWrapper* convex_wrap = m_swapped ? w1 : w0;
    const btCollisionObjectWrapper* mesh_wrap = m_swapped ? w0 : w1;
    if (!m_manifold)
      m_manifold = m_dispatcher->getNewManifold(convex_wrap->getCollisionObject(), mesh_wrap->getCollisionObject());
    result->setPersistentManifold(m_manifold);

    const BoxtreeMeshShape& mesh = mesh_shape(mesh_wrap);
    const auto* convex = static_cast<const btConvexShape*>(convex_wrap->getCollisionShape());
    const btTransform mesh_to_world = mesh_wrap->getWorldTransform();
    const btTransform convex_in_mesh = mesh_to_world.inverseTimes(convex_wrap->getWorldTransform());
    // Contacts are wanted up to the manifold's breaking distance (as Bullet's GJK reports them),
    // with the triangles thickened by the mesh's margin.
    const Real mesh_margin = Real(mesh.getMargin());
    const Real reach =
        Real(m_manifold->getContactBreakingThreshold() + result->m_closestPointDistanceThreshold) + mesh_margin;
    const bool mesh_is_result_b = result->getBody1Internal() == mesh_wrap->getCollisionObject();

    const int type = convex->getShapeType();
    // Hulls (and other polyhedral shapes but boxes) whose faces Bullet has computed.
    const ConvexPolyhedron* hull =
        m_settings->analyticContacts && m_settings->hullFaces && type != BOX_SHAPE_PROXYTYPE && convex->isPolyhedral()
            ? polyhedronOf(*convex)
            : nullptr;
    const bool analytic =
        m_settings->analyticContacts && mesh.hasUnitScaling() &&
        (type == SPHERE_SHAPE_PROXYTYPE || type == BOX_SHAPE_PROXYTYPE || type == CAPSULE_SHAPE_PROXYTYPE || hull);
    if (analytic) {
      processAnalytic(mesh, *convex, hull, convex_in_mesh, mesh_to_world, reach, mesh_margin, mesh_is_result_b,
                      *result);
    } else {
      processGjk(mesh, *convex, convex_wrap, mesh_wrap, convex_in_mesh, reach, info, *result);
    }
    if (m_manifold->getNumContacts()) result->refreshContactPoints();
  }

  btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                 btManifoldResult*) override {
    return 1;  // continuous collision against meshes goes through convexSweepTest (the fast sweep path)
  }

  void getAllContactManifolds(btManifoldArray& manifolds) override {
    if (m_manifold) manifolds.push_back(m_manifold);
  }

  struct CreateFunc : btCollisionAlgorithmCreateFunc {
    const AlgorithmSettings* settings = nullptr;
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
      void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(ConvexMeshAlgorithm));
      return new (memory) ConvexMeshAlgorithm(ci, w0, w1, m_swapped, settings);
    }
  };

 private:
  // Spheres, boxes, capsules and hulls with faces: the body's own volume (grown by the contact
  // reach; a hull's oriented box) queries the tree down to the facets, and the core's analytic
  // routines give the contacts. Hulls take this path with AlgorithmSettings::hullFaces, once
  // Bullet has computed their polyhedral features (algorithms.h says what it gains and costs).
  void processAnalytic(const BoxtreeMeshShape& mesh, const btConvexShape& convex, const ConvexPolyhedron* polyhedron,
                       const btTransform& convex_in_mesh, const btTransform& mesh_to_world, Real reach,
                       Real mesh_margin, bool mesh_is_result_b, btManifoldResult& result) {
    thread_local std::vector<ContactPoint> contacts;
    contacts.clear();
    ContactOptions options;
    options.margin = reach;
    options.two_sided = mesh.isTwoSided();
    const Vec3 center = to_vec(convex_in_mesh.getOrigin());
    const Mat3 basis = to_mat(convex_in_mesh.getBasis());
    const TriangleMesh& m = mesh.mesh();
    const std::vector<std::uint8_t>& active = mesh.activeEdges();
    ContactPoint out[std::max(kMaxBoxTriangleContacts, kMaxPolyhedronTriangleContacts)];
    auto run = [&](const auto& query, auto&& contact_fn, FacetTest test = FacetTest::exact_triangle) {
      mesh.tree().query_overlap(
          query,
          [&](FacetId f) {
            mesh.countNarrowphaseTriangles(1);
            const int n = contact_fn(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), out);
            for (int i = 0; i < n; ++i) {
              out[i].facet = f;
              if (correct_internal_edge_contact(out[i], m.corner(f, 0), m.corner(f, 1), m.corner(f, 2), active[f]) !=
                  EdgeContact::discard)
                contacts.push_back(out[i]);
            }
            return true;
          },
          nullptr, test);
    };
    switch (convex.getShapeType()) {
      case SPHERE_SHAPE_PROXYTYPE: {
        const Sphere sphere{center, Real(static_cast<const btSphereShape&>(convex).getRadius())};
        run(Sphere{center, sphere.radius + reach}, [&](const Vec3& a, const Vec3& b, const Vec3& c, ContactPoint* o) {
          return contact_sphere_triangle(sphere, a, b, c, options, o);
        });
        break;
      }
      case BOX_SHAPE_PROXYTYPE: {
        Obb box{center, basis, to_vec(static_cast<const btBoxShape&>(convex).getHalfExtentsWithMargin())};
        Obb grown = box;
        grown.half_extents.array() += reach;
        run(grown, [&](const Vec3& a, const Vec3& b, const Vec3& c, ContactPoint* o) {
          return contact_box_triangle(box, a, b, c, options, o);
        });
        break;
      }
      case CAPSULE_SHAPE_PROXYTYPE: {
        const auto& capsule_shape = static_cast<const btCapsuleShape&>(convex);
        const Vec3 axis = basis.col(capsule_shape.getUpAxis()) * Real(capsule_shape.getHalfHeight());
        const Capsule capsule{center - axis, center + axis, Real(capsule_shape.getRadius())};
        run(Capsule{capsule.p0, capsule.p1, capsule.radius + reach},
            [&](const Vec3& a, const Vec3& b, const Vec3& c, ContactPoint* o) {
              return contact_capsule_triangle(capsule, a, b, c, options, o);
            });
        break;
      }
      default: {
        // A hull with faces: the exact separating axes of the core polyhedron (a patch where a
        // face rests on a facet), the shape's margin added to the depth as Bullet's rounded hull
        // has it (its extent along any axis is the core's plus the margin).
        if (!polyhedron) break;  // (processCollision sends no other shape here)
        const Real hull_margin = Real(convex.getMargin());
        thread_local ConvexPolyhedron hull;
        transform_polyhedron(*polyhedron, RigidTransform{basis, center}, hull);
        ContactOptions hull_options = options;
        hull_options.margin = reach + hull_margin;
        btVector3 lo, hi;
        convex.getAabb(btTransform::getIdentity(), lo, hi);  // margin included, in the body's frame
        Obb box{to_vec(convex_in_mesh((lo + hi) * btScalar(0.5))), basis, to_vec((hi - lo) * btScalar(0.5))};
        box.half_extents.array() += reach;
        run(
            box,
            [&](const Vec3& a, const Vec3& b, const Vec3& c, ContactPoint* o) {
              const int n = contact_polyhedron_triangle(hull, a, b, c, hull_options, o);
              for (int i = 0; i < n; ++i) o[i].depth += hull_margin;
              return n;
            },
            FacetTest::leaf_volume);  // the hull's own axes reject what the box's triangle test would (as in the ODE
                                      // adapter)
        break;
      }
    }
    if (contacts.empty()) return;
    reduce_contacts(contacts, kMaxContactsPerPair, Real(m_manifold->getContactBreakingThreshold()));
    for (const ContactPoint& c : contacts) {
      int part = 0, index = 0;
      mesh.facetToPart(c.facet, part, index);
      set_mesh_identifiers(result, mesh_is_result_b, part, index);
      add_contact(result, mesh_to_world, c, mesh_margin);
    }
  }

  // Other convex shapes (cylinders, cones, hulls without faces): the body's box in the mesh frame,
  // as an oriented box (tighter than the axis-aligned box Bullet's own algorithm queries with),
  // picks the triangles; Bullet's own convex-triangle algorithm (GJK/EPA) gives the contacts,
  // exactly as in btConvexConcaveCollisionAlgorithm.
  void processGjk(const BoxtreeMeshShape& mesh, const btConvexShape& convex,
                  const btCollisionObjectWrapper* convex_wrap, const btCollisionObjectWrapper* mesh_wrap,
                  const btTransform& convex_in_mesh, Real reach, const btDispatcherInfo& info,
                  btManifoldResult& result) {
    btVector3 lo, hi;
    convex.getAabb(btTransform::getIdentity(), lo, hi);  // in the body's own frame
    const bool mesh_is_result_b = result.getBody1Internal() == mesh_wrap->getCollisionObject();
    EdgeCorrectingResult corrected(result.getBody0Wrap(), result.getBody1Wrap());
    corrected.setPersistentManifold(m_manifold);
    corrected.m_closestPointDistanceThreshold = result.m_closestPointDistanceThreshold;
    corrected.mesh = &mesh;
    corrected.mesh_to_world = mesh_wrap->getWorldTransform();
    corrected.convex = &convex;
    corrected.convex_in_mesh = convex_in_mesh;

    // The body's extent along the facet's normal, from its support function: a facet whose plane
    // the body is wholly above (or below) by more than the reach can give no contact, and skips
    // Bullet's per-triangle algorithm (GJK, the dearest part of a convex-mesh pair).
    const btMatrix3x3 mesh_to_convex = convex_in_mesh.getBasis().transpose();
    const btScalar bt_reach = btScalar(reach);
    auto out_of_reach = [&](const btVector3 tri[3]) {
      const btVector3 normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      const btScalar length = normal.length();
      if (!(length > 0)) return false;
      const btVector3 n = normal / length;
      const btScalar plane = n.dot(tri[0]);
      const btScalar lowest = n.dot(convex_in_mesh(convex.localGetSupportingVertex(mesh_to_convex * -n)));
      if (lowest - plane > bt_reach) return true;
      const btScalar highest = n.dot(convex_in_mesh(convex.localGetSupportingVertex(mesh_to_convex * n)));
      return plane - highest > bt_reach;
    };

    auto visit = [&](FacetId f) {
      btVector3 tri[3];
      mesh.scaledTriangle(f, tri);
      if (out_of_reach(tri)) return true;
      mesh.countNarrowphaseTriangles(1);
      btTriangleShape triangle(tri[0], tri[1], tri[2]);
      triangle.setMargin(mesh.getMargin());
      int part = 0, index = 0;
      mesh.facetToPart(f, part, index);
      btCollisionObjectWrapper tri_wrap(mesh_wrap, &triangle, mesh_wrap->getCollisionObject(),
                                        mesh_wrap->getWorldTransform(), part, index);
      btCollisionAlgorithm* algorithm =
          m_dispatcher->findAlgorithm(convex_wrap, &tri_wrap, m_manifold, BT_CONTACT_POINT_ALGORITHMS);
      corrected.facet = f;
      // The result sees the triangle in the mesh's place; the algorithm was found for the order
      // (convex, triangle) and is always called in that order (the result handles the swap).
      if (mesh_is_result_b) {
        corrected.setBody1Wrap(&tri_wrap);
      } else {
        corrected.setBody0Wrap(&tri_wrap);
      }
      set_mesh_identifiers(corrected, mesh_is_result_b, part, index);
      algorithm->processCollision(convex_wrap, &tri_wrap, info, &corrected);
      algorithm->~btCollisionAlgorithm();
      m_dispatcher->freeCollisionAlgorithm(algorithm);
      return true;
    };
    if (mesh.hasUnitScaling()) {
      Obb box;
      box.axes = to_mat(convex_in_mesh.getBasis());
      box.center = to_vec(convex_in_mesh((lo + hi) * btScalar(0.5)));
      box.half_extents = to_vec((hi - lo) * btScalar(0.5)) + Vec3::Constant(reach);
      mesh.tree().query_overlap(box, visit);
    } else {
      btVector3 wlo, whi;
      convex.getAabb(convex_in_mesh, wlo, whi);
      const btScalar r = static_cast<btScalar>(reach);
      const btVector3 grow{r, r, r};
      // The tree is unscaled and a scaled oriented box is no box: take the candidates of the
      // body's scaled-frame box through processAllTriangles' own mapping.
      struct Collect : btTriangleCallback {
        std::vector<FacetId> facets;
        const BoxtreeMeshShape* shape = nullptr;
        void processTriangle(btVector3*, int part, int index) override {
          facets.push_back(shape->partToFacet(part, index));
        }
      } collect;
      collect.shape = &mesh;
      mesh.processAllTriangles(&collect, wlo - grow, whi + grow);
      for (FacetId f : collect.facets) visit(f);
    }
  }

  // The body's hull with faces, converted once per pair from Bullet's polyhedral features (null
  // if it has none, or the core refused them: then GJK as for any convex).
  const ConvexPolyhedron* polyhedronOf(const btConvexShape& convex) {
    // isPolyhedral() also holds for CUSTOM_POLYHEDRAL_SHAPE_TYPE, a user's class that need not
    // derive from btPolyhedralConvexShape.
    const auto* shape = dynamic_cast<const btPolyhedralConvexShape*>(&convex);
    const btConvexPolyhedron* source = shape ? shape->getConvexPolyhedron() : nullptr;
    if (source != m_polyhedronSource) {
      m_polyhedronSource = source;
      m_polyhedron = source ? convert_polyhedron(*source) : nullptr;
    }
    return m_polyhedron.get();
  }

  btPersistentManifold* m_manifold = nullptr;
  bool m_swapped;
  const AlgorithmSettings* m_settings;
  const btConvexPolyhedron* m_polyhedronSource = nullptr;
  std::unique_ptr<const ConvexPolyhedron> m_polyhedron;
};

// ---------------------------------------------------------------------------------------------
// Boxtree mesh vs boxtree mesh: tree-vs-tree finds the intersecting facet pairs, and face-normal
// triangle contacts (contact_triangle_faces; normal from b's triangle to a's) turn them into
// manifold points. Face normals rather than the least-penetration axis of the two triangles:
// with edge-edge axes a resting mesh kept being pushed sideways and never settled.
class MeshMeshAlgorithm : public btActivatingCollisionAlgorithm {
 public:
  MeshMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                    const btCollisionObjectWrapper* w1)
      : btActivatingCollisionAlgorithm(ci, w0, w1) {}
  ~MeshMeshAlgorithm() override {
    if (m_manifold) m_dispatcher->releaseManifold(m_manifold);
  }

  void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1, const btDispatcherInfo&,
                        btManifoldResult* result) override {
    if (!m_manifold) m_manifold = m_dispatcher->getNewManifold(w0->getCollisionObject(), w1->getCollisionObject());
    result->setPersistentManifold(m_manifold);
    const BoxtreeMeshShape& a = mesh_shape(w0);
    const BoxtreeMeshShape& b = mesh_shape(w1);
    // Non-unit scaling would need trees of the scaled meshes; such pairs get no contacts
    // (documented in engine/bullet/README.md).
    if (!a.hasUnitScaling() || !b.hasUnitScaling()) return;
    const btTransform a_to_world = w0->getWorldTransform();
    const btTransform b_in_a = a_to_world.inverseTimes(w1->getWorldTransform());
    const RigidTransform a_from_b = to_rigid(b_in_a);

    thread_local std::vector<ContactPoint> contacts;
    contacts.clear();
    ContactOptions options;
    options.margin = Real(m_manifold->getContactBreakingThreshold());
    // A static or kinematic mesh (a terrain) is the surface that deep overlaps are resolved
    // through (contact.h): a torus pressed under the pile was pulled through the terrain by its own
    // upward faces.
    const FixedSurface fixed = w0->getCollisionObject()->isStaticOrKinematicObject()   ? FixedSurface::a
                               : w1->getCollisionObject()->isStaticOrKinematicObject() ? FixedSurface::b
                                                                                       : FixedSurface::neither;
    const TriangleMesh& ma = a.mesh();
    const TriangleMesh& mb = b.mesh();
    ContactPoint out[kMaxTriangleFaceContacts];
    a.tree().collide(b.tree(), a_from_b, [&](const FacetPair& pair) {
      b.countNarrowphaseTriangles(1);
      const Vec3 b0 = a_from_b.apply(mb.corner(pair.b, 0)), b1 = a_from_b.apply(mb.corner(pair.b, 1)),
                 b2 = a_from_b.apply(mb.corner(pair.b, 2));
      const int n = contact_triangle_faces(ma.corner(pair.a, 0), ma.corner(pair.a, 1), ma.corner(pair.a, 2), b0, b1, b2,
                                           options, out, fixed);
      for (int i = 0; i < n; ++i) {
        out[i].facet = pair.b;
        out[i].other_facet = pair.a;
        contacts.push_back(out[i]);
      }
      return true;
    });
    if (contacts.empty()) {
      // Last step's points are still in the manifold: refreshed (moved with the bodies, dropped
      // once apart beyond the breaking threshold) as Bullet's own algorithms do, not left to the
      // solver at the depths they had.
      if (m_manifold->getNumContacts()) result->refreshContactPoints();
      return;
    }
    reduce_contacts(contacts, kMaxContactsPerPair, Real(m_manifold->getContactBreakingThreshold()));
    for (const ContactPoint& c : contacts) {
      int part_a = 0, index_a = 0, part_b = 0, index_b = 0;
      a.facetToPart(c.other_facet, part_a, index_a);
      b.facetToPart(c.facet, part_b, index_b);
      result->setShapeIdentifiersA(part_a, index_a);
      result->setShapeIdentifiersB(part_b, index_b);
      // The contact's "shape" is a's triangle and its position is on b's triangle: b is Bullet's
      // body B, the normal on B points from b to a. The shapes' margins are not added: contacts
      // exist only while triangles intersect (tree-vs-tree has no margin), so pushing the meshes
      // a margin apart would lose the contact every other step, a limit cycle in which a
      // resting rock never settled (measured: still rolling after 10 s; without: at rest in 2.5 s).
      result->addContactPoint(a_to_world.getBasis() * to_bt(c.normal), a_to_world(to_bt(c.position)),
                              -btScalar(c.depth));
    }
    result->refreshContactPoints();
  }

  btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                 btManifoldResult*) override {
    return 1;
  }
  void getAllContactManifolds(btManifoldArray& manifolds) override {
    if (m_manifold) manifolds.push_back(m_manifold);
  }

  struct CreateFunc : btCollisionAlgorithmCreateFunc {
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
      void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(MeshMeshAlgorithm));
      return new (memory) MeshMeshAlgorithm(ci, w0, w1);
    }
  };

 private:
  btPersistentManifold* m_manifold = nullptr;
};

}  // namespace

int boxtreeAlgorithmMaxSize() {
  return static_cast<int>(std::max(sizeof(ConvexMeshAlgorithm), sizeof(MeshMeshAlgorithm)));
}

void registerBoxtreeAlgorithms(btCollisionDispatcher* dispatcher, const AlgorithmSettings& settings) {
  if (!dispatcher) throw Error("registerBoxtreeAlgorithms: null dispatcher");
  // Bullet's pool hands out fixed-size elements and ignores the requested size in release
  // builds: a larger algorithm would corrupt memory silently.
  if (btCollisionConfiguration* config = dispatcher->getCollisionConfiguration()) {
    if (btPoolAllocator* pool = config->getCollisionAlgorithmPool();
        pool && pool->getElementSize() < boxtreeAlgorithmMaxSize()) {
      throw Error("registerBoxtreeAlgorithms: the collision configuration's algorithm pool has " +
                  std::to_string(pool->getElementSize()) + "-byte elements, boxtree's algorithms need " +
                  std::to_string(boxtreeAlgorithmMaxSize()) +
                  "; raise btDefaultCollisionConstructionInfo::m_customCollisionAlgorithmMaxElementSize");
    }
  }
  // The create functions and settings must outlive the dispatcher's use of them; one set per
  // settings value is kept for the life of the program (a handful of small objects).
  struct Registration {
    AlgorithmSettings settings;
    ConvexMeshAlgorithm::CreateFunc convex, swapped;
    MeshMeshAlgorithm::CreateFunc mesh_mesh;
  };
  static std::vector<std::unique_ptr<Registration>> registrations;
  auto& r = *registrations.emplace_back(std::make_unique<Registration>());
  r.settings = settings;
  r.convex.settings = &r.settings;
  r.swapped.settings = &r.settings;
  r.swapped.m_swapped = true;

  const int mesh = FAST_CONCAVE_MESH_PROXYTYPE;
  if (settings.convexAlgorithm) {
    for (int type = 0; type < CONCAVE_SHAPES_START_HERE; ++type) {
      if (!btBroadphaseProxy::isConvex(type)) continue;
      dispatcher->registerCollisionCreateFunc(type, mesh, &r.convex);
      dispatcher->registerCollisionCreateFunc(mesh, type, &r.swapped);
    }
  }
  if (settings.meshMeshAlgorithm) {
    dispatcher->registerCollisionCreateFunc(mesh, mesh, &r.mesh_mesh);
    dispatcher->registerClosestPointsCreateFunc(mesh, mesh, &r.mesh_mesh);
  }
}

}  // namespace boxtree::bullet
