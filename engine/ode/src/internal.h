// SPDX-License-Identifier: MIT
#pragma once
// Shared between geom.cpp (the class, creation, AABB, registries) and colliders.cpp.
#include <atomic>
#include <memory>
#include <vector>

#include "boxtree/convex_polyhedron.h"
#include "boxtree/ode/boxtree_geom.h"

namespace boxtree::ode::detail {

// What the class data points to (the class data itself is ODE's zero-filled dAlloc block, so it
// holds only this pointer; the object is made with new and deleted by the class destructor).
struct GeomObject {
  AnyTree tree;
  Aabb local_bounds;                       // of the mesh, in the geom's frame (AnyTree::bounds() walks every facet)
  std::vector<std::uint8_t> active_edges;  // per facet, boxtree/active_edges.h
  GeomSettings settings;
  std::atomic<std::uint64_t> calls{0};
  std::atomic<std::uint64_t> candidate_facets{0};
  std::atomic<std::uint64_t> contacts{0};
};

GeomObject* object_of(dGeomID geom);  // nullptr if not a boxtree geom

// A geom's placement: x_world = rotation * x_geom + translation.
RigidTransform pose_of(dGeomID geom);

// What set_convex / set_convex_points registered for a convex geom, in the convex's own frame:
// its points, and its faces when they were given (then the collider runs the separating-axis
// narrowphase instead of GJK/EPA on the points).
struct ConvexEntry {
  std::vector<Vec3> points;
  std::unique_ptr<const ConvexPolyhedron> polyhedron;  // null: points only
};
// The entry of a convex geom, checked against ODE's AABB of the geom; null if there is none or it
// does not match (a destroyed geom's address reused).
std::shared_ptr<const ConvexEntry> convex_entry(dGeomID convex);

// An ODE trimesh's triangles as a boxtree in the trimesh's frame (facet ids = ODE's triangle
// indices), with what the colliders need beside it. Built once per data and method, cached.
struct TrimeshTree {
  AnyTree tree;
  Aabb bounds;
  std::vector<std::uint8_t> active_edges;
  int triangle_count = 0;
};
std::shared_ptr<const TrimeshTree> trimesh_tree(dGeomID trimesh, const Method& method);

// The collider table lookup (dGeomClass::collider): a pure function of the other class number.
dColliderFn* collider_for(int other_class);

// ODE keeps the mask of the contact count private (NUMC_MASK in collision_kernel.h).
constexpr int kContactCountMask = 0xffff;

}  // namespace boxtree::ode::detail
