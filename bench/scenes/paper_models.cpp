// SPDX-License-Identifier: MIT
#include "scenes/paper_models.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "boxtree/error.h"
#include "boxtree/generate.h"

namespace boxtree::scenes {

TriangleMesh convex_hull(const std::vector<Vec3>& points) {
  std::vector<coordT> coords;
  coords.reserve(points.size() * 3);
  for (const Vec3& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  qhT qh_storage;
  qhT* qh = &qh_storage;
  QHULL_LIB_CHECK
  qh_zero(qh, stderr);
  char options[] = "qhull Qt";  // Qt: triangulated output
  const int exit_code = qh_new_qhull(qh, 3, int(points.size()), coords.data(), False, options, nullptr, stderr);
  TriangleMesh mesh;
  if (exit_code == 0) {
    mesh.vertices = points;
    Vec3 interior = Vec3::Zero();
    for (const Vec3& p : points) interior += p;
    interior /= Real(points.size());
    facetT* facet;
    FORALLfacets {
      Triangle t{};
      int k = 0;
      vertexT *vertex, **vertexp;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) t[std::size_t(k)] = VertexId(qh_pointid(qh, vertex->point));
        ++k;
      }
      if (k != 3) continue;
      // Orient outward: the normal points away from the centroid of the point set.
      const Vec3 n = (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]);
      if (n.dot(points[t[0]] - interior) < 0) std::swap(t[1], t[2]);
      mesh.triangles.push_back(t);
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  if (exit_code != 0) throw Error("convex_hull: qhull failed with code " + std::to_string(exit_code));
  return mesh;
}

TriangleMesh random_sphere(int points, std::uint64_t seed, Real radius) {
  Random random(seed);
  std::vector<Vec3> p(static_cast<std::size_t>(points));
  for (Vec3& v : p) v = random.unit_vector() * radius;
  return convex_hull(p);
}

namespace {

// Comb dimensions: teeth 1 wide and 5 long every 3 units on a spine 1 thick, depth 2.
constexpr Real kToothWidth = 1, kToothLength = 5, kSpacing = 3, kSpine = 1, kDepth = 2;
constexpr int kTeeth = 6;
constexpr Real kWidth = (kTeeth - 1) * kSpacing + kToothWidth;  // 16
constexpr Real kLength = kSpine + kToothLength;                 // 6

// Extrudes a counter-clockwise polygon (with a triangulation of it) along z into a closed solid.
TriangleMesh extrude(const std::vector<Eigen::Vector2d>& polygon, const std::vector<Triangle>& cap, Real depth) {
  TriangleMesh mesh;
  const VertexId n = VertexId(polygon.size());
  for (const auto& p : polygon) mesh.vertices.emplace_back(p.x(), p.y(), 0);
  for (const auto& p : polygon) mesh.vertices.emplace_back(p.x(), p.y(), depth);
  for (const Triangle& t : cap) {
    mesh.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});  // top, facing +z
    mesh.triangles.push_back({t[0], t[2], t[1]});              // bottom, facing -z
  }
  for (VertexId i = 0; i < n; ++i) {
    const VertexId j = (i + 1) % n;
    mesh.triangles.push_back({i, j, j + n});
    mesh.triangles.push_back({i, j + n, i + n});
  }
  return mesh;
}

}  // namespace

// Polygon corners: P0 = (0,0), P1 = (W,0), the rightmost tooth (W,L), (W-w,L), (W-w,1), four
// middle teeth (a+w,1), (a+w,L), (a,L), (a,1) from right to left, the leftmost tooth (w,1),
// (w,L), (0,L). Triangulation (22 triangles, no extra points):
//   spine:  (P0, P1, t0) and the fan (P0, t_i, t_i+1) over the spine-top corners t0..t9;
//   the outer teeth with the spine ends as convex quads; each middle tooth as a rectangle.
TriangleMesh comb() {
  std::vector<Eigen::Vector2d> poly = {
      {0, 0}, {kWidth, 0}, {kWidth, kLength}, {kWidth - kToothWidth, kLength}, {kWidth - kToothWidth, kSpine}};
  std::vector<VertexId> spine_top = {4};
  std::vector<Triangle> cap = {{1, 2, 3}, {1, 3, 4}};
  for (int k = kTeeth - 2; k >= 1; --k) {
    const Real a = k * kSpacing;
    const VertexId first = VertexId(poly.size());
    poly.insert(poly.end(), {{a + kToothWidth, kSpine}, {a + kToothWidth, kLength}, {a, kLength}, {a, kSpine}});
    spine_top.insert(spine_top.end(), {first, first + 3});
    cap.push_back({first + 3, first, first + 1});
    cap.push_back({first + 3, first + 1, first + 2});
  }
  const VertexId last = VertexId(poly.size());
  poly.insert(poly.end(), {{kToothWidth, kSpine}, {kToothWidth, kLength}, {0, kLength}});
  spine_top.push_back(last);
  cap.push_back({0, last, last + 1});
  cap.push_back({0, last + 1, last + 2});
  cap.push_back({0, 1, spine_top.front()});
  for (std::size_t i = 0; i + 1 < spine_top.size(); ++i) cap.push_back({0, spine_top[i], spine_top[i + 1]});
  return extrude(poly, cap, kDepth);
}

TriangleMesh interleaved_comb(Real gap) {
  TriangleMesh mesh = comb();
  // Turned by 180 degrees about z (x -> -x, y -> -y keeps the orientation), then moved: its
  // teeth land halfway between the first comb's teeth (x gaps of (spacing - 2 width)/2 = 0.5),
  // `gap` above the first comb's spine, and its spine `gap` above the first comb's tooth tips.
  const Real tx = kWidth + kSpacing / 2, ty = kLength + kSpine + gap;
  for (Vec3& v : mesh.vertices) v = Vec3(tx - v.x(), ty - v.y(), v.z());
  return mesh;
}

namespace {
// Surface of revolution about z of a profile (r_i, z_i), closed by the two axis points.
TriangleMesh lathe(const std::vector<Eigen::Vector2d>& profile, int segments, Real z_bottom, Real z_top) {
  TriangleMesh mesh;
  const Real pi = std::acos(Real(-1));
  mesh.vertices.emplace_back(0, 0, z_bottom);
  for (const auto& p : profile)
    for (int s = 0; s < segments; ++s)
      mesh.vertices.emplace_back(p.x() * std::cos(2 * pi * s / segments), p.x() * std::sin(2 * pi * s / segments),
                                 p.y());
  mesh.vertices.emplace_back(0, 0, z_top);
  const VertexId top = VertexId(mesh.vertices.size() - 1);
  auto id = [&](std::size_t ring, int s) {
    return VertexId(1 + ring * std::size_t(segments) + std::size_t(s % segments));
  };
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back({0, id(0, s + 1), id(0, s)});
  for (std::size_t r = 0; r + 1 < profile.size(); ++r)
    for (int s = 0; s < segments; ++s) {
      mesh.triangles.push_back({id(r, s), id(r, s + 1), id(r + 1, s + 1)});
      mesh.triangles.push_back({id(r, s), id(r + 1, s + 1), id(r + 1, s)});
    }
  const std::size_t last = profile.size() - 1;
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back({id(last, s), id(last, s + 1), top});
  return mesh;
}
}  // namespace

TriangleMesh rook() {
  return lathe({{1.0, 0.0}, {1.0, 0.3}, {0.75, 0.5}, {0.55, 1.7}, {0.85, 2.1}, {0.85, 2.7}, {0.6, 2.7}, {0.6, 2.45}},
               16, 0.0, 2.45);
}

TriangleMesh banana() {
  // Rings of 16 vertices along a 100-degree arc of radius 4, thickest in the middle.
  const int rings = 16, segments = 16;
  const Real pi = std::acos(Real(-1));
  TriangleMesh mesh;
  std::vector<Vec3> centres;
  for (int r = 0; r < rings; ++r) {
    const Real s = Real(r) / (rings - 1);
    const Real angle = (-50 + 100 * s) * pi / 180;
    const Vec3 centre(4 * std::sin(angle), 4 * (1 - std::cos(angle)), 0);
    const Vec3 tangent(std::cos(angle), std::sin(angle), 0);
    const Vec3 normal(-std::sin(angle), std::cos(angle), 0);
    const Real radius = 0.15 + 0.45 * std::sin(pi * (0.08 + 0.84 * s));
    for (int k = 0; k < segments; ++k) {
      const Real phi = 2 * pi * k / segments;
      mesh.vertices.push_back(centre + radius * (std::cos(phi) * normal + std::sin(phi) * Vec3::UnitZ()));
    }
    centres.push_back(centre - (r == 0 ? 0.1 : r == rings - 1 ? -0.1 : 0.0) * tangent);
  }
  const VertexId cap0 = VertexId(mesh.vertices.size());
  mesh.vertices.push_back(centres.front());
  mesh.vertices.push_back(centres.back());
  auto id = [&](int r, int k) { return VertexId(r * segments + (k % segments)); };
  for (int r = 0; r + 1 < rings; ++r)
    for (int k = 0; k < segments; ++k) {
      mesh.triangles.push_back({id(r, k), id(r + 1, k), id(r + 1, k + 1)});
      mesh.triangles.push_back({id(r, k), id(r + 1, k + 1), id(r, k + 1)});
    }
  for (int k = 0; k < segments; ++k) {
    mesh.triangles.push_back({cap0, id(0, k + 1), id(0, k)});
    mesh.triangles.push_back({cap0 + 1, id(rings - 1, k), id(rings - 1, k + 1)});
  }
  return mesh;
}

}  // namespace boxtree::scenes
