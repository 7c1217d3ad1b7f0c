// SPDX-License-Identifier: MIT
// The colliders of the boxtree geom. ODE always calls them with the boxtree geom as o1 (it swaps
// the arguments, negates the normals and swaps g1/g2 and side1/side2 itself for the reverse
// order), so each one is written as "my mesh = g1".
//
// Every collider follows the same three steps:
//  1. put the other shape into the mesh's frame and query the tree with its tight volume
//     (sphere, oriented box, capsule) to get the candidate facets;
//  2. run the core narrowphase (boxtree/contact.h) on each candidate facet;
//  3. merge near-duplicates and keep the requested number (reduce_contacts), then write them in
//     ODE's convention: contact.h's normal points from the triangle towards the shape (g2), ODE's
//     from g2 into g1, so it is negated; pos stays on the mesh's surface (as dCollideSTL does).
#include <algorithm>
#include <cmath>
#include <vector>

#include "boxtree/active_edges.h"
#include "boxtree/contact.h"
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

// Per-thread scratch, so that a collider call does not allocate once warmed up.
std::vector<ContactPoint>& scratch_contacts() {
  thread_local std::vector<ContactPoint> contacts;
  contacts.clear();
  return contacts;
}

// Step 3: reduce (unless unimportant), convert to world and ODE's convention, write.
// `negate`: the contacts' normals point from my mesh towards g2 and must be turned around.
int write_contacts(GeomObject& object, const ContactArray& out, const RigidTransform& world_from_mesh,
                   std::vector<ContactPoint>& contacts, Real merge_distance, bool negate, bool has_other_facet) {
  const auto capacity = std::size_t(out.capacity());
  if (contacts.empty()) return 0;
  if (out.unimportant()) {
    if (contacts.size() > capacity) contacts.resize(capacity);
  } else {
    reduce_contacts(contacts, capacity, merge_distance);
  }
  const int count = int(std::min(contacts.size(), capacity));
  for (int i = 0; i < count; ++i) {
    const ContactPoint& c = contacts[std::size_t(i)];
    const Vec3 pos = world_from_mesh.apply(c.position);
    Vec3 normal = world_from_mesh.rotation * c.normal;
    if (negate) normal = -normal;
    dContactGeom* g = out.at(i);
    for (int k = 0; k < 3; ++k) {
      g->pos[k] = pos[k];
      g->normal[k] = normal[k];
    }
    g->pos[3] = 0;
    g->normal[3] = 0;
    g->depth = std::max(c.depth, Real(0));  // within-margin contacts are reported as touching
    g->g1 = out.g1;
    g->g2 = out.g2;
    g->side1 = int(c.facet);
    g->side2 = has_other_facet ? int(c.other_facet) : -1;
  }
  object.contacts.fetch_add(std::uint64_t(count), std::memory_order_relaxed);
  return count;
}

ContactOptions options_of(const GeomObject& object) {
  ContactOptions options;
  options.margin = object.settings.margin;
  options.two_sided = object.settings.two_sided;
  return options;
}

Real merge_distance_for(const GeomObject& object, Real shape_size) {
  return object.settings.merge_fraction * std::max(shape_size, Real(1e-9));
}

// Steps 1-3 for a convex primitive: `query` is its volume in the mesh's frame (already widened
// by the margin), `per_facet(a, b, c, options, out)` the core routine for one triangle.
template <class Query, class PerFacet>
int collide_convex_shape(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip, const Query& query,
                         Real shape_size, const RigidTransform& world_from_mesh, PerFacet&& per_facet,
                         FacetTest test = FacetTest::exact_triangle) {
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  const ContactOptions options = options_of(object);
  const TriangleMesh& mesh = object.tree.mesh();
  std::vector<ContactPoint>& contacts = scratch_contacts();
  ContactPoint found[std::max({kMaxBoxTriangleContacts, kMaxPolyhedronTriangleContacts, kMaxCylinderTriangleContacts,
                               kMaxCapsuleTriangleContacts})];  // the largest per-facet count of the shapes here
  std::uint64_t candidates = 0;
  object.tree.query_overlap(
      query,
      [&](FacetId facet) {
        ++candidates;
        const Vec3& a = mesh.corner(facet, 0);
        const Vec3& b = mesh.corner(facet, 1);
        const Vec3& c = mesh.corner(facet, 2);
        const int n = per_facet(a, b, c, options, found);
        for (int i = 0; i < n; ++i) {
          found[i].facet = facet;
          if (object.settings.internal_edges &&
              correct_internal_edge_contact(found[i], a, b, c, object.active_edges[facet]) == EdgeContact::discard)
            continue;  // beside this facet: its neighbour reports the real contact
          contacts.push_back(found[i]);
        }
        return !(out.unimportant() && contacts.size() >= std::size_t(out.capacity()));
      },
      nullptr, test);
  object.calls.fetch_add(1, std::memory_order_relaxed);
  object.candidate_facets.fetch_add(candidates, std::memory_order_relaxed);
  return write_contacts(object, out, world_from_mesh, contacts, merge_distance_for(object, shape_size), true, false);
}

// ---- sphere ----
int collide_sphere(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const GeomObject& object = *object_of(o1);
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform mesh_from_world = world_from_mesh.inverse();
  const Sphere sphere{mesh_from_world.apply(pose_of(o2).translation), dGeomSphereGetRadius(o2)};
  const Sphere query{sphere.center, sphere.radius + object.settings.margin};
  return collide_convex_shape(o1, o2, flags, contact, skip, query, sphere.radius, world_from_mesh,
                              [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o,
                                  ContactPoint* found) { return contact_sphere_triangle(sphere, a, b, c, o, found); });
}

// ---- box ----
int collide_box(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const GeomObject& object = *object_of(o1);
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform mesh_from_world = world_from_mesh.inverse();
  const RigidTransform world_from_box = pose_of(o2);
  dVector3 lengths;
  dGeomBoxGetLengths(o2, lengths);  // full side lengths
  Obb box;
  box.center = mesh_from_world.apply(world_from_box.translation);
  box.axes = mesh_from_world.rotation * world_from_box.rotation;
  box.half_extents = Vec3(lengths[0], lengths[1], lengths[2]) * Real(0.5);
  Obb query = box;
  query.half_extents.array() += object.settings.margin;
  return collide_convex_shape(o1, o2, flags, contact, skip, query, box.half_extents.norm(), world_from_mesh,
                              [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o,
                                  ContactPoint* found) { return contact_box_triangle(box, a, b, c, o, found); });
}

// The segment of a capsule's or cylinder's axis (ODE: local Z, `length` long, centred), in the
// mesh's frame.
void axis_segment(const RigidTransform& mesh_from_world, dGeomID geom, Real length, Vec3& p0, Vec3& p1) {
  const RigidTransform world_from_geom = pose_of(geom);
  const Vec3 center = mesh_from_world.apply(world_from_geom.translation);
  const Vec3 half_axis = mesh_from_world.rotation * world_from_geom.rotation.col(2) * (length * Real(0.5));
  p0 = center - half_axis;
  p1 = center + half_axis;
}

// ---- capsule ----
int collide_capsule(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const GeomObject& object = *object_of(o1);
  const RigidTransform world_from_mesh = pose_of(o1);
  dReal radius = 0, length = 0;
  dGeomCapsuleGetParams(o2, &radius, &length);  // length: the cylinder part only
  Capsule capsule;
  axis_segment(world_from_mesh.inverse(), o2, length, capsule.p0, capsule.p1);
  capsule.radius = radius;
  const Capsule query{capsule.p0, capsule.p1, capsule.radius + object.settings.margin};
  return collide_convex_shape(
      o1, o2, flags, contact, skip, query, radius + length / 2, world_from_mesh,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* found) {
        return contact_capsule_triangle(capsule, a, b, c, o, found);
      });
}

// ---- cylinder ----
int collide_cylinder(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const GeomObject& object = *object_of(o1);
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform mesh_from_world = world_from_mesh.inverse();
  dReal radius = 0, length = 0;
  dGeomCylinderGetParams(o2, &radius, &length);
  Vec3 p0, p1;
  axis_segment(mesh_from_world, o2, length, p0, p1);
  Obb query;  // the cylinder's box: radius across, half the length along the axis (local Z)
  query.center = (p0 + p1) * Real(0.5);
  query.axes = mesh_from_world.rotation * pose_of(o2).rotation;
  query.half_extents = Vec3(radius, radius, length / 2).array() + object.settings.margin;
  const Real r = radius;
  return collide_convex_shape(
      o1, o2, flags, contact, skip, query, std::hypot(radius, length / 2), world_from_mesh,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* found) {
        return contact_cylinder_triangle(p0, p1, r, a, b, c, o, found);
      });
}

// ---- convex: what set_convex or set_convex_points registered ----
int collide_convex(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  const std::shared_ptr<const ConvexEntry> entry = convex_entry(o2);
  if (!entry) return 0;
  const GeomObject& object = *object_of(o1);
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform world_from_convex = pose_of(o2);
  // Query volume: the points' box in the convex's own frame, as an oriented box in the mesh's.
  Aabb local = Aabb::empty();
  for (const Vec3& p : entry->points) local.expand(p);
  const RigidTransform mesh_from_convex{
      world_from_mesh.rotation.transpose() * world_from_convex.rotation,
      world_from_mesh.rotation.transpose() * (world_from_convex.translation - world_from_mesh.translation)};
  Obb query;
  query.center = mesh_from_convex.apply(local.center());
  query.axes = mesh_from_convex.rotation;
  query.half_extents = (local.extent() * Real(0.5)).array() + object.settings.margin;
  if (entry->polyhedron) {
    // Faces known: the exact separating-axis narrowphase, on the hull moved into the mesh's frame
    // once per call. The query stops at the leaf boxes: the narrowphase's first axes (the
    // triangle's normal, the hull's faces at three dot products each) reject the facets the box's
    // exact triangle test would have, and the box is looser than the hull anyway (ODE drop scene,
    // pair_replay --only convex: 17.6 -> 15.4 us per call, 37.1 instead of 27.9 facets, the same
    // contacts; the box's and cylinder's narrowphases reject a facet at a higher cost, so they
    // keep the exact test).
    thread_local ConvexPolyhedron hull;
    transform_polyhedron(*entry->polyhedron, mesh_from_convex, hull);
    return collide_convex_shape(
        o1, o2, flags, contact, skip, query, local.extent().norm() / 2, world_from_mesh,
        [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* found) {
          return contact_polyhedron_triangle(hull, a, b, c, o, found);
        },
        FacetTest::leaf_volume);
  }
  thread_local std::vector<Vec3> points;
  points.resize(entry->points.size());
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = mesh_from_convex.apply(entry->points[i]);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : points) centroid += p;
  centroid /= Real(points.size());
  auto support = [&](const Vec3& direction) { return support_points(points, direction); };
  const ConvexSupport shape{support, centroid, true};
  return collide_convex_shape(o1, o2, flags, contact, skip, query, local.extent().norm() / 2, world_from_mesh,
                              [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o,
                                  ContactPoint* found) { return contact_convex_triangle(shape, a, b, c, o, found); });
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
  const bool first_contact = dGeomRayGetFirstContact(o2) != 0;
  const bool backface_cull = dGeomRayGetBackfaceCull(o2) != 0;
  const bool closest_hit = dGeomRayGetClosestHit(o2) != 0;
  const TriangleMesh& mesh = object.tree.mesh();

  struct Hit {
    Real t;
    FacetId facet;
  };
  thread_local std::vector<Hit> hits;
  hits.clear();
  std::uint64_t candidates = 0;
  object.tree.ray_candidates(ray, [&](FacetId facet, Real t_max) -> Real {
    ++candidates;
    const Vec3& a = mesh.corner(facet, 0);
    const Vec3& b = mesh.corner(facet, 1);
    const Vec3& c = mesh.corner(facet, 2);
    Ray bounded = ray;
    bounded.t_max = t_max;
    TriangleHit hit;
    if (!intersect_ray_triangle(bounded, a, b, c, hit)) return t_max;
    // Culling keeps front faces only: those the ray enters against their CCW normal.
    if (backface_cull && (b - a).cross(c - a).dot(ray.direction) >= 0) return t_max;
    if (closest_hit) {
      // Keep the nearer (on a tie the smaller facet id, as ray_closest_hit does).
      if (hits.empty() || hit.t < hits[0].t || (hit.t == hits[0].t && facet < hits[0].facet))
        hits.assign(1, {hit.t, facet});
      return hit.t;
    }
    hits.push_back({hit.t, facet});
    if (first_contact) return Real(-1);  // below t_min: stops the walk
    return t_max;
  });
  object.calls.fetch_add(1, std::memory_order_relaxed);
  object.candidate_facets.fetch_add(candidates, std::memory_order_relaxed);
  std::sort(hits.begin(), hits.end(),
            [](const Hit& x, const Hit& y) { return x.t != y.t ? x.t < y.t : x.facet < y.facet; });
  int count = 0;
  for (const Hit& hit : hits) {
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
// The tree prunes: only facets meeting the half-space below the plane are visited, found with
// an oriented box that covers the part of the mesh's bounds below the plane.
int collide_plane(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  GeomObject& object = *object_of(o1);
  const ContactArray out{o1, o2, flags, contact, skip};
  const RigidTransform world_from_mesh = pose_of(o1);
  dVector4 params;
  dGeomPlaneGetParams(o2, params);  // a x + b y + c z = d, (a, b, c) unit
  const Vec3 world_normal = Vec3(params[0], params[1], params[2]).normalized();
  // The plane in the mesh's frame: n . x = offset.
  const Vec3 n = world_from_mesh.rotation.transpose() * world_normal;
  const Real offset = params[3] - world_normal.dot(world_from_mesh.translation);
  const Real margin = object.settings.margin;

  const Vec3 center = object.local_bounds.center();
  const Real radius = object.local_bounds.extent().norm() * Real(0.5);
  const Real center_height = n.dot(center) - offset;
  if (center_height - radius > margin) return 0;  // the whole mesh is above the plane
  // The slab of heights [lo, hi] relative to the plane that can hold vertices below it.
  const Real lo = center_height - radius;
  const Real hi = std::min(margin, center_height + radius);
  Obb query;
  Vec3 u = n.unitOrthogonal();
  query.axes.col(0) = u;
  query.axes.col(1) = n.cross(u);
  query.axes.col(2) = n;
  query.center = center + n * ((lo + hi) * Real(0.5) - center_height);
  query.half_extents = Vec3(radius, radius, (hi - lo) * Real(0.5));

  const TriangleMesh& mesh = object.tree.mesh();
  thread_local std::vector<unsigned char> seen;  // vertex visited (shared by several facets)
  thread_local std::vector<VertexId> touched;
  if (seen.size() < mesh.vertices.size()) seen.assign(mesh.vertices.size(), 0);
  touched.clear();
  std::vector<ContactPoint>& contacts = scratch_contacts();
  std::uint64_t candidates = 0;
  object.tree.query_overlap(
      query,
      [&](FacetId facet) {
        ++candidates;
        for (int k = 0; k < 3; ++k) {
          const VertexId v = mesh.triangles[facet][k];
          if (seen[v]) continue;
          seen[v] = 1;
          touched.push_back(v);
          const Real height = n.dot(mesh.vertices[v]) - offset;
          if (height > margin) continue;
          ContactPoint c;
          c.position = mesh.vertices[v];
          c.normal = -n;  // negated on writing: ODE's normal is the plane's (from the plane into the mesh)
          c.depth = -height;
          c.facet = facet;
          contacts.push_back(c);
        }
        return !(out.unimportant() && contacts.size() >= std::size_t(out.capacity()));
      },
      nullptr, FacetTest::leaf_volume);
  for (VertexId v : touched) seen[v] = 0;
  object.calls.fetch_add(1, std::memory_order_relaxed);
  object.candidate_facets.fetch_add(candidates, std::memory_order_relaxed);
  return write_contacts(object, out, world_from_mesh, contacts, merge_distance_for(object, radius), true, false);
}

// ---- mesh vs mesh: tree vs tree, then triangle-triangle contacts ----
// The other mesh, as the colliders below see it: its tree (of my volume kind), bounds and edges.
struct OtherMesh {
  const AnyTree* tree;
  const Aabb* bounds;
  const std::vector<std::uint8_t>* active_edges;
};

// contact_triangle_triangle(a = the other's triangle, b = mine) gives the normal from my triangle
// towards the other and the position on mine, like the convex shapes above: negated on writing.
// Triangle pairs are always two-sided here: ODE picks which of two meshes is o1 (for two boxtree
// geoms it is even the second argument), and pushing a big triangle of one closed mesh out
// through the front of the other's facet because its centroid is behind would make deep bogus
// contacts; the least penetration per pair is what resting closed meshes need.
// (contact_triangle_faces, face normals only, was tried: for a cube's side wall crossing a ground
// facet of the same size it reports the wall's side, a deep horizontal contact.)
int collide_meshes(GeomObject& object, const OtherMesh& other, dGeomID o1, dGeomID o2, int flags, dContactGeom* contact,
                   int skip) {
  const ContactArray out{o1, o2, flags, contact, skip};
  const RigidTransform world_from_mesh = pose_of(o1);
  const RigidTransform world_from_other = pose_of(o2);
  const RigidTransform mesh_from_other{
      world_from_mesh.rotation.transpose() * world_from_other.rotation,
      world_from_mesh.rotation.transpose() * (world_from_other.translation - world_from_mesh.translation)};
  ContactOptions options = options_of(object);
  options.two_sided = true;
  const bool internal_edges = object.settings.internal_edges;
  const TriangleMesh& mine = object.tree.mesh();
  const TriangleMesh& theirs = other.tree->mesh();
  std::vector<ContactPoint>& contacts = scratch_contacts();
  ContactPoint found[kMaxTriangleTriangleContacts];
  std::uint64_t candidates = 0;
  object.tree.collide(*other.tree, mesh_from_other, [&](const FacetPair& pair) {
    ++candidates;
    const Vec3 a0 = mesh_from_other.apply(theirs.corner(pair.b, 0));
    const Vec3 a1 = mesh_from_other.apply(theirs.corner(pair.b, 1));
    const Vec3 a2 = mesh_from_other.apply(theirs.corner(pair.b, 2));
    const Vec3& b0 = mine.corner(pair.a, 0);
    const Vec3& b1 = mine.corner(pair.a, 1);
    const Vec3& b2 = mine.corner(pair.a, 2);
    const int n = contact_triangle_triangle(a0, a1, a2, b0, b1, b2, options, found);
    for (int i = 0; i < n; ++i) {
      ContactPoint& c = found[i];
      c.facet = pair.a;
      c.other_facet = pair.b;
      if (internal_edges) {
        // On my side (the contact's position is on my triangle), then on theirs: seen from their
        // triangle the same contact sits at the deepest point of mine with the opposite normal.
        EdgeContact verdict = correct_internal_edge_contact(c, b0, b1, b2, object.active_edges[pair.a]);
        if (verdict == EdgeContact::keep) {
          ContactPoint flipped = c;
          flipped.position = c.point_on_shape();
          flipped.normal = -c.normal;
          verdict = correct_internal_edge_contact(flipped, a0, a1, a2, (*other.active_edges)[pair.b]);
          if (verdict == EdgeContact::corrected) {
            c.normal = -flipped.normal;
            c.depth = flipped.depth;
            c.position = flipped.point_on_shape();
          }
        }
        if (verdict == EdgeContact::discard) continue;
      }
      contacts.push_back(c);
    }
    return !(out.unimportant() && contacts.size() >= std::size_t(out.capacity()));
  });
  object.calls.fetch_add(1, std::memory_order_relaxed);
  object.candidate_facets.fetch_add(candidates, std::memory_order_relaxed);
  // Merge at a fraction of the smaller mesh's size.
  const Real size = std::min(object.local_bounds.extent().norm(), other.bounds->extent().norm()) * Real(0.5);
  return write_contacts(object, out, world_from_mesh, contacts, merge_distance_for(object, size), true, true);
}

// Both boxtree geoms. Tree-vs-tree needs one volume kind: if the two geoms use different methods,
// the other mesh gets a tree of my method, built once and kept (per thread) for the last mesh seen.
bool same_volume_kind(const Method& a, const Method& b) {
  if (a.kind != b.kind) return false;
  return a.kind == VolumeKind::aabb || (a.hybrid_level > 0) == (b.hybrid_level > 0);
}

int collide_boxtree(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  GeomObject& object = *object_of(o1);
  const GeomObject& other = *object_of(o2);
  const AnyTree* other_tree = &other.tree;
  thread_local std::shared_ptr<const TriangleMesh> converted_mesh;
  thread_local Method converted_method;
  thread_local AnyTree converted;
  if (!same_volume_kind(object.tree.method(), other.tree.method())) {
    if (converted_mesh != other.tree.shared_mesh() || !same_volume_kind(converted_method, object.tree.method())) {
      converted = AnyTree::build(other.tree.shared_mesh(), object.tree.method());
      converted_mesh = other.tree.shared_mesh();
      converted_method = object.tree.method();
    }
    other_tree = &converted;
  }
  return collide_meshes(object, {other_tree, &other.local_bounds, &other.active_edges}, o1, o2, flags, contact, skip);
}

// ODE's own trimesh: its triangles, read once into a cached boxtree in its frame.
int collide_trimesh(dGeomID o1, dGeomID o2, int flags, dContactGeom* contact, int skip) {
  GeomObject& object = *object_of(o1);
  const std::shared_ptr<const TrimeshTree> other = trimesh_tree(o2, object.tree.method());
  if (!other) return 0;
  return collide_meshes(object, {&other->tree, &other->bounds, &other->active_edges}, o1, o2, flags, contact, skip);
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
      return &collide_convex;
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
