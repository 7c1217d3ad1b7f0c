// SPDX-License-Identifier: MIT
#include "boxtree/collider.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "boxtree/active_edges.h"
#include "boxtree/geometry.h"
#include "contact_cylinder.h"
#include "contact_polytope.h"
#include "internal.h"

namespace boxtree {
namespace {

// Steps 1-5 of collider.h for one query volume: `per_facet(a, b, c, options, out)` is the
// narrowphase for one triangle and returns how many contacts it wrote (at most `Capacity`). Under
// FacetTest::none it also makes the exact triangle test, and returns -1 for a facet that fails it
// (which is then no candidate).
template <int Capacity, class Query, class PerFacet>
void run_pipeline(const CollisionMesh& mesh, const Query& query, FacetTest test, const ContactRequest& request,
                  const ContactOptions& options, ContactResult& result, PerFacet&& per_facet) {
  const TriangleMesh& m = mesh.mesh();
  const std::vector<std::uint8_t>& active = mesh.active_edges();
  const std::size_t max_contacts = std::max<std::size_t>(request.max_contacts, 1);
  ContactPoint found[Capacity];
  mesh.tree().query_overlap(
      query,
      [&](FacetId facet) {
        const Vec3& a = m.corner(facet, 0);
        const Vec3& b = m.corner(facet, 1);
        const Vec3& c = m.corner(facet, 2);
        const int n = per_facet(a, b, c, options, found);
        if (n < 0) return true;
        ++result.counts.candidates;
        result.counts.found += std::size_t(n);
        if (n > 0) {
          const InternalEdgeCorrection correct_edge(a, b, c,
                                                    request.internal_edges ? active[facet] : std::uint8_t(0x7));
          for (int i = 0; i < n; ++i) {
            found[i].facet = facet;
            if (request.internal_edges) {
              const EdgeContact verdict = correct_edge(found[i]);
              if (verdict == EdgeContact::discard) {
                ++result.counts.edge_discarded;
                continue;  // beside this facet: its neighbour reports the real contact
              }
              if (verdict == EdgeContact::corrected) ++result.counts.edge_corrected;
            }
            result.contacts.push_back(found[i]);
          }
        }
        return !(request.early_stop && result.contacts.size() >= max_contacts);
      },
      nullptr, test);
}

// Step 5.
void reduce(const ContactRequest& request, ContactResult& result) {
  const std::size_t max_contacts = std::max<std::size_t>(request.max_contacts, 1);
  if (request.early_stop) {
    if (result.contacts.size() > max_contacts) {
      result.counts.dropped += result.contacts.size() - max_contacts;
      result.contacts.resize(max_contacts);
    }
    return;
  }
  const ReductionCounts counts = reduce_contacts(result.contacts, max_contacts, request.merge_distance);
  result.counts.merged += counts.merged;
  result.counts.dropped += counts.dropped;
}

// The options of the per-facet routines, with the mesh's fronts applied.
ContactOptions options_for(const CollisionMesh& mesh, const ContactRequest& request, ContactResult& result) {
  ContactOptions options;
  options.margin = request.margin;
  options.two_sided = request.two_sided || !mesh.consistent_winding();
  result.counts.two_sided_fallback = !request.two_sided && !mesh.consistent_winding();
  return options;
}

bool valid_request(const ContactRequest& request) { return request.margin >= 0 && request.merge_distance >= 0; }

// A box around a segment p0-p1 grown by `radius` sideways and along it.
Obb segment_box(const Vec3& p0, const Vec3& p1, Real radius_across, Real half_length_extra) {
  Obb box;
  const Vec3 axis = p1 - p0;
  const Real length = axis.norm();
  const Vec3 z = length > 0 ? Vec3(axis / length) : Vec3::UnitZ();
  Vec3 x, y;
  detail::orthonormal_completion(z, x, y);
  box.center = (p0 + p1) * Real(0.5);
  box.axes.col(0) = x;
  box.axes.col(1) = y;
  box.axes.col(2) = z;
  box.half_extents = Vec3(radius_across, radius_across, length / 2 + half_length_extra);
  return box;
}

// The oriented box of local points, placed, grown by `grow`.
Obb placed_box(const std::vector<Vec3>& local, const RigidTransform& mesh_from_local, Real grow) {
  Aabb box = Aabb::empty();
  for (const Vec3& p : local) box.expand(p);
  Obb placed;
  placed.center = mesh_from_local.apply(box.center());
  placed.axes = mesh_from_local.rotation;
  placed.half_extents = (box.extent() * Real(0.5)).array() + grow;
  return placed;
}

bool finite(const RigidTransform& t) { return t.rotation.allFinite() && t.translation.allFinite(); }

// An engine narrowphase's contacts, kept to the request's reach (depth >= -margin), as the
// analytic routines keep theirs: an engine may report farther (Bullet's GJK adds its manifold's
// breaking distance to the one it is given), and such contacts would take the places of nearer
// ones in the reduction, only to be thrown away by the engine afterwards.
int within_margin(ContactPoint* out, int n, Real margin) {
  int kept = 0;
  for (int i = 0; i < n; ++i)
    if (out[i].depth >= -margin) out[kept++] = out[i];
  return kept;
}

// Step 3 for an engine narrowphase: a contact whose normal points behind a one-sided facet is
// turned to the facet's front, at the depth the shape's deepest point along the front normal
// lies behind the facet's plane; a shape wholly in front gives none.
int apply_front(const SupportShape& shape, const Vec3& a, const Vec3& b, const Vec3& c, ContactPoint* out, int n) {
  const Vec3 front_scaled = (b - a).cross(c - a);
  const Real length = front_scaled.norm();
  if (!(length > 0)) return n;  // degenerate: no front, two-sided
  const Vec3 front = front_scaled / length;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (out[i].normal.dot(front) >= 0) {
      out[kept++] = out[i];
      continue;
    }
    const Vec3 deepest = shape.support(-front);
    const Real behind = (a - deepest).dot(front);
    if (behind < 0) continue;  // apart along the front normal: no contact from this side
    ContactPoint turned = out[i];
    turned.position = deepest + front * behind;
    turned.normal = front;
    turned.depth = behind;
    out[kept++] = turned;
  }
  return kept;
}

void collide_shape(const CollisionMesh& mesh, const Sphere& sphere, const ContactRequest& request,
                   ContactResult& result) {
  if (!is_valid(sphere) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  // The exact test is triangle_overlaps_sphere's on the grown sphere, and its closest point is
  // the narrowphase's.
  const Sphere query{sphere.center, sphere.radius + request.margin};
  run_pipeline<kMaxSphereTriangleContacts>(
      mesh, query, FacetTest::none, request, options, result,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        const Vec3 closest = closest_point_on_triangle(query.center, a, b, c);
        if (!((closest - query.center).squaredNorm() <= query.radius * query.radius)) return -1;
        return detail::contact_sphere_triangle_from(sphere, a, b, c, closest, o, out);
      });
  reduce(request, result);
}

void collide_shape(const CollisionMesh& mesh, const Obb& box, const ContactRequest& request, ContactResult& result) {
  if (!is_valid(box) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  Obb query = box;
  query.half_extents.array() += request.margin;
  const detail::BoxTriangleContacts contacts(box);  // contact_box_triangle, the box's polytope built once
  run_pipeline<kMaxBoxTriangleContacts>(mesh, query, FacetTest::exact_triangle, request, options, result, contacts);
  reduce(request, result);
}

void collide_shape(const CollisionMesh& mesh, const Capsule& capsule, const ContactRequest& request,
                   ContactResult& result) {
  if (!is_valid(capsule) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  // The exact test is triangle_overlaps_capsule's on the grown capsule (valid: the walk reaches no
  // facet otherwise), and the closest pairs it computes are the narrowphase's.
  const Capsule query{capsule.p0, capsule.p1, capsule.radius + request.margin};
  const detail::CapsuleAcross across(query);  // once per call, not per facet
  run_pipeline<kMaxCapsuleTriangleContacts>(
      mesh, query, FacetTest::none, request, options, result,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        detail::SegmentTrianglePair boundary;
        if (!detail::triangle_overlaps_capsule(a, b, c, query, across, boundary)) return -1;
        return detail::contact_capsule_triangle_from(capsule, a, b, c, boundary, o, out);
      });
  reduce(request, result);
}

void collide_shape(const CollisionMesh& mesh, const Cylinder& cylinder, const ContactRequest& request,
                   ContactResult& result) {
  if (!cylinder.p0.allFinite() || !cylinder.p1.allFinite() || !(cylinder.radius >= 0) ||
      !std::isfinite(cylinder.radius) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  const Obb query = segment_box(cylinder.p0, cylinder.p1, cylinder.radius + request.margin, request.margin);
  // contact_cylinder_triangle, the cylinder's axis and support set up once
  const detail::CylinderTriangleContacts contacts(cylinder.p0, cylinder.p1, cylinder.radius);
  run_pipeline<kMaxCylinderTriangleContacts>(mesh, query, FacetTest::exact_triangle, request, options, result,
                                             contacts);
  reduce(request, result);
}

void collide_shape(const CollisionMesh& mesh, const PlacedPolyhedron& hull, const ContactRequest& request,
                   ContactResult& result) {
  if (!finite(hull.mesh_from_local) || !(hull.rounding >= 0) || !std::isfinite(hull.rounding) ||
      !valid_request(request) || hull.local.vertices.empty()) {
    result.counts.invalid_input = true;
    return;
  }
  ContactOptions options = options_for(mesh, request, result);
  options.margin += hull.rounding;
  // The exact triangle test of the hull's box (its frame taken once per query, its face axes
  // first) is cheaper per leaf than the leaf boxes' 15-axis test against it, and passes fewer
  // facets to the narrowphase (in the drop scene 27.9 instead of 37.1 per call): every facet
  // within the margin of the hull meets its box grown by the margin.
  const Obb query = placed_box(hull.local.vertices, hull.mesh_from_local, hull.rounding + request.margin);
  // Each candidate triangle is taken into the hull's frame: three corners instead of the hull's
  // every vertex, face plane and edge (bench/RESULTS.md: ODE's hulls of 64 points on rough
  // terrain took 14-22% fewer instructions per call than with the hull moved once per call).
  run_pipeline<kMaxPolyhedronTriangleContacts>(
      mesh, query, FacetTest::exact_triangle, request, options, result,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        const int n = contact_polyhedron_triangle(hull.local, hull.mesh_from_local, a, b, c, o, out);
        for (int i = 0; i < n; ++i) out[i].depth += hull.rounding;
        return n;
      });
  reduce(request, result);
}

void collide_shape(const CollisionMesh& mesh, const PlacedPoints& hull, const ContactRequest& request,
                   ContactResult& result) {
  if (!finite(hull.mesh_from_local) || !valid_request(request) || hull.local.empty()) {
    result.counts.invalid_input = true;
    return;
  }
  thread_local std::vector<Vec3> points;
  points.resize(hull.local.size());
  Vec3 centroid = Vec3::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = hull.mesh_from_local.apply(hull.local[i]);
    centroid += points[i];
  }
  centroid /= Real(points.size());
  if (!centroid.allFinite()) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  auto support = [&](const Vec3& direction) { return support_points(points, direction); };
  const ConvexSupport shape{support, centroid, true};
  run_pipeline<kMaxConvexTriangleContacts>(
      mesh, placed_box(hull.local, hull.mesh_from_local, request.margin), FacetTest::exact_triangle, request, options,
      result, [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        return contact_convex_triangle(shape, a, b, c, o, out);
      });
  reduce(request, result);
}

}  // namespace

// ---- ConvexPairCache ----

namespace detail {

// The input of one collide_convex call as bytes: the placement (the shape's numbers in the mesh's
// frame, the request, a hull's address and sizes) and a hull's arrays; the mesh is the cache's
// tree_ (a call on another tree clears the cache). Built in per-thread storage, so that a warm
// call does not allocate.
struct ConvexPairCacheAccess {
  std::vector<unsigned char>& placement;
  std::vector<unsigned char>& hull;

  static ConvexPairCacheAccess scratch() {
    thread_local std::vector<unsigned char> placement_bytes, hull_bytes;
    placement_bytes.clear();
    hull_bytes.clear();
    return {placement_bytes, hull_bytes};
  }

  // The bytes of plain values: numbers, pointers, and Eigen's fixed-size vectors (their
  // coefficients) and aggregates of them. Padding bytes could only make equal inputs unequal (a
  // call that collides again), never the reverse.
  template <class T>
  static void append(std::vector<unsigned char>& bytes, const T& value) {
    static_assert(std::is_standard_layout_v<T>);
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  template <class T>
  static void append_array(std::vector<unsigned char>& bytes, const std::vector<T>& values) {
    static_assert(std::is_standard_layout_v<T>);
    append(bytes, values.size());
    const auto* p = reinterpret_cast<const unsigned char*>(values.data());
    bytes.insert(bytes.end(), p, p + values.size() * sizeof(T));
  }
  // Eigen's fixed-size vectors and matrices are their coefficients (no padding).
  void add(Real x) { append(placement, x); }
  void add(const Vec3& v) {
    for (int k = 0; k < 3; ++k) add(v[k]);
  }
  void add(const Mat3& m) {
    for (int k = 0; k < 9; ++k) add(m.data()[k]);
  }
  void add(const RigidTransform& t) {
    add(t.rotation);
    add(t.translation);
  }

  void add_request(const ContactRequest& request) {
    add(request.margin);
    append(placement, request.two_sided);
    append(placement, request.internal_edges);
    append(placement, request.max_contacts);
    add(request.merge_distance);
    append(placement, request.early_stop);
  }

  void add_shape(const Sphere& sphere) {
    append(placement, 's');
    add(sphere.center);
    add(sphere.radius);
  }
  void add_shape(const Obb& box) {
    append(placement, 'b');
    add(box.center);
    add(box.axes);
    add(box.half_extents);
  }
  void add_shape(const Capsule& capsule) {
    append(placement, 'c');
    add(capsule.p0);
    add(capsule.p1);
    add(capsule.radius);
  }
  void add_shape(const Cylinder& cylinder) {
    append(placement, 'y');
    add(cylinder.p0);
    add(cylinder.p1);
    add(cylinder.radius);
  }
  void add_shape(const PlacedPolyhedron& placed) {
    const ConvexPolyhedron& p = placed.local;
    append(placement, 'h');
    add(placed.mesh_from_local);
    add(placed.rounding);
    append(placement, &p);
    for (std::size_t size : {p.vertices.size(), p.faces.size(), p.loops.size(), p.edge_from.size()})
      append(placement, size);
  }
  void add_shape(const PlacedPoints& placed) {
    append(placement, 'p');
    add(placed.mesh_from_local);
    append(placement, &placed.local);
    append(placement, placed.local.size());
  }

  // A hull's arrays: every one the narrowphase reads (a polyhedron's columns too: they are read,
  // not recomputed). The other shapes are their placement.
  template <class Shape>
  static constexpr bool kHasHull = std::is_same_v<Shape, PlacedPolyhedron> || std::is_same_v<Shape, PlacedPoints>;
  template <class Shape>
  void add_hull(const Shape&) {}
  void add_hull(const PlacedPolyhedron& placed) {
    const ConvexPolyhedron& p = placed.local;
    append_array(hull, p.vertices);
    append_array(hull, p.faces);
    append_array(hull, p.face_width);
    append_array(hull, p.face_begin);
    append_array(hull, p.loops);
    append_array(hull, p.sides);
    append_array(hull, p.edge_from);
    append_array(hull, p.edge_to);
    append_array(hull, p.edge_direction);
    append_array(hull, p.edge_cone);
    append_array(hull, p.directions);
    append(hull, p.center);
    append(hull, p.size);
    append(hull, p.coord);
    append_array(hull, p.vertex_columns);
    append_array(hull, p.face_columns);
    append_array(hull, p.edge_columns);
  }
  void add_hull(const PlacedPoints& placed) { append_array(hull, placed.local); }

  // Where the shape lies, cheaply (equal inputs give equal boxes): only a call whose box is the
  // last call's builds and keeps its input.
  static Aabb shape_box(const Sphere& s, Real margin) {
    const Vec3 r = Vec3::Constant(s.radius + margin);
    return {s.center - r, s.center + r};
  }
  static Aabb shape_box(const Obb& box, Real margin) {
    return bounding_aabb(Obb{box.center, box.axes, (box.half_extents.array() + margin).matrix()});
  }
  static Aabb segment_shape_box(const Vec3& p0, const Vec3& p1, Real radius) {
    const Vec3 r = Vec3::Constant(radius);
    return {p0.cwiseMin(p1) - r, p0.cwiseMax(p1) + r};
  }
  static Aabb shape_box(const Capsule& c, Real margin) { return segment_shape_box(c.p0, c.p1, c.radius + margin); }
  static Aabb shape_box(const Cylinder& c, Real margin) { return segment_shape_box(c.p0, c.p1, c.radius + margin); }
  static Aabb placement_box(const RigidTransform& place) {
    return Aabb::from_points(place.translation, place.translation + place.rotation * Vec3(1, 2, 3));
  }
  static Aabb shape_box(const PlacedPolyhedron& hull, Real) { return placement_box(hull.mesh_from_local); }
  static Aabb shape_box(const PlacedPoints& hull, Real) { return placement_box(hull.mesh_from_local); }

  static bool same_bits(const Aabb& x, const Aabb& y) {
    return std::memcmp(x.min.data(), y.min.data(), 3 * sizeof(Real)) == 0 &&
           std::memcmp(x.max.data(), y.max.data(), 3 * sizeof(Real)) == 0;
  }

  // The call: the cache's contacts when its last input equals this one, else collide_shape and,
  // when the shape lies where it did, the input and contacts kept.
  template <class Shape>
  static void collide(ConvexPairCache* cache, const CollisionMesh& mesh, const Shape& shape,
                      const ContactRequest& request, ContactResult& result) {
    if (!cache) return collide_shape(mesh, shape, request, result);
    result.clear();
    ConvexPairCache& c = *cache;
    if (c.tree_.identity() != mesh.tree().identity()) {
      c.clear();
      c.tree_ = mesh.tree();
    }
    const Aabb box = shape_box(shape, request.margin);
    const bool still = !c.shape_box_.is_empty() && same_bits(box, c.shape_box_);
    c.shape_box_ = box;
    ConvexPairCacheAccess input = scratch();
    bool same_placement = false;
    if (still) {
      input.add_shape(shape);
      input.add_request(request);
      same_placement = c.placed_ && c.placement_ == input.placement;
      if (same_placement) input.add_hull(shape);
      if (same_placement && c.hull_copied_ && c.hull_ == input.hull) {
        result.contacts.assign(c.contacts_.begin(), c.contacts_.end());
        result.counts.reused = true;
        result.counts.two_sided_fallback = c.two_sided_fallback_;
        return;
      }
    }
    collide_shape(mesh, shape, request, result);
    if (result.counts.invalid_input) {
      c.clear();
      return;
    }
    c.placed_ = still;
    if (!still) return;
    c.placement_.swap(input.placement);
    // A hull's arrays are copied when its placement is the last call's: a body at rest.
    c.hull_copied_ = same_placement || !kHasHull<Shape>;
    c.hull_.swap(input.hull);
    c.contacts_.assign(result.contacts.begin(), result.contacts.end());
    c.two_sided_fallback_ = result.counts.two_sided_fallback;
  }
};

}  // namespace detail

void ConvexPairCache::clear() {
  tree_ = {};
  shape_box_ = Aabb::empty();
  placement_.clear();
  hull_.clear();
  placed_ = false;
  hull_copied_ = false;
  contacts_.clear();
  two_sided_fallback_ = false;
}

std::size_t ConvexPairCache::memory_bytes() const {
  return placement_.capacity() + hull_.capacity() + contacts_.capacity() * sizeof(ContactPoint);
}

void collide_convex(const CollisionMesh& mesh, const Sphere& sphere, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, sphere, request, result);
}
void collide_convex(const CollisionMesh& mesh, const Obb& box, const ContactRequest& request, ContactResult& result,
                    ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, box, request, result);
}
void collide_convex(const CollisionMesh& mesh, const Capsule& capsule, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, capsule, request, result);
}
void collide_convex(const CollisionMesh& mesh, const Cylinder& cylinder, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, cylinder, request, result);
}
void collide_convex(const CollisionMesh& mesh, const PlacedPolyhedron& hull, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, hull, request, result);
}
void collide_convex(const CollisionMesh& mesh, const PlacedPoints& hull, const ContactRequest& request,
                    ContactResult& result, ConvexPairCache* cache) {
  detail::ConvexPairCacheAccess::collide(cache, mesh, hull, request, result);
}

namespace {

// Whether the support shape and a facet are proved apart by more than `reach` (then no contact
// can come from it), along one of two axes: the direction from the middle of the shape's box to
// the facet's closest point (a distance search's first direction), and the facet's normal (the
// shape wholly above or below its plane). The first separates most facets that are near a shape
// but not under it, which the normal does not: around a hull resting on a rough terrain it
// halved the facets left to an engine's GJK (Bullet, bench/RESULTS.md), and it is tried first
// since it proves most of them (there 30.2k of 41.1k, against 10.9k by the normal), with one
// support call instead of the normal's two. It asks for a gap wider than `reach` by a millionth
// of the sizes, so that a facet whose distance an iterative narrowphase would put just within
// the reach is not dropped on rounding.
bool out_of_reach(const SupportShape& shape, const Vec3& a, const Vec3& b, const Vec3& c, Real reach) {
  const Vec3 normal = (b - a).cross(c - a);
  const Real length = normal.norm();
  if (!(length > 0)) return false;
  const Vec3& middle = shape.bounds.center;
  const Vec3 toward = closest_point_on_triangle(middle, a, b, c) - middle;
  const Real distance = toward.norm();
  if (distance > 0) {
    const Vec3 u = toward / distance;
    const Real slack = 1e-6 * (distance + shape.bounds.half_extents.maxCoeff() + reach);
    if (std::min({u.dot(a), u.dot(b), u.dot(c)}) - u.dot(shape.support(u)) > reach + slack) return true;
  }
  const Vec3 n = normal / length;
  const Real plane = n.dot(a);
  if (n.dot(shape.support(-n)) - plane > reach) return true;
  return plane - n.dot(shape.support(n)) > reach;
}

bool valid_support(const SupportShape& shape, const ContactRequest& request) {
  return shape.center.allFinite() && is_valid(shape.bounds) && valid_request(request);
}

}  // namespace

void collide_convex(const CollisionMesh& mesh, const SupportShape& shape, const ContactRequest& request,
                    ContactResult& result) {
  if (!valid_support(shape, request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  Obb query = shape.bounds;
  query.half_extents.array() += request.margin;
  const ConvexSupport convex{shape.support, shape.center, shape.polytope};
  run_pipeline<kMaxConvexTriangleContacts>(
      mesh, query, FacetTest::exact_triangle, request, options, result,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        if (out_of_reach(shape, a, b, c, o.margin)) return 0;
        return contact_convex_triangle(convex, a, b, c, o, out);
      });
  reduce(request, result);
}

void collide_convex(const CollisionMesh& mesh, const SupportShape& shape, TriangleNarrowphase narrowphase,
                    const ContactRequest& request, ContactResult& result) {
  if (!valid_support(shape, request)) {
    result.counts.invalid_input = true;
    return;
  }
  const ContactOptions options = options_for(mesh, request, result);
  ContactOptions engine_options = options;
  engine_options.two_sided = true;
  Obb query = shape.bounds;
  query.half_extents.array() += request.margin;
  run_pipeline<kMaxEngineTriangleContacts>(
      mesh, query, FacetTest::exact_triangle, request, options, result,
      [&](const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& o, ContactPoint* out) {
        if (out_of_reach(shape, a, b, c, o.margin)) return 0;
        const int n = within_margin(
            out, std::min(narrowphase(a, b, c, engine_options, out), kMaxEngineTriangleContacts), o.margin);
        return o.two_sided ? n : apply_front(shape, a, b, c, out, n);
      });
  reduce(request, result);
}

std::size_t ray_hits(const CollisionMesh& mesh, const Ray& ray, const RayHitsRequest& request,
                     std::vector<FacetHit>& hits) {
  hits.clear();
  const TriangleMesh& m = mesh.mesh();
  std::size_t candidates = 0;
  mesh.tree().ray_candidates(ray, [&](FacetId facet, Real t_max) -> Real {
    ++candidates;
    const Vec3& a = m.corner(facet, 0);
    const Vec3& b = m.corner(facet, 1);
    const Vec3& c = m.corner(facet, 2);
    Ray bounded = ray;
    bounded.t_max = t_max;
    TriangleHit hit;
    if (!intersect_ray_triangle(bounded, a, b, c, hit)) return t_max;
    // Front faces are those the ray enters against their counter-clockwise normal.
    if (request.cull_back_faces && (b - a).cross(c - a).dot(ray.direction) >= 0) return t_max;
    if (request.closest_only) {
      if (hits.empty() || hit.t < hits[0].t || (hit.t == hits[0].t && facet < hits[0].facet))
        hits.assign(1, {hit.t, facet});
      return hit.t;
    }
    hits.push_back({hit.t, facet});
    if (request.first_only) return Real(-1);  // below t_min: stops the walk
    return t_max;
  });
  std::sort(hits.begin(), hits.end(),
            [](const FacetHit& x, const FacetHit& y) { return x.t != y.t ? x.t < y.t : x.facet < y.facet; });
  return candidates;
}

std::size_t sweep_candidates(const CollisionMesh& mesh, const Vec3& from, const Vec3& to, const Vec3& half,
                             FunctionRef<Real()> hit_fraction, FunctionRef<void(FacetId)> visit) {
  const Vec3 motion = to - from;
  const Real length = motion.norm();
  if (!from.allFinite() || !to.allFinite() || !half.allFinite() || !(half.array() >= 0).all()) return 0;
  thread_local std::vector<std::pair<Real, FacetId>> candidates;
  candidates.clear();
  const Vec3 axis = length > 0 ? Vec3(motion / length) : Vec3::UnitX();
  const TriangleMesh& m = mesh.mesh();
  auto collect = [&](FacetId f) {
    Real start = std::numeric_limits<Real>::infinity();
    for (int k = 0; k < 3; ++k) start = std::min(start, (m.corner(f, k) - from).dot(axis));
    candidates.emplace_back(start, f);
    return true;
  };
  if (length > 0) {
    mesh.tree().query_overlap(swept_box(from, to, half), collect);
  } else {
    mesh.tree().query_overlap(Obb{from, Mat3::Identity(), half}, collect);
  }
  // Nearest first: the box's leading face reaches a facet starting at distance s along the motion
  // no earlier than fraction (s - reach) / length; once that exceeds the engine's closest hit, no
  // later candidate can be hit earlier.
  std::sort(candidates.begin(), candidates.end());
  const Real reach = axis.cwiseAbs().dot(half);
  std::size_t visited = 0;
  for (const auto& [start, f] : candidates) {
    if (length > 0 && (start - reach) / length > hit_fraction()) break;
    visit(f);
    ++visited;
  }
  return visited;
}

void collide_half_space(const CollisionMesh& mesh, const Plane& plane, const ContactRequest& request,
                        ContactResult& result) {
  if (!is_valid(plane) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  const Real length = plane.normal.norm();
  const Vec3 n = plane.normal / length;
  const Real offset = plane.offset / length;
  const Real margin = request.margin;
  const Aabb& bounds = mesh.bounds();
  const Vec3 center = bounds.center();
  const Real radius = bounds.extent().norm() * Real(0.5);
  const Real center_height = n.dot(center) - offset;
  if (center_height - radius > margin) return;  // the whole mesh is above the plane
  // The part of the bounds' sphere that can hold vertices below the plane: heights [lo, hi]
  // relative to it, as an oriented box along the normal.
  const Real lo = center_height - radius;
  const Real hi = std::min(margin, center_height + radius);
  Obb query;
  const Vec3 u = n.unitOrthogonal();
  query.axes.col(0) = u;
  query.axes.col(1) = n.cross(u);
  query.axes.col(2) = n;
  query.center = center + n * ((lo + hi) * Real(0.5) - center_height);
  query.half_extents = Vec3(radius, radius, (hi - lo) * Real(0.5));

  const TriangleMesh& m = mesh.mesh();
  thread_local std::vector<unsigned char> seen;  // vertex visited (shared by several facets)
  thread_local std::vector<VertexId> touched;
  if (seen.size() < m.vertices.size()) seen.assign(m.vertices.size(), 0);
  touched.clear();
  const std::size_t max_contacts = std::max<std::size_t>(request.max_contacts, 1);
  mesh.tree().query_overlap(
      query,
      [&](FacetId facet) {
        ++result.counts.candidates;
        for (int k = 0; k < 3; ++k) {
          const VertexId v = m.triangles[facet][k];
          if (seen[v]) continue;
          seen[v] = 1;
          touched.push_back(v);
          const Real height = n.dot(m.vertices[v]) - offset;
          if (height > margin) continue;
          ContactPoint c;
          c.position = m.vertices[v];
          c.normal = -n;
          c.depth = -height;
          c.facet = facet;
          ++result.counts.found;
          result.contacts.push_back(c);
        }
        return !(request.early_stop && result.contacts.size() >= max_contacts);
      },
      nullptr, FacetTest::leaf_volume);
  for (VertexId v : touched) seen[v] = 0;
  reduce(request, result);
}

void MeshPairCache::clear() {
  front_.clear();
  mine_ = {};
  theirs_ = {};
  pairs_.clear();
}

void collide_meshes(const CollisionMesh& mesh, const CollisionMesh& other, const RigidTransform& mesh_from_other,
                    const MeshContactRequest& request, ContactResult& result, MeshPairCache* cache) {
  if (!finite(mesh_from_other) || !valid_request(request)) {
    result.counts.invalid_input = true;
    return;
  }
  RigidTransform pose = mesh_from_other;
  if (!is_rotation(pose.rotation)) {
    // Engines' rotations drift from orthonormal (single-precision Bullet: ~1e-7); the walk needs
    // a rotation, so take the nearest one through its quaternion.
    Eigen::Quaternion<Real> q(pose.rotation);
    if (!(q.norm() > 0)) {
      result.counts.invalid_input = true;
      return;
    }
    pose.rotation = q.normalized().toRotationMatrix();
  }
  // Tree-vs-tree needs one volume kind: convert the other's tree (once, kept by that mesh), or
  // both to the packed aabb form when the other cannot be converted to this tree's form.
  const AnyTree* mine = &mesh.tree();
  const AnyTree* theirs = &other.tree();
  if (!mine->can_collide(*theirs)) {
    theirs = &other.tree_as(mesh.method());
    if (!mine->can_collide(*theirs)) {
      mine = &mesh.tree_as(Method{});
      theirs = &other.tree_as(Method{});
    }
  }

  ContactOptions options;
  options.margin = request.margin;
  options.two_sided = true;
  const FixedSurface fixed = request.static_mesh == StaticMesh::other  ? FixedSurface::a
                             : request.static_mesh == StaticMesh::mesh ? FixedSurface::b
                                                                       : FixedSurface::neither;
  const TriangleMesh& m = mesh.mesh();
  const TriangleMesh& o = other.mesh();
  const std::vector<std::uint8_t>& my_edges = mesh.active_edges();
  const std::vector<std::uint8_t>& their_edges = other.active_edges();
  const std::size_t max_contacts = std::max<std::size_t>(request.max_contacts, 1);
  ContactPoint found[std::max(kMaxTriangleTriangleContacts, kMaxTriangleFaceContacts)];
  // The contacts of one intersecting facet pair; false once early_stop has its contacts.
  const auto contacts_of = [&](const FacetPair& pair) {
    ++result.counts.candidates;
    // Triangle a of the routines is the other's, b is mine: normals from mine towards the other,
    // positions on mine.
    const Vec3 a0 = pose.apply(o.corner(pair.b, 0));
    const Vec3 a1 = pose.apply(o.corner(pair.b, 1));
    const Vec3 a2 = pose.apply(o.corner(pair.b, 2));
    const Vec3& b0 = m.corner(pair.a, 0);
    const Vec3& b1 = m.corner(pair.a, 1);
    const Vec3& b2 = m.corner(pair.a, 2);
    const bool faces = request.policy == MeshContactPolicy::face_normals;
    const int n = faces ? contact_triangle_faces(a0, a1, a2, b0, b1, b2, options, found, fixed)
                        : contact_triangle_triangle(a0, a1, a2, b0, b1, b2, options, found);
    result.counts.found += std::size_t(n);
    for (int i = 0; i < n; ++i) {
      ContactPoint& c = found[i];
      c.facet = pair.a;
      c.other_facet = pair.b;
      // Face normals need no edge correction; the least-penetration axis does, on my side (the
      // position is on my triangle), then on the other's: seen from its triangle the same
      // contact sits at the deepest point of mine with the opposite normal.
      if (request.internal_edges && !faces) {
        EdgeContact verdict = correct_internal_edge_contact(c, b0, b1, b2, my_edges[pair.a]);
        if (verdict == EdgeContact::keep) {
          ContactPoint flipped = c;
          flipped.position = c.point_on_shape();
          flipped.normal = -c.normal;
          verdict = correct_internal_edge_contact(flipped, a0, a1, a2, their_edges[pair.b]);
          if (verdict == EdgeContact::corrected) {
            c.normal = -flipped.normal;
            c.depth = flipped.depth;
            c.position = flipped.point_on_shape();
          }
        }
        if (verdict == EdgeContact::discard) {
          ++result.counts.edge_discarded;
          continue;
        }
        if (verdict == EdgeContact::corrected) ++result.counts.edge_corrected;
      }
      result.contacts.push_back(c);
    }
    return !(request.early_stop && result.contacts.size() >= max_contacts);
  };

  if (request.early_stop) {
    // Any contacts will do: taken as the walk finds them, and the walk stops at enough.
    if (cache) cache->clear();
    QueryStats stats;
    mine->collide(*theirs, pose, contacts_of, &stats);
    result.counts.volume_tests += stats.volume_tests;
    reduce(request, result);
    return;
  }
  // Every intersecting facet pair first, then their contacts in sorted order: the same contacts
  // whatever order the walk (fresh or from a front) found the pairs in.
  thread_local std::vector<FacetPair> scratch;
  std::vector<FacetPair>& pairs = cache ? cache->pairs_ : scratch;
  pairs.clear();
  const auto keep = [&](const FacetPair& pair) {
    pairs.push_back(pair);
    return true;
  };
  QueryStats stats;
  const bool coherent = cache && request.coherence && mine->packed() && theirs->packed();
  if (coherent) {
    if (cache->mine_.identity() != mine->identity() || cache->theirs_.identity() != theirs->identity()) {
      cache->front_.clear();
      cache->mine_ = *mine;
      cache->theirs_ = *theirs;
    }
    collide(*mine->packed(), *theirs->packed(), pose, cache->front_, keep, &stats);
  } else {
    if (cache) cache->clear();
    mine->collide(*theirs, pose, keep, &stats);
  }
  result.counts.volume_tests += stats.volume_tests;
  std::sort(pairs.begin(), pairs.end());
  for (const FacetPair& pair : pairs) contacts_of(pair);
  reduce(request, result);
}

}  // namespace boxtree
