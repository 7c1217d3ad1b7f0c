// SPDX-License-Identifier: MIT
#include "boxtree/active_edges.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "boxtree/geometry.h"
#include "internal.h"

namespace boxtree {
namespace {

// Welds vertices by exact position: id[v] is the smallest vertex index with the same position.
std::vector<VertexId> weld_by_position(const TriangleMesh& mesh) {
  std::vector<VertexId> order(mesh.vertices.size());
  for (VertexId v = 0; v < order.size(); ++v) order[v] = v;
  auto key = [&](VertexId v) {
    return std::make_tuple(mesh.vertices[v].x(), mesh.vertices[v].y(), mesh.vertices[v].z());
  };
  std::sort(order.begin(), order.end(),
            [&](VertexId p, VertexId q) { return std::make_pair(key(p), p) < std::make_pair(key(q), q); });
  std::vector<VertexId> id(mesh.vertices.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    id[order[i]] = (i > 0 && key(order[i]) == key(order[i - 1])) ? id[order[i - 1]] : order[i];
  return id;
}

Vec3 face_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

}  // namespace

std::vector<std::uint8_t> compute_active_edges(const TriangleMesh& mesh, Real crease_degrees,
                                               std::size_t* inconsistent_edges) {
  if (inconsistent_edges) *inconsistent_edges = 0;
  const std::vector<VertexId> id = weld_by_position(mesh);
  struct EdgeUse {
    VertexId lo, hi;
    FacetId facet;
    int k;
    bool operator<(const EdgeUse& o) const { return std::tie(lo, hi, facet, k) < std::tie(o.lo, o.hi, o.facet, o.k); }
  };
  std::vector<EdgeUse> uses;
  uses.reserve(mesh.triangles.size() * 3);
  for (FacetId f = 0; f < mesh.triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const VertexId p = id[mesh.triangles[f][k]], q = id[mesh.triangles[f][(k + 1) % 3]];
      if (p != q) uses.push_back({std::min(p, q), std::max(p, q), f, k});
    }
  }
  std::sort(uses.begin(), uses.end());
  // Every edge starts active; edges shared by exactly two facets that are flat or concave are
  // switched off.
  std::vector<std::uint8_t> active(mesh.triangles.size(), 0x7);
  const Real cos_crease = std::cos(crease_degrees * Real(3.14159265358979323846) / 180);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    if (j - i == 2) {
      const EdgeUse& e0 = uses[i];
      const EdgeUse& e1 = uses[i + 1];
      // Consistently wound neighbours run along the shared edge in opposite directions; an
      // inconsistent pair cannot be judged and stays active.
      const bool consistent = id[mesh.triangles[e0.facet][e0.k]] != id[mesh.triangles[e1.facet][e1.k]];
      if (!consistent && inconsistent_edges) ++*inconsistent_edges;
      const Vec3 n0 = face_normal(mesh.corner(e0.facet, 0), mesh.corner(e0.facet, 1), mesh.corner(e0.facet, 2));
      const Vec3 n1 = face_normal(mesh.corner(e1.facet, 0), mesh.corner(e1.facet, 1), mesh.corner(e1.facet, 2));
      const Real l0 = n0.norm(), l1 = n1.norm();
      if (l0 > 0 && l1 > 0) {
        // Convex if facet 1's far corner lies behind facet 0's plane (and vice versa, the same
        // for consistently wound neighbours).
        const Vec3& far1 = mesh.corner(e1.facet, (e1.k + 2) % 3);
        const Real side = n0.dot(far1 - mesh.corner(e0.facet, e0.k)) / l0;
        const bool flat = n0.dot(n1) / (l0 * l1) >= cos_crease;
        const bool concave = side > 0;
        if (consistent && (flat || concave)) {
          active[e0.facet] &= static_cast<std::uint8_t>(~(1u << e0.k));
          active[e1.facet] &= static_cast<std::uint8_t>(~(1u << e1.k));
        }
      }
    }
    i = j;
  }
  return active;
}

InternalEdgeCorrection::InternalEdgeCorrection(const Vec3& a, const Vec3& b, const Vec3& c, std::uint8_t active_edges)
    : corners_{&a, &b, &c}, active_edges_(active_edges) {
  if (active_edges == 0x7) return;
  Vec3 n = face_normal(a, b, c);
  const Real len = n.norm();
  if (!(len > 0)) return;
  normal_ = n / len;
  for (int k = 0; k < 3; ++k) {
    edges_[k] = *corners_[(k + 1) % 3] - *corners_[k];
    edge_squared_[k] = edges_[k].squaredNorm();
  }
  // The longest edge: sqrt is monotonic and correctly rounded, so this is the largest of the
  // three lengths to the bit, for one square root instead of three.
  scale_ = std::sqrt(std::max({edge_squared_[0], edge_squared_[1], edge_squared_[2]}));
  judged_ = true;
}

EdgeContact InternalEdgeCorrection::operator()(ContactPoint& contact) const {
  if (!judged_) return EdgeContact::keep;
  const Vec3& n = normal_;
  const Real cosine = std::abs(contact.normal.dot(n));
  if (cosine >= Real(1) - Real(1e-9)) return EdgeContact::keep;  // already the face normal
  // Which edges the contact's feature lies on, within a tolerance relative to the triangle's
  // size. The feature is the triangle's point closest to the shape's deepest point: for a
  // separated contact the routines' position may be anywhere on the touching patch, while the
  // closest point tells whether the shape is over this facet or beside it.
  const Vec3 feature = detail::closest_point_on_triangle_with_edges(
      contact.point_on_shape(), *corners_[0], *corners_[1], *corners_[2], edges_[0], edges_[1], edges_[2],
      edge_squared_[0], edge_squared_[1], edge_squared_[2]);
  // A penetrating shape's deepest point is inside the triangle by up to the depth: an edge
  // contact of a shape just crossing the edge still counts as on the edge.
  const Real tolerance = scale_ * Real(1e-6) + std::max(contact.depth, Real(0));
  int on_edges = 0;
  bool touches_active = false;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = *corners_[k];
    const Vec3& e = edges_[k];
    const Real t = std::clamp((feature - p).dot(e) / std::max(edge_squared_[k], Real(1e-300)), Real(0), Real(1));
    if ((p + t * e - feature).norm() <= tolerance) {
      ++on_edges;
      if (active_edges_ & (1u << k)) touches_active = true;
      // The verdict below is settled: on an active edge, or on an edge of a facet with none.
      if (touches_active || active_edges_ == 0) break;
    }
  }
  // Interior contacts keep their normal (it is a face contact of the shape, e.g. a box corner),
  // and so do contacts on any active edge.
  if (on_edges == 0 || touches_active) return EdgeContact::keep;
  // Nearly in the plane, the side is a matter of rounding and the contact is a side contact of
  // a shape over the neighbouring facet: that facet reports the contact that matters.
  if (cosine < Real(0.5)) return EdgeContact::discard;
  contact.normal = contact.normal.dot(n) < 0 ? Vec3(-n) : n;
  contact.depth *= cosine;  // the same separation, measured along the face normal
  return EdgeContact::corrected;
}

EdgeContact correct_internal_edge_contact(ContactPoint& contact, const Vec3& a, const Vec3& b, const Vec3& c,
                                          std::uint8_t active_edges) {
  return InternalEdgeCorrection(a, b, c, active_edges)(contact);
}

}  // namespace boxtree
