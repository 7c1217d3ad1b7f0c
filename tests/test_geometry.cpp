// SPDX-License-Identifier: MIT
// Tests of the exact leaf tests (geometry.h) and of the out-of-line box tests of volume/aabb.h.
//
// Every overlap test is checked against an independent reference on thousands of fixed-seed
// random cases:
//  * where the answer is "do two convex sets meet", an exact linear program (is some convex
//    combination of the corners of one equal to one of the other?) solved in rational
//    arithmetic. Coordinates are small integers or halves, so touching, coplanar and degenerate
//    configurations occur often and both the reference and the code under test decide them
//    exactly. Rotations that are not exact in floating point (Pythagorean ones, random ones) are
//    checked outside a band: the reference is run with the box grown and shrunk by tau, and only
//    the cases that both agree on are asserted.
//  * where the answer is a distance, dense sampling: the sampled minimum is an upper bound of the
//    true distance and, by the 1-Lipschitz property, exceeds it by at most the sample spacing.
// BOXTREE_TEST_SCALE (a positive factor, default 1) scales the number of random cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "boxtree/geometry.h"
#include "support/exact.h"
#include "support/random.h"
#include "support/reference_geometry.h"

namespace boxtree {
namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kPi = 3.14159265358979323846;

std::string str(const Vec3& v) {
  return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + ")";
}

// ------------------------------------------------------------------------------------------
// Random data

// A triangle with small grid coordinates, degenerate (coincident or collinear corners) with
// probability `degenerate`.
std::array<Vec3, 3> grid_triangle(Random& rng, int lo, int hi, int denominator, Real degenerate) {
  std::array<Vec3, 3> t = {rng.grid_point(lo, hi, denominator), rng.grid_point(lo, hi, denominator),
                           rng.grid_point(lo, hi, denominator)};
  if (rng.chance(degenerate)) {
    switch (rng.integer(0, 3)) {
      case 0:
        t[2] = t[0];
        break;  // two corners coincide
      case 1:
        t[1] = t[0];
        t[2] = t[0];
        break;  // a point
      case 2:
        t[2] = t[0] + Real(2) * (t[1] - t[0]);
        break;  // collinear, c beyond b
      default:
        t[2] = t[0] + Real(0.5) * (t[1] - t[0]);
        break;  // collinear, c between
    }
    rng.shuffle(t.begin(), t.end());
  }
  return t;
}

std::vector<RPoint> exact_points(std::initializer_list<Vec3> points) {
  std::vector<RPoint> r;
  for (const Vec3& p : points) r.push_back(exact(p));
  return r;
}

// Corners of {center + r * s : |s_i| <= h_i}; h_i may be zero (duplicate corners are harmless).
std::vector<RPoint> box_corners(const RPoint& center, const RMat& r, const RPoint& h) {
  std::vector<RPoint> corners;
  for (int mask = 0; mask < 8; ++mask) {
    RPoint s;
    for (int k = 0; k < 3; ++k) s[k] = (mask >> k & 1) ? h[k] : -h[k];
    corners.push_back(plus(center, rotate(r, s)));
  }
  return corners;
}

RMat identity_rmat() {
  RMat m;
  for (int i = 0; i < 3; ++i) m[i][i] = 1;
  return m;
}

// Random signed permutation: a rotation or reflection that is exact in floating point and keeps
// every axis parallel to some axis of the other frame.
RMat signed_permutation(Random& rng) {
  std::array<int, 3> perm = {0, 1, 2};
  rng.shuffle(perm.begin(), perm.end());
  RMat m;
  for (int i = 0; i < 3; ++i) m[i][perm[i]] = rng.chance(0.5) ? 1 : -1;
  return m;
}

// Random rational rotation: one or two rotations by Pythagorean angles (cos, sin) = (3/5, 4/5),
// (5/13, 12/13), ... about coordinate axes, times a signed permutation. One factor leaves an axis
// pair exactly parallel; two give a general orientation.
RMat pythagorean_rotation(Random& rng) {
  static const int triples[][3] = {{3, 4, 5}, {4, 3, 5}, {5, 12, 13}, {12, 5, 13}, {8, 15, 17}};
  RMat m = signed_permutation(rng);
  const int factors = rng.integer(1, 2);
  int previous_axis = -1;
  for (int f = 0; f < factors; ++f) {
    int axis = rng.integer(0, 2);
    if (axis == previous_axis) axis = (axis + 1) % 3;
    previous_axis = axis;
    const int* tr = triples[rng.integer(0, 4)];
    const Rational c = Rational::of(tr[0], tr[2]);
    const Rational s = Rational::of(rng.chance(0.5) ? tr[1] : -tr[1], tr[2]);
    const int i = (axis + 1) % 3;
    const int j = (axis + 2) % 3;
    RMat g = identity_rmat();
    g[i][i] = c;
    g[i][j] = -s;
    g[j][i] = s;
    g[j][j] = c;
    m = multiply(m, g);
  }
  return m;
}

// ------------------------------------------------------------------------------------------
// Sampling references

// Points a + (i/n)(b - a) + (j/n)(c - a), i + j <= n. Every point of the triangle is within
// (longest edge)/n of one of them.
std::vector<Vec3> sample_triangle(const Vec3& a, const Vec3& b, const Vec3& c, int n) {
  std::vector<Vec3> s;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) s.push_back(a + (Real(i) / n) * (b - a) + (Real(j) / n) * (c - a));
  }
  return s;
}
Real longest_edge(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
}

// ==========================================================================================
// Ray / triangle

TEST(GeometryRayTriangle, HitReportsParameterAndBarycentrics) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  TriangleHit hit;
  const Ray ray{Vec3(1, 2, 5), Vec3(0, 0, -2), 0, kInf};  // not normalized: t in units of |d|
  ASSERT_TRUE(intersect_ray_triangle(ray, a, b, c, hit));
  EXPECT_DOUBLE_EQ(hit.t, 2.5);
  EXPECT_DOUBLE_EQ(hit.u, 0.25);
  EXPECT_DOUBLE_EQ(hit.v, 0.5);
  const Vec3 point = (1 - hit.u - hit.v) * a + hit.u * b + hit.v * c;
  EXPECT_LT((point - (ray.origin + hit.t * ray.direction)).norm(), 1e-12);
}

TEST(GeometryRayTriangle, TwoSided) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  TriangleHit up, down;
  ASSERT_TRUE(intersect_ray_triangle(Ray{Vec3(1, 1, -3), Vec3(0, 0, 1), 0, kInf}, a, b, c, up));
  ASSERT_TRUE(intersect_ray_triangle(Ray{Vec3(1, 1, 3), Vec3(0, 0, -1), 0, kInf}, a, b, c, down));
  EXPECT_DOUBLE_EQ(up.t, 3);
  EXPECT_DOUBLE_EQ(down.t, 3);
  EXPECT_DOUBLE_EQ(up.u, down.u);
  EXPECT_DOUBLE_EQ(up.v, down.v);
}

TEST(GeometryRayTriangle, EdgesAndCornersAreInclusive) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  const Vec3 targets[] = {a, b, c, Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(2, 2, 0), Vec3(1, 3, 0)};
  for (const Vec3& target : targets) {
    for (const Vec3& direction : {Vec3(0, 0, -1), Vec3(1, 1, -1), Vec3(-2, 1, -4), Vec3(0.5, 0, 1)}) {
      TriangleHit hit;
      const Ray ray{target - 2 * direction, direction, 0, kInf};
      ASSERT_TRUE(intersect_ray_triangle(ray, a, b, c, hit)) << str(target) << " " << str(direction);
      EXPECT_DOUBLE_EQ(hit.t, 2);
      EXPECT_GE(hit.u, 0);
      EXPECT_GE(hit.v, 0);
      EXPECT_LE(hit.u + hit.v, 1);
    }
  }
  TriangleHit hit;
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(2.0000001, 2, 1), Vec3(0, 0, -1), 0, kInf}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(-1e-300, 1, 1), Vec3(0, 0, -1), 0, kInf}, a, b, c, hit));
}

TEST(GeometryRayTriangle, ParameterRangeIsInclusive) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  const Vec3 origin(1, 1, 3);
  const Vec3 direction(0, 0, -0.5);  // hit at t = 6
  TriangleHit hit;
  EXPECT_TRUE(intersect_ray_triangle(Ray{origin, direction, 6, 6}, a, b, c, hit));
  EXPECT_TRUE(intersect_ray_triangle(Ray{origin, direction, 0, 6}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{origin, direction, 0, 5.999}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{origin, direction, 6.001, kInf}, a, b, c, hit));
  // Behind the origin: only with a negative t_min.
  EXPECT_FALSE(intersect_ray_triangle(Ray{origin, -direction, 0, kInf}, a, b, c, hit));
  ASSERT_TRUE(intersect_ray_triangle(Ray{origin, -direction, -kInf, kInf}, a, b, c, hit));
  EXPECT_DOUBLE_EQ(hit.t, -6);
  // A segment from p to q is Ray{p, q - p, 0, 1}.
  EXPECT_TRUE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3(0, 0, -1), 0, 1}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1.5), Vec3(0, 0, -1), 0, 1}, a, b, c, hit));
}

TEST(GeometryRayTriangle, RayInThePlaneMisses) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  TriangleHit hit;
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(-1, 1, 0), Vec3(1, 0, 0), 0, kInf}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(-1, -1, 0), Vec3(1, 1, 0), 0, kInf}, a, b, c, hit));
}

TEST(GeometryRayTriangle, DegenerateTrianglesAreNeverHit) {
  Random rng(11);
  for (int i = 0; i < scaled(2000); ++i) {
    const Vec3 a = rng.grid_point(-4, 4, 2);
    const Vec3 b = rng.grid_point(-4, 4, 2);
    const Vec3 tris[][3] = {{a, a, b}, {a, b, b}, {a, a, a}, {a, b, a + 3 * (b - a)}, {a, a + 0.5 * (b - a), b}};
    const Vec3 origin = rng.point(-6, 6);
    for (const auto& t : tris) {
      for (const Vec3& target : {t[0], t[1], t[2], Vec3(0.5 * (t[0] + t[2])), Vec3(0.25 * t[0] + 0.75 * t[1])}) {
        TriangleHit hit;
        EXPECT_FALSE(intersect_ray_triangle(Ray{origin, target - origin, -kInf, kInf}, t[0], t[1], t[2], hit));
      }
    }
  }
}

TEST(GeometryRayTriangle, InvalidInputNeverHitsNorCrashes) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  TriangleHit hit;
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3::Zero(), 0, kInf}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3(0, 0, kNaN), 0, kInf}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(kNaN, 1, 1), Vec3(0, 0, -1), 0, kInf}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3(0, 0, -1), kNaN, kNaN}, a, b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3(0, 0, -1), 0, kInf}, Vec3(kNaN, 0, 0), b, c, hit));
  EXPECT_FALSE(intersect_ray_triangle(Ray{Vec3(1, 1, 1), Vec3(0, 0, -1), 0, kInf}, Vec3(kInf, 0, 0), b, c, hit));
}

// Reference: Cramer's rule in long double on well-conditioned random cases, asserted only where
// the hit is decided with a margin.
TEST(GeometryRayTriangle, MatchesLinearSolveAwayFromEdges) {
  Random rng(12);
  int hits = 0;
  int misses = 0;
  for (int i = 0; i < scaled(20000); ++i) {
    const Vec3 a = rng.point(-2, 2), b = rng.point(-2, 2), c = rng.point(-2, 2);
    // Aimed at a point of the triangle's plane around it, with a random scale and range.
    const Vec3 origin = rng.point(-4, 4);
    const Real toward_c = rng.uniform(-0.3, 1.3);  // first: see tests/support/random.h
    const Vec3 aim = a + rng.uniform(-0.3, 1.3) * (b - a) + toward_c * (c - a);
    const Ray ray{origin, (aim - origin) * rng.uniform(0.2, 2), rng.uniform(-1, 0.5),
                  rng.chance(0.5) ? kInf : rng.uniform(0.5, 3)};
    using L = long double;
    const auto to_l = [](const Vec3& v) { return Eigen::Matrix<L, 3, 1>(v.x(), v.y(), v.z()); };
    Eigen::Matrix<L, 3, 3> m;
    m.col(0) = -to_l(ray.direction);
    m.col(1) = to_l(b - a);
    m.col(2) = to_l(c - a);
    const L det = m.determinant();
    if (std::abs(det) < 1e-3) continue;
    const Eigen::Matrix<L, 3, 1> x = m.inverse() * (to_l(ray.origin) - to_l(a));
    const L t = x[0], u = x[1], v = x[2];
    const L inside = std::min({u, v, 1 - u - v});
    const L in_range = std::min(t - ray.t_min, ray.t_max - t);
    TriangleHit hit;
    const bool got = intersect_ray_triangle(ray, a, b, c, hit);
    if (inside > 1e-9 && in_range > 1e-9) {
      ++hits;
      ASSERT_TRUE(got) << i;
      EXPECT_NEAR(hit.t, static_cast<Real>(t), 1e-9 * (1 + std::abs(static_cast<Real>(t))));
      EXPECT_NEAR(hit.u, static_cast<Real>(u), 1e-9);
      EXPECT_NEAR(hit.v, static_cast<Real>(v), 1e-9);
    } else if (inside < -1e-9 || in_range < -1e-9) {
      ++misses;
      ASSERT_FALSE(got) << i;
    }
  }
  EXPECT_GT(hits, scaled(20000) / 20);
  EXPECT_GT(misses, scaled(20000) / 20);
}

// --- Watertightness on closed meshes ---

struct Mesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> faces;
  Vec3 normal(int f) const {
    const auto& t = faces[f];
    return (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
  }
  // Orients every face so its normal points away from `inside` (valid for star-shaped meshes).
  void orient_outward(const Vec3& inside) {
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (normal(static_cast<int>(f)).dot(vertices[faces[f][0]] - inside) < 0) std::swap(faces[f][1], faces[f][2]);
    }
  }
  std::map<std::pair<int, int>, std::vector<int>> edge_faces() const {
    std::map<std::pair<int, int>, std::vector<int>> map;
    for (std::size_t f = 0; f < faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int i = faces[f][k], j = faces[f][(k + 1) % 3];
        map[{std::min(i, j), std::max(i, j)}].push_back(static_cast<int>(f));
      }
    }
    return map;
  }
  std::vector<std::vector<int>> vertex_faces() const {
    std::vector<std::vector<int>> star(vertices.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) star[faces[f][k]].push_back(static_cast<int>(f));
    }
    return star;
  }
  int count_hits(const Ray& ray) const {
    int hits = 0;
    for (const auto& t : faces) {
      TriangleHit hit;
      hits += intersect_ray_triangle(ray, vertices[t[0]], vertices[t[1]], vertices[t[2]], hit);
    }
    return hits;
  }
};

Mesh octahedron() {
  Mesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int x : {0, 1}) {
    for (int y : {2, 3}) {
      for (int z : {4, 5}) m.faces.push_back({x, y, z});
    }
  }
  m.orient_outward(Vec3::Zero());
  return m;
}

Mesh icosahedron() {
  const Real phi = (1 + std::sqrt(Real(5))) / 2;
  Mesh m;
  for (Real s : {-1.0, 1.0}) {
    for (Real t : {-1.0, 1.0}) {
      m.vertices.push_back({0, s, t * phi});
      m.vertices.push_back({s, t * phi, 0});
      m.vertices.push_back({t * phi, 0, s});
    }
  }
  const int n = static_cast<int>(m.vertices.size());
  const auto adjacent = [&](int i, int j) {
    return std::abs((m.vertices[i] - m.vertices[j]).squaredNorm() - 4) < 1e-9;
  };
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      for (int k = j + 1; k < n; ++k) {
        if (adjacent(i, j) && adjacent(j, k) && adjacent(k, i)) m.faces.push_back({i, j, k});
      }
    }
  }
  m.orient_outward(Vec3::Zero());
  return m;
}

// The surface of the cube [-n/2, n/2]^3 split into n x n quads per side, each cut along a random
// diagonal, every vertex then moved radially by a random factor: closed and star-shaped around
// the origin (each face covers exactly the cone its corners span), usually far from convex.
Mesh random_star_mesh(Random& rng, int n) {
  Mesh m;
  std::map<std::array<int, 3>, int> index;
  const auto vertex = [&](std::array<int, 3> lattice) {
    const auto it = index.find(lattice);
    if (it != index.end()) return it->second;
    const Vec3 p(lattice[0] - 0.5 * n, lattice[1] - 0.5 * n, lattice[2] - 0.5 * n);
    m.vertices.push_back(p * rng.uniform(0.6, 1.4));
    return index[lattice] = static_cast<int>(m.vertices.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side : {0, n}) {
      for (int u = 0; u < n; ++u) {
        for (int v = 0; v < n; ++v) {
          int q[4];
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> l;
            l[axis] = side;
            l[(axis + 1) % 3] = u + du[k];
            l[(axis + 2) % 3] = v + dv[k];
            q[k] = vertex(l);
          }
          if (rng.chance(0.5)) {
            m.faces.push_back({q[0], q[1], q[2]});
            m.faces.push_back({q[0], q[2], q[3]});
          } else {
            m.faces.push_back({q[0], q[1], q[3]});
            m.faces.push_back({q[1], q[2], q[3]});
          }
        }
      }
    }
  }
  // Orientation from the unmoved cube, where "away from the origin" is unambiguous; radial moves keep it.
  for (auto& f : m.faces) {
    const Vec3 a = m.vertices[f[0]].normalized(), b = m.vertices[f[1]].normalized(), c = m.vertices[f[2]].normalized();
    if ((b - a).cross(c - a).dot(a + b + c) < 0) std::swap(f[1], f[2]);
  }
  return m;
}

void check_closed(const Mesh& m) {
  for (const auto& [edge, faces] : m.edge_faces()) ASSERT_EQ(faces.size(), 2u) << edge.first << "-" << edge.second;
}

// A ray through a point of a shared edge or vertex where the surface is crossed (not grazed)
// must hit at least one of the facets around it: the watertightness of Woop et al.
void check_watertight_from(const Mesh& m, Random& rng, const Vec3& origin_center, Real origin_radius,
                           bool origin_inside, int rays, int& checked) {
  const auto edges = m.edge_faces();
  std::vector<std::pair<int, int>> edge_list;
  for (const auto& e : edges) edge_list.push_back(e.first);
  const auto star = m.vertex_faces();
  // Crossing: the direction is on the same side of every facet around the target, with margin.
  const auto crossing = [&](const Vec3& d, const std::vector<int>& faces) {
    if (origin_inside) return true;
    int front = 0, back = 0;
    for (int f : faces) {
      const Vec3 n = m.normal(f);
      const Real s = d.dot(n) / (d.norm() * n.norm());
      front += s < -1e-6;
      back += s > 1e-6;
    }
    return front == static_cast<int>(faces.size()) || back == static_cast<int>(faces.size());
  };
  for (int i = 0; i < rays; ++i) {
    const Vec3 direction = rng.unit_vector();  // first: see tests/support/random.h
    const Vec3 origin = origin_center + origin_radius * (origin_inside ? rng.uniform(0, 1) : 1.0) * direction;
    Vec3 target;
    std::vector<int> around;
    std::string what;
    if (rng.chance(0.3)) {
      const int v = rng.integer(0, static_cast<int>(m.vertices.size()) - 1);
      target = m.vertices[v];
      around = star[v];
      what = "vertex " + std::to_string(v);
    } else {
      const auto e = edge_list[rng.integer(0, static_cast<int>(edge_list.size()) - 1)];
      const Real s = rng.chance(0.3) ? 0.5 : rng.uniform(0, 1);
      target = m.vertices[e.first] + s * (m.vertices[e.second] - m.vertices[e.first]);
      around = edges.at(e);
      what = "edge " + std::to_string(e.first) + "-" + std::to_string(e.second);
    }
    // Scale the direction arbitrarily: t is in its units and the result must not care.
    const Vec3 d = (target - origin) * (rng.chance(0.5) ? 1.0 : rng.uniform(0.01, 100));
    if (!crossing(d, around)) continue;
    ++checked;
    ASSERT_GE(m.count_hits(Ray{origin, d, 0, kInf}), 1) << what << " from " << str(origin);
  }
}

TEST(GeometryRayTriangle, WatertightOnConvexPolyhedra) {
  Random rng(13);
  for (const Mesh& m : {octahedron(), icosahedron()}) {
    check_closed(m);
    int checked = 0;
    check_watertight_from(m, rng, Vec3::Zero(), 0.5, true, scaled(5000), checked);
    check_watertight_from(m, rng, Vec3::Zero(), 10, false, scaled(5000), checked);
    check_watertight_from(m, rng, Vec3(0.1, -0.2, 0.3), 1e6, false, scaled(2000), checked);
    EXPECT_GT(checked, scaled(6000));
    // Random rays from inside a closed convex mesh hit it at least once, at t >= 0.
    for (int i = 0; i < scaled(5000); ++i) {
      // Each product's right operand first: see tests/support/random.h.
      const Vec3 origin_direction = rng.unit_vector();
      const Vec3 origin = 0.5 * rng.uniform(0, 1) * origin_direction;
      const Real length = rng.uniform(0.001, 1000);
      const Ray ray{origin, rng.unit_vector() * length, 0, kInf};
      ASSERT_GE(m.count_hits(ray), 1);
    }
  }
}

TEST(GeometryRayTriangle, WatertightOnRandomStarShapedMeshes) {
  Random rng(14);
  for (int mesh = 0; mesh < scaled(20); ++mesh) {
    const Mesh m = random_star_mesh(rng, 1 + mesh % 5);
    check_closed(m);
    int checked = 0;
    // From the center every ray crosses the surface; from outside only where it is not grazing.
    check_watertight_from(m, rng, Vec3::Zero(), 0, true, 1000, checked);
    check_watertight_from(m, rng, Vec3::Zero(), 50, false, 1000, checked);
    EXPECT_GT(checked, 1000);
    for (int i = 0; i < 500; ++i) {
      ASSERT_GE(m.count_hits(Ray{Vec3::Zero(), rng.unit_vector(), 0, kInf}), 1);
    }
  }
}

// ==========================================================================================
// Triangle / triangle

bool tri_tri(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& q) {
  return triangles_intersect(p[0], p[1], p[2], q[0], q[1], q[2]);
}

TEST(GeometryTriangleTriangle, AnalyticCases) {
  const std::array<Vec3, 3> base = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  // Crossing: a vertical triangle piercing the base.
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(3, -2, 0.5)}));
  // Parallel planes.
  EXPECT_FALSE(tri_tri(base, {Vec3(0, 0, 1), Vec3(4, 0, 1), Vec3(0, 4, 1)}));
  // Touching at a single vertex (corner of one on the face of the other, and corner to corner).
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, 0), Vec3(1, 2, 3), Vec3(2, 1, 3)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(4, 0, 0), Vec3(5, 0, 3), Vec3(5, 1, 3)}));
  EXPECT_FALSE(tri_tri(base, {Vec3(1, 1, 1e-9), Vec3(1, 2, 3), Vec3(2, 1, 3)}));
  // Touching along an edge (folded away) and edge against edge crossing.
  EXPECT_TRUE(tri_tri(base, {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 0, 4)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(2, -1, 0), Vec3(2, 1, 0), Vec3(2, 0, 3)}));
  // An edge lying on the other's face, with the triangle standing on it.
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 1, 2)}));
  // Coplanar: overlapping, touching at an edge, at a corner, one inside the other, disjoint.
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, 0), Vec3(5, 1, 0), Vec3(1, 5, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(4, 0, 0), Vec3(0, 4, 0), Vec3(4, 4, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(4, 0, 0), Vec3(6, 0, 0), Vec3(6, 2, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}));
  EXPECT_TRUE(tri_tri({Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}, base));
  EXPECT_FALSE(tri_tri(base, {Vec3(3, 3, 0), Vec3(5, 3, 0), Vec3(3, 5, 0)}));
  EXPECT_FALSE(tri_tri(base, {Vec3(2.5, 2.5, 0), Vec3(5, 2.5, 0), Vec3(2.5, 5, 0)}));
  // Degenerate: a segment piercing, lying on, or missing the face; a point on and off the face;
  // two segments crossing and two collinear segments overlapping or not.
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, 1, 1)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(1, 1, 0), Vec3(3, 1, 0), Vec3(2, 1, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(-1, 2, 0), Vec3(5, 2, 0), Vec3(2, 2, 0)}));
  EXPECT_FALSE(tri_tri(base, {Vec3(3, 3, -1), Vec3(3, 3, 1), Vec3(3, 3, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(2, 2, 0), Vec3(2, 2, 0), Vec3(2, 2, 0)}));
  EXPECT_TRUE(tri_tri(base, {Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 0)}));
  EXPECT_FALSE(tri_tri(base, {Vec3(2, 2, 0.5), Vec3(2, 2, 0.5), Vec3(2, 2, 0.5)}));
  EXPECT_TRUE(tri_tri({Vec3(0, 0, 0), Vec3(2, 2, 2), Vec3(1, 1, 1)}, {Vec3(0, 2, 0), Vec3(2, 0, 2), Vec3(2, 0, 2)}));
  EXPECT_FALSE(tri_tri({Vec3(0, 0, 0), Vec3(2, 2, 2), Vec3(1, 1, 1)}, {Vec3(0, 2, 1), Vec3(2, 0, 2), Vec3(2, 0, 2)}));
  EXPECT_TRUE(tri_tri({Vec3(0, 0, 0), Vec3(2, 2, 2), Vec3(1, 1, 1)}, {Vec3(2, 2, 2), Vec3(3, 3, 3), Vec3(3, 3, 3)}));
  EXPECT_FALSE(tri_tri({Vec3(0, 0, 0), Vec3(2, 2, 2), Vec3(1, 1, 1)}, {Vec3(3, 3, 3), Vec3(4, 4, 4), Vec3(4, 4, 4)}));
}

// Permutation-invariant and symmetric; compared with the exact LP on many grid cases.
void check_tri_tri(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& q, int& positives, int& negatives,
                   int& failures) {
  const bool expected = hulls_intersect(exact_points({p[0], p[1], p[2]}), exact_points({q[0], q[1], q[2]}));
  (expected ? positives : negatives) += 1;
  const std::array<Vec3, 3> p2 = {p[1], p[2], p[0]}, p3 = {p[0], p[2], p[1]};
  const std::array<Vec3, 3> q2 = {q[2], q[0], q[1]}, q3 = {q[1], q[0], q[2]};
  const bool got[] = {tri_tri(p, q), tri_tri(q, p), tri_tri(p2, q3), tri_tri(q2, p3), tri_tri(p3, q2)};
  for (bool g : got) {
    if (g != expected && failures++ < 5) {
      ADD_FAILURE() << "expected " << expected << " for P = " << str(p[0]) << str(p[1]) << str(p[2])
                    << "  Q = " << str(q[0]) << str(q[1]) << str(q[2]);
    }
  }
}

TEST(GeometryTriangleTriangle, MatchesExactReferenceOnIntegerGrid) {
  Random rng(21);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(6000); ++i) {
    const auto second = grid_triangle(rng, -2, 2, 1, 0.2);  // the second first: see tests/support/random.h
    check_tri_tri(grid_triangle(rng, -2, 2, 1, 0.2), second, positives, negatives, failures);
  }
  EXPECT_GT(positives, scaled(6000) / 10);
  EXPECT_GT(negatives, scaled(6000) / 10);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryTriangleTriangle, MatchesExactReferenceWhenCoplanarOrSharingFeatures) {
  Random rng(22);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(6000); ++i) {
    // Both triangles in the plane o + i u + j v (small integer basis), or sharing a corner or edge.
    const Vec3 o = rng.grid_point(-1, 1), u = rng.grid_point(-1, 1), v = rng.grid_point(-1, 1);
    const auto in_plane = [&] {
      const int j = rng.integer(-2, 2);  // j first: see tests/support/random.h
      return Vec3(o + rng.integer(-2, 2) * u + j * v);
    };
    std::array<Vec3, 3> p, q;
    const int mode = rng.integer(0, 2);
    if (mode == 0) {
      p = {in_plane(), in_plane(), in_plane()};
      q = {in_plane(), in_plane(), in_plane()};
    } else {
      p = grid_triangle(rng, -2, 2, 1, 0.1);
      q = grid_triangle(rng, -2, 2, 1, 0.1);
      q[0] = p[rng.integer(0, 2)];
      if (mode == 2) q[1] = p[(rng.integer(0, 2))];
    }
    check_tri_tri(p, q, positives, negatives, failures);
  }
  EXPECT_GT(positives, scaled(6000) / 10);
  EXPECT_GT(negatives, scaled(6000) / 20);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryTriangleTriangle, MatchesExactReferenceOnFineDyadicGrid) {
  // Coordinates k/1024 in [-1, 1]: general position (few touching cases), and still every
  // orientation determinant is exact in double, so the answer must match exactly.
  Random rng(23);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(4000); ++i) {
    const auto second = grid_triangle(rng, -1, 1, 1024, 0.05);  // the second first: see tests/support/random.h
    check_tri_tri(grid_triangle(rng, -1, 1, 1024, 0.05), second, positives, negatives, failures);
  }
  EXPECT_GT(positives, scaled(4000) / 20);
  EXPECT_GT(negatives, scaled(4000) / 20);
  EXPECT_EQ(failures, 0);
}

// Non-dyadic coordinates, where the orientation determinants round: facets that share a corner
// or an edge (the same doubles) always meet, as do triangles with a corner put on the other's
// plane as nearly as rounding allows, exactly when the independent oracle of the brute-force
// tests (reference_geometry.h, exact expansions) says so. Before the signs were exact, 580 of the
// 3370 touching pairs of make_terrain(12, 12, 2, 10, 2) with itself were missed.
TEST(GeometryTriangleTriangle, TouchingIsExactForAnyCoordinates) {
  Random rng(24);
  int shared = 0, near_plane = 0, near_plane_meeting = 0, failures = 0;
  const auto expect = [&](const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& q, bool expected) {
    const std::array<Vec3, 3> p2 = {p[1], p[2], p[0]}, q2 = {q[2], q[1], q[0]};
    for (const bool got : {tri_tri(p, q), tri_tri(q, p), tri_tri(p2, q2), tri_tri(q2, p2)}) {
      if (got != expected && failures++ < 5) {
        std::ostringstream out;
        out.precision(17);
        for (const Vec3& v : {p[0], p[1], p[2], q[0], q[1], q[2]}) out << " (" << v.transpose() << ")";
        ADD_FAILURE() << "expected " << expected << " for P, Q =" << out.str();
      }
    }
  };
  for (int i = 0; i < scaled(4000); ++i) {
    const Vec3 offset = rng.point(-1e3, 1e3);
    const std::array<Vec3, 3> p = {offset + rng.point(-1, 1), offset + rng.point(-1, 1), offset + rng.point(-1, 1)};
    // Sharing one corner or one edge, folded to any side.
    std::array<Vec3, 3> q = {p[i % 3], offset + rng.point(-1, 1), offset + rng.point(-1, 1)};
    if (i % 2) q[1] = p[(i + 1) % 3];
    expect(p, q, true);
    ++shared;
    // A corner on p's plane (rounded): the oracle decides.
    const Real s = rng.uniform(-0.5, 1), t = rng.uniform(-0.5, 1);
    q[0] = p[0] + s * (p[1] - p[0]) + t * (p[2] - p[0]);
    q[1] = q[0] + rng.point(0.1, 1);
    q[2] = q[0] + rng.point(0.1, 1).cwiseProduct(Vec3(1, 1, -1));
    const bool meets = reference::triangles_meet(p, q);
    expect(p, q, meets);
    ++near_plane;
    near_plane_meeting += meets;
  }
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(shared, scaled(4000));
  EXPECT_GT(near_plane_meeting, near_plane / 20);
  EXPECT_LT(near_plane_meeting, near_plane - near_plane / 20);
}

TEST(GeometryTriangleTriangle, InvalidInputDoesNotCrash) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), n(kNaN, 0, 0), inf(kInf, 0, 0);
  (void)triangles_intersect(a, b, c, n, b, c);
  (void)triangles_intersect(a, b, n, a, b, c);
  (void)triangles_intersect(inf, b, c, a, b, c);
  SUCCEED();
}

// ==========================================================================================
// Triangle / box

TEST(GeometryTriangleAabb, AnalyticCases) {
  const Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(0.2, 0.2, 0.2), Vec3(0.3, 0.2, 0.2), Vec3(0.2, 0.3, 0.2), box));  // inside
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(-5, -5, 0.5), Vec3(5, -5, 0.5), Vec3(0, 10, 0.5), box));  // box inside
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(1, 1, 1), Vec3(2, 1, 1), Vec3(1, 2, 3), box));            // corner touch
  EXPECT_TRUE(
      triangle_overlaps_aabb(Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2), Aabb{Vec3(-1, -1, -1), Vec3(1, 1, 1)}));
  // Plane x + y + z = 3.5 misses the unit box's far corner (sum 3): only the normal axis tells.
  EXPECT_FALSE(triangle_overlaps_aabb(Vec3(3.5, 0, 0), Vec3(0, 3.5, 0), Vec3(0, 0, 3.5), box));
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(3, 0, 0), Vec3(0, 3, 0), Vec3(0, 0, 3), box));
  // Only an edge cross-product axis separates: a thin triangle passing diagonally near an edge.
  EXPECT_FALSE(triangle_overlaps_aabb(Vec3(2.2, 0, -5), Vec3(0, 2.2, -5), Vec3(1.1, 1.1, 5), box));
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(2, 0, -5), Vec3(0, 2, -5), Vec3(1, 1, 5), box));
  // Degenerate triangles: a segment through the box, a segment passing by, a point on a face.
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(-1, 0.5, 0.5), Vec3(2, 0.5, 0.5), Vec3(0.5, 0.5, 0.5), box));
  EXPECT_FALSE(triangle_overlaps_aabb(Vec3(-1, 1.5, 0.5), Vec3(1, 3.5, 0.5), Vec3(1, 3.5, 0.5), box));
  EXPECT_TRUE(
      triangle_overlaps_aabb(Vec3(-1, 1, 0.5), Vec3(1, 3, 0.5), Vec3(1, 3, 0.5), Aabb{Vec3(0, 0, 0), Vec3(1, 2, 1)}));
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(1, 0.5, 0.5), Vec3(1, 0.5, 0.5), Vec3(1, 0.5, 0.5), box));
  EXPECT_FALSE(triangle_overlaps_aabb(Vec3(1.5, 0.5, 0.5), Vec3(1.5, 0.5, 0.5), Vec3(1.5, 0.5, 0.5), box));
  // Flat box (a square) and empty box.
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(0.6, 0.5, 1),
                                     Aabb{Vec3(0, 0, 0), Vec3(1, 1, 0)}));
  EXPECT_FALSE(triangle_overlaps_aabb(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Aabb::empty()));
  // A corner on the boundary of a half-space, with heights that are not short dyadics: the box
  // clipped to the triangle's bounds touches it at that corner only (a facet of make_terrain(16,
  // 16, 2) that the half-space query x <= 50 used to miss).
  const Real inf = std::numeric_limits<Real>::infinity();
  EXPECT_TRUE(triangle_overlaps_aabb(Vec3(50, 0, 3.3369014553087006), Vec3(56.25, 0, 3.9260098344930077),
                                     Vec3(56.25, 6.25, 4.0246857479155578),
                                     Aabb{Vec3::Constant(-inf), Vec3(50, inf, inf)}));
}

TEST(GeometryTriangleAabb, MatchesExactReferenceOnHalfIntegerGrid) {
  Random rng(31);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(5000); ++i) {
    const auto t = grid_triangle(rng, -2, 3, 2, 0.25);
    Aabb box;
    box.min = rng.grid_point(-2, 2, 2);
    box.max = box.min;
    for (int k = 0; k < 3; ++k) box.max[k] += rng.chance(0.2) ? 0 : rng.grid(0, 3, 2);
    const RPoint half = exact(Vec3(0.5 * (box.max - box.min)));
    const bool expected = hulls_intersect(exact_points({t[0], t[1], t[2]}),
                                          box_corners(exact(Vec3(box.center())), identity_rmat(), half));
    (expected ? positives : negatives) += 1;
    if (triangle_overlaps_aabb(t[0], t[1], t[2], box) != expected && failures++ < 5) {
      ADD_FAILURE() << "expected " << expected << " for " << str(t[0]) << str(t[1]) << str(t[2]) << " box "
                    << str(box.min) << str(box.max);
    }
  }
  EXPECT_GT(positives, scaled(5000) / 10);
  EXPECT_GT(negatives, scaled(5000) / 10);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryTriangleObb, MatchesExactReferenceForAxisPermutations) {
  Random rng(32);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(4000); ++i) {
    const auto t = grid_triangle(rng, -3, 3, 2, 0.25);
    const RMat r = signed_permutation(rng);
    Obb box;
    box.center = rng.grid_point(-2, 2, 2);
    box.axes = to_double(r);
    for (int k = 0; k < 3; ++k) box.half_extents[k] = rng.chance(0.2) ? 0 : rng.grid(0, 2, 2);
    const bool expected =
        hulls_intersect(exact_points({t[0], t[1], t[2]}), box_corners(exact(box.center), r, exact(box.half_extents)));
    (expected ? positives : negatives) += 1;
    if (triangle_overlaps_obb(t[0], t[1], t[2], box) != expected && failures++ < 5) {
      ADD_FAILURE() << "expected " << expected << " at case " << i;
    }
  }
  EXPECT_GT(positives, scaled(4000) / 10);
  EXPECT_GT(negatives, scaled(4000) / 10);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryTriangleObb, MatchesExactReferenceUnderRandomRigidMotionOutsideBand) {
  // An exact grid scene (triangle + axis-aligned box), then the whole scene moved by a random
  // rigid motion. Asserted where the exact answer does not change when the box grows or shrinks
  // by tau (rounding of the motion is ~1e-15, far inside the band).
  Random rng(33);
  const Rational tau = Rational::of(1, 64);
  int asserted = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const auto t = grid_triangle(rng, -3, 3, 2, 0.25);
    const Vec3 center = rng.grid_point(-2, 2, 2);
    Vec3 half;
    for (int k = 0; k < 3; ++k) half[k] = rng.chance(0.2) ? 0 : rng.grid(0, 2, 2);
    const auto tri = exact_points({t[0], t[1], t[2]});
    RPoint grown = exact(half), shrunk = exact(half);
    bool can_shrink = true;
    for (int k = 0; k < 3; ++k) {
      grown[k] = grown[k] + tau;
      shrunk[k] = shrunk[k] - tau;
      can_shrink = can_shrink && shrunk[k].sign() >= 0;
    }
    const bool outer = hulls_intersect(tri, box_corners(exact(center), identity_rmat(), grown));
    const bool inner = can_shrink && hulls_intersect(tri, box_corners(exact(center), identity_rmat(), shrunk));
    if (outer && !inner) continue;
    ++asserted;
    const Mat3 q = rng.rotation();
    const Vec3 shift = rng.point(-100, 100);
    const Obb box{q * center + shift, q, half};
    EXPECT_EQ(triangle_overlaps_obb(q * t[0] + shift, q * t[1] + shift, q * t[2] + shift, box), inner) << i;
  }
  EXPECT_GT(asserted, scaled(3000) / 2);
}

// ==========================================================================================
// Triangle / plane

TEST(GeometryTrianglePlane, ClosedAndMatchesCornerSigns) {
  const Plane plane{Vec3(0, 0, 2), 2};  // z == 1, normal not unit length
  EXPECT_TRUE(triangle_crosses_plane(Vec3(0, 0, 0), Vec3(1, 0, 2), Vec3(0, 1, 0), plane));
  EXPECT_TRUE(triangle_crosses_plane(Vec3(0, 0, 1), Vec3(1, 0, 2), Vec3(0, 1, 2), plane));  // touching corner
  EXPECT_TRUE(triangle_crosses_plane(Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1), plane));  // in the plane
  EXPECT_FALSE(triangle_crosses_plane(Vec3(0, 0, 1.5), Vec3(1, 0, 2), Vec3(0, 1, 2), plane));
  EXPECT_FALSE(triangle_crosses_plane(Vec3(0, 0, 0), Vec3(1, 0, 0.5), Vec3(0, 1, 0.99), plane));
  Random rng(41);
  for (int i = 0; i < scaled(5000); ++i) {
    const auto t = grid_triangle(rng, -2, 2, 2, 0.2);
    const Plane p{rng.grid_point(-2, 2), static_cast<Real>(rng.integer(-3, 3))};
    int below = 0, above = 0, on = 0;
    for (const Vec3& v : t) {
      const Real s = p.normal.dot(v) - p.offset;  // exact on this grid
      below += s < 0;
      above += s > 0;
      on += s == 0;
    }
    EXPECT_EQ(triangle_crosses_plane(t[0], t[1], t[2], p), on > 0 || (below > 0 && above > 0));
  }
}

// ==========================================================================================
// Closest point, sphere, distances

TEST(GeometryClosestPoint, VoronoiRegions) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, -1, 3), a, b, c), a);
  EXPECT_EQ(closest_point_on_triangle(Vec3(5, -1, -3), a, b, c), b);
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, 6, 1), a, b, c), c);
  EXPECT_EQ(closest_point_on_triangle(Vec3(2, -3, 1), a, b, c), Vec3(2, 0, 0));
  EXPECT_EQ(closest_point_on_triangle(Vec3(-2, 1, 1), a, b, c), Vec3(0, 1, 0));
  EXPECT_TRUE(closest_point_on_triangle(Vec3(3, 3, 0), a, b, c).isApprox(Vec3(2, 2, 0)));
  EXPECT_TRUE(closest_point_on_triangle(Vec3(1, 1, -7), a, b, c).isApprox(Vec3(1, 1, 0)));
  EXPECT_EQ(closest_point_on_triangle(Vec3(1, 1, 0), a, b, c), Vec3(1, 1, 0));
}

TEST(GeometryClosestPoint, DegenerateTriangles) {
  const Vec3 a(0, 0, 0), b(2, 0, 0);
  // Coincident corners: a segment, in every order; all corners equal: a point.
  for (const auto& t : {std::array<Vec3, 3>{a, a, b}, {a, b, a}, {b, a, a}, {a, b, b}}) {
    EXPECT_EQ(closest_point_on_triangle(Vec3(1, 3, 0), t[0], t[1], t[2]), Vec3(1, 0, 0));
    EXPECT_EQ(closest_point_on_triangle(Vec3(-1, 3, 4), t[0], t[1], t[2]), a);
    EXPECT_EQ(closest_point_on_triangle(Vec3(7, 3, 0), t[0], t[1], t[2]), b);
  }
  EXPECT_EQ(closest_point_on_triangle(Vec3(5, 5, 5), a, a, a), a);
  // Collinear corners, the middle one in each position.
  const Vec3 m(1, 0, 0);
  for (const auto& t : {std::array<Vec3, 3>{a, m, b}, {m, a, b}, {a, b, m}}) {
    EXPECT_EQ(closest_point_on_triangle(Vec3(1.5, -2, 0), t[0], t[1], t[2]), Vec3(1.5, 0, 0));
    EXPECT_EQ(closest_point_on_triangle(Vec3(3, 1, 1), t[0], t[1], t[2]), b);
    EXPECT_EQ(closest_point_on_triangle(Vec3(-3, 1, 1), t[0], t[1], t[2]), a);
  }
  // A sliver (positive but tiny area): answer within its width of the segment answer.
  const Vec3 q = closest_point_on_triangle(Vec3(1, 0.5e-12, 1), a, b, Vec3(1, 1e-12, 0));
  EXPECT_NEAR(q.x(), 1, 1e-9);
  EXPECT_NEAR(q.y(), 0.5e-12, 1e-12);
  EXPECT_NEAR(q.z(), 0, 1e-12);
  for (const Real x : {kNaN, kInf}) {
    const Vec3 r = closest_point_on_triangle(Vec3(x, 0, 0), a, b, Vec3(0, 1, 0));
    (void)r;  // no crash; the value is meaningless
  }
}

// Optimality against dense samples, and "on the triangle" (degenerate triangles included).
TEST(GeometryClosestPoint, MatchesSamplingOnRandomTriangles) {
  Random rng(51);
  constexpr int kSubdivisions = 40;
  for (int i = 0; i < scaled(600); ++i) {
    std::array<Vec3, 3> t;
    if (rng.chance(0.2)) {
      t = grid_triangle(rng, -2, 2, 2, 1.0);  // degenerate
    } else if (rng.chance(0.2)) {
      t = {rng.point(-2, 2), rng.point(-2, 2), Vec3::Zero()};  // sliver
      const Vec3 off_line = rng.unit_vector();                 // first: see tests/support/random.h
      t[2] = t[0] + rng.uniform(-1, 2) * (t[1] - t[0]) + 1e-9 * off_line;
    } else {
      t = {rng.point(-2, 2), rng.point(-2, 2), rng.point(-2, 2)};
    }
    const auto samples = sample_triangle(t[0], t[1], t[2], kSubdivisions);
    const Real spacing = longest_edge(t[0], t[1], t[2]) / kSubdivisions;
    for (int j = 0; j < 5; ++j) {
      const Vec3 p = rng.point(-3, 3);
      const Vec3 q = closest_point_on_triangle(p, t[0], t[1], t[2]);
      Real sampled = kInf;
      for (const Vec3& s : samples) sampled = std::min(sampled, (s - p).norm());
      const Real got = (q - p).norm();
      ASSERT_LE(got, sampled + 1e-12) << i;
      ASSERT_GE(got, sampled - spacing - 1e-12) << i;
      // q is on the triangle: its own closest point is itself, and it is near some sample.
      Real to_samples = kInf;
      for (const Vec3& s : samples) to_samples = std::min(to_samples, (s - q).norm());
      ASSERT_LE(to_samples, spacing + 1e-12) << i;
      ASSERT_LE((closest_point_on_triangle(q, t[0], t[1], t[2]) - q).norm(), 1e-12 * (1 + sampled))
          << i << " " << str(t[0]) << str(t[1]) << str(t[2]) << " p " << str(p) << " q " << str(q);
      // Sphere overlap: sampled-overlap implies overlap; clear separation implies none.
      const Real radius = sampled * rng.uniform(0.9, 1.1);
      const bool overlap = triangle_overlaps_sphere(t[0], t[1], t[2], Sphere{p, radius});
      if (sampled <= radius) {
        ASSERT_TRUE(overlap) << i;
      }
      if (sampled - spacing > radius) {
        ASSERT_FALSE(overlap) << i;
      }
    }
  }
}

TEST(GeometrySphere, TouchingCountsAndSeparatedDoesNot) {
  const Vec3 a(0, 0, 0), b(4, 0, 0), c(0, 4, 0);
  EXPECT_TRUE(triangle_overlaps_sphere(a, b, c, Sphere{Vec3(1, 1, 2), 2}));
  EXPECT_FALSE(triangle_overlaps_sphere(a, b, c, Sphere{Vec3(1, 1, 2), 1.999}));
  EXPECT_TRUE(triangle_overlaps_sphere(a, b, c, Sphere{Vec3(-3, -4, 0), 5}));
  EXPECT_FALSE(triangle_overlaps_sphere(a, b, c, Sphere{Vec3(-3, -4, 0), 4.999}));
  EXPECT_TRUE(triangle_overlaps_sphere(a, b, c, Sphere{Vec3(1, 1, 0), 0}));  // point on the face
  EXPECT_TRUE(triangle_overlaps_sphere(a, a, b, Sphere{Vec3(2, 3, 0), 3}));  // degenerate
  EXPECT_FALSE(triangle_overlaps_sphere(a, a, b, Sphere{Vec3(2, 3, 0), 2.999}));
}

TEST(GeometrySegmentDistance, AnalyticCases) {
  const Vec3 o(0, 0, 0), x(2, 0, 0);
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(1, -1, 1), Vec3(1, 1, 1)), 1);  // crossing above
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(1, -1, 0), Vec3(1, 1, 0)), 0);  // crossing
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(3, 0, 0), Vec3(5, 0, 0)), 1);   // collinear, apart
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(1, 0, 0), Vec3(5, 0, 0)), 0);   // collinear, overlap
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(-1, 2, 0), Vec3(5, 2, 0)), 4);  // parallel
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(3, 3, 0), Vec3(5, 3, 0)), 10);  // parallel, apart
  EXPECT_EQ(segment_segment_distance_squared(o, x, Vec3(1, 3, 0), Vec3(1, 3, 0)), 9);   // zero length
  EXPECT_EQ(segment_segment_distance_squared(o, o, Vec3(1, 3, 0), Vec3(1, 3, 0)), 10);  // both
  EXPECT_EQ(segment_segment_distance_squared(Vec3(3, 1, 0), Vec3(3, 1, 0), o, x), 2);
  EXPECT_EQ(segment_segment_distance_squared(x, o, Vec3(4, 0, 0), Vec3(4, 1, 0)), 4);  // end to end
  // Nearly parallel segments crossing at x = 1: the cross-product form keeps this exact-ish.
  EXPECT_LT(segment_segment_distance_squared(o, x, Vec3(0, -1e-9, 0), Vec3(2, 1e-9, 0)), 1e-30);
  EXPECT_NEAR(segment_segment_distance_squared(o, x, Vec3(0, -1e-9, 1e-6), Vec3(2, 1e-9, 1e-6)), 1e-12, 1e-20);
}

TEST(GeometrySegmentDistance, MatchesSamplingOnRandomSegments) {
  Random rng(61);
  constexpr int kSamples = 200;
  for (int i = 0; i < scaled(400); ++i) {
    const Vec3 p0 = rng.point(-2, 2);
    const Vec3 p1 = rng.chance(0.1) ? p0 : rng.point(-2, 2);  // zero length sometimes
    const Vec3 q0 =
        rng.chance(0.1) ? Vec3(p0 + rng.uniform(-1, 2) * (p1 - p0)) : rng.point(-2, 2);  // collinear sometimes
    Vec3 q1 = rng.chance(0.1) ? q0 : rng.point(-2, 2);
    if (rng.chance(0.3)) q1 = q0 + rng.uniform(-2, 2) * (p1 - p0);  // parallel
    Real sampled = kInf;
    for (int s = 0; s < kSamples; ++s) {
      const Vec3 ps = p0 + (Real(s) / (kSamples - 1)) * (p1 - p0);
      for (int t = 0; t < kSamples; ++t) {
        sampled = std::min(sampled, (ps - (q0 + (Real(t) / (kSamples - 1)) * (q1 - q0))).norm());
      }
    }
    const Real spacing = 0.5 * ((p1 - p0).norm() + (q1 - q0).norm()) / (kSamples - 1);
    const Real got = std::sqrt(segment_segment_distance_squared(p0, p1, q0, q1));
    ASSERT_LE(got, sampled + 1e-12) << i;
    ASSERT_GE(got, sampled - spacing - 1e-12) << i;
    EXPECT_NEAR(got, std::sqrt(segment_segment_distance_squared(q1, q0, p0, p1)), 1e-12);
  }
}

TEST(GeometrySegmentTriangleDistance, ZeroExactlyWhenTheyMeet) {
  Random rng(71);
  int positives = 0, negatives = 0;
  for (int i = 0; i < scaled(5000); ++i) {
    const auto t = grid_triangle(rng, -2, 2, 1, 0.25);
    const Vec3 p0 = rng.grid_point(-2, 2);
    const Vec3 p1 = rng.chance(0.1) ? p0 : rng.grid_point(-2, 2);
    const bool meet = hulls_intersect(exact_points({p0, p1}), exact_points({t[0], t[1], t[2]}));
    (meet ? positives : negatives) += 1;
    const Real d2 = segment_triangle_distance_squared(p0, p1, t[0], t[1], t[2]);
    if (meet) {
      ASSERT_LE(d2, 1e-24) << i;
      ASSERT_TRUE(triangle_overlaps_capsule(t[0], t[1], t[2], Capsule{p0, p1, 0}));
    } else {
      ASSERT_GT(d2, 1e-6) << i;  // grid configurations that miss are far apart
    }
  }
  EXPECT_GT(positives, scaled(5000) / 10);
  EXPECT_GT(negatives, scaled(5000) / 10);
}

TEST(GeometrySegmentTriangleDistance, MatchesSamplingAndDrivesCapsuleTest) {
  Random rng(72);
  constexpr int kTriangleSubdivisions = 24;
  constexpr int kSegmentSamples = 64;
  for (int i = 0; i < scaled(400); ++i) {
    const auto t = rng.chance(0.2) ? grid_triangle(rng, -2, 2, 2, 1.0)
                                   : std::array<Vec3, 3>{rng.point(-2, 2), rng.point(-2, 2), rng.point(-2, 2)};
    const Vec3 p0 = rng.point(-3, 3);
    const Vec3 p1 = rng.chance(0.1) ? p0 : rng.point(-3, 3);
    const auto tri_samples = sample_triangle(t[0], t[1], t[2], kTriangleSubdivisions);
    Real sampled = kInf;
    for (int s = 0; s < kSegmentSamples; ++s) {
      const Vec3 ps = p0 + (Real(s) / (kSegmentSamples - 1)) * (p1 - p0);
      for (const Vec3& q : tri_samples) sampled = std::min(sampled, (ps - q).norm());
    }
    const Real spacing =
        longest_edge(t[0], t[1], t[2]) / kTriangleSubdivisions + 0.5 * (p1 - p0).norm() / (kSegmentSamples - 1);
    const Real got = std::sqrt(segment_triangle_distance_squared(p0, p1, t[0], t[1], t[2]));
    ASSERT_LE(got, sampled + 1e-12) << i;
    ASSERT_GE(got, sampled - spacing - 1e-12) << i;
    const Real radius = sampled * rng.uniform(0.8, 1.2);
    const bool overlap = triangle_overlaps_capsule(t[0], t[1], t[2], Capsule{p0, p1, radius});
    if (sampled <= radius) {
      ASSERT_TRUE(overlap) << i;
    }
    if (sampled - spacing > radius) {
      ASSERT_FALSE(overlap) << i;
    }
  }
}

// triangle_overlaps_capsule stops early and rejects by separating planes first (the triangle's
// own and its three edge walls); neither may change its answer from "the distance is within the
// radius", also when the capsule only just touches: radii at the distance to a few ulps, on
// random triangles, needles and segments seen from every side.
TEST(GeometrySegmentTriangleDistance, CapsuleTestIsTheDistanceAtTheRadius) {
  Random rng(73);
  int touching = 0, apart = 0;
  for (int i = 0; i < scaled(20000); ++i) {
    std::array<Vec3, 3> t;
    t[0] = rng.point(-2, 2);
    t[1] = rng.point(-2, 2);
    t[2] = rng.point(-2, 2);
    if (i % 7 == 0) {  // a needle
      const Real along = rng.uniform(0, 1);
      const Vec3 off = rng.point(-1e-7, 1e-7);
      t[2] = t[0] + (t[1] - t[0]) * along + off;
    }
    const Vec3 p0 = rng.point(-3, 3);
    const Vec3 p1 = rng.chance(0.1) ? p0 : rng.point(-3, 3);
    const Real distance = std::sqrt(segment_triangle_distance_squared(p0, p1, t[0], t[1], t[2]));
    const Real ulps = Real(rng.integer(-4, 4));
    const Real radius =
        i % 2 == 0 ? distance * (1 + ulps * std::numeric_limits<Real>::epsilon()) : distance * rng.uniform(0.5, 1.5);
    const bool expected = segment_triangle_distance_squared(p0, p1, t[0], t[1], t[2]) <= radius * radius;
    ASSERT_EQ(triangle_overlaps_capsule(t[0], t[1], t[2], Capsule{p0, p1, radius}), expected) << i;
    (expected ? touching : apart) += 1;
  }
  EXPECT_GT(touching, scaled(20000) / 5);
  EXPECT_GT(apart, scaled(20000) / 5);
}

// ==========================================================================================
// Box / box in two frames, box / OBB

TEST(GeometryBoxBox, AnalyticCases) {
  const Aabb unit{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  const Mat3 rz45 = Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix();
  // Touching faces, same orientation.
  EXPECT_TRUE(overlaps(unit, Obb{Vec3(2, 0, 0), Mat3::Identity(), Vec3(1, 1, 1)}));
  EXPECT_FALSE(overlaps(unit, Obb{Vec3(2.001, 0, 0), Mat3::Identity(), Vec3(1, 1, 1)}));
  // A diamond (rotated 45 degrees about z) touching with its vertical edge.
  const Real reach = 1 + std::sqrt(2.0);
  EXPECT_TRUE(overlaps(unit, Obb{Vec3(reach - 1e-9, 0, 0), rz45, Vec3(1, 1, 1)}));
  EXPECT_FALSE(overlaps(unit, Obb{Vec3(reach + 1e-9, 0, 0), rz45, Vec3(1, 1, 1)}));
  // Only an edge/edge axis separates: a thin rod along e = (1, -1, 1)/sqrt(3) passing the cube's
  // edge x = y = 1 at distance s - sqrt(2) along l = (1, 1, 0)/sqrt(2); its square cross-section,
  // turned 45 degrees about e, reaches 0.1 * sqrt(2) along l. No face axis separates at s = 1.6.
  {
    const Vec3 e = Vec3(1, -1, 1).normalized();
    const Vec3 l = Vec3(1, 1, 0).normalized();
    const Vec3 f = (l + e.cross(l)).normalized();
    Mat3 axes;
    axes << e, f, e.cross(f);
    const Vec3 half(10, 0.1, 0.1);
    EXPECT_TRUE(overlaps(unit, Obb{1.5 * l, axes, half}));
    EXPECT_TRUE(overlaps(unit, Obb{(std::sqrt(2.0) * 1.1 - 1e-9) * l, axes, half}));
    EXPECT_FALSE(overlaps(unit, Obb{(std::sqrt(2.0) * 1.1 + 1e-9) * l, axes, half}));
    EXPECT_FALSE(overlaps(unit, Obb{1.6 * l, axes, half}));
  }
  // Flat boxes: two unit squares in z = 0, one turned 45 degrees, touching corner to edge.
  const Aabb square{Vec3(-1, -1, 0), Vec3(1, 1, 0)};
  EXPECT_TRUE(overlaps(square, Obb{Vec3(1 + std::sqrt(2.0) - 1e-12, 0, 0), rz45, Vec3(1, 1, 0)}));
  EXPECT_FALSE(overlaps(square, Obb{Vec3(1 + std::sqrt(2.0) + 1e-9, 0, 0), rz45, Vec3(1, 1, 0)}));
  // Segments (flat in two axes) that are exactly parallel and collinear, overlapping or not.
  const Aabb segment{Vec3(0, 0, 0), Vec3(2, 0, 0)};
  EXPECT_TRUE(overlaps(segment, Obb{Vec3(2.5, 0, 0), Mat3::Identity(), Vec3(0.5, 0, 0)}));
  EXPECT_FALSE(overlaps(segment, Obb{Vec3(2.5, 0, 0), Mat3::Identity(), Vec3(0.4, 0, 0)}));
  // Empty box.
  EXPECT_FALSE(overlaps(Aabb::empty(), Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)}));
  EXPECT_FALSE(overlaps(Aabb::empty(), unit, RigidTransform::identity()));
  EXPECT_FALSE(overlaps(unit, Aabb::empty(), RigidTransform::identity()));
  // Two frames: b is a in a frame turned 90 degrees about z and shifted by 2 in x.
  RigidTransform a_from_b;
  a_from_b.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // x_a = -y_b + 3, y_a = x_b
  a_from_b.translation = Vec3(3, 0, 0);
  EXPECT_TRUE(overlaps(unit, Aabb{Vec3(-1, 1, -1), Vec3(1, 2, 1)}, a_from_b));       // x_a in [1, 2]
  EXPECT_FALSE(overlaps(unit, Aabb{Vec3(-1, 0.5, -1), Vec3(1, 1.9, 1)}, a_from_b));  // x_a in [1.1, 2.5]
  EXPECT_TRUE(overlaps(Aabb{Vec3(-1, 1, -1), Vec3(1, 2, 1)}, unit, a_from_b.inverse()));
}

struct BoxPair {
  Aabb a;
  RPoint b_center;  // in a's frame
  RMat b_axes;      // in a's frame
  RPoint b_half;
};

// A random pair of grid boxes (flat ones included), b turned by `r`.
BoxPair random_box_pair(Random& rng, const RMat& r) {
  BoxPair pair;
  pair.a.min = rng.grid_point(-2, 2, 2);
  pair.a.max = pair.a.min;
  for (int k = 0; k < 3; ++k) pair.a.max[k] += rng.chance(0.2) ? 0 : rng.grid(0, 2, 2);
  pair.b_center = exact(rng.grid_point(-1, 3, 2));
  pair.b_axes = r;
  for (int k = 0; k < 3; ++k) pair.b_half[k] = exact(rng.chance(0.2) ? 0.0 : rng.grid(0, 2, 2));
  return pair;
}

std::vector<RPoint> corners_of(const Aabb& box) {
  return box_corners(exact(Vec3(box.center())), identity_rmat(), exact(Vec3(0.5 * (box.max - box.min))));
}

// Both entry points on one pair: overlaps(Aabb, Obb) and overlaps(Aabb, Aabb, a_from_b) with b
// given in its own frame (centered at b_local), plus the reversed query with the inverse transform.
std::array<bool, 3> box_answers(const BoxPair& pair, Random& rng) {
  const Mat3 r = to_double(pair.b_axes);
  const Vec3 c = to_double(pair.b_center);
  const Vec3 h = to_double(pair.b_half);
  const bool obb = overlaps(pair.a, Obb{c, r, h});
  // b in its own frame: an Aabb around a random grid center; the translation puts it at c.
  const Vec3 b_local = rng.grid_point(-2, 2, 2);
  const Aabb b{b_local - h, b_local + h};
  RigidTransform a_from_b{r, c - r * b_local};
  const bool two_frames = overlaps(pair.a, b, a_from_b);
  const bool reversed = overlaps(b, pair.a, a_from_b.inverse());
  return {obb, two_frames, reversed};
}

TEST(GeometryBoxBox, MatchesExactReferenceForAxisPermutations) {
  Random rng(81);
  int positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const BoxPair pair = random_box_pair(rng, signed_permutation(rng));
    const bool expected = hulls_intersect(corners_of(pair.a), box_corners(pair.b_center, pair.b_axes, pair.b_half));
    (expected ? positives : negatives) += 1;
    for (bool got : box_answers(pair, rng)) {
      if (got != expected && failures++ < 5) ADD_FAILURE() << "expected " << expected << " at case " << i;
    }
  }
  EXPECT_GT(positives, scaled(3000) / 10);
  EXPECT_GT(negatives, scaled(3000) / 10);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryBoxBox, MatchesExactReferenceForRationalRotationsOutsideBand) {
  // Pythagorean rotations are exact for the reference but rounded for the code under test:
  // asserted where growing and shrinking b by tau does not change the exact answer.
  Random rng(82);
  const Rational tau = Rational::of(1, 256);
  int asserted = 0, failures = 0, cross_axis_only = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const BoxPair pair = random_box_pair(rng, pythagorean_rotation(rng));
    RPoint grown = pair.b_half, shrunk = pair.b_half;
    bool can_shrink = true;
    for (int k = 0; k < 3; ++k) {
      grown[k] = grown[k] + tau;
      shrunk[k] = shrunk[k] - tau;
      can_shrink = can_shrink && shrunk[k].sign() >= 0;
    }
    const bool outer = hulls_intersect(corners_of(pair.a), box_corners(pair.b_center, pair.b_axes, grown));
    const bool inner =
        can_shrink && hulls_intersect(corners_of(pair.a), box_corners(pair.b_center, pair.b_axes, shrunk));
    if (outer && !inner) continue;
    ++asserted;
    for (bool got : box_answers(pair, rng)) {
      if (got != inner && failures++ < 5) ADD_FAILURE() << "expected " << inner << " at case " << i;
    }
    if (!outer) {
      // Separated: count the cases that the six face axes alone would have missed, so that the
      // nine edge/edge axes are known to be exercised.
      const Mat3 r = to_double(pair.b_axes);
      const Vec3 t = to_double(pair.b_center) - pair.a.center();
      const Vec3 ha = 0.5 * (pair.a.max - pair.a.min), hb = to_double(pair.b_half);
      bool face_separated = false;
      for (int k = 0; k < 3; ++k) {
        face_separated |= std::abs(t[k]) > ha[k] + hb.dot(r.row(k).cwiseAbs());
        face_separated |= std::abs(t.dot(r.col(k))) > ha.dot(r.col(k).cwiseAbs()) + hb[k];
      }
      cross_axis_only += !face_separated;
    }
  }
  EXPECT_GT(asserted, scaled(3000) / 2);
  EXPECT_GT(cross_axis_only, 0);
  EXPECT_EQ(failures, 0);
}

TEST(GeometryBoxBox, RandomRotationsNeverMissAContainedCorner) {
  // Never a false "separated": any corner of one box inside the other means overlap.
  Random rng(83);
  for (int i = 0; i < scaled(5000); ++i) {
    const Aabb a{rng.point(-2, 0), rng.point(0, 2)};
    const Mat3 r = rng.rotation();
    const Vec3 extent = rng.point(0, 1);
    const Real flat_z = rng.chance(0.3) ? 0 : 1;  // z first: see tests/support/random.h
    const Real flat_x = rng.chance(0.3) ? 0 : 1;
    const Vec3 h = extent.cwiseProduct(Vec3(flat_x, 1, flat_z));
    const Vec3 corner_sign = vec3_z_first([&] { return rng.chance(0.5) ? 1 : -1; });
    const Vec3 corner = rng.point(-1.9, 1.9).cwiseMax(a.min).cwiseMin(a.max);  // a point of a
    const Vec3 center = corner - r * h.cwiseProduct(corner_sign);              // b's corner there
    ASSERT_TRUE(overlaps(a, Obb{center, r, h})) << i;
    const Aabb b{-h, h};
    ASSERT_TRUE(overlaps(a, b, RigidTransform{r, center})) << i;
    ASSERT_TRUE(overlaps(b, a, RigidTransform{r, center}.inverse())) << i;
  }
}

// ==========================================================================================
// Box / capsule, box / plane

TEST(GeometryAabbCapsule, AnalyticCases) {
  const Aabb box{Vec3(0, 0, 0), Vec3(10, 10, 10)};
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(5, 5, 5), Vec3(6, 6, 6), 0}));    // inside
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(-5, 5, 5), Vec3(15, 5, 5), 0}));  // through
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(12, 5, 5), Vec3(20, 5, 5), 2}));  // end touches a face
  EXPECT_FALSE(overlaps(box, Capsule{Vec3(12, 5, 5), Vec3(20, 5, 5), 1.999}));
  // Parallel to the edge x = 10, y = 10 at offset (3, 4): distance exactly 5.
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(13, 14, -3), Vec3(13, 14, 30), 5}));
  EXPECT_FALSE(overlaps(box, Capsule{Vec3(13, 14, -3), Vec3(13, 14, 30), 4.999999}));
  // Passing the vertical edge x = y = 10 diagonally: the segment's midpoint (11.5, 11.5) is
  // closest, at distance 1.5 * sqrt(2).
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(12, 11, 5), Vec3(11, 12, 5), 1.5 * std::sqrt(2.0) + 1e-12}));
  EXPECT_FALSE(overlaps(box, Capsule{Vec3(12, 11, 5), Vec3(11, 12, 5), 1.5 * std::sqrt(2.0) - 1e-9}));
  // A long diagonal capsule whose bounding box overlaps the box but which passes the corner
  // (10, 10) on the line x + y = 30, at distance 10 / sqrt(2).
  EXPECT_TRUE(overlaps(box, Capsule{Vec3(5, 25, 5), Vec3(25, 5, 5), 10 / std::sqrt(2.0) + 1e-9}));
  EXPECT_FALSE(overlaps(box, Capsule{Vec3(5, 25, 5), Vec3(25, 5, 5), 10 / std::sqrt(2.0) - 1e-9}));
  EXPECT_FALSE(overlaps(box, Capsule{Vec3(-10, 40, 5), Vec3(40, -10, 20), 1}));
  EXPECT_FALSE(overlaps(Aabb::empty(), Capsule{Vec3(0, 0, 0), Vec3(1, 1, 1), 100}));
  // Flat box and zero-length capsule (a sphere).
  EXPECT_TRUE(overlaps(Aabb{Vec3(0, 0, 0), Vec3(1, 1, 0)}, Capsule{Vec3(0.5, 0.5, 2), Vec3(0.5, 0.5, 2), 2}));
  EXPECT_FALSE(overlaps(Aabb{Vec3(0, 0, 0), Vec3(1, 1, 0)}, Capsule{Vec3(0.5, 0.5, 2), Vec3(0.5, 0.5, 2), 1.99}));
}

TEST(GeometryAabbCapsule, NeverMissesAndIsTightAgainstSampling) {
  Random rng(91);
  constexpr int kSamples = 2048;
  int positives = 0, negatives = 0;
  for (int i = 0; i < scaled(2000); ++i) {
    Aabb box{rng.point(-1, 0.5), Vec3::Zero()};
    box.max = box.min + rng.point(0, 1.5).cwiseProduct(Vec3(rng.chance(0.2) ? 0 : 1, 1, 1));
    const Vec3 p0 = rng.point(-3, 3);
    const Vec3 p1 = rng.chance(0.1) ? p0 : rng.point(-3, 3);
    Real sampled = kInf;
    for (int s = 0; s < kSamples; ++s) {
      const Vec3 p = p0 + (Real(s) / (kSamples - 1)) * (p1 - p0);
      sampled = std::min(sampled, (p.cwiseMax(box.min).cwiseMin(box.max) - p).norm());
    }
    const Real spacing = 0.5 * (p1 - p0).norm() / (kSamples - 1);
    const Real radius = sampled * rng.uniform(0.9, 1.1);
    const bool got = overlaps(box, Capsule{p0, p1, radius});
    (got ? positives : negatives) += 1;
    if (sampled <= radius) {
      ASSERT_TRUE(got) << i;
    }  // a sampled point of the axis is within r
    if (sampled - spacing > radius + 1e-9) {
      ASSERT_FALSE(got) << i;
    }
    // The capsule exactly touching at a sampled axis point.
    ASSERT_TRUE(overlaps(box, Capsule{p0, p1, sampled})) << i;
  }
  EXPECT_GT(positives, scaled(2000) / 5);
  EXPECT_GT(negatives, scaled(2000) / 5);
}

TEST(GeometryAabbPlane, ClosedAndMatchesCornerSigns) {
  const Aabb unit{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  EXPECT_TRUE(overlaps(unit, Plane{Vec3(1, 1, 1), 3}));  // through the far corner only
  EXPECT_FALSE(overlaps(unit, Plane{Vec3(1, 1, 1), 3.000001}));
  EXPECT_TRUE(overlaps(unit, Plane{Vec3(0, 0, -2), 0}));  // containing a face
  EXPECT_FALSE(overlaps(Aabb::empty(), Plane{Vec3(0, 0, 1), 0}));
  Random rng(92);
  for (int i = 0; i < scaled(5000); ++i) {
    Aabb box{rng.grid_point(-2, 2, 2), Vec3::Zero()};
    box.max = box.min;
    for (int k = 0; k < 3; ++k) box.max[k] += rng.chance(0.2) ? 0 : rng.grid(0, 2, 2);
    const Plane plane{rng.grid_point(-2, 2), rng.grid(-4, 4, 2)};
    int below = 0, above = 0, on = 0;
    for (int mask = 0; mask < 8; ++mask) {
      const Vec3 corner((mask & 1) ? box.max.x() : box.min.x(), (mask & 2) ? box.max.y() : box.min.y(),
                        (mask & 4) ? box.max.z() : box.min.z());
      const Real s = plane.signed_distance_scaled(corner);  // exact on this grid
      below += s < 0;
      above += s > 0;
      on += s == 0;
    }
    ASSERT_EQ(overlaps(box, plane), on > 0 || (below > 0 && above > 0)) << i;
  }
}

}  // namespace
}  // namespace boxtree
