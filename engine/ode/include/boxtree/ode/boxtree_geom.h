// SPDX-License-Identifier: MIT
#pragma once
// A custom ODE geom class backed by a boxtree: a drop-in replacement for dCreateTriMesh.
//
//   dInitODE2(0);
//   dBoxtreeInit();                                   // after every dInitODE2
//   dGeomID ground = dCreateBoxtreeMesh(space, mesh, "aabb");   // instead of dCreateTriMesh
//   ...
//   dBoxtreeClose();                                  // before (or after) dCloseODE
//
// The geom is placeable (static, or attached to a body with dGeomSetBody) and lives in any space.
// It collides with ODE's sphere, box, capsule, cylinder, ray, plane and convex, with ODE's own
// trimesh and with other boxtree geoms. Contacts follow ODE's conventions: g1/side1 are this
// geom and the facet index (the mesh's triangle order), g2/side2 the other geom and -1 (or the
// other mesh's triangle index); the normal points from g2 into g1; depth >= 0. ODE swaps all of
// that itself for dCollide(other, mesh).
//
// Ownership: the geom holds a boxtree::CollisionMesh (boxtree/collision_mesh.h: the tree, its
// bounds and edge data), shared by every geom made from the same tree; it lives as long as any
// geom or caller holds it. The collider (boxtree/collider.h) does the work; this adapter converts.
// Threading: like the rest of ODE, a given geom must not be collided from two threads at once.
#include <cstdint>
#include <memory>

#include <ode/ode.h>

#include "boxtree/any_tree.h"
#include "boxtree/collider.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/ode/config.h"

// ---- class registration ----

// Registers the boxtree geom class with ODE and returns its class number. Call it after
// dInitODE2 (ODE clears its collider table there: a class registered before gets no colliders).
// Calling it again before dBoxtreeClose returns the same number; dCreateBoxtreeMesh calls it
// itself if needed. ODE allows at most 4 user classes per session (dMaxUserClasses).
int dBoxtreeInit();
// Forgets the class number: call it around dCloseODE, so that the next dBoxtreeInit (after the
// next dInitODE2) registers the class again. Geoms of the old session must be destroyed first.
void dBoxtreeClose();
// The class number, or -1 when not registered.
int dBoxtreeGetClass();

// ---- creation: the one-line replacement for dCreateTriMesh ----

// `method` is a boxtree method name ("aabb", "obb-min", "pie-min+aabb@3", ...; see boxtree/method.h).
// Throws boxtree::Error for an invalid mesh or an unknown method (before any ODE object is made).
dGeomID dCreateBoxtreeMesh(dSpaceID space, std::shared_ptr<const boxtree::TriangleMesh> mesh,
                           const char* method = "aabb");
// From a tree built once and shared by many geoms (instances of the same mesh): the geoms of one
// built tree share one CollisionMesh (no per-facet memory per geom).
dGeomID dCreateBoxtreeMesh(dSpaceID space, const boxtree::AnyTree& tree);
// From a collision mesh built once (boxtree::CollisionMesh::build) and shared.
dGeomID dCreateBoxtreeMesh(dSpaceID space, std::shared_ptr<const boxtree::CollisionMesh> mesh);
// From the arrays dGeomTriMeshDataBuildDouble / dGeomTriMeshDataBuildSingle take (strides in
// bytes; index_count = 3 * triangles). Unlike ODE, the data is copied: the arrays may be freed.
dGeomID dCreateBoxtreeMesh(dSpaceID space, const double* vertices, int vertex_stride, int vertex_count,
                           const dTriIndex* indices, int index_count, int tri_stride, const char* method = "aabb");
dGeomID dCreateBoxtreeMesh(dSpaceID space, const float* vertices, int vertex_stride, int vertex_count,
                           const dTriIndex* indices, int index_count, int tri_stride, const char* method = "aabb");

namespace boxtree::ode {

// ---- per-geom settings and access ----

struct GeomSettings {
  // false (default, like ODE's trimesh and a terrain wants): facets are one-sided, a shape whose
  // centre is behind a facet is pushed out through its front (counter-clockwise) face. true: out
  // through whichever side the shape's centre is on (open meshes seen from both sides). A mesh
  // whose facets are not wound consistently collides two-sided whatever this says (ODE's message
  // handler is told once, when its first geom is made).
  bool two_sided = false;
  // Contacts are also made for shapes within this distance of a facet (reported with depth 0):
  // speculative contacts that keep fast resting bodies steadier. 0 = touching or penetrating only.
  Real margin = 0;
  // Contacts closer than this fraction of the other shape's size (with similar normals) are
  // merged into the deeper one before the set is cut down to the requested count.
  Real merge_fraction = 0.01;
  // Internal edges (boxtree/active_edges.h): a contact on a flat or concave edge between two
  // facets gets the facet's normal instead of a tilted edge normal, so that bodies rest and slide
  // over the seams of a mesh without bumps. Edges folding convexly by more than 10 degrees stay.
  bool internal_edges = true;
  // How two meshes' intersecting facet pairs become contacts (boxtree/collider.h). Face normals
  // by default, as in the Bullet adapter: chosen by measurement (bench/results/mesh_contacts.txt).
  MeshContactPolicy mesh_contacts = MeshContactPolicy::face_normals;
  // Mesh vs mesh with temporal coherence (boxtree/collider.h's MeshPairCache): the tree walk
  // starts from the front of the pair's last walk. The contacts are the same bit for bit. Off by
  // default: on a resting pile of meshes it cut the volume tests to 0.06x but took 1.2x the
  // collision time (boxtree/collide_front.h). See mesh_pair_cache_info for where the state lives.
  bool mesh_coherence = false;
  // Convex geoms with temporal coherence (boxtree/collider.h's ConvexPairCache): a pair whose
  // geoms are both static or disabled (auto-disable, dBodyDisable) keeps its last input and
  // contacts, and gets them again without collision work while neither geom moves (ODE collides
  // disabled bodies with static geoms every step, at the same pose). The contacts are the same
  // bit for bit. Pairs with an enabled body never look the state up. See convex_pair_cache_info.
  bool convex_coherence = true;
};

bool is_boxtree_geom(dGeomID geom);
// The geom's tree (nullptr if `geom` is not a boxtree geom). Valid while the geom lives.
const AnyTree* geom_tree(dGeomID geom);
// The geom's collision mesh (null if `geom` is not a boxtree geom).
std::shared_ptr<const CollisionMesh> geom_collision_mesh(dGeomID geom);
// Throws boxtree::Error if `geom` is not a boxtree geom.
void set_geom_settings(dGeomID geom, const GeomSettings& settings);
GeomSettings geom_settings(dGeomID geom);

// Work counters of one geom, summed over its collider calls (for benchmarks and tests).
// Atomic: ODE programs may collide different pairs of one geom from several threads.
struct CollisionCounters {
  std::uint64_t calls = 0;                   // collider calls that reached the tree
  std::uint64_t candidate_facets = 0;        // facets the tree query returned (narrowphase runs)
  std::uint64_t mesh_volume_tests = 0;       // mesh vs mesh: volume pairs the tree walks tested
  std::uint64_t contacts = 0;                // contacts written to ODE's arrays
  std::uint64_t merged = 0;                  // contacts merged into a deeper near-duplicate
  std::uint64_t dropped = 0;                 // contacts left out to fit ODE's array (or its count)
  std::uint64_t convexes_read_from_ode = 0;  // calls with a convex nobody registered (read through ODE)
  std::uint64_t convexes_without_data = 0;   // calls with a convex whose points ODE did not give: no contacts
  std::uint64_t reused = 0;                  // calls answered with a ConvexPairCache's last contacts
};
CollisionCounters geom_counters(dGeomID geom);
void reset_geom_counters(dGeomID geom);

// ---- mesh-vs-mesh coherence state ----
// ODE has no pair object and no call when two geoms stop overlapping, so the adapter keeps the
// per-pair state (a MeshPairCache: the front of the last tree walk, at most 384 KiB) in one
// registry keyed by the ordered geom pair: an entry is made on the pair's first mesh-vs-mesh
// call, evicted once unseen for 3 steps (a step is inferred: a pair collided again means a new
// step began), and dropped when either geom is a boxtree geom being destroyed (other geoms, such
// as ODE trimeshes, age out; a stale entry is never wrong, since the state checks its trees and
// tracks the pose). At most 1,024 pairs are kept; pairs beyond descend fresh. Thread-safe.
struct MeshPairCacheInfo {
  std::size_t pairs = 0;          // entries kept
  std::size_t bytes = 0;          // their memory (MeshPairCache::memory_bytes)
  std::size_t largest_front = 0;  // records of the largest front
  std::uint64_t steps = 0;        // steps inferred so far
  std::uint64_t evicted = 0;      // entries evicted unseen so far
};
MeshPairCacheInfo mesh_pair_cache_info();
// Drops every entry (dBoxtreeClose does too).
void clear_mesh_pair_caches();

// ---- convex coherence state ----
// GeomSettings::convex_coherence's per-pair state (a ConvexPairCache: the last call's input and
// contacts, a few hundred bytes, a registered hull's arrays too) lives in a registry like the
// mesh pairs' above: made on the first call of a pair whose geoms are both static or disabled,
// evicted once unseen for 3 steps (a body that wakes stops looking it up), dropped when either
// geom is a boxtree geom being destroyed or a convex given to forget_convex. A stale entry is
// never wrong: it is used only for an input equal to its own bit for bit. At most 16,384 pairs are
// kept; pairs beyond collide without it. Thread-safe.
struct ConvexPairCacheInfo {
  std::size_t pairs = 0;    // entries kept
  std::size_t bytes = 0;    // their memory (ConvexPairCache::memory_bytes)
  std::uint64_t steps = 0;  // steps inferred so far
  std::uint64_t evicted = 0;
};
ConvexPairCacheInfo convex_pair_cache_info();
// Drops every entry (dBoxtreeClose does too).
void clear_convex_pair_caches();

// ---- convex geoms ----
// ODE has no getter for a dConvex's data. Register it once per convex geom, in the convex's own
// frame, to give the collider its faces:
//  * set_convex: the arguments of dCreateConvex / dGeomSetConvex (planes a x + b y + c z = d with
//    outward normals, points 3 dReals each, polygons as per plane a corner count and the corner
//    indices). With the faces the collider uses the exact separating-axis narrowphase (a patch
//    of up to 8 points per triangle where a face rests on it). Throws boxtree::Error unless the
//    data is a closed convex polyhedron whose planes are its polygons' (make_convex_polyhedron,
//    boxtree/convex_polyhedron.h), faces of at most 64 corners.
//  * set_convex_points: the points only; the collider then runs GJK/EPA on their hull (one point
//    per triangle).
// A convex nobody registered still collides: its points are read through ODE's public API on
// first contact (by its convex-plane collider) and kept as a points-only registration; ODE's
// message handler is told once, and CollisionCounters::convexes_read_from_ode counts such calls.
// Each call checks the registration against ODE's AABB of the geom, so stale data (a destroyed
// geom's address reused, dGeomSetConvex since) is read again rather than used; still, call
// forget_convex before dGeomDestroy.
void set_convex(dGeomID convex, const dReal* planes, unsigned plane_count, const dReal* points, unsigned point_count,
                const unsigned* polygons);
void set_convex_points(dGeomID convex, const dReal* points, unsigned point_count);
void forget_convex(dGeomID convex);
// dCreateConvex + set_convex in one call (on an Error the new geom is destroyed before rethrowing).
dGeomID create_convex(dSpaceID space, const dReal* planes, unsigned plane_count, const dReal* points,
                      unsigned point_count, const unsigned* polygons);

// ---- ODE trimeshes as the other geom ----
// For contacts against ODE's dTriMesh, the adapter reads the trimesh's triangles once
// (dGeomTriMeshGetTriangle), builds a boxtree of them in the trimesh's frame with this geom's
// method, and caches it per (dTriMeshDataID, method), checking a few triangles on every call.
// Drop the cache entry after changing or destroying the data.
void forget_trimesh_data(dTriMeshDataID data);

}  // namespace boxtree::ode
