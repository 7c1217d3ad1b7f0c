// SPDX-License-Identifier: MIT
#pragma once
// The mesh collider: contacts between a CollisionMesh (collision_mesh.h) and a convex shape, or
// between two meshes, through one pipeline that both engine adapters call:
//   1. the tree query with the shape's tight volume grown by the margin (candidate facets);
//   2. the per-facet narrowphase of contact.h (or the engine's own, for shapes it alone knows);
//   3. one-sided facets: a contact pushing the shape out through a facet's back is turned to the
//      front (the analytic routines do it themselves; for an engine narrowphase it is done here);
//   4. internal edges (active_edges.h): contacts on flat or concave seams get the face normal;
//   5. the contact set cut to the requested count (reduce_contacts), or, with early_stop, the
//      first ones found.
// Everything is in the mesh's frame: shapes are given in it and contacts come back in it, in
// contact.h's conventions (position on the mesh's facet, normal from the facet towards the shape
// or the other mesh, depth > 0 for penetration, `facet` = the mesh's facet). Engines convert.
//
// The functions do not throw and do not allocate once the result's vector has grown: the
// physics step calls them. Invalid shapes (shapes.h's is_valid) or non-finite poses give no
// contacts.
#include <cstddef>
#include <vector>

#include "boxtree/collide_front.h"
#include "boxtree/collision_mesh.h"
#include "boxtree/contact.h"
#include "boxtree/convex_polyhedron.h"

namespace boxtree {

// What one call asks for.
struct ContactRequest {
  // Contacts also for shapes within this distance of a facet (depth >= -margin): speculative
  // contacts, as engines keep them up to their breaking distance.
  Real margin = 0;
  // One-sided by default (ContactOptions::two_sided, contact.h): a shape is pushed out through a
  // facet's front (counter-clockwise) side, never further in. A mesh whose winding is not
  // consistent (CollisionMesh::consistent_winding) is treated as two-sided whatever is asked, and
  // the result says so.
  bool two_sided = false;
  // Correct contacts on inactive edges to the face normal (active_edges.h).
  bool internal_edges = true;
  // At most this many contacts come back (>= 1), the deepest and the widest spread.
  std::size_t max_contacts = 4;
  // Contacts this close (with normals within ~10 degrees) are merged into the deeper one.
  Real merge_distance = 0;
  // Any max_contacts contacts will do (ODE's CONTACTS_UNIMPORTANT): the walk stops as soon as
  // that many are found, and they are not reduced.
  bool early_stop = false;
};

// What one call did.
struct CollisionCounts {
  std::size_t candidates = 0;       // facets (or facet pairs) the narrowphase ran on
  std::size_t found = 0;            // contacts the narrowphase gave
  std::size_t edge_corrected = 0;   // turned to the face normal on an inactive edge
  std::size_t edge_discarded = 0;   // dropped on an inactive edge (the neighbour facet reports it)
  std::size_t merged = 0;           // merged into a deeper near-duplicate by the reduction
  std::size_t dropped = 0;          // left out by the reduction (or by early_stop)
  std::size_t volume_tests = 0;     // mesh vs mesh: volume pairs the tree walk tested
  bool two_sided_fallback = false;  // one-sided asked, but the mesh's winding is inconsistent
  bool invalid_input = false;       // a non-finite pose or an invalid shape: nothing was done
  bool reused = false;              // the contacts of a ConvexPairCache's last call, no collision work done
};

struct ContactResult {
  std::vector<ContactPoint> contacts;  // deepest first
  CollisionCounts counts;
  void clear() {
    contacts.clear();
    counts = {};
  }
};

// ---- convex shapes (all in the mesh's frame) ----

namespace detail {
struct ConvexPairCacheAccess;
}

// The state one pair of a mesh and a convex body keeps between calls of collide_convex (temporal
// coherence: one per pair of bodies, freed with the pair): the last input and its contacts. A call
// whose input equals the last one bit for bit (the shape as placed in the mesh's frame, the
// request, the mesh's tree; a hull's arrays too), as for a body that has not moved relative to the
// mesh (an engine's disabled or kinematic body at rest), gets those contacts again without any
// collision work; its counts are zero but for `reused` and `two_sided_fallback`. Any other call
// collides. The contacts are therefore those of a call without the cache, bit for bit, whatever
// the sequence of calls. The input is kept only once a call's shape lies where the last one did,
// and a hull's arrays only once its placement repeats, so that a moving body pays neither: a
// shape at rest is answered from its third call on, a hull from its fourth. Memory: the input's
// bytes (a hull's arrays: about 0.6 KiB per corner) and at most max_contacts contacts
// (memory_bytes()). The mesh's tree is held, so that a tree cannot die and another take its
// address. Not shared between threads.
class ConvexPairCache {
 public:
  void clear();
  std::size_t memory_bytes() const;

 private:
  friend struct detail::ConvexPairCacheAccess;
  AnyTree tree_;                          // the last call's; everything below belongs to it
  Aabb shape_box_ = Aabb::empty();        // the last call's shape, grown by the margin
  std::vector<unsigned char> placement_;  // the shape's placement and numbers, the request
  std::vector<unsigned char> hull_;       // a hull's arrays, once copied
  bool placed_ = false;                   // placement_ is a call's, contacts_ its contacts
  bool hull_copied_ = false;              // hull_ is that call's hull
  std::vector<ContactPoint> contacts_;
  bool two_sided_fallback_ = false;
};

// A cylinder with axis p0-p1 and the given radius (contact_cylinder_triangle).
struct Cylinder {
  Vec3 p0 = Vec3::Zero();
  Vec3 p1 = Vec3::UnitZ();
  Real radius = 0;
};

// A convex polyhedron with faces (the exact separating-axis narrowphase, contact_polyhedron_triangle)
// placed by `mesh_from_local`, grown by `rounding` (a sphere-swept hull, as Bullet's hulls with
// their collision margin; the depth is the polyhedron's plus the rounding).
struct PlacedPolyhedron {
  const ConvexPolyhedron& local;
  RigidTransform mesh_from_local;
  Real rounding = 0;
};

// The convex hull of points placed by `mesh_from_local` (GJK/EPA, contact_convex_triangle).
struct PlacedPoints {
  const std::vector<Vec3>& local;
  RigidTransform mesh_from_local;
};

// Any convex shape by its support mapping (mesh frame), with an interior point and an oriented
// box that contains it (the query volume).
struct SupportShape {
  FunctionRef<Vec3(const Vec3& direction)> support;
  Vec3 center = Vec3::Zero();
  Obb bounds;
  bool polytope = false;  // ConvexSupport::polytope
};

// An engine's own narrowphase for one triangle of the mesh (e.g. Bullet's GJK for its convex
// shapes): writes at most kMaxEngineTriangleContacts contacts in contact.h's conventions and
// returns how many. `options.two_sided` is always true here: step 3 applies the mesh's fronts.
using TriangleNarrowphase =
    FunctionRef<int(const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options, ContactPoint* out)>;
constexpr int kMaxEngineTriangleContacts = 16;

// With `cache` (ConvexPairCache, temporal coherence) a call with the last call's input gets its
// contacts again; `result` is cleared first then. Without, contacts and counts are added to it.
void collide_convex(const CollisionMesh& mesh, const Sphere& sphere, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache = nullptr);
void collide_convex(const CollisionMesh& mesh, const Obb& box, const ContactRequest& request, ContactResult& result,
                    ConvexPairCache* cache = nullptr);
void collide_convex(const CollisionMesh& mesh, const Capsule& capsule, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache = nullptr);
void collide_convex(const CollisionMesh& mesh, const Cylinder& cylinder, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache = nullptr);
void collide_convex(const CollisionMesh& mesh, const PlacedPolyhedron& hull, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache = nullptr);
void collide_convex(const CollisionMesh& mesh, const PlacedPoints& hull, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache = nullptr);
// The support shape through GJK/EPA (contact_convex_triangle), or through `narrowphase` when
// given. Facets whose plane the shape lies wholly above or below by more than the margin are
// skipped before the narrowphase (two support calls each). No ConvexPairCache: a support
// function's shape cannot be compared between calls.
void collide_convex(const CollisionMesh& mesh, const SupportShape& shape, const ContactRequest& request,
                    ContactResult& result);
void collide_convex(const CollisionMesh& mesh, const SupportShape& shape, TriangleNarrowphase narrowphase,
                    const ContactRequest& request, ContactResult& result);

// The half-space below `plane` ({x : normal . x <= offset}, ODE's and Bullet's static planes):
// a contact at every mesh vertex within the margin of it or below it (as ODE's trimesh-plane
// collider), normal -normal/|normal| (from the mesh into the half-space), depth the vertex's
// distance below the plane; then reduced. The tree prunes to the facets that reach below.
void collide_half_space(const CollisionMesh& mesh, const Plane& plane, const ContactRequest& request,
                        ContactResult& result);

// ---- rays and sweeps, as engines ask for them ----

// Which hits of a ray an engine wants (ODE's dGeomRaySetParams / dGeomRaySetClosestHit).
struct RayHitsRequest {
  bool closest_only = false;     // just the nearest hit (ties: the smaller facet id)
  bool first_only = false;       // any one hit, the walk stops at it
  bool cull_back_faces = false;  // only facets the ray enters through their front
};
struct FacetHit {
  Real t = 0;  // in units of |ray.direction|
  FacetId facet = 0;
};
// The ray's hits with the mesh's facets (intersect_ray_triangle, geometry.h) in `hits`, nearest
// first (ties: the smaller facet id). Returns how many facets were tested.
std::size_t ray_hits(const CollisionMesh& mesh, const Ray& ray, const RayHitsRequest& request,
                     std::vector<FacetHit>& hits);

// The facets an axis-aligned box of half extents `half` (mesh frame) can touch while its centre
// moves from `from` to `to` (the box swept along the motion, as an oriented box), nearest first:
// `visit` gets each one until the box's leading face could not reach the next before
// `hit_fraction()` (the engine's closest hit so far, as a fraction of the motion; re-read after
// every visit). Returns how many facets were visited.
std::size_t sweep_candidates(const CollisionMesh& mesh, const Vec3& from, const Vec3& to, const Vec3& half,
                             FunctionRef<Real()> hit_fraction, FunctionRef<void(FacetId)> visit);

// ---- mesh vs mesh ----

// How a pair of intersecting facets becomes contacts.
enum class MeshContactPolicy {
  // contact_triangle_triangle: the least penetration of the two triangles (face or edge-edge
  // axes), two-sided, internal edges corrected on both meshes.
  triangle_pairs,
  // contact_triangle_faces: face normals only (clipping, as GImpact); needs outward winding; the
  // static mesh's faces resolve deep overlaps (MeshContactRequest::static_mesh).
  face_normals,
};

// Which of the two meshes, if either, is a fixed surface (a static terrain).
enum class StaticMesh { neither, mesh, other };

struct MeshContactRequest : ContactRequest {
  MeshContactPolicy policy = MeshContactPolicy::triangle_pairs;
  StaticMesh static_mesh = StaticMesh::neither;
  // Temporal coherence: with a MeshPairCache given, the tree walk starts from the cache's front
  // (collide_front.h; what it costs and saves is measured there). Off: the cache is cleared and
  // every call descends fresh. The contacts are the same either way, bit for bit.
  bool coherence = true;
};

// The state one pair of meshes keeps between calls of collide_meshes (one per pair of bodies,
// freed with the pair): the front of the last tree-vs-tree walk (collide_front.h) and the two
// trees it belongs to (held, so that a tree cannot die and another take its address while the
// front refers to it). At most CollideFront's cap in memory (384 KiB by default, measured by
// memory_bytes()) plus the last call's facet pairs. A call with other meshes, other trees (a
// mesh of another method converted: CollisionMesh::tree_as) or mesh and other swapped starts
// afresh; a call with early_stop, with coherence off, or with trees other than the packed `aabb`
// form on both sides (the front exists for that layout only, the engine adapters' default)
// descends fresh and clears the front. Not shared between threads.
class MeshPairCache {
 public:
  void clear();
  const CollideFront& front() const { return front_; }
  std::size_t memory_bytes() const { return front_.memory_bytes() + pairs_.capacity() * sizeof(FacetPair); }

 private:
  friend void collide_meshes(const CollisionMesh&, const CollisionMesh&, const RigidTransform&,
                             const MeshContactRequest&, ContactResult&, MeshPairCache*);
  AnyTree mine_, theirs_;
  CollideFront front_;
  std::vector<FacetPair> pairs_;  // scratch: the call's facet pairs, sorted
};

// Contacts between `mesh` and `other` placed by `mesh_from_other` (a rotation and translation;
// a rotation that is not orthonormal to 1e-9 is made so). Positions are on `mesh`'s facets,
// normals point from `mesh` towards `other`, `facet` is mesh's and `other_facet` other's. Meshes
// of different methods are walked with a tree of one method built once and kept by the mesh
// (CollisionMesh::tree_as): never an error. Facet pairs are always two-sided for triangle_pairs.
// The intersecting facet pairs go to the contact routines in sorted order (without early_stop),
// so that the contacts do not depend on the order the walk finds them in; with `cache`
// (MeshPairCache, temporal coherence) the walk starts from the last call's front.
void collide_meshes(const CollisionMesh& mesh, const CollisionMesh& other, const RigidTransform& mesh_from_other,
                    const MeshContactRequest& request, ContactResult& result, MeshPairCache* cache = nullptr);

}  // namespace boxtree
