// SPDX-License-Identifier: MIT
#pragma once
// Shared between geom.cpp (the class, creation, AABB, registries) and colliders.cpp.
#include <atomic>
#include <memory>
#include <vector>

#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/convex_polyhedron.h"
#include "boxtree/ode/boxtree_geom.h"

namespace boxtree::ode::detail {

// What the class data points to (the class data itself is ODE's zero-filled dAlloc block, so it
// holds only this pointer; the object is made with new and deleted by the class destructor).
struct GeomObject {
  std::shared_ptr<const CollisionMesh> mesh;  // shared by every geom made from the same tree
  GeomSettings settings;
  std::atomic<std::uint64_t> calls{0};
  std::atomic<std::uint64_t> candidate_facets{0};
  std::atomic<std::uint64_t> mesh_volume_tests{0};
  std::atomic<std::uint64_t> contacts{0};
  std::atomic<std::uint64_t> merged{0};
  std::atomic<std::uint64_t> dropped{0};
  std::atomic<std::uint64_t> convexes_read_from_ode{0};
  std::atomic<std::uint64_t> convexes_without_data{0};
  std::atomic<std::uint64_t> reused{0};
};

GeomObject* object_of(dGeomID geom);  // nullptr if not a boxtree geom

// A geom's placement: x_world = rotation * x_geom + translation.
RigidTransform pose_of(dGeomID geom);

// What set_convex / set_convex_points registered for a convex geom, in the convex's own frame:
// its points, and its faces when they were given (then the collider runs the separating-axis
// narrowphase instead of GJK/EPA on the points). A convex nobody registered is read through ODE
// once (its points, by colliding it with two planes: see geom.cpp) and registered points-only.
struct ConvexEntry {
  std::vector<Vec3> points;
  std::unique_ptr<const ConvexPolyhedron> polyhedron;  // null: points only
  bool read_from_ode = false;
};
// The entry of a convex geom, checked against ODE's AABB of the geom; read through ODE (and
// registered) if there is none or it does not match (a destroyed geom's address reused, or
// dGeomSetConvex since); null only if ODE gives no points.
std::shared_ptr<const ConvexEntry> convex_entry(dGeomID convex);

// An ODE trimesh's triangles as a collision mesh in the trimesh's frame (facet ids = ODE's
// triangle indices), built once per data and method, cached.
std::shared_ptr<const CollisionMesh> trimesh_mesh(dGeomID trimesh, const Method& method);

// The collider table lookup (dGeomClass::collider): a pure function of the other class number.
dColliderFn* collider_for(int other_class);

// Temporal coherence (pair_cache.cpp): the state of the ordered pair (my geom, the other), made
// on first use; null when its registry is full (the call then collides without state).
constexpr std::uint64_t kUnseenSteps = 3;  // entries unseen for more steps are evicted
constexpr std::size_t kMaxMeshPairs = 1024;
constexpr std::size_t kMaxConvexPairs = 16384;
std::shared_ptr<MeshPairCache> mesh_pair_cache(dGeomID mine, dGeomID other);
std::shared_ptr<ConvexPairCache> convex_pair_cache(dGeomID mine, dGeomID other);
// Drops every entry of `geom`, of both kinds (its destructor calls it).
void forget_pair_caches(dGeomID geom);

// ODE keeps the mask of the contact count private (NUMC_MASK in collision_kernel.h).
constexpr int kContactCountMask = 0xffff;

}  // namespace boxtree::ode::detail
