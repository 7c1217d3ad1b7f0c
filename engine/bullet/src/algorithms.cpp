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
#include <mutex>
#include <string>
#include <vector>

#include "boxtree/bullet/mesh_shape.h"
#include "boxtree/collider.h"
#include "boxtree/convex_polyhedron.h"
#include "boxtree/error.h"
#include "convert.h"

namespace boxtree::bullet {
namespace {

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
void set_mesh_identifiers(btManifoldResult& result, bool mesh_is_result_b, int part, int index) {
  if (mesh_is_result_b) {
    result.setShapeIdentifiersA(-1, -1);
    result.setShapeIdentifiersB(part, index);
  } else {
    result.setShapeIdentifiersA(part, index);
    result.setShapeIdentifiersB(-1, -1);
  }
}

// The collider's contacts (mesh frame; normal from the mesh's facet towards the body, position on
// the facet) into the manifold, in the world, the mesh's margin added to the depth.
void add_contacts(btManifoldResult& result, const BoxtreeMeshShape& mesh, const btTransform& mesh_to_world,
                  bool mesh_is_result_b, const ContactResult& contacts, Real extra_depth) {
  for (const ContactPoint& c : contacts.contacts) {
    int part = 0, index = 0;
    mesh.facetToPart(c.facet, part, index);
    set_mesh_identifiers(result, mesh_is_result_b, part, index);
    result.addContactPoint(mesh_to_world.getBasis() * to_bt(c.normal), mesh_to_world(to_bt(c.position)),
                           -btScalar(c.depth + extra_depth));
  }
}

// Bullet's own convex-triangle algorithm (GJK/EPA) as the collider's engine narrowphase: its
// contacts are caught here instead of going to the manifold. The algorithm runs in the order
// (convex, triangle), so its normals are on the triangle, pointing to the convex, as the
// collider's are.
struct CatchingResult : btManifoldResult {
  CatchingResult(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1) : btManifoldResult(w0, w1) {}
  btTransform mesh_to_world;
  Real mesh_margin = 0;
  ContactPoint* out = nullptr;
  int count = 0;

  void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
    if (count >= kMaxEngineTriangleContacts) return;
    ContactPoint& c = out[count++];
    c.normal = to_vec(mesh_to_world.getBasis().transpose() * normalOnBInWorld);
    c.position = to_vec(mesh_to_world.invXform(pointInWorld));
    c.depth = -Real(depth) - mesh_margin;  // the margin is added back with every contact
  }
};

// ---------------------------------------------------------------------------------------------
// Convex body vs boxtree mesh: the body in the mesh's frame, the core collider, the contacts back.
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
    const Real mesh_margin = Real(mesh.getMargin());
    // Contacts up to the manifold's breaking distance (as Bullet's GJK reports them), with the
    // triangles thickened by the mesh's margin; the manifold keeps 4 points, and the collider's
    // reduction picks the deepest and the widest spread, so 4 it gets.
    ContactRequest request;
    request.margin =
        Real(m_manifold->getContactBreakingThreshold() + result->m_closestPointDistanceThreshold) + mesh_margin;
    request.two_sided = mesh.isTwoSided();
    request.max_contacts = 4;
    request.merge_distance = Real(m_manifold->getContactBreakingThreshold());
    thread_local ContactResult contacts;
    contacts.clear();
    ConvexPairCache* cache = nullptr;
    if (m_settings->convexCoherence) {
      if (!m_cache) m_cache = std::make_unique<ConvexPairCache>();
      cache = m_cache.get();
    }
    collide(mesh, *convex, convex_wrap, mesh_wrap, convex_in_mesh, mesh_margin, request, info, contacts, cache);
    mesh.countCollision(contacts.counts);
    const bool mesh_is_result_b = result->getBody1Internal() == mesh_wrap->getCollisionObject();
    add_contacts(*result, mesh, mesh_to_world, mesh_is_result_b, contacts, mesh_margin);
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
  // The shape in the mesh's (scaled) frame and the collider call for it: spheres, boxes and
  // capsules analytic; hulls with Bullet's faces (AlgorithmSettings::hullFaces) by exact separating
  // axes with the hull's margin as rounding; every other convex shape by its support mapping with
  // Bullet's own per-triangle algorithm (GJK/EPA) as the narrowphase.
  void collide(const BoxtreeMeshShape& mesh, const btConvexShape& convex, const btCollisionObjectWrapper* convex_wrap,
               const btCollisionObjectWrapper* mesh_wrap, const btTransform& convex_in_mesh, Real mesh_margin,
               const ContactRequest& request, const btDispatcherInfo& info, ContactResult& contacts,
               ConvexPairCache* cache) {
    const CollisionMesh& target = mesh.collisionMesh();
    const Vec3 center = to_vec(convex_in_mesh.getOrigin());
    const Mat3 basis = to_mat(convex_in_mesh.getBasis());
    const int type = convex.getShapeType();
    if (m_settings->analyticContacts) {
      switch (type) {
        case SPHERE_SHAPE_PROXYTYPE:
          return collide_convex(target, Sphere{center, Real(static_cast<const btSphereShape&>(convex).getRadius())},
                                request, contacts, cache);
        case BOX_SHAPE_PROXYTYPE:
          return collide_convex(
              target, Obb{center, basis, to_vec(static_cast<const btBoxShape&>(convex).getHalfExtentsWithMargin())},
              request, contacts, cache);
        case CAPSULE_SHAPE_PROXYTYPE: {
          const auto& capsule = static_cast<const btCapsuleShape&>(convex);
          const Vec3 axis = basis.col(capsule.getUpAxis()) * Real(capsule.getHalfHeight());
          return collide_convex(target, Capsule{center - axis, center + axis, Real(capsule.getRadius())}, request,
                                contacts, cache);
        }
        case CYLINDER_SHAPE_PROXYTYPE: {
          // Bullet's cylinder (btCylinderShape, X or Z variants) with its margin inside its
          // dimensions: the sharp cylinder of those dimensions.
          const auto& cylinder = static_cast<const btCylinderShape&>(convex);
          const int up = cylinder.getUpAxis();
          const Vec3 axis = basis.col(up) * Real(cylinder.getHalfExtentsWithMargin()[up]);
          return collide_convex(target, Cylinder{center - axis, center + axis, Real(cylinder.getRadius())}, request,
                                contacts, cache);
        }
        default:
          break;
      }
      if (const ConvexPolyhedron* hull =
              m_settings->hullFaces && convex.isPolyhedral() ? polyhedronOf(convex) : nullptr)
        return collide_convex(target, PlacedPolyhedron{*hull, to_rigid(convex_in_mesh), Real(convex.getMargin())},
                              request, contacts, cache);
    }
    // Any other convex shape: its support mapping (margin included), its box, Bullet's GJK.
    const btMatrix3x3 mesh_to_convex = convex_in_mesh.getBasis().transpose();
    auto support = [&](const Vec3& direction) {
      return to_vec(convex_in_mesh(convex.localGetSupportingVertex(mesh_to_convex * to_bt(direction))));
    };
    btVector3 lo, hi;
    convex.getAabb(btTransform::getIdentity(), lo, hi);  // in the body's own frame, margin included
    const Obb bounds{to_vec(convex_in_mesh((lo + hi) * btScalar(0.5))), basis, to_vec((hi - lo) * btScalar(0.5))};
    CatchingResult catcher(convex_wrap, mesh_wrap);
    catcher.setPersistentManifold(m_manifold);
    // The caller's own threshold, as btConvexConcaveCollisionAlgorithm passes it on (the request's
    // margin less the mesh's margin and the breaking distance): Bullet's convex-convex algorithm
    // adds the manifold's breaking distance itself. (Passing the whole margin made GJK report up
    // to twice the breaking distance; the collider now drops such contacts either way.)
    catcher.m_closestPointDistanceThreshold =
        btScalar(request.margin - mesh_margin) - m_manifold->getContactBreakingThreshold();
    catcher.mesh_to_world = mesh_wrap->getWorldTransform();
    catcher.mesh_margin = mesh_margin;
    auto narrowphase = [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions&, ContactPoint* out) {
      btTriangleShape triangle(to_bt(a), to_bt(b), to_bt(c));
      triangle.setMargin(mesh.getMargin());
      btCollisionObjectWrapper tri_wrap(mesh_wrap, &triangle, mesh_wrap->getCollisionObject(),
                                        mesh_wrap->getWorldTransform(), -1, -1);
      btCollisionAlgorithm* algorithm =
          m_dispatcher->findAlgorithm(convex_wrap, &tri_wrap, m_manifold, BT_CONTACT_POINT_ALGORITHMS);
      catcher.out = out;
      catcher.count = 0;
      catcher.setBody0Wrap(convex_wrap);
      catcher.setBody1Wrap(&tri_wrap);
      algorithm->processCollision(convex_wrap, &tri_wrap, info, &catcher);
      algorithm->~btCollisionAlgorithm();
      m_dispatcher->freeCollisionAlgorithm(algorithm);
      return catcher.count;
    };
    collide_convex(target, SupportShape{support, center, bounds, false}, narrowphase, request, contacts);
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
  std::unique_ptr<ConvexPairCache> m_cache;  // AlgorithmSettings::convexCoherence, made on first use
};

// ---------------------------------------------------------------------------------------------
// Boxtree mesh vs boxtree mesh (Bullet itself has nothing for concave vs concave): the core
// collider's mesh pair, in body 1's frame (normals from body 1 towards body 0, positions on body
// 1: Bullet's convention for the manifold's body B).
class MeshMeshAlgorithm : public btActivatingCollisionAlgorithm {
 public:
  MeshMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* w0,
                    const btCollisionObjectWrapper* w1, const AlgorithmSettings* settings)
      : btActivatingCollisionAlgorithm(ci, w0, w1), m_settings(settings) {}
  ~MeshMeshAlgorithm() override {
    if (m_manifold) m_dispatcher->releaseManifold(m_manifold);
  }

  void processCollision(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1, const btDispatcherInfo&,
                        btManifoldResult* result) override {
    if (!m_manifold) m_manifold = m_dispatcher->getNewManifold(w0->getCollisionObject(), w1->getCollisionObject());
    result->setPersistentManifold(m_manifold);
    const BoxtreeMeshShape& a = mesh_shape(w0);
    const BoxtreeMeshShape& b = mesh_shape(w1);
    const btTransform b_to_world = w1->getWorldTransform();
    MeshContactRequest request;
    request.margin = Real(m_manifold->getContactBreakingThreshold());
    request.max_contacts = 4;
    request.merge_distance = request.margin;
    request.policy = m_settings->meshContacts;
    // A static or kinematic mesh (a terrain) is the surface that deep overlaps are resolved
    // through (collider.h, face_normals).
    request.static_mesh = w1->getCollisionObject()->isStaticOrKinematicObject()   ? StaticMesh::mesh
                          : w0->getCollisionObject()->isStaticOrKinematicObject() ? StaticMesh::other
                                                                                  : StaticMesh::neither;
    request.coherence = m_settings->meshCoherence;
    if (request.coherence && !m_cache) m_cache = std::make_unique<MeshPairCache>();
    thread_local ContactResult contacts;
    contacts.clear();
    collide_meshes(b.collisionMesh(), a.collisionMesh(), to_rigid(b_to_world.inverseTimes(w0->getWorldTransform())),
                   request, contacts, m_cache.get());
    b.countCollision(contacts.counts);
    if (contacts.contacts.empty()) {
      // Last step's points are still in the manifold: refreshed (moved with the bodies, dropped
      // once apart beyond the breaking threshold) as Bullet's own algorithms do, not left to the
      // solver at the depths they had.
      if (m_manifold->getNumContacts()) result->refreshContactPoints();
      return;
    }
    for (const ContactPoint& c : contacts.contacts) {
      int part_a = 0, index_a = 0, part_b = 0, index_b = 0;
      a.facetToPart(c.other_facet, part_a, index_a);
      b.facetToPart(c.facet, part_b, index_b);
      result->setShapeIdentifiersA(part_a, index_a);
      result->setShapeIdentifiersB(part_b, index_b);
      // The shapes' margins are not added: contacts exist only while triangles intersect
      // (tree-vs-tree has no margin), so pushing the meshes a margin apart would lose the contact
      // every other step, a limit cycle in which a resting rock never settled.
      result->addContactPoint(b_to_world.getBasis() * to_bt(c.normal), b_to_world(to_bt(c.position)),
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
    const AlgorithmSettings* settings = nullptr;
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* w0,
                                                   const btCollisionObjectWrapper* w1) override {
      void* memory = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(MeshMeshAlgorithm));
      return new (memory) MeshMeshAlgorithm(ci, w0, w1, settings);
    }
  };

 private:
  btPersistentManifold* m_manifold = nullptr;
  const AlgorithmSettings* m_settings;
  // The pair's state between steps (meshCoherence), freed with the algorithm, i.e. with the pair.
  // Held by pointer: the algorithm lives in Bullet's pool of fixed-size elements.
  std::unique_ptr<MeshPairCache> m_cache;
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
  // Worlds may be set up from several threads at once (ThreadSanitizer found the list unguarded).
  static std::mutex registrations_mutex;
  static std::vector<std::unique_ptr<Registration>> registrations;
  Registration* made = nullptr;
  {
    std::lock_guard<std::mutex> lock(registrations_mutex);
    made = registrations.emplace_back(std::make_unique<Registration>()).get();
  }
  auto& r = *made;
  r.settings = settings;
  r.convex.settings = &r.settings;
  r.swapped.settings = &r.settings;
  r.mesh_mesh.settings = &r.settings;
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
