// SPDX-License-Identifier: MIT
// Incremental convex hull (de Berg et al., Computational Geometry, 3rd ed., section 11.2, without
// the conflict graph): each new point removes the facets it sees and joins the horizon to itself.
#include "hull.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>

#include "boxtree/error.h"

namespace demo {

namespace {

using boxtree::Real;
using boxtree::Vec3;
using Facet = std::array<int, 3>;

// Positive when p is on the side of facet (a, b, c) that its counter-clockwise normal points to.
Real side(const std::vector<Vec3>& points, const Facet& f, const Vec3& p) {
  const Vec3 &a = points[f[0]], &b = points[f[1]], &c = points[f[2]];
  return (b - a).cross(c - a).dot(p - a);
}

}  // namespace

boxtree::TriangleMesh convex_hull(const std::vector<Vec3>& points) {
  const int n = int(points.size());
  Real extent = 0;
  for (const Vec3& p : points) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  // Volumes (side) below this are taken as coplanar: relative to the points' extent, cubed.
  const Real eps = 1e-12 * extent * extent * extent;
  // A first tetrahedron: points 0 and the next ones off the line, off the plane.
  int i1 = -1, i2 = -1, i3 = -1;
  for (int i = 1; i < n && i1 < 0; ++i)
    if ((points[i] - points[0]).norm() > 1e-9 * extent) i1 = i;
  for (int i = 1; i1 >= 0 && i < n && i2 < 0; ++i)
    if ((points[i1] - points[0]).cross(points[i] - points[0]).norm() > 1e-9 * extent * extent) i2 = i;
  for (int i = 1; i2 >= 0 && i < n && i3 < 0; ++i)
    if (std::abs(side(points, {0, i1, i2}, points[i])) > eps) i3 = i;
  if (i3 < 0) throw boxtree::Error("convex_hull: the points span no volume");
  std::vector<Facet> facets;
  if (side(points, {0, i1, i2}, points[i3]) > 0) std::swap(i1, i2);  // i3 behind facet (0, i1, i2)
  facets = {{0, i1, i2}, {0, i3, i1}, {i1, i3, i2}, {0, i2, i3}};
  for (int p = 1; p < n; ++p) {
    if (p == i1 || p == i2 || p == i3) continue;
    std::vector<Facet> kept;
    std::set<std::pair<int, int>> seen_edges;  // directed edges of the facets p sees
    for (const Facet& f : facets) {
      if (side(points, f, points[p]) > eps) {
        for (int k = 0; k < 3; ++k) seen_edges.insert({f[k], f[(k + 1) % 3]});
      } else {
        kept.push_back(f);
      }
    }
    if (seen_edges.empty()) continue;  // inside the hull
    // The horizon: edges of seen facets whose other facet is not seen; each joins p in its order.
    for (const auto& [a, b] : seen_edges)
      if (!seen_edges.count({b, a})) kept.push_back({a, b, p});
    facets = std::move(kept);
  }
  // Keep the corners only, renumbered in input order.
  std::vector<int> index(std::size_t(n), -1);
  boxtree::TriangleMesh mesh;
  for (const Facet& f : facets)
    for (int v : f) index[std::size_t(v)] = 0;
  for (int v = 0; v < n; ++v)
    if (index[std::size_t(v)] == 0) {
      index[std::size_t(v)] = int(mesh.vertices.size());
      mesh.vertices.push_back(points[std::size_t(v)]);
    }
  for (const Facet& f : facets)
    mesh.triangles.push_back({boxtree::VertexId(index[std::size_t(f[0])]), boxtree::VertexId(index[std::size_t(f[1])]),
                              boxtree::VertexId(index[std::size_t(f[2])])});
  return mesh;
}

}  // namespace demo
