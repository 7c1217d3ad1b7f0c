// SPDX-License-Identifier: MIT
// The packed pie-slice tree (packed_prism_tree.h): construction, and the queries, which are the
// generic walks of walks.h (those of Tree<V>) run over this form through PackedPrismView (below).
//
// Why every decoded prism holds its exact prism (and so every facet below it):
//  1. The exact prism E of a node (base b0 b1 b2, unit axis a, height h) is the convex hull of
//     its six corners, and the exact tree keeps every facet below the node inside E (its parent
//     rule encloses the children's corners with a margin; a leaf is its facet).
//  2. The stored prism D is E grown by a margin d: the base triangle's sides moved outward by d
//     in its plane (scaling about the incentre by 1 + d / inradius moves each side by exactly d),
//     the base lowered by d along a and the height raised by 2 d; then rounded to float. The
//     axis of D is not stored but recomputed as the unit normal of the rounded base, so it is
//     tilted from a by about (rounding error) / (the base's smallest altitude); the margin must
//     cover that tilt over the prism's size as well as the rounding itself.
//  3. Rather than bound all of that a priori, construction decodes D exactly as the queries do
//     (PackedPrismTree::prism) and checks in double that E's six corners lie strictly inside D
//     by D's own planes: on the inner side of its three side planes (through a base edge, along
//     D's axis) and within its axial range [max_k a.(d_k - d_0), min_k a.(d_k - d_0) + h],
//     each by 64 double ulps of the magnitudes involved (far above the check's own rounding).
//     A point that passes is p = x + t a with x in D's base triangle and t in [0, h]: in D.
//     If a corner fails, d doubles and the node is encoded again; the margin starts at one
//     float ulp of the node's coordinates, which many nodes need, and the loop ends because
//     the tilt error (~ rounding / altitude) shrinks as the grown triangle fattens while d
//     grows. A sliver base (tiny inradius: its offset corners would run far out) is also tried
//     as a thin isosceles triangle around its bounding rectangle; the smaller prism is kept.
//  4. D is convex and holds E's corners, so D contains E and every facet below the node. The
//     prism tests of volume/pie_slice.h never miss an overlap with the prism they are given, so
//     a walk over the decoded prisms reaches every leaf that the walk over Tree<PieSlice>
//     reaches (its prism tests are passed by a superset), and the leaf tests are identical
//     (the same prism_from_triangle, the same exact triangle tests).
#include "boxtree/packed_prism_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.h"
#include "walks.h"

namespace boxtree {

namespace {

constexpr Real kFloatEpsilon = std::numeric_limits<float>::epsilon();  // 2^-23
constexpr Real kCheckSlack = 64 * std::numeric_limits<Real>::epsilon();
// Doublings of the margin tried: for the side offset (up to 2^24 times four float ulps, far
// beyond any proper triangle's need), and for the triangle around the base's bounding rectangle.
constexpr int kOffsetSteps = 24;
constexpr int kFallbackSteps = 80;

// Are all `points` strictly inside `outer` (see step 3 at the top of the file)?
bool holds_strictly(const Prism& outer, const std::array<Vec3, 6>& points) {
  const Vec3& a = outer.axis;
  if (!a.allFinite() || !(outer.height >= 0)) return false;
  const Vec3& o = outer.base[0];
  const std::array<Vec3, 3> rel = {Vec3::Zero(), Vec3(outer.base[1] - o), Vec3(outer.base[2] - o)};
  Real reach = outer.height;
  Real cap_lo = -std::numeric_limits<Real>::infinity(), cap_hi = std::numeric_limits<Real>::infinity();
  for (const Vec3& r : rel) {
    reach = std::max(reach, r.cwiseAbs().maxCoeff() + outer.height);
    cap_lo = std::max(cap_lo, a.dot(r));
    cap_hi = std::min(cap_hi, a.dot(r) + outer.height);
  }
  std::array<Vec3, 3> side;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, opposite = (i + 2) % 3;
    side[i] = (rel[j] - rel[i]).cross(a);
    const Real inward = side[i].dot(rel[opposite] - rel[i]);
    if (!(inward != 0)) return false;  // a degenerate base holds nothing strictly
    if (inward > 0) side[i] = -side[i];
  }
  for (const Vec3& p : points) {
    const Vec3 r = p - o;
    const Real scale = r.cwiseAbs().maxCoeff() + reach;
    const Real s = a.dot(r);
    const Real axial_slack = kCheckSlack * a.cwiseAbs().sum() * scale;
    if (!(s >= cap_lo + axial_slack && s <= cap_hi - axial_slack)) return false;
    for (int i = 0; i < 3; ++i) {
      if (!(side[i].dot(r - rel[i]) <= -kCheckSlack * side[i].cwiseAbs().sum() * scale)) return false;
    }
  }
  return true;
}

// `base` with each side moved outward by d in its plane: scaled about its incentre (equally far,
// the inradius, from all three sides) by 1 + d / inradius. False for a degenerate triangle.
bool offset_sides(const std::array<Vec3, 3>& base, Real d, std::array<Vec3, 3>& out) {
  const Real opposite[3] = {(base[1] - base[2]).norm(), (base[2] - base[0]).norm(), (base[0] - base[1]).norm()};
  const Real perimeter = opposite[0] + opposite[1] + opposite[2];
  const Real twice_area = (base[1] - base[0]).cross(base[2] - base[0]).norm();
  if (!(perimeter > 0) || !(twice_area > 0)) return false;
  const Vec3 incentre = (opposite[0] * base[0] + opposite[1] * base[1] + opposite[2] * base[2]) / perimeter;
  const Real grow = 1 + d / (twice_area / perimeter);
  if (!std::isfinite(grow)) return false;
  for (int k = 0; k < 3; ++k) out[k] = incentre + grow * (base[k] - incentre);
  return true;
}

// The fallback for slivers: an isosceles triangle around the W x H bounding rectangle (grown by
// d) of `base` in the plane normal to `axis`, u along the base's longest edge, at the base's mean
// height along the axis. Its base side runs a past the rectangle at both ends and its apex is
// just high enough for the legs to pass over the rectangle's top corners:
//
//                   * apex (W/2, H (W/2 + a) / a)
//                 /   \   legs through the rectangle's top corners
//        (0, H) +-------+ (W, H)
//             / |       | \   perimeter about 2 W + 4 a + H^2 W / (2 a^2) for H << W,
//   (-a, 0) *---+-------+---* (W + a, 0)
//
// least for a = (H^2 W / 4)^(1/3): then for a flat rectangle barely more than the sliver's own,
// with an apex height (H W / 2a, much more than H) that keeps the rounded triangle's normal
// accurate.
std::array<Vec3, 3> around_rectangle(const std::array<Vec3, 3>& base, const Vec3& axis, Real d) {
  int longest = 0;
  for (int i = 1; i < 3; ++i) {
    if ((base[(i + 1) % 3] - base[i]).squaredNorm() > (base[(longest + 1) % 3] - base[longest]).squaredNorm())
      longest = i;
  }
  const Vec3 edge = base[(longest + 1) % 3] - base[longest];
  const Vec3 flat = edge - axis.dot(edge) * axis;
  Vec3 u, v;
  if (flat.norm() > 0 && std::isfinite(flat.norm())) {
    u = flat.normalized();
    v = axis.cross(u);
  } else {
    detail::orthonormal_completion(axis, u, v);
  }
  Real u_lo = 0, u_hi = 0, v_lo = 0, v_hi = 0, w = 0;
  for (const Vec3& b : base) {
    const Vec3 r = b - base[0];
    u_lo = std::min(u_lo, u.dot(r));
    u_hi = std::max(u_hi, u.dot(r));
    v_lo = std::min(v_lo, v.dot(r));
    v_hi = std::max(v_hi, v.dot(r));
    w += axis.dot(r) / 3;
  }
  const Real width = u_hi - u_lo + 2 * d, height = v_hi - v_lo + 2 * d;
  const Real a = std::cbrt(height * height * width / 4);
  const Vec3 corner = base[0] + u * (u_lo - d) + v * (v_lo - d) + axis * w;  // the rectangle's (0, 0)
  return {Vec3(corner - a * u), Vec3(corner + (width + a) * u),
          Vec3(corner + (width / 2) * u + (height * (width / 2 + a) / a) * v)};
}

// The node as it is in memory. GCC 12 at -O3 (its SLP vectorizer) folds double(float(x)) back
// to x when a node is written and decoded in one function, so a check of the decoded prism could
// pass on coordinates that are never stored; read through volatile, the stored floats are what
// the check decodes, exactly as the queries will.
PackedPrismTree::Node as_stored(const PackedPrismTree::Node& node) {
  const volatile PackedPrismTree::Node& memory = node;
  PackedPrismTree::Node copy{};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) copy.base[k][i] = memory.base[k][i];
  copy.height = memory.height;
  return copy;
}

// x as a float, rounded up.
float float_up(Real x) {
  float f = float(x);
  if (Real(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

std::optional<PackedPrismTree::Node> PackedPrismTree::encode_grown(const Prism& exact,
                                                                   const std::array<Vec3, 3>& grown_base, Real d,
                                                                   const std::array<Vec3, 6>& must_hold) const {
  Node node{};
  for (int k = 0; k < 3; ++k) {
    const Vec3 rel = (grown_base[k] - d * exact.axis - origin_) / unit_;
    for (int i = 0; i < 3; ++i) node.base[k][i] = float(rel[i]);
  }
  node.height = float_up((exact.height + 2 * d) / unit_);
  // The winding gives the axis its sign: counterclockwise about the exact axis.
  const auto corner = [&](int k) { return Vec3(node.base[k][0], node.base[k][1], node.base[k][2]); };
  const Real turn = (corner(1) - corner(0)).cross(corner(2) - corner(0)).dot(exact.axis);
  if (!(turn != 0)) return std::nullopt;
  if (turn < 0)
    for (int i = 0; i < 3; ++i) std::swap(node.base[1][i], node.base[2][i]);
  const Node stored = as_stored(node);
  if (!holds_strictly(prism(stored), must_hold)) return std::nullopt;
  return stored;
}

PackedPrismTree::Node PackedPrismTree::encode(const Prism& exact) const {
  const std::array<Vec3, 6> must_hold = corners(exact);
  Real magnitude = 0;
  for (const Vec3& c : must_hold) magnitude = std::max(magnitude, (c - origin_).cwiseAbs().maxCoeff());
  // Rounding to float moves a stored coordinate by at most 2^-24 of the largest one (relative to
  // the origin), a point by at most sqrt(3) 2^-24 of it: start at 2^-23 (one float ulp), with a
  // floor for a prism at the origin.
  const Real start = std::max(kFloatEpsilon * magnitude, std::ldexp(unit_, -60));
  // Two ways to grow the base, each with the least margin that passes; the smaller prism wins.
  // Offsetting the sides keeps the triangle's shape, the best for most nodes; but a sliver base
  // (an angle near 180 degrees, or two corners almost together: the fits make some) has a tiny
  // inradius, and moving its sides by d sends its corners far out. A thin triangle around its
  // bounding rectangle (around_rectangle) is then far smaller.
  std::optional<Node> best;
  Real best_area = std::numeric_limits<Real>::infinity();
  const auto keep_smaller = [&](const std::optional<Node>& node) {
    if (!node) return false;
    const Real area = surface_area(prism(*node));
    if (!best || area < best_area) {
      best = node;
      best_area = area;
    }
    return true;
  };
  for (int step = 0; step < kOffsetSteps; ++step) {
    const Real d = std::ldexp(start, step);
    std::array<Vec3, 3> grown;
    if (!offset_sides(exact.base, d, grown)) break;
    if (keep_smaller(encode_grown(exact, grown, d, must_hold))) break;
  }
  for (int step = 0; step < kFallbackSteps; ++step) {
    const Real d = std::ldexp(start, step);
    if (keep_smaller(encode_grown(exact, around_rectangle(exact.base, exact.axis, d), d, must_hold))) break;
  }
  BOXTREE_ASSERT(best.has_value(), "PackedPrismTree: no float prism holds the exact one (non-finite prism?)");
  return *best;
}

template <class V>
void PackedPrismTree::pack(const Tree<V>& tree) {
  if (tree.empty()) return;
  mesh_ = tree.shared_mesh();
  height_ = tree.height();
  // Coordinates relative to the centre of the root's box (which holds every node), in units of
  // a power of two at least half its size (so scaling is exact and stored values are below 1).
  const Aabb box = bounding_aabb(tree.volume(tree.root()));
  origin_ = box.center();
  const Real reach = (box.max - origin_).cwiseAbs().cwiseMax((box.min - origin_).cwiseAbs()).maxCoeff();
  unit_ = reach > 0 && std::isfinite(reach) ? std::ldexp(Real(1), std::ilogb(reach) + 1) : Real(1);
  if (tree.is_leaf(tree.root())) {
    root_link_ = kLeafFlag | tree.facet(tree.root());
    return;
  }
  root_link_ = 0;
  nodes_.reserve(tree.facet_count() - 1);
  // Depth first, preorder: a node's first inner child is the next node. Each pending entry is a
  // source node, its parent's packed index and which of the parent's links points to it.
  struct Pending {
    NodeIndex source;
    std::uint32_t parent;
    int slot;  // -1 for the root
  };
  std::vector<Pending> pending{{tree.root(), 0, -1}};
  while (!pending.empty()) {
    const Pending p = pending.back();
    pending.pop_back();
    const auto index = std::uint32_t(nodes_.size());
    if (p.slot >= 0) nodes_[p.parent].child[p.slot] = index;
    Node node = encode(tree.volume(p.source).prism);
    const NodeIndex first = tree.first_child(p.source);
    for (int k = 0; k < 2; ++k) {
      const NodeIndex c = first + NodeIndex(k);
      node.child[k] = tree.is_leaf(c) ? (kLeafFlag | tree.facet(c)) : 0;  // inner: set when laid out
    }
    nodes_.push_back(node);
    for (int k = 1; k >= 0; --k) {
      const NodeIndex c = first + NodeIndex(k);
      if (!tree.is_leaf(c)) pending.push_back({c, index, k});
    }
  }
}

template void PackedPrismTree::pack(const Tree<PieMax>&);
template void PackedPrismTree::pack(const Tree<PieMin>&);
template void PackedPrismTree::pack(const Tree<PieMaxGeneral>&);
template void PackedPrismTree::pack(const Tree<PieMinGeneral>&);

// ---- The queries: the generic walks (walks.h) over decoded prisms ----

namespace {

// How the walks see this form (the View of walks.h): a node is a link (kLeafFlag | facet, or an
// inner node's index); a leaf's volume is its facet's prism, rebuilt from the mesh.
struct PackedPrismView {
  using Node = std::uint32_t;
  const PackedPrismTree& tree;

  bool empty() const { return tree.empty(); }
  const TriangleMesh& mesh() const { return tree.mesh(); }
  Node root() const { return tree.root_link(); }
  static bool is_leaf(Node node) { return PackedPrismTree::is_leaf(node); }
  static FacetId facet(Node node) { return PackedPrismTree::facet(node); }
  std::array<Node, 2> children(Node inner) const {
    const PackedPrismTree::Node& node = tree.nodes()[inner];
    return {node.child[0], node.child[1]};
  }
  Prism volume(Node node) const { return tree.prism_of_link(node); }
};

using detail::all_hits_of;
using detail::candidates_of;
using detail::closest_hit_of;
using detail::overlap_of;
using detail::plane_of;

}  // namespace

std::optional<RayHit> ray_closest_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return closest_hit_of(PackedPrismView{tree}, ray, stats);
}

void ray_candidates(const PackedPrismTree& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats) {
  candidates_of(PackedPrismView{tree}, ray, visit, stats);
}

void ray_all_hits(const PackedPrismTree& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats) {
  all_hits_of(PackedPrismView{tree}, ray, visit, stats);
}

std::optional<RayHit> ray_any_hit(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::first_hit([&](auto visit) { ray_all_hits(tree, ray, visit, stats); });
}

std::vector<RayHit> ray_all_hits(const PackedPrismTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::collect_sorted<RayHit>([&](auto visit) { ray_all_hits(tree, ray, visit, stats); }, detail::nearer_hit);
}

template <class Shape>
void query_overlap(const PackedPrismTree& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                   FacetTest test) {
  overlap_of(PackedPrismView{tree}, shape, visit, stats, test);
}

template <class Shape>
std::vector<FacetId> query_overlap(const PackedPrismTree& tree, const Shape& shape, QueryStats* stats, FacetTest test) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_overlap<Shape>(tree, shape, visit, stats, test); });
}

void query_plane(const PackedPrismTree& tree, const Plane& plane, FunctionRef<bool(FacetId)> visit, QueryStats* stats) {
  plane_of(PackedPrismView{tree}, plane, visit, stats);
}

std::vector<FacetId> query_plane(const PackedPrismTree& tree, const Plane& plane, QueryStats* stats) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_plane(tree, plane, visit, stats); });
}

#define BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(S)                                                         \
  template void query_overlap<S>(const PackedPrismTree&, const S&, FunctionRef<bool(FacetId)>, QueryStats*, \
                                 FacetTest);                                                                \
  template std::vector<FacetId> query_overlap<S>(const PackedPrismTree&, const S&, QueryStats*, FacetTest);
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Aabb)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Obb)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Sphere)
BOXTREE_INSTANTIATE_PACKED_PRISM_OVERLAP(Capsule)

void collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  detail::collide_views(PackedPrismView{a}, PackedPrismView{b}, a_from_b, visit, stats, settings);
}

std::vector<FacetPair> collide(const PackedPrismTree& a, const PackedPrismTree& b, const RigidTransform& a_from_b,
                               QueryStats* stats, const CollideSettings& settings) {
  return detail::collect_sorted<FacetPair>([&](auto visit) { collide(a, b, a_from_b, visit, stats, settings); });
}

}  // namespace boxtree
