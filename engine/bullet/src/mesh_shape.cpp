// SPDX-License-Identifier: MIT
#include "boxtree/bullet/mesh_shape.h"

#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <LinearMath/btAabbUtil2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "convert.h"

namespace boxtree::bullet {
namespace {

// Reads index k of a face from a Bullet index array of any of its integer types.
VertexId read_index(const unsigned char* face, PHY_ScalarType type, int k) {
  switch (type) {
    case PHY_INTEGER:
      return static_cast<VertexId>(reinterpret_cast<const int*>(face)[k]);
    case PHY_SHORT:
      return reinterpret_cast<const unsigned short*>(face)[k];
    case PHY_UCHAR:
      return face[k];
    default:
      throw Error("BoxtreeMeshShape: unsupported index type in btStridingMeshInterface");
  }
}

Vec3 read_vertex(const unsigned char* base, int stride, PHY_ScalarType type, VertexId v) {
  const unsigned char* p = base + static_cast<std::size_t>(v) * static_cast<std::size_t>(stride);
  if (type == PHY_FLOAT) {
    const float* f = reinterpret_cast<const float*>(p);
    return {f[0], f[1], f[2]};
  }
  if (type == PHY_DOUBLE) {
    const double* d = reinterpret_cast<const double*>(p);
    return {d[0], d[1], d[2]};
  }
  throw Error("BoxtreeMeshShape: unsupported vertex type in btStridingMeshInterface");
}

// Copies every part of a Bullet mesh interface into one boxtree mesh; part p's triangles get
// consecutive facet ids starting at part_first[p], so a facet maps back to (part, index).
std::shared_ptr<const TriangleMesh> copy_mesh(const btStridingMeshInterface& source, std::vector<FacetId>& part_first) {
  auto mesh = std::make_shared<TriangleMesh>();
  part_first.assign(1, 0);
  for (int part = 0; part < source.getNumSubParts(); ++part) {
    const unsigned char* vertices = nullptr;
    const unsigned char* indices = nullptr;
    int num_vertices = 0, vertex_stride = 0, index_stride = 0, num_faces = 0;
    PHY_ScalarType vertex_type = PHY_FLOAT, index_type = PHY_INTEGER;
    source.getLockedReadOnlyVertexIndexBase(&vertices, num_vertices, vertex_type, vertex_stride, &indices, index_stride,
                                            num_faces, index_type, part);
    // Unlock on every exit path: the interface is the caller's and must be left as it was.
    struct Unlock {
      const btStridingMeshInterface& s;
      int part;
      ~Unlock() { s.unLockReadOnlyVertexBase(part); }
    } unlock{source, part};
    if (num_faces < 0 || num_vertices < 0)
      throw Error("BoxtreeMeshShape: negative face or vertex count in part " + std::to_string(part));
    const VertexId base = static_cast<VertexId>(mesh->vertices.size());
    for (int v = 0; v < num_vertices; ++v)
      mesh->vertices.push_back(read_vertex(vertices, vertex_stride, vertex_type, static_cast<VertexId>(v)));
    for (int f = 0; f < num_faces; ++f) {
      const unsigned char* face = indices + static_cast<std::size_t>(f) * static_cast<std::size_t>(index_stride);
      Triangle t;
      for (int k = 0; k < 3; ++k) {
        const VertexId v = read_index(face, index_type, k);
        if (v >= static_cast<VertexId>(num_vertices)) {
          throw Error("BoxtreeMeshShape: part " + std::to_string(part) + ", triangle " + std::to_string(f) +
                      ": vertex index " + std::to_string(static_cast<long long>(static_cast<int>(v))) +
                      " out of range (the part has " + std::to_string(num_vertices) + " vertices)");
        }
        t[k] = base + v;
      }
      mesh->triangles.push_back(t);
    }
    part_first.push_back(static_cast<FacetId>(mesh->triangles.size()));
  }
  return mesh;
}

Method checked_method(const std::string& name) { return parse_method(name); }

}  // namespace

BoxtreeMeshShape::BoxtreeMeshShape(const btStridingMeshInterface& mesh, const std::string& method,
                                   const BuildSettings& settings) {
  const Method m = checked_method(method);
  auto copy = copy_mesh(mesh, m_partFirstFacet);
  m_base = CollisionMesh::build(std::move(copy), m, settings);
  init();
  setLocalScaling(mesh.getScaling());
}

namespace {
const btStridingMeshInterface& checked_interface(const btStridingMeshInterface* mesh) {
  if (mesh == nullptr) throw Error("BoxtreeMeshShape: the mesh interface is null");
  return *mesh;
}
}  // namespace

BoxtreeMeshShape::BoxtreeMeshShape(btStridingMeshInterface* meshInterface, bool /*useQuantizedAabbCompression*/,
                                   bool /*buildBvh*/)
    : BoxtreeMeshShape(checked_interface(meshInterface), "aabb") {}

BoxtreeMeshShape::BoxtreeMeshShape(btStridingMeshInterface* meshInterface, bool /*useQuantizedAabbCompression*/,
                                   const btVector3& /*bvhAabbMin*/, const btVector3& /*bvhAabbMax*/, bool /*buildBvh*/)
    : BoxtreeMeshShape(checked_interface(meshInterface), "aabb") {}

BoxtreeMeshShape::BoxtreeMeshShape(btStridingMeshInterface* meshInterface, const std::string& method,
                                   const BuildSettings& settings)
    : BoxtreeMeshShape(checked_interface(meshInterface), method, settings) {}

BoxtreeMeshShape::BoxtreeMeshShape(btStridingMeshInterface* meshInterface, const char* method,
                                   const BuildSettings& settings)
    : BoxtreeMeshShape(checked_interface(meshInterface), std::string(method != nullptr ? method : ""), settings) {}

BoxtreeMeshShape::BoxtreeMeshShape(std::shared_ptr<const TriangleMesh> mesh, const std::string& method,
                                   const BuildSettings& settings)
    : m_base(CollisionMesh::build(std::move(mesh), checked_method(method), settings)) {
  m_partFirstFacet = {0, static_cast<FacetId>(m_base->mesh().facet_count())};
  init();
}

namespace {
std::shared_ptr<const CollisionMesh> collision_mesh_of(const AnyTree& tree) {
  if (tree.empty()) throw Error("BoxtreeMeshShape: the tree is empty");
  return CollisionMesh::of(tree);
}
}  // namespace

BoxtreeMeshShape::BoxtreeMeshShape(AnyTree tree) : BoxtreeMeshShape(collision_mesh_of(tree)) {}

BoxtreeMeshShape::BoxtreeMeshShape(std::shared_ptr<const CollisionMesh> mesh) : m_base(std::move(mesh)) {
  if (!m_base) throw Error("BoxtreeMeshShape: the collision mesh is null");
  m_partFirstFacet = {0, static_cast<FacetId>(m_base->mesh().facet_count())};
  init();
}

namespace {
// One line on stderr per collision mesh, the first time a shape is made from it.
void warn_if_inconsistently_wound(const CollisionMesh& mesh) {
  if (!mesh.first_winding_report()) return;
  std::fprintf(stderr,
               "boxtree: a mesh of %zu facets has %zu edges whose two facets are wound the same way, so its "
               "facets have no consistent front; its BoxtreeMeshShapes collide two-sided. Wind every facet "
               "counter-clockwise seen from outside to make them one-sided.\n",
               mesh.mesh().facet_count(), mesh.inconsistent_edges());
}
}  // namespace

void BoxtreeMeshShape::init() {
  m_shapeType = FAST_CONCAVE_MESH_PROXYTYPE;
  warn_if_inconsistently_wound(*m_base);
  m_collision = m_base;
  m_localAabbMin = to_bt(m_collision->bounds().min);
  m_localAabbMax = to_bt(m_collision->bounds().max);
}

void BoxtreeMeshShape::setLocalScaling(const btVector3& scaling) {
  if (!std::isfinite(double(scaling.x())) || !std::isfinite(double(scaling.y())) ||
      !std::isfinite(double(scaling.z())) || scaling.x() == 0 || scaling.y() == 0 || scaling.z() == 0) {
    throw Error("BoxtreeMeshShape::setLocalScaling: scaling must be finite and non-zero");
  }
  m_localScaling = scaling;
  m_unitScaling = scaling == btVector3(1, 1, 1);
  m_collision = m_base->scaled(to_vec(scaling));
  m_localAabbMin = to_bt(m_collision->bounds().min);
  m_localAabbMax = to_bt(m_collision->bounds().max);
}

BoxtreeMeshShape::Counters BoxtreeMeshShape::counters() const {
  Counters c;
  c.queries = m_counters.queries.load(std::memory_order_relaxed);
  c.triangles = m_counters.triangles.load(std::memory_order_relaxed);
  c.ray_queries = m_counters.ray_queries.load(std::memory_order_relaxed);
  c.narrowphase_triangles = m_counters.narrowphase_triangles.load(std::memory_order_relaxed);
  c.merged_contacts = m_counters.merged_contacts.load(std::memory_order_relaxed);
  c.dropped_contacts = m_counters.dropped_contacts.load(std::memory_order_relaxed);
  c.mesh_volume_tests = m_counters.mesh_volume_tests.load(std::memory_order_relaxed);
  c.reused_calls = m_counters.reused_calls.load(std::memory_order_relaxed);
  return c;
}

void BoxtreeMeshShape::resetCounters() const {
  for (auto* counter : {&m_counters.queries, &m_counters.triangles, &m_counters.ray_queries,
                        &m_counters.narrowphase_triangles, &m_counters.merged_contacts, &m_counters.dropped_contacts,
                        &m_counters.mesh_volume_tests, &m_counters.reused_calls})
    counter->store(0, std::memory_order_relaxed);
}

void BoxtreeMeshShape::countCollision(const CollisionCounts& counts) const {
  // Atomic adds are locked instructions (~20 cycles each): zeros, the usual merged, dropped and
  // volume-test counts of a convex pair, are not added.
  const auto add = [](std::atomic<std::uint64_t>& counter, std::uint64_t value) {
    if (value != 0) counter.fetch_add(value, std::memory_order_relaxed);
  };
  add(m_counters.narrowphase_triangles, counts.candidates);
  add(m_counters.merged_contacts, counts.merged);
  add(m_counters.dropped_contacts, counts.dropped);
  add(m_counters.mesh_volume_tests, counts.volume_tests);
  add(m_counters.reused_calls, counts.reused ? 1 : 0);
}

void BoxtreeMeshShape::getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const {
  // The scaled local box grown by the margin, then transformed.
  const btVector3 margin(getMargin(), getMargin(), getMargin());
  const btVector3 half = (m_localAabbMax - m_localAabbMin) * btScalar(0.5) + margin;
  const btVector3 center = t((m_localAabbMax + m_localAabbMin) * btScalar(0.5));
  const btVector3 extent = t.getBasis().absolute() * half;
  aabbMin = center - extent;
  aabbMax = center + extent;
}

void BoxtreeMeshShape::calculateLocalInertia(btScalar mass, btVector3& inertia) const {
  // The inertia of the (scaled) bounding box, as btGImpactMeshShape does by default: meshes are
  // rarely closed or of known density, and a box keeps the solver stable.
  const btVector3 e = m_localAabbMax - m_localAabbMin;
  inertia = mass / btScalar(12) *
            btVector3(e.y() * e.y() + e.z() * e.z(), e.x() * e.x() + e.z() * e.z(), e.x() * e.x() + e.y() * e.y());
}

void BoxtreeMeshShape::facetToPart(FacetId facet, int& partId, int& triangleIndex) const {
  const auto it = std::upper_bound(m_partFirstFacet.begin(), m_partFirstFacet.end(), facet);
  partId = static_cast<int>(it - m_partFirstFacet.begin()) - 1;
  triangleIndex = static_cast<int>(facet - m_partFirstFacet[static_cast<std::size_t>(partId)]);
}

FacetId BoxtreeMeshShape::partToFacet(int partId, int triangleIndex) const {
  return m_partFirstFacet[static_cast<std::size_t>(partId)] + static_cast<FacetId>(triangleIndex);
}

void BoxtreeMeshShape::scaledTriangle(FacetId facet, btVector3 out[3]) const {
  const TriangleMesh& m = m_base->mesh();
  for (int k = 0; k < 3; ++k) out[k] = to_bt(m.corner(facet, k)) * m_localScaling;
}

void BoxtreeMeshShape::processAllTriangles(btTriangleCallback* callback, const btVector3& aabbMin,
                                           const btVector3& aabbMax) const {
  btVector3 triangle[3];
  // `in_box`: report the triangle only if its own box overlaps the query box, in Bullet's frame.
  auto report = [&](FacetId f, bool in_box = false) {
    int part = 0, index = 0;
    facetToPart(f, part, index);
    scaledTriangle(f, triangle);
    if (in_box) {
      btVector3 lo = triangle[0], hi = triangle[0];
      for (int k = 1; k < 3; ++k) {
        lo.setMin(triangle[k]);
        hi.setMax(triangle[k]);
      }
      if (!TestAabbAgainstAabb2(lo, hi, aabbMin, aabbMax)) return;
    }
    m_counters.triangles.fetch_add(1, std::memory_order_relaxed);
    callback->processTriangle(triangle, part, index);
  };

  // Rays (btCollisionWorld::rayTest on this shape): walk the tree front to back, pruned by the
  // callback's own closest hit, instead of scanning the segment's whole box. The callback keeps
  // doing Bullet's ray/triangle test, so hits, normals and ids are Bullet's.
  if (auto* ray_cb = dynamic_cast<btTriangleRaycastCallback*>(callback)) {
    m_counters.ray_queries.fetch_add(1, std::memory_order_relaxed);
    Ray ray;
    ray.origin = to_vec(ray_cb->m_from);
    ray.direction = to_vec(ray_cb->m_to - ray_cb->m_from);
    // The callback computes hit fractions in single precision, a few float ulps of the ray's
    // length either side of the exact ones; the tree walks in double. Pruning at the callback's
    // fraction itself could skip a triangle whose rounded fraction Bullet would have taken (a
    // near-tie at a shared edge): prune a little beyond it (1e-5 of the ray's length).
    constexpr Real kFractionSlack = 1e-5;
    ray.t_min = 0;
    ray.t_max = Real(ray_cb->m_hitFraction) + kFractionSlack;
    m_collision->tree().ray_candidates(ray, [&](FacetId f, Real) {
      report(f);
      return Real(ray_cb->m_hitFraction) + kFractionSlack;
    });
    return;
  }

  // Convex sweeps (convexSweepTest): the swept box of the cast shape, as an oriented box along
  // the sweep, instead of the axis-aligned box of the whole sweep; candidates are handed over
  // nearest first so that the callback's hit fraction prunes the rest.
  if (auto* cast_cb = dynamic_cast<btTriangleConvexcastCallback*>(callback)) {
    sweepCandidates(*cast_cb, [&](FacetId f) { report(f); });
    return;
  }

  // Everything else (convex-concave contacts, debug drawing, internal-edge info, CCD, GImpact):
  // the triangles overlapping the query box.
  m_counters.queries.fetch_add(1, std::memory_order_relaxed);
  const Aabb box = toTreeFrame(aabbMin, aabbMax);
  if (box.is_empty()) return;
  const Method& method = m_collision->method();
  const bool aabb_tree = method.kind == VolumeKind::aabb && method.hybrid_level == 0;
  // Axis-aligned trees report exactly the triangles whose own box overlaps the query box (what
  // btBvhTriangleMeshShape reports, without its quantization slack); oriented ones report the
  // triangles that overlap the query box itself (their leaves are tighter than a triangle's box).
  // The packed tree's leaf boxes are a grid step or two larger than the triangles' own, so the
  // triangle, fetched for the callback anyway, is checked against the query box.
  m_collision->tree().query_overlap(
      box,
      [&](FacetId f) {
        report(f, aabb_tree);
        return true;
      },
      nullptr, aabb_tree ? FacetTest::leaf_volume : FacetTest::exact_triangle);
}

Aabb BoxtreeMeshShape::toTreeFrame(const btVector3& aabbMin, const btVector3& aabbMax) const {
  for (int i = 0; i < 3; ++i) {
    if (std::isnan(double(aabbMin[i])) || std::isnan(double(aabbMax[i])) || aabbMin[i] > aabbMax[i])
      return Aabb::empty();
  }
  Aabb box = Aabb::from_points(to_vec(aabbMin), to_vec(aabbMax));
  // Clip to the mesh's bounds: keeps Bullet's "everything" boxes (±BT_LARGE_FLOAT, debug drawing)
  // finite, and costs nothing.
  const Aabb& bounds = m_collision->bounds();
  box.min = box.min.cwiseMax(bounds.min);
  box.max = box.max.cwiseMin(bounds.max);
  return box;
}

void BoxtreeMeshShape::sweepCandidates(btTriangleConvexcastCallback& cast, FunctionRef<void(FacetId)> report) const {
  m_counters.ray_queries.fetch_add(1, std::memory_order_relaxed);
  // The cast shape's box at both ends of the sweep, in the mesh's (scaled) local frame, grown by
  // the triangles' collision margin.
  const btTransform to_local = cast.m_triangleToWorld.inverse();
  btVector3 lo0, hi0, lo1, hi1;
  cast.m_convexShape->getAabb(to_local * cast.m_convexShapeFrom, lo0, hi0);
  cast.m_convexShape->getAabb(to_local * cast.m_convexShapeTo, lo1, hi1);
  const Vec3 c0 = to_vec((lo0 + hi0) * btScalar(0.5)), c1 = to_vec((lo1 + hi1) * btScalar(0.5));
  const Vec3 half = to_vec((hi0 - lo0) * btScalar(0.5)).cwiseMax(to_vec((hi1 - lo1) * btScalar(0.5))) +
                    Vec3::Constant(Real(cast.m_triangleCollisionMargin));
  sweep_candidates(
      *m_collision, c0, c1, half, [&] { return Real(cast.m_hitFraction); }, report);
}

}  // namespace boxtree::bullet
