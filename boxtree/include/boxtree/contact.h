// SPDX-License-Identifier: MIT
#pragma once
// Per-facet narrowphase: contact points between one triangle and a convex shape, and between two
// triangles. The boxtree queries (query.h, collide.h) find the candidate facets; these routines
// turn a candidate into contacts. They are engine-agnostic: the Bullet and ODE adapters
// (engine/) only convert conventions.
//
// Conventions, for every routine here:
//  - `normal` is unit length and points from the triangle towards the shape (for two triangles:
//    from triangle b towards triangle a): translating the shape by depth * normal separates them.
//  - `depth` > 0 is penetration; depth <= 0 means the two are apart by -depth (reported only when
//    -depth <= options.margin, so engines can keep speculative contacts).
//  - `position` is on the triangle (for two triangles: on triangle b), in the same frame as the
//    inputs; the matching deepest point of the shape is point_on_shape().
//  - Triangles may be degenerate (zero area): the routines then treat them as a segment or a
//    point, and never divide by zero or return NaN.
#include <cstddef>
#include <vector>

#include "boxtree/convex_polyhedron.h"
#include "boxtree/detail/function_ref.h"
#include "boxtree/shapes.h"

namespace boxtree {

struct ContactPoint {
  Vec3 position = Vec3::Zero();  // on the triangle (triangle b for triangle pairs)
  Vec3 normal = Vec3::UnitZ();   // unit, from the triangle towards the shape
  Real depth = 0;                // > 0: penetration; <= 0: separation within the margin
  FacetId facet = 0;             // not set by the routines; callers record which facet it was
  FacetId other_facet = 0;       // mesh-vs-mesh: the facet of the other mesh (triangle a)

  // The deepest point of the shape: position - normal * depth.
  Vec3 point_on_shape() const { return position - normal * depth; }
};

struct ContactOptions {
  // Report pairs closer than this (depth >= -margin) as well as penetrating ones.
  Real margin = 0;
  // false: the triangle is one-sided (a terrain, a closed surface seen from outside): a shape
  // whose centre is behind the triangle's plane (counter-clockwise winding is the front) is
  // pushed out through the front face, never further in. true: whichever side the shape's
  // centre is on.
  // Details of one-sided (implementation notes): the front normal is (b-a)x(c-a) normalized. A
  // shape whose centre is behind, or whose two-sided normal would point behind, gets the front
  // normal and the *directional* depth along it (the least lift along the front normal that
  // clears the triangle), and only if it really overlaps: such a shape that is apart is not
  // reported even within the margin. Every one-sided normal has normal . front >= -1e-9.
  // Degenerate triangles have no front and are treated as two-sided.
  bool two_sided = true;
};

// Upper bounds on what one call writes (size the output arrays with these).
constexpr int kMaxSphereTriangleContacts = 1;
constexpr int kMaxCapsuleTriangleContacts = 2;
constexpr int kMaxBoxTriangleContacts = 8;
constexpr int kMaxConvexTriangleContacts = 1;
constexpr int kMaxPolyhedronTriangleContacts = 8;
constexpr int kMaxCylinderTriangleContacts = 4;
constexpr int kMaxTriangleTriangleContacts = 4;

// Each returns how many contacts it wrote into `out` (0: apart by more than the margin). All the
// contacts of one call share one normal, and the deepest comes first. Non-finite input gives 0.
int contact_sphere_triangle(const Sphere& sphere, const Vec3& a, const Vec3& b, const Vec3& c,
                            const ContactOptions& options, ContactPoint* out);
// Up to two: a capsule lying flat on a face touches along a segment, and both ends are reported.
// (When the normal is the face's, the two ends of the core's part over the triangle are reported,
// each at its own depth along the normal, positions projected on the face; ends deeper than
// -margin only. Otherwise one contact.)
int contact_capsule_triangle(const Capsule& capsule, const Vec3& a, const Vec3& b, const Vec3& c,
                             const ContactOptions& options, ContactPoint* out);
// Separating axes (3 box faces, the triangle's normal, 9 edge crosses); the axis of least
// penetration gives the normal, and the contact points come from clipping the box's face
// against the triangle (face cases) or from the closest points of the two edges (edge cases).
// Face cases report a patch (each point at its own depth along the normal; the deepest one is the
// penetration along that normal); edge-edge cases one point. Apart (within the margin): the exact
// gap; a patch when the gap is along a face normal, else the closest pair.
int contact_box_triangle(const Obb& box, const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options,
                         ContactPoint* out);

// A convex polyhedron with known faces (convex_polyhedron.h), in the triangle's frame: the same
// separating axes as the box (its faces, the triangle's normal, edge x triangle edge: by parallel
// class, or edge by edge through the edges' normal cones when there are many classes), so the
// depth is the exact least penetration and a face case gives a patch, as contact_box_triangle
// does (a face is kept only if its patch holds the depth; else the edge pair or the triangle's
// face). For hulls this replaces GJK/EPA (contact_convex_triangle with support_points): exact
// instead of ~1e-6 of the sizes, several points where a face rests on the triangle, no
// iteration. Its cost grows with the corners, faster than GJK/EPA's: for hulls of many corners
// the support mapping can be the cheaper route (bench/RESULTS.md, narrowphase notes).
int contact_polyhedron_triangle(const ConvexPolyhedron& polyhedron, const Vec3& a, const Vec3& b, const Vec3& c,
                                const ContactOptions& options, ContactPoint* out);
// The same for the polyhedron placed by `mesh_from_local` (an orthogonal rotation, a reflection
// too, and a translation) against a triangle in the mesh's frame: the triangle is taken into the
// polyhedron's frame and the contacts are brought back, so the polyhedron is never moved (three
// corners per triangle instead of every vertex, face plane and edge of the polyhedron per call).
// The contacts are those of the polyhedron moved by transform_polyhedron, up to rounding (where
// two axes tie, rounding may pick the other one, as it may in any frame).
int contact_polyhedron_triangle(const ConvexPolyhedron& local, const RigidTransform& mesh_from_local, const Vec3& a,
                                const Vec3& b, const Vec3& c, const ContactOptions& options, ContactPoint* out);

// A convex shape given by its support mapping: the point of the shape farthest along `direction`
// (direction is not normalized). `center` is any interior point (used to start the search and to
// pick the side for two-sided triangles).
struct ConvexSupport {
  FunctionRef<Vec3(const Vec3& direction)> support;
  Vec3 center = Vec3::Zero();
  // The shape is a polytope (e.g. support_points): EPA's answer is then exact to its tolerance
  // (~1e-6 of the sizes) and the local polish of the normal, meant for curved shapes, is skipped.
  bool polytope = false;
};
// General convex shapes (cylinders, convex hulls) by GJK + EPA/MPR (libccd). One contact: the
// deepest point, with the penetration normal.
// (GJK + EPA against the triangle rounded by the margin, then a local polish of the normal on the
// exact projection overlap: moving the shape by depth along the normal always separates it; the
// depth is the least penetration to ~1e-4 of the sizes on curved shapes, and EPA may rarely end
// in another local minimum on deep configurations.)
int contact_convex_triangle(const ConvexSupport& shape, const Vec3& a, const Vec3& b, const Vec3& c,
                            const ContactOptions& options, ContactPoint* out);

// A cylinder (axis p0-p1, radius): the answer contact_convex_triangle approximates with
// support_cylinder, the least overlap of the projections over unit normals, taken as the least
// over the critical normals of every kind of face of the two shapes' Minkowski difference: the
// triangle's normal, the axis, axis x edge, the radial directions from the corners to the axis
// (closed form), and the normals across each edge where a rim meets it (a smooth 1D function,
// minimized by branch and bound plus Newton's method, to ~1e-9 rad: the depth to ~1e-15 of the
// sizes); apart, the directions from the corners to their nearest rim points too. Penetrating,
// that is the least overlap (the least is at a smooth point of the difference's boundary); the
// overlap along the returned normal equals the depth. One-sided triangles: over the normals in
// front only, the circle bounding them included when the least overall is behind. No GJK/EPA
// runs except behind a one-sided triangle (the push-out) or for degenerate input. When the normal
// is the triangle's, a patch: the ends of the side's lowest line and points of the lower disk's
// rim over the triangle (a cylinder lying or standing on a facet), each at its own depth.
int contact_cylinder_triangle(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& a, const Vec3& b, const Vec3& c,
                              const ContactOptions& options, ContactPoint* out);

// Support mappings of the shapes engines hand us, for contact_convex_triangle.
Vec3 support_cylinder(const Vec3& p0, const Vec3& p1, Real radius, const Vec3& direction);  // axis p0-p1
Vec3 support_points(const std::vector<Vec3>& points, const Vec3& direction);                // convex hull of points

// Two triangles (mesh vs mesh): contacts when they intersect or are within the margin. The normal
// points from triangle b towards triangle a; positions are on triangle b.
int contact_triangle_triangle(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                              const Vec3& b2, const ContactOptions& options, ContactPoint* out);

// Mesh vs mesh by face normals only (the clipping method of GImpact and other trimesh
// colliders): a's triangle clipped to the prism over b's face gives points on b's front with
// normal +n_b, and b's triangle clipped to the prism over a's face gives points with normal
// -n_a; the side of a face more than twice the other's area is reported, else the side with the
// shallower deepest point (the other side if one has no points). Normals are the faces'
// counter-clockwise normals, so both meshes must be wound outward (closed meshes, terrains seen
// from above). Unlike contact_triangle_triangle's edge-edge axes, face normals do not swing
// between steps, which keeps resting meshes still. Up to kMaxTriangleFaceContacts points with
// depth >= -margin; positions on triangle b; normals from b towards a.
// `fixed`: which triangle, if either, belongs to a fixed surface (a static terrain). Where the
// faces point the same way (n_a . n_b > 0) the triangles cross in an overlap deeper than the
// surfaces' local shape can tell: the faces of a body sunk past the middle of its tube point up
// from under the ground, and their normals would pull it further down. There the fixed
// surface's face gives the normal (when it has points), so that bodies come back out of it.
enum class FixedSurface { neither, a, b };
constexpr int kMaxTriangleFaceContacts = 6;
int contact_triangle_faces(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                           const Vec3& b2, const ContactOptions& options, ContactPoint* out,
                           FixedSurface fixed = FixedSurface::neither);

// Reduces a contact set the way a stable trimesh collider does: merges near-duplicates (positions
// closer than `merge_distance` with normals within ~10 degrees: keeps the deeper one), then, if
// more than `max_count` remain, keeps the deepest and then greedily the points that spread the
// set the most (largest area). Order of the result: deepest first. max_count >= 1 (0 is read as
// 1). Returns how many contacts went: merged into a deeper near-duplicate, or dropped by the
// selection (merged + dropped + the size after == the size before).
struct ReductionCounts {
  std::size_t merged = 0;
  std::size_t dropped = 0;
};
ReductionCounts reduce_contacts(std::vector<ContactPoint>& contacts, std::size_t max_count, Real merge_distance);

}  // namespace boxtree
