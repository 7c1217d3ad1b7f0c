// SPDX-License-Identifier: MIT
// The boxtree geom class: registration with ODE, creation, the world AABB, and the registries the
// colliders read (convex points, trees of ODE trimeshes).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <unordered_map>

#include "boxtree/error.h"
#include "boxtree/volume/aabb.h"
#include "boxtree/volume/obb.h"
#include "internal.h"

namespace boxtree::ode::detail {
namespace {

// ODE's registration is process-global, so the class number is too. Guarded, since ODE programs
// may create geoms from several threads (ODE itself does not lock dCreateGeomClass).
std::mutex g_class_mutex;
std::atomic<int> g_class{-1};  // read lock-free by object_of on every collider call

GeomObject*& slot_of(dGeomID geom) { return *static_cast<GeomObject**>(dGeomGetClassData(geom)); }

// World AABB: the local bounds' box turned by the pose (|R| times the half extents bounds the
// turned box tightly), so it follows the body. Layout {minx,maxx, miny,maxy, minz,maxz}.
void class_aabb(dGeomID geom, dReal aabb[6]) {
  const GeomObject* object = slot_of(geom);
  const RigidTransform pose = pose_of(geom);
  const Aabb& bounds = object->mesh->bounds();
  const Vec3 center = pose.apply(bounds.center());
  const Vec3 half = pose.rotation.cwiseAbs() * (bounds.extent() * Real(0.5));
  // The speculative margin widens the box so that spaces pair shapes within it too.
  const Vec3 widen = half + Vec3::Constant(object->settings.margin);
  for (int i = 0; i < 3; ++i) {
    aabb[2 * i] = center[i] - widen[i];
    aabb[2 * i + 1] = center[i] + widen[i];
  }
}

// Called by spaces only, after the plain AABB overlap passed: the other geom's world AABB seen
// in this geom's frame (an oriented box) against the mesh's local bounds. Cheaper than a tree
// query and removes the diagonal misses of a rotated mesh's world AABB.
int class_aabb_test(dGeomID self, dGeomID /*other*/, dReal aabb[6]) {
  for (int i = 0; i < 6; ++i)
    if (!std::isfinite(aabb[i])) return 1;  // planes and other infinite geoms: let the collider decide
  const GeomObject* object = slot_of(self);
  const RigidTransform mesh_from_world = pose_of(self).inverse();
  Obb box;
  const Vec3 lo(aabb[0], aabb[2], aabb[4]);
  const Vec3 hi(aabb[1], aabb[3], aabb[5]);
  box.center = mesh_from_world.apply((lo + hi) * Real(0.5));
  box.axes = mesh_from_world.rotation;
  box.half_extents = (hi - lo) * Real(0.5) + Vec3::Constant(object->settings.margin);
  return overlaps(object->mesh->bounds(), box) ? 1 : 0;
}

void class_dtor(dGeomID geom) {
  forget_pair_caches(geom);
  GeomObject*& slot = slot_of(geom);
  delete slot;
  slot = nullptr;
}

dColliderFn* class_collider(int other_class) { return collider_for(other_class); }

// One message per collision mesh, the first time a geom is made from it, through ODE's message
// handler.
void warn_if_inconsistently_wound(const CollisionMesh& mesh) {
  if (!mesh.first_winding_report()) return;
  dMessage(0,
           "boxtree: a mesh of %zu facets has %zu edges whose two facets are wound the same way, so its facets "
           "have no consistent front; its geoms collide two-sided (GeomSettings::two_sided). Wind every facet "
           "counter-clockwise seen from outside to make them one-sided.",
           mesh.mesh().facet_count(), mesh.inconsistent_edges());
}

dGeomID create_geom(dSpaceID space, std::shared_ptr<const CollisionMesh> mesh) {
  if (!mesh) throw Error("dCreateBoxtreeMesh: no collision mesh");
  warn_if_inconsistently_wound(*mesh);
  auto object = std::make_unique<GeomObject>();
  object->mesh = std::move(mesh);
  const int class_number = dBoxtreeInit();
  dGeomID geom = dCreateGeom(class_number);
  slot_of(geom) = object.release();
  if (space) dSpaceAdd(space, geom);
  return geom;
}

template <class Scalar>
std::shared_ptr<const TriangleMesh> mesh_from_arrays(const Scalar* vertices, int vertex_stride, int vertex_count,
                                                     const dTriIndex* indices, int index_count, int tri_stride) {
  if (!vertices || !indices || vertex_count <= 0 || index_count <= 0 || index_count % 3 != 0 ||
      vertex_stride < int(3 * sizeof(Scalar)) || tri_stride < int(3 * sizeof(dTriIndex))) {
    throw Error(
        "dCreateBoxtreeMesh: bad vertex/index arrays (need vertex_stride >= 3 coordinates, "
        "tri_stride >= 3 indices, index_count a positive multiple of 3)");
  }
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->vertices.reserve(std::size_t(vertex_count));
  const auto* vertex_bytes = reinterpret_cast<const unsigned char*>(vertices);
  for (int i = 0; i < vertex_count; ++i) {
    const auto* v = reinterpret_cast<const Scalar*>(vertex_bytes + std::size_t(i) * std::size_t(vertex_stride));
    mesh->vertices.emplace_back(Real(v[0]), Real(v[1]), Real(v[2]));
  }
  const auto* index_bytes = reinterpret_cast<const unsigned char*>(indices);
  for (int t = 0; t < index_count / 3; ++t) {
    const auto* tri = reinterpret_cast<const dTriIndex*>(index_bytes + std::size_t(t) * std::size_t(tri_stride));
    mesh->triangles.push_back({VertexId(tri[0]), VertexId(tri[1]), VertexId(tri[2])});
  }
  return mesh;
}

// ---- convex registry ----
std::mutex g_convex_mutex;
std::unordered_map<dGeomID, std::shared_ptr<const ConvexEntry>> g_convex_entries;

// ---- ODE trimesh trees ----
struct TrimeshEntry {
  std::shared_ptr<const CollisionMesh> mesh;
  int triangle_count = 0;
};
using TrimeshKey = std::tuple<dTriMeshDataID, int /*kind*/, int /*hybrid level*/>;
std::mutex g_trimesh_mutex;
std::map<TrimeshKey, TrimeshEntry> g_trimesh_meshes;

// Triangle i of an ODE trimesh in the trimesh's own frame.
void trimesh_triangle(dGeomID trimesh, int i, const RigidTransform& local_from_world, Vec3 out[3]) {
  dVector3 v[3];
  dGeomTriMeshGetTriangle(trimesh, i, &v[0], &v[1], &v[2]);
  for (int k = 0; k < 3; ++k) out[k] = local_from_world.apply(Vec3(v[k][0], v[k][1], v[k][2]));
}

// The cached mesh still describes this trimesh: same count, and the first, middle and last
// triangles agree (catches data replaced in place or a freed data id reused).
bool trimesh_entry_matches(const TrimeshEntry& entry, dGeomID trimesh, const RigidTransform& local_from_world) {
  const int count = dGeomTriMeshGetTriangleCount(trimesh);
  if (count != entry.triangle_count || count == 0) return false;
  const TriangleMesh& mesh = entry.mesh->mesh();
  const Real scale = 1 + mesh.vertices.front().cwiseAbs().maxCoeff();
  for (int i : {0, count / 2, count - 1}) {
    Vec3 corners[3];
    trimesh_triangle(trimesh, i, local_from_world, corners);
    for (int k = 0; k < 3; ++k)
      if ((corners[k] - mesh.corner(FacetId(i), k)).cwiseAbs().maxCoeff() > 1e-6 * scale) return false;
  }
  return true;
}

// A convex geom's points, read through ODE's public API: ODE has no getter for a dConvex's data,
// but its convex-plane collider reports every point on or below a plane (as long as some point is
// on or above it). Two planes through the middle of the geom's AABB, facing opposite ways, give
// every point between them; the points come back in world coordinates, turned into the convex's
// frame here. Empty if ODE gives none (a convex of no points, or all on one side: flat).
std::vector<Vec3> read_convex_points(dGeomID convex) {
  dReal box[6];
  dGeomGetAABB(convex, box);
  const Vec3 middle((box[0] + box[1]) / 2, (box[2] + box[3]) / 2, (box[4] + box[5]) / 2);
  const RigidTransform local_from_world = pose_of(convex).inverse();
  std::vector<Vec3> points;
  std::vector<dContactGeom> found;
  for (const Real side : {Real(1), Real(-1)}) {
    dGeomID plane = dCreatePlane(nullptr, 0, 0, side, side * middle.z());
    for (int capacity = 256;; capacity *= 4) {
      found.resize(std::size_t(capacity));
      const int n = dCollide(convex, plane, std::min(capacity, kContactCountMask), found.data(), sizeof(dContactGeom));
      if (n < capacity || capacity >= kContactCountMask) {
        for (int i = 0; i < n; ++i)
          points.push_back(local_from_world.apply(Vec3(found[i].pos[0], found[i].pos[1], found[i].pos[2])));
        break;
      }
    }
    dGeomDestroy(plane);
  }
  // Points on the middle plane come from both calls.
  std::sort(points.begin(), points.end(), [](const Vec3& a, const Vec3& b) {
    return std::make_tuple(a.x(), a.y(), a.z()) < std::make_tuple(b.x(), b.y(), b.z());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  return points;
}

}  // namespace

GeomObject* object_of(dGeomID geom) {
  if (!geom || g_class < 0 || dGeomGetClass(geom) != g_class) return nullptr;
  return slot_of(geom);
}

RigidTransform pose_of(dGeomID geom) {
  const dReal* p = dGeomGetPosition(geom);
  const dReal* r = dGeomGetRotation(geom);  // dMatrix3: 3 rows of 4, the 4th column is padding
  RigidTransform pose;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) pose.rotation(row, col) = r[row * 4 + col];
  pose.translation = Vec3(p[0], p[1], p[2]);
  return pose;
}

namespace {

// The entry matches ODE's AABB of the geom: ODE's AABB of a convex is exactly the box of its
// turned points (dxConvex::computeAABB); a mismatch means the entry belongs to another
// (destroyed) geom, or the data changed since.
bool entry_matches(const ConvexEntry& entry, dGeomID convex) {
  dReal ode_box[6];
  dGeomGetAABB(convex, ode_box);
  const RigidTransform pose = pose_of(convex);
  Aabb box = Aabb::empty();
  for (const Vec3& p : entry.points) box.expand(pose.apply(p));
  const Real tolerance = 1e-7 * (1 + box.max.cwiseAbs().maxCoeff() + box.min.cwiseAbs().maxCoeff());
  for (int i = 0; i < 3; ++i) {
    if (std::abs(box.min[i] - ode_box[2 * i]) > tolerance || std::abs(box.max[i] - ode_box[2 * i + 1]) > tolerance)
      return false;
  }
  return true;
}

}  // namespace

std::shared_ptr<const ConvexEntry> convex_entry(dGeomID convex) {
  {
    std::lock_guard<std::mutex> lock(g_convex_mutex);
    auto it = g_convex_entries.find(convex);
    if (it != g_convex_entries.end() && entry_matches(*it->second, convex)) return it->second;
  }
  // Nobody registered this convex (or its registration is stale): read its points through ODE,
  // once, and keep them as a points-only registration (GJK/EPA on the hull).
  auto entry = std::make_shared<ConvexEntry>();
  entry->points = read_convex_points(convex);
  entry->read_from_ode = true;
  if (entry->points.empty() || !entry_matches(*entry, convex)) return nullptr;
  static std::atomic<bool> told{false};
  if (!told.exchange(true)) {
    dMessage(0,
             "boxtree: a dConvex geom that was not registered with boxtree collided with a boxtree mesh; its "
             "points were read through ODE and it collides by GJK/EPA on them. Create convexes with "
             "boxtree::ode::create_convex (or call boxtree::ode::set_convex after dCreateConvex) for the exact "
             "face contacts. (Said once per process.)");
  }
  std::lock_guard<std::mutex> lock(g_convex_mutex);
  g_convex_entries[convex] = entry;
  return entry;
}

std::shared_ptr<const CollisionMesh> trimesh_mesh(dGeomID trimesh, const Method& method) {
  const dTriMeshDataID data = dGeomTriMeshGetData(trimesh);
  const RigidTransform local_from_world = pose_of(trimesh).inverse();
  const TrimeshKey key{data, int(method.kind), method.hybrid_level};
  {
    std::lock_guard<std::mutex> lock(g_trimesh_mutex);
    auto it = g_trimesh_meshes.find(key);
    if (it != g_trimesh_meshes.end() && trimesh_entry_matches(it->second, trimesh, local_from_world))
      return it->second.mesh;
  }
  const int count = dGeomTriMeshGetTriangleCount(trimesh);
  if (count <= 0) return nullptr;
  // Unshared corners (3 per facet) keep facet ids equal to ODE's triangle indices.
  auto mesh = std::make_shared<TriangleMesh>();
  mesh->vertices.reserve(std::size_t(count) * 3);
  mesh->triangles.reserve(std::size_t(count));
  for (int i = 0; i < count; ++i) {
    Vec3 corners[3];
    trimesh_triangle(trimesh, i, local_from_world, corners);
    const auto base = VertexId(mesh->vertices.size());
    for (const Vec3& c : corners) mesh->vertices.push_back(c);
    mesh->triangles.push_back({base, base + 1, base + 2});
  }
  TrimeshEntry entry;
  try {
    entry.mesh = CollisionMesh::build(std::move(mesh), method);
  } catch (const Error&) {
    return nullptr;  // e.g. NaN vertices: ODE would not collide such a mesh sensibly either
  }
  entry.triangle_count = count;
  std::lock_guard<std::mutex> lock(g_trimesh_mutex);
  g_trimesh_meshes[key] = entry;
  return entry.mesh;
}

}  // namespace boxtree::ode::detail

using boxtree::ode::detail::g_class;
using boxtree::ode::detail::g_class_mutex;

int dBoxtreeInit() {
  std::lock_guard<std::mutex> lock(g_class_mutex);
  if (g_class >= 0) return g_class.load();
  dGeomClass geom_class{};
  geom_class.bytes = int(sizeof(boxtree::ode::detail::GeomObject*));
  geom_class.collider = &boxtree::ode::detail::class_collider;
  geom_class.aabb = &boxtree::ode::detail::class_aabb;
  geom_class.aabb_test = &boxtree::ode::detail::class_aabb_test;
  geom_class.dtor = &boxtree::ode::detail::class_dtor;
  g_class = dCreateGeomClass(&geom_class);
  return g_class.load();
}

void dBoxtreeClose() {
  std::lock_guard<std::mutex> lock(g_class_mutex);
  g_class = -1;
  boxtree::ode::clear_mesh_pair_caches();
  boxtree::ode::clear_convex_pair_caches();
}

int dBoxtreeGetClass() { return g_class.load(); }

dGeomID dCreateBoxtreeMesh(dSpaceID space, std::shared_ptr<const boxtree::TriangleMesh> mesh, const char* method) {
  if (!mesh) throw boxtree::Error("dCreateBoxtreeMesh: no mesh");
  const boxtree::Method parsed = boxtree::parse_method(method ? method : "aabb");
  return boxtree::ode::detail::create_geom(space, boxtree::CollisionMesh::build(std::move(mesh), parsed));
}

dGeomID dCreateBoxtreeMesh(dSpaceID space, const boxtree::AnyTree& tree) {
  if (tree.empty()) throw boxtree::Error("dCreateBoxtreeMesh: the tree is empty");
  return boxtree::ode::detail::create_geom(space, boxtree::CollisionMesh::of(tree));
}

dGeomID dCreateBoxtreeMesh(dSpaceID space, std::shared_ptr<const boxtree::CollisionMesh> mesh) {
  return boxtree::ode::detail::create_geom(space, std::move(mesh));
}

dGeomID dCreateBoxtreeMesh(dSpaceID space, const double* vertices, int vertex_stride, int vertex_count,
                           const dTriIndex* indices, int index_count, int tri_stride, const char* method) {
  return dCreateBoxtreeMesh(
      space,
      boxtree::ode::detail::mesh_from_arrays(vertices, vertex_stride, vertex_count, indices, index_count, tri_stride),
      method);
}

dGeomID dCreateBoxtreeMesh(dSpaceID space, const float* vertices, int vertex_stride, int vertex_count,
                           const dTriIndex* indices, int index_count, int tri_stride, const char* method) {
  return dCreateBoxtreeMesh(
      space,
      boxtree::ode::detail::mesh_from_arrays(vertices, vertex_stride, vertex_count, indices, index_count, tri_stride),
      method);
}

namespace boxtree::ode {

bool is_boxtree_geom(dGeomID geom) { return detail::object_of(geom) != nullptr; }

const AnyTree* geom_tree(dGeomID geom) {
  const detail::GeomObject* object = detail::object_of(geom);
  return object ? &object->mesh->tree() : nullptr;
}

std::shared_ptr<const CollisionMesh> geom_collision_mesh(dGeomID geom) {
  const detail::GeomObject* object = detail::object_of(geom);
  return object ? object->mesh : nullptr;
}

namespace {
detail::GeomObject& checked_object(dGeomID geom, const char* caller) {
  detail::GeomObject* object = detail::object_of(geom);
  if (!object) throw Error(std::string(caller) + ": not a boxtree geom");
  return *object;
}
}  // namespace

void set_geom_settings(dGeomID geom, const GeomSettings& settings) {
  detail::GeomObject& object = checked_object(geom, "boxtree::ode::set_geom_settings");
  if (!(settings.margin >= 0) || !(settings.merge_fraction >= 0))
    throw Error("boxtree::ode::set_geom_settings: margin and merge_fraction must be >= 0");
  const bool margin_changed = object.settings.margin != settings.margin;
  object.settings = settings;
  // The AABB depends on the margin: mark it dirty (dGeomMoved is not public; setting the same
  // position does it).
  if (margin_changed) {
    const dReal* p = dGeomGetPosition(geom);
    dGeomSetPosition(geom, p[0], p[1], p[2]);
  }
}

GeomSettings geom_settings(dGeomID geom) { return checked_object(geom, "boxtree::ode::geom_settings").settings; }

CollisionCounters geom_counters(dGeomID geom) {
  const detail::GeomObject& object = checked_object(geom, "boxtree::ode::geom_counters");
  CollisionCounters counters;
  counters.calls = object.calls.load();
  counters.candidate_facets = object.candidate_facets.load();
  counters.mesh_volume_tests = object.mesh_volume_tests.load();
  counters.contacts = object.contacts.load();
  counters.merged = object.merged.load();
  counters.dropped = object.dropped.load();
  counters.convexes_read_from_ode = object.convexes_read_from_ode.load();
  counters.convexes_without_data = object.convexes_without_data.load();
  counters.reused = object.reused.load();
  return counters;
}

void reset_geom_counters(dGeomID geom) {
  detail::GeomObject& object = checked_object(geom, "boxtree::ode::reset_geom_counters");
  object.calls = 0;
  object.candidate_facets = 0;
  object.mesh_volume_tests = 0;
  object.contacts = 0;
  object.merged = 0;
  object.dropped = 0;
  object.convexes_read_from_ode = 0;
  object.convexes_without_data = 0;
  object.reused = 0;
}

namespace {

void check_convex_geom(dGeomID convex, const char* caller) {
  if (!convex || dGeomGetClass(convex) != dConvexClass)
    throw Error(std::string("boxtree::ode::") + caller + ": not a dConvex geom");
}

std::vector<Vec3> copy_points(const dReal* points, unsigned point_count, const char* caller) {
  if (!points || point_count == 0) throw Error(std::string("boxtree::ode::") + caller + ": no points");
  std::vector<Vec3> copy;
  copy.reserve(point_count);
  for (unsigned i = 0; i < point_count; ++i) {
    copy.emplace_back(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    if (!copy.back().allFinite())
      throw Error(std::string("boxtree::ode::") + caller + ": point " + std::to_string(i) + " is not finite");
  }
  return copy;
}

void register_convex(dGeomID convex, std::shared_ptr<const detail::ConvexEntry> entry) {
  std::lock_guard<std::mutex> lock(detail::g_convex_mutex);
  detail::g_convex_entries[convex] = std::move(entry);
}

// The entry for dCreateConvex's arguments, checked (throws boxtree::Error).
std::shared_ptr<const detail::ConvexEntry> convex_entry_of(const dReal* planes, unsigned plane_count,
                                                           const dReal* points, unsigned point_count,
                                                           const unsigned* polygons) {
  auto entry = std::make_shared<detail::ConvexEntry>();
  entry->points = copy_points(points, point_count, "set_convex");
  if (!planes || !polygons || plane_count == 0) throw Error("boxtree::ode::set_convex: no planes or polygons");
  // ODE's layout: per plane, the corner count and then the corner indices.
  std::vector<std::vector<int>> faces(plane_count);
  const unsigned* next = polygons;
  for (unsigned f = 0; f < plane_count; ++f) {
    const unsigned count = *next++;
    if (count < 3 || count > unsigned(kMaxPolyhedronFaceCorners))
      throw Error("boxtree::ode::set_convex: polygon " + std::to_string(f) + " has " + std::to_string(count) +
                  " corners (3 to " + std::to_string(kMaxPolyhedronFaceCorners) + " are accepted)");
    for (unsigned k = 0; k < count; ++k) {
      const unsigned index = *next++;
      if (index >= point_count)
        throw Error("boxtree::ode::set_convex: polygon " + std::to_string(f) + ": point index " +
                    std::to_string(index) + " out of range");
      faces[f].push_back(int(index));
    }
  }
  ConvexPolyhedron polyhedron;
  try {
    polyhedron = make_convex_polyhedron(entry->points, faces);
  } catch (const Error& e) {
    throw Error(std::string("boxtree::ode::set_convex: ") + e.what());
  }
  // ODE's own colliders read the planes: they must be the faces' (a x + b y + c z = d, outward):
  // the polygon's normal, and its corners on the plane to the builder's planarity tolerance (not
  // compared with the built face's offset, which is one choice within that tolerance).
  for (unsigned f = 0; f < plane_count; ++f) {
    const Vec3 n(planes[4 * f], planes[4 * f + 1], planes[4 * f + 2]);
    const Real length = n.norm();
    const Plane& face = polyhedron.faces[f];
    bool on_plane = std::isfinite(planes[4 * f + 3]);
    for (const int corner : faces[f])
      on_plane = on_plane && std::abs(n.dot(entry->points[std::size_t(corner)]) - planes[4 * f + 3]) <=
                                 1e-6 * polyhedron.size * length;
    if (!(length > 0) || !n.allFinite() || n.dot(face.normal) < (1 - 1e-6) * length || !on_plane)
      throw Error("boxtree::ode::set_convex: plane " + std::to_string(f) + " is not the outward plane of polygon " +
                  std::to_string(f));
  }
  entry->polyhedron = std::make_unique<const ConvexPolyhedron>(std::move(polyhedron));
  return entry;
}

}  // namespace

void set_convex_points(dGeomID convex, const dReal* points, unsigned point_count) {
  check_convex_geom(convex, "set_convex_points");
  auto entry = std::make_shared<detail::ConvexEntry>();
  entry->points = copy_points(points, point_count, "set_convex_points");
  register_convex(convex, std::move(entry));
}

void set_convex(dGeomID convex, const dReal* planes, unsigned plane_count, const dReal* points, unsigned point_count,
                const unsigned* polygons) {
  check_convex_geom(convex, "set_convex");
  register_convex(convex, convex_entry_of(planes, plane_count, points, point_count, polygons));
}

void forget_convex(dGeomID convex) {
  detail::forget_pair_caches(convex);
  std::lock_guard<std::mutex> lock(detail::g_convex_mutex);
  detail::g_convex_entries.erase(convex);
}

dGeomID create_convex(dSpaceID space, const dReal* planes, unsigned plane_count, const dReal* points,
                      unsigned point_count, const unsigned* polygons) {
  // Checked before ODE sees it: nothing half-made is left in the caller's space on an Error.
  auto entry = convex_entry_of(planes, plane_count, points, point_count, polygons);
  dGeomID convex = dCreateConvex(space, planes, plane_count, points, point_count, polygons);
  register_convex(convex, std::move(entry));
  return convex;
}

void forget_trimesh_data(dTriMeshDataID data) {
  std::lock_guard<std::mutex> lock(detail::g_trimesh_mutex);
  for (auto it = detail::g_trimesh_meshes.begin(); it != detail::g_trimesh_meshes.end();) {
    if (std::get<0>(it->first) == data)
      it = detail::g_trimesh_meshes.erase(it);
    else
      ++it;
  }
}

}  // namespace boxtree::ode
