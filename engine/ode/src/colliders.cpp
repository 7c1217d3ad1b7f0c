// SPDX-License-Identifier: MIT
// The colliders of the boxtree geom: conversions between ODE and the core collider
// (boxtree/collider.h), which does the work. ODE always calls them with the boxtree geom as o1 (it
// swaps the arguments, negates the normals and swaps g1/g2 and side1/side2 itself for the reverse
// order), so each one is written as "my mesh = g1": the other geom is put into the mesh's frame,
// the collider runs there, and its contacts are written in ODE's convention. contact.h's normal
// points from the mesh towards the other geom, ODE's from g2 into g1: it is negated; pos stays on
// the mesh's surface (as dCollideSTL does); depth >= 0 (contacts within the margin touch).
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "boxtree/collider.h"
#include "boxtree/geometry.h"
#include "internal.h"

namespace boxtree::ode::detail {
namespace {

// The contact array as ODE hands it over: at most flags & 0xffff entries, `skip` bytes apart.
struct ContactArray {
  dGeomID g1;
  dGeomID g2;
  int flags;
  dContactGeom* first;
  int skip;

  int capacity() const { return flags & kContactCountMask; }
  // Any contacts will do: no merging or deepest selection, stop as soon as the array is full.
  bool unimportant() const { return (flags & int(CONTACTS_UNIMPORTANT)) != 0; }
  dContactGeom* at(int i) const {
    return reinterpret_cast<dContactGeom*>(reinterpret_cast<char*>(first) + std::size_t(i) * std::size_t(skip));
  }
};

// Per-thread result storage, so that a collider call does not allocate once warmed up.
ContactResult& scratch_result() {
  thread_local ContactResult result;
  result.clear();
  return result;
}

// The request of a geom's settings for ODE's array; `shape_size` scales the merge distance.
ContactRequest request_for(const GeomObject& object, const ContactArray& out, Real shape_size) {
  ContactRequest request;
  request.margin = object.settings.margin;
  request.two_sided = object.settings.two_sided;
  request.internal_edges = object.settings.internal_edges;
  request.max_contacts = std::size_t(std::max(out.capacity(), 1));
  request.merge_distance = object.settings.merge_fraction * std::max(shape_size, Real(1e-9));
  request.early_stop = out.unimportant();
  return request;
}

// `value` added to a geom's counter. Each atomic add is a locked instruction, ~20 cycles: seven
// of them were 7% of a sphere's call on flat terrain (pair_replay), so zeros are not added.
void add(std::atomic<std::uint64_t>& counter, std::uint64_t value) {
  if (value != 0) counter.fetch_add(value, std::memory_order_relaxed);
}

// The result into ODE's array, in world coordinates and ODE's convention.
int write_contacts(GeomObject& object, const ContactArray& out, const RigidTransform& world_from_mesh,
                   const ContactResult& result, bool has_other_facet) {
  const int count = int(std::min(result.contacts.size(), std::size_t(out.capacity())));
  for (int i = 0; i < count; ++i) {
    const ContactPoint& c = result.contacts[std::size_t(i)];
    const Vec3 pos = world_from_mesh.apply(c.position);
    const Vec3 normal = -(world_from_mesh.rotation * c.normal);
    dContactGeom* g = out.at(i);
    for (int k = 0; k < 3; ++k) {
      g->pos[k] = pos[k];
      g->normal[k] = normal[k];
    }
    g->pos[3] = 0;
    g->normal[3] = 0;
    g->depth = std::max(c.depth, Real(0));
    g->g1 = out.g1;
    g->g2 = out.g2;
    g->side1 = int(c.facet);
    g->side2 = has_other_facet ? int(c.other_facet) : -1;
  }
  add(object.calls, 1);
  add(object.candidate_facets, result.counts.candidates);
  add(object.merged, result.counts.merged);
  add(object.dropped, result.counts.dropped);
  add(object.mesh_volume_tests, result.counts.volume_tests);
  add(object.reused, result.counts.reused ? 1 : 0);
  add(object.contacts, std::uint64_t(count));
  return count;
}

// The other geom's placement in my mesh's frame.
RigidTransform mesh_from(dGeomID mesh, dGeomID other) {
  const RigidTransform world_from_mesh = pose_of(mesh);
  const RigidTransform world_from_other = pose_of(other);
  return {world_from_mesh.rotation.transpose() * world_from_other.rotation,
          world_from_mesh.rotation.transpose() * (world_from_other.translation - world_from_mesh.translation)};
}

// A geom that does not move by itself: static (no body) or with a disabled body. Only such pairs
// can repeat their input (ODE collides a disabled body with a static geom every step).
bool at_rest(dGeomID geom) {
  const dBodyID body = dGeomGetBody(geom);
  return body == nullptr || !dBodyIsEnabled(body);
}

// Runs `collide(mesh, request, result, cache)` for a convex geom of size `shape_size` and writes,
// the mesh at `world_from_mesh` (its pose, pose_of(o1)). `cache` is the pair's ConvexPairCache
// when convex_coherence is on and both geoms are at rest, else null.
template <class Collide>
int collide_with(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip, Real shape_size,
                 const RigidTransform& world_from_mesh, Collide&& collide) {
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  ContactResult& result = scratch_result();
  const std::shared_ptr<ConvexPairCache> cache =
      object.settings.convex_coherence && at_rest(o1) && at_rest(o2) ? convex_pair_cache(o1, o2) : nullptr;
  collide(*object.mesh, request_for(object, out, shape_size), result, cache.get());
  return write_contacts(object, out, world_from_mesh, result, false);
}

template <class Collide>
int collide_with(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip, Real shape_size,
                 Collide&& collide) {
  return collide_with(o1, o2, flags, contact, skip, shape_size, pose_of(o1), std::forward<Collide>(collide));
}

int collide_sphere(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  // Only the sphere's centre is needed in the mesh's frame (mesh_from's translation, the same
  // expression), with the mesh's pose read once.
  const RigidTransform world_from_mesh = pose_of(o1);
  const dReal* p = dGeomGetPosition(o2);
  const Sphere sphere{world_from_mesh.rotation.transpose() * (Vec3(p[0], p[1], p[2]) - world_from_mesh.translation),
                      dGeomSphereGetRadius(o2)};
  return collide_with(o1, o2, flags, contact, skip, sphere.radius, world_from_mesh,
                      [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
                        collide_convex(m, sphere, r, res, cache);
                      });
}

int collide_box(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const RigidTransform place = mesh_from(o1, o2);
  dVector3 lengths;
  dGeomBoxGetLengths(o2, lengths);  // full side lengths
  const Obb box{place.translation, place.rotation, Vec3(lengths[0], lengths[1], lengths[2]) * Real(0.5)};
  return collide_with(o1, o2, flags, contact, skip, box.half_extents.norm(),
                      [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
                        collide_convex(m, box, r, res, cache);
                      });
}

// ODE's capsules and cylinders lie along their local Z, `length` long, centred.
void axis_ends(const RigidTransform& place, Real length, Vec3& p0, Vec3& p1) {
  const Vec3 half_axis = place.rotation.col(2) * (length * Real(0.5));
  p0 = place.translation - half_axis;
  p1 = place.translation + half_axis;
}

int collide_capsule(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  dReal radius = 0, length = 0;
  dGeomCapsuleGetParams(o2, &radius, &length);  // length: the cylinder part only
  Capsule capsule;
  axis_ends(mesh_from(o1, o2), length, capsule.p0, capsule.p1);
  capsule.radius = radius;
  return collide_with(o1, o2, flags, contact, skip, radius + length / 2,
                      [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
                        collide_convex(m, capsule, r, res, cache);
                      });
}

int collide_cylinder(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  dReal radius = 0, length = 0;
  dGeomCylinderGetParams(o2, &radius, &length);
  Cylinder cylinder;
  axis_ends(mesh_from(o1, o2), length, cylinder.p0, cylinder.p1);
  cylinder.radius = radius;
  return collide_with(o1, o2, flags, contact, skip, std::hypot(radius, length / 2),
                      [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
                        collide_convex(m, cylinder, r, res, cache);
                      });
}

// A convex: what set_convex or set_convex_points registered, or its points read through ODE.
int collide_convex_geom(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const std::shared_ptr<const ConvexEntry> entry = convex_entry(o2);
  GeomObject& object = *object_of(o1);
  if (!entry) {
    object.convexes_without_data.fetch_add(1, std::memory_order_relaxed);
    return 0;
  }
  if (entry->read_from_ode) object.convexes_read_from_ode.fetch_add(1, std::memory_order_relaxed);
  const RigidTransform place = mesh_from(o1, o2);
  Aabb local = Aabb::empty();
  for (const Vec3& p : entry->points) local.expand(p);
  const Real size = local.extent().norm() / 2;
  if (entry->polyhedron) {
    return collide_with(
        o1, o2, flags, contact, skip, size,
        [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
          collide_convex(m, PlacedPolyhedron{*entry->polyhedron, place, 0}, r, res, cache);
        });
  }
  return collide_with(o1, o2, flags, contact, skip, size,
                      [&](const CollisionMesh& m, const ContactRequest& r, ContactResult& res, ConvexPairCache* cache) {
                        collide_convex(m, PlacedPoints{entry->points, place}, r, res, cache);
                      });
}

// ---- ray: as dCollideRTL (length, FirstContact, BackfaceCull, ClosestHit) ----
// depth = distance along the unit direction, pos = hit point, normal = -(face normal) whichever
// side was hit (ODE's trimesh does the same), side1 = facet, side2 = -1.
int collide_ray(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform mesh_from_world = world_from_mesh.inverse();
  dVector3 start, direction;
  dGeomRayGet(o2, start, direction);  // ODE keeps the direction unit length
  const Vec3 world_direction = Vec3(direction[0], direction[1], direction[2]).normalized();
  Ray ray;
  ray.origin = mesh_from_world.apply(Vec3(start[0], start[1], start[2]));
  ray.direction = mesh_from_world.rotation * world_direction;
  ray.t_min = 0;
  ray.t_max = dGeomRayGetLength(o2);
  RayHitsRequest request;
  request.first_only = dGeomRayGetFirstContact(o2) != 0;
  request.cull_back_faces = dGeomRayGetBackfaceCull(o2) != 0;
  request.closest_only = dGeomRayGetClosestHit(o2) != 0;
  const TriangleMesh& mesh = object.mesh->mesh();
  thread_local std::vector<FacetHit> hits;
  const std::size_t candidates = ray_hits(*object.mesh, ray, request, hits);
  object.calls.fetch_add(1, std::memory_order_relaxed);
  object.candidate_facets.fetch_add(candidates, std::memory_order_relaxed);
  int count = 0;
  for (const FacetHit& hit : hits) {
    if (count >= out.capacity()) break;
    const Vec3 a = world_from_mesh.apply(mesh.corner(hit.facet, 0));
    const Vec3 b = world_from_mesh.apply(mesh.corner(hit.facet, 1));
    const Vec3 c = world_from_mesh.apply(mesh.corner(hit.facet, 2));
    const Vec3 face_normal = (b - a).cross(c - a);
    const Real length = face_normal.norm();
    if (!(length > 0)) continue;  // a degenerate facet has no normal (intersect never hits one anyway)
    const Vec3 normal = -face_normal / length;
    const Vec3 pos = Vec3(start[0], start[1], start[2]) + world_direction * hit.t;
    dContactGeom* g = out.at(count++);
    for (int k = 0; k < 3; ++k) {
      g->pos[k] = pos[k];
      g->normal[k] = normal[k];
    }
    g->pos[3] = 0;
    g->normal[3] = 0;
    g->depth = hit.t;
    g->g1 = o1;
    g->g2 = o2;
    g->side1 = int(hit.facet);
    g->side2 = -1;
  }
  object.contacts.fetch_add(std::uint64_t(count), std::memory_order_relaxed);
  return count;
}

// ---- plane: every mesh vertex below it (as dCollideTrimeshPlane), deepest and widest kept ----
int collide_plane(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const RigidTransform world_from_mesh = pose_of(o1);
  dVector4 params;
  dGeomPlaneGetParams(o2, params);  // a x + b y + c z = d, (a, b, c) unit
  const Vec3 world_normal = Vec3(params[0], params[1], params[2]).normalized();
  // The plane in the mesh's frame: n . x = offset.
  const Plane plane{world_from_mesh.rotation.transpose() * world_normal,
                    params[3] - world_normal.dot(world_from_mesh.translation)};
  // A plane is not a convex body: no ConvexPairCache (collide_with's) for it.
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  ContactResult& result = scratch_result();
  const Real size = object.mesh->bounds().extent().norm() * Real(0.5);
  collide_half_space(*object.mesh, plane, request_for(object, out, size), result);
  return write_contacts(object, out, world_from_mesh, result, false);
}

// ---- mesh vs mesh ----
int collide_meshes_geom(const CollisionMesh& other, dGeomID o1, dGeomID o2, int flags, dContactGeom* contact,
                        int skip) {
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  // Merge at a fraction of the smaller mesh's size.
  const Real size = std::min(object.mesh->bounds().extent().norm(), other.bounds().extent().norm()) * Real(0.5);
  MeshContactRequest request;
  static_cast<ContactRequest&>(request) = request_for(object, out, size);
  request.policy = object.settings.mesh_contacts;
  // A static mesh (no body: a terrain) is the surface that deep overlaps resolve through.
  const bool mine_static = dGeomGetBody(o1) == nullptr;
  const bool theirs_static = dGeomGetBody(o2) == nullptr;
  request.static_mesh = mine_static && !theirs_static   ? StaticMesh::mesh
                        : theirs_static && !mine_static ? StaticMesh::other
                                                        : StaticMesh::neither;
  request.coherence = object.settings.mesh_coherence;
  const std::shared_ptr<MeshPairCache> cache =
      request.coherence && !request.early_stop ? mesh_pair_cache(o1, o2) : nullptr;
  ContactResult& result = scratch_result();
  collide_meshes(*object.mesh, other, mesh_from(o1, o2), request, result, cache.get());
  return write_contacts(object, out, pose_of(o1), result, true);
}

int collide_boxtree(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  return collide_meshes_geom(*object_of(o2)->mesh, o1, o2, flags, contact, skip);
}

// ODE's own trimesh: its triangles, read once into a cached collision mesh in its frame.
int collide_trimesh(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const std::shared_ptr<const CollisionMesh> other = trimesh_mesh(o2, object_of(o1)->mesh->method());
  if (!other) return 0;
  return collide_meshes_geom(*other, o1, o2, flags, contact, skip);
}

}  // namespace

dColliderFn* collider_for(int other_class) {
  switch (other_class) {
    case dSphereClass:
      return &collide_sphere;
    case dBoxClass:
      return &collide_box;
    case dCapsuleClass:
      return &collide_capsule;
    case dCylinderClass:
      return &collide_cylinder;
    case dConvexClass:
      return &collide_convex_geom;
    case dRayClass:
      return &collide_ray;
    case dPlaneClass:
      return &collide_plane;
    case dTriMeshClass:
      return &collide_trimesh;
    default:
      break;
  }
  if (other_class == dBoxtreeGetClass()) return &collide_boxtree;
  return nullptr;  // heightfields, other user classes: ODE then reports no contacts
}

}  // namespace boxtree::ode::detail
