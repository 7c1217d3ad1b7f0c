// SPDX-License-Identifier: MIT
#pragma once
// BoxtreeMeshShape: a static (or kinematic, or dynamic) triangle-mesh shape for Bullet whose
// midphase is a boxtree. Drop-in where a program uses btBvhTriangleMeshShape:
//
//   btCollisionShape* ground = new boxtree::bullet::BoxtreeMeshShape(meshInterface, "aabb");
//   boxtree::bullet::registerBoxtreeAlgorithms(dispatcher);  // once, before adding bodies
//
// What it answers, and how (see ../../README.md for the details and the measurements):
//  - processAllTriangles (Bullet's generic concave contract): the boxtree's volume query with the
//    query box; triangles are reported in the shape's local frame with local scaling applied,
//    with the mesh's own part id and triangle index so user callbacks and materials work.
//  - rayTest / convexSweepTest: recognised inside processAllTriangles (the callbacks are
//    btTriangleRaycastCallback / btTriangleConvexcastCallback) and answered by a front-to-back
//    ray walk of the tree that prunes with the current closest hit.
//  - convex bodies against the mesh, and mesh against mesh: collision algorithms registered by
//    registerBoxtreeAlgorithms (algorithms.h) that call the core collider (boxtree/collider.h).
//
// The shape holds a boxtree::CollisionMesh (boxtree/collision_mesh.h): the tree, its bounds and
// edge data, shared by every shape made from the same tree or collision mesh. A non-unit local
// scaling builds a scaled copy once (as btBvhTriangleMeshShape::setLocalScaling rebuilds its
// BVH), so scaled shapes, mirrored ones included, collide exactly like pre-scaled meshes.
//
// Facets are one-sided by default (counter-clockwise is the front; setTwoSided(true) for open
// meshes seen from both sides); a mesh whose winding is inconsistent collides two-sided, and
// says so once on stderr.
//
// The shape type is FAST_CONCAVE_MESH_PROXYTYPE: Bullet gives it the generic concave treatment
// and casts it to nothing (CUSTOM_CONCAVE_SHAPE_TYPE would be taken for an SDF shape in 3.24).
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include <btBulletCollisionCommon.h>

#include "boxtree/bullet/config.h"

class btTriangleConvexcastCallback;

#include "boxtree/any_tree.h"
#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"

namespace boxtree::bullet {

class alignas(16) BoxtreeMeshShape : public btConcaveShape {
 public:
  BT_DECLARE_ALIGNED_ALLOCATOR();

  // Copies the triangles of every part of `mesh` (its scaling becomes the shape's local
  // scaling) and builds the tree with `method` (boxtree::parse_method names: "aabb",
  // "obb-min", "pie-min+aabb@3", ...). Throws boxtree::Error on a bad method or a mesh with
  // NaN/Inf or out-of-range indices; the interface is not modified or kept.
  explicit BoxtreeMeshShape(const btStridingMeshInterface& mesh, const std::string& method = "aabb",
                            const BuildSettings& settings = {});
  // The same from a pointer, with btBvhTriangleMeshShape's constructor signatures, so that the swap
  // is one line: `new btBvhTriangleMeshShape(meshInterface, true)` -> `new BoxtreeMeshShape(meshInterface,
  // true)`. The arrays are copied as above (the interface may be freed afterwards) and the method is
  // "aabb"; the two flags are accepted and ignored (the boxtree is always built and compact), as are
  // the bounds of the third form (the tree's bounds are the mesh's). Throws boxtree::Error on a null
  // pointer. A method name may follow the pointer as well: BoxtreeMeshShape(meshInterface, "obb-min").
  BoxtreeMeshShape(btStridingMeshInterface* meshInterface, bool useQuantizedAabbCompression, bool buildBvh = true);
  BoxtreeMeshShape(btStridingMeshInterface* meshInterface, bool useQuantizedAabbCompression,
                   const btVector3& bvhAabbMin, const btVector3& bvhAabbMax, bool buildBvh = true);
  explicit BoxtreeMeshShape(btStridingMeshInterface* meshInterface, const std::string& method = "aabb",
                            const BuildSettings& settings = {});
  // (A string literal would otherwise convert to the bool of the first form.)
  BoxtreeMeshShape(btStridingMeshInterface* meshInterface, const char* method, const BuildSettings& settings = {});
  // From a boxtree mesh (one part, id 0; triangle index = facet id). The tree shares the mesh.
  explicit BoxtreeMeshShape(std::shared_ptr<const TriangleMesh> mesh, const std::string& method = "aabb",
                            const BuildSettings& settings = {});
  // From an already built tree (e.g. shared between shapes of several bodies): the shapes of one
  // built tree share one CollisionMesh.
  explicit BoxtreeMeshShape(AnyTree tree);
  // From a collision mesh built once and shared (throws boxtree::Error on null).
  explicit BoxtreeMeshShape(std::shared_ptr<const CollisionMesh> mesh);

  // ---- btConcaveShape / btCollisionShape ----
  void processAllTriangles(btTriangleCallback* callback, const btVector3& aabbMin,
                           const btVector3& aabbMax) const override;
  void getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const override;
  void setLocalScaling(const btVector3& scaling) override;
  const btVector3& getLocalScaling() const override { return m_localScaling; }
  // A static or kinematic mesh needs none; for a dynamic mesh: the inertia of the mesh's box
  // (like btGImpactMeshShape's default), which is what Bullet programs expect for meshes.
  void calculateLocalInertia(btScalar mass, btVector3& inertia) const override;
  const char* getName() const override { return "BoxtreeMesh"; }

  // ---- boxtree side ----
  // The tree and mesh as built (unscaled; facet ids are the mesh's triangle order).
  const AnyTree& tree() const { return m_base->tree(); }
  const TriangleMesh& mesh() const { return m_base->mesh(); }
  // What the collider reads: the collision mesh with the local scaling applied (the built one
  // itself for unit scaling).
  const CollisionMesh& collisionMesh() const { return *m_collision; }
  const std::shared_ptr<const CollisionMesh>& sharedCollisionMesh() const { return m_base; }
  // Bullet's (part id, triangle index) of a facet, and back.
  void facetToPart(FacetId facet, int& partId, int& triangleIndex) const;
  FacetId partToFacet(int partId, int triangleIndex) const;
  // A facet's corners in the shape's local frame, local scaling applied (as Bullet reports them).
  void scaledTriangle(FacetId facet, btVector3 out[3]) const;
  bool hasUnitScaling() const { return m_unitScaling; }
  // Per facet, which edges are convex creases (boxtree/active_edges.h; of the scaled mesh);
  // contacts on the others get the face normal, so bodies slide over flat and concave edges
  // without bumping.
  const std::vector<std::uint8_t>& activeEdges() const { return m_collision->active_edges(); }
  // One-sided facets (the default) or two-sided ones for the boxtree algorithms' contacts:
  // one-sided, a body whose centre has been pushed behind a facet (counter-clockwise winding is
  // the front) is pushed back out through the front, never further in: terrains and closed
  // meshes wound outward. Two-sided: open meshes seen from both sides (a two-sided terrain lets
  // a body pressed past a facet's plane under a deep pile fall through: boxtree/contact.h).
  void setTwoSided(bool twoSided) { m_twoSided = twoSided; }
  bool isTwoSided() const { return m_twoSided; }

  // Counters for benchmarks and tests; atomic (relaxed), so that a multithreaded dispatcher may
  // collide several pairs of one shape at once.
  struct Counters {
    std::uint64_t queries = 0;                // processAllTriangles box queries
    std::uint64_t triangles = 0;              // triangles handed to Bullet callbacks by processAllTriangles
    std::uint64_t ray_queries = 0;            // rays and sweeps answered by the ray path
    std::uint64_t narrowphase_triangles = 0;  // triangles the boxtree algorithms ran a contact routine on
    std::uint64_t merged_contacts = 0;        // contacts the algorithms merged into a deeper near-duplicate
    std::uint64_t dropped_contacts = 0;       // contacts the algorithms left out (beyond the manifold's 4)
    std::uint64_t mesh_volume_tests = 0;      // mesh vs mesh: volume pairs the tree walks tested
    std::uint64_t reused_calls = 0;           // convex calls answered with a ConvexPairCache's last contacts
  };
  Counters counters() const;
  void resetCounters() const;
  // For the algorithms: what one collider call did.
  void countCollision(const CollisionCounts& counts) const;

 private:
  void init();
  // A query box of the scaled local frame, clipped to the mesh.
  Aabb toTreeFrame(const btVector3& aabbMin, const btVector3& aabbMax) const;
  void sweepCandidates(btTriangleConvexcastCallback& cast, FunctionRef<void(FacetId)> report) const;

  std::shared_ptr<const CollisionMesh> m_base;       // as built
  std::shared_ptr<const CollisionMesh> m_collision;  // m_base scaled by m_localScaling
  std::vector<FacetId> m_partFirstFacet;             // part p owns facets [m_partFirstFacet[p], m_partFirstFacet[p+1])
  btVector3 m_localScaling{1, 1, 1};
  bool m_unitScaling = true;
  bool m_twoSided = false;
  btVector3 m_localAabbMin, m_localAabbMax;  // of the scaled mesh
  struct AtomicCounters {
    std::atomic<std::uint64_t> queries{0}, triangles{0}, ray_queries{0}, narrowphase_triangles{0}, merged_contacts{0},
        dropped_contacts{0}, mesh_volume_tests{0}, reused_calls{0};
  };
  mutable AtomicCounters m_counters;
};

}  // namespace boxtree::bullet
