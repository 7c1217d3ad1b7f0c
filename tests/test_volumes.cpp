// SPDX-License-Identifier: MIT
// Tests of the oriented node volumes: oriented boxes (volume/obb.h, paper 3.2), pie slices
// (volume/pie_slice.h, paper 3.3) and the convex-polytope separating-axis test between them
// (volume/polytope.h). Suites: Volume* (fits, measures, queries), Sat* (separating axes).
//
// References, all independent of the code under test:
//  * "do two convex polytopes meet": an exact linear program (is a convex combination of one's
//    corners equal to one of the other's?) in rational arithmetic, on scenes whose coordinates
//    are small dyadics (boxes with signed-permutation axes, prisms with a coordinate axis as their
//    axis and arbitrary grid triangles as their base), so touching, coplanar, flat and degenerate
//    configurations are frequent and decided exactly by both sides. Float scenes (the same
//    scenes after a random rigid motion, or tilted by tiny angles) are asserted only outside a
//    band: where growing one polytope by a cube of half-size tau (Minkowski sum) and shrinking it
//    about its centroid give the same exact answer.
//  * containment: long-double coordinates in the volume's frame (boxes) or against its planes
//    (prisms), with a stated tolerance;
//  * distances (spheres, capsules): dense samples of the volume, whose minimum distance is an
//    upper bound of the true one and exceeds it by at most the samples' spacing;
//  * ray entry: bisection on the same long-double membership test;
//  * fit rules: the fit.h primitives they are defined by (principal axes of the child corners,
//    minimum-area rectangle / triangle of their projection), and brute force for the leaf
//    rectangle.
// Tolerances: fits contain their input by contains(v, p, 0) and, independently, to 1e-12 of the
// coordinates' magnitude; flat means thinner than 1e-12 of it (1e-14 for leaves); overlap tests
// are asserted exactly on exact scenes and outside a 1/64 band (or analytic 1e-6 gaps) on float
// ones; rays enter no later than the exact entry and no earlier than the entry into the volume
// grown by 1e-9 of its magnitude.
// BOXTREE_TEST_SCALE (a positive factor, default 1) scales the number of random cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "boxtree/detail/fit.h"
#include "boxtree/geometry.h"
#include "boxtree/volume/pie_slice.h"
#include "boxtree/volume/volume.h"
#include "support/exact.h"
#include "support/random.h"

namespace boxtree {

// Every oriented volume kind provides the whole set of volume operations (volume/volume.h).
static_assert(is_volume_v<ObbAll>, "ObbAll must provide every volume operation");
static_assert(is_volume_v<ObbMax>, "ObbMax must provide every volume operation");
static_assert(is_volume_v<ObbMin>, "ObbMin must provide every volume operation");
static_assert(is_volume_v<PieMax>, "PieMax must provide every volume operation");
static_assert(is_volume_v<PieMin>, "PieMin must provide every volume operation");
static_assert(is_volume_v<PieMaxGeneral>, "PieMaxGeneral must provide every volume operation");
static_assert(is_volume_v<PieMinGeneral>, "PieMinGeneral must provide every volume operation");

namespace {

using namespace test;
using test::Random;  // not boxtree::Random: the tests' conveniences (support/random.h)

constexpr Real kInf = std::numeric_limits<Real>::infinity();

std::string str(const Vec3& v) {
  return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + ")";
}

// ------------------------------------------------------------------------------------------
// Random data

// A triangle around `center` of size about `size`; degenerate (a point, a segment, collinear
// corners, a needle) with probability `degenerate`.
std::array<Vec3, 3> random_triangle(Random& rng, const Vec3& center, Real size, Real degenerate) {
  std::array<Vec3, 3> t = {center + size * rng.point(-1, 1), center + size * rng.point(-1, 1),
                           center + size * rng.point(-1, 1)};
  if (rng.chance(degenerate)) {
    switch (rng.integer(0, 4)) {
      case 0:
        t[1] = t[0];
        t[2] = t[0];
        break;  // a point
      case 1:
        t[2] = t[0];
        break;  // two corners coincide
      case 2:
        t[2] = t[0] + rng.uniform(-1, 2) * (t[1] - t[0]);
        break;  // collinear
      case 3:
        t[2] = t[0] + 0.5 * (t[1] - t[0]) + 1e-9 * size * rng.unit_vector();
        break;  // needle
      default:
        t[2] = t[0] + 0.3 * (t[1] - t[0]) + 1e-3 * size * rng.unit_vector();
        break;  // sliver
    }
  }
  return t;
}

// The Minkowski sum with the cube [-tau, tau]^3 (as the hull of the sums of corners).
std::vector<RPoint> grown(const std::vector<RPoint>& p, const Rational& tau) {
  std::vector<RPoint> out;
  for (const RPoint& x : p) {
    for (int mask = 0; mask < 8; ++mask) {
      RPoint y = x;
      for (int k = 0; k < 3; ++k) y[k] = (mask >> k & 1) ? y[k] + tau : y[k] - tau;
      out.push_back(y);
    }
  }
  return out;
}

// Scaled about the centroid by (1 - sigma).
std::vector<RPoint> shrunk(const std::vector<RPoint>& p, const Rational& sigma) {
  RPoint c;
  for (const RPoint& x : p) {
    for (int k = 0; k < 3; ++k) c[k] = c[k] + x[k];
  }
  const Rational inv = Rational::of(1, static_cast<long long>(p.size()));
  for (int k = 0; k < 3; ++k) c[k] = c[k] * inv;
  std::vector<RPoint> out;
  for (const RPoint& x : p) {
    RPoint y;
    for (int k = 0; k < 3; ++k) y[k] = c[k] + (x[k] - c[k]) * (Rational(1) - sigma);
    out.push_back(y);
  }
  return out;
}

// Random signed permutation with determinant +1: a rotation that is exact in floating point.
Mat3 signed_permutation(Random& rng) {
  std::array<int, 3> perm = {0, 1, 2};
  rng.shuffle(perm.begin(), perm.end());
  Mat3 m = Mat3::Zero();
  for (int i = 0; i < 3; ++i) m(i, perm[i]) = rng.chance(0.5) ? 1 : -1;
  if (m.determinant() < 0) m.col(0) = -m.col(0);
  return m;
}

// ------------------------------------------------------------------------------------------
// Exact scenes: boxes, oriented boxes with signed-permutation axes, axis-aligned prisms on
// arbitrary grid triangles. Half-integer coordinates; zero extents, flat and degenerate prisms
// are frequent.

struct ExactShape {
  enum Kind { kAabb, kObb, kPrism } kind = kAabb;
  Aabb aabb;
  Obb obb;
  Prism prism;
  std::vector<Vec3> corner_list;  // all exact dyadics

  ConvexPolytope polytope() const {
    switch (kind) {
      case kAabb:
        return polytope_of(aabb);
      case kObb:
        return polytope_of(obb);
      default:
        return polytope_of(prism);
    }
  }
  std::vector<RPoint> exact_corners() const {
    std::vector<RPoint> r;
    for (const Vec3& c : corner_list) r.push_back(exact(c));
    return r;
  }
  bool flat() const {
    switch (kind) {
      case kAabb:
        return (aabb.max - aabb.min).minCoeff() == 0;
      case kObb:
        return obb.half_extents.minCoeff() == 0;
      default:
        return prism.height == 0 || (prism.base[1] - prism.base[0]).cross(prism.base[2] - prism.base[0]).isZero(0);
    }
  }
};

Real half_or_zero(Random& rng, int hi, Real zero_chance) { return rng.chance(zero_chance) ? 0 : rng.grid(0, hi, 2); }

ExactShape random_exact_shape(Random& rng, ExactShape::Kind kind, int reach = 3) {
  ExactShape s;
  s.kind = kind;
  if (kind == ExactShape::kAabb) {
    s.aabb.min = rng.grid_point(-reach, reach, 2);
    s.aabb.max = s.aabb.min;
    for (int k = 0; k < 3; ++k) s.aabb.max[k] += half_or_zero(rng, 3, 0.25);
    for (const Vec3& c : polytope_of(s.aabb).vertices) s.corner_list.push_back(c);
  } else if (kind == ExactShape::kObb) {
    s.obb.center = rng.grid_point(-reach, reach, 2);
    s.obb.axes = signed_permutation(rng);
    for (int k = 0; k < 3; ++k) s.obb.half_extents[k] = half_or_zero(rng, 2, 0.25);
    for (const Vec3& c : corners(s.obb)) s.corner_list.push_back(c);
  } else {
    const int k = rng.integer(0, 2);
    const Real level = rng.grid(-reach, reach, 2);
    std::array<Vec3, 3> base;
    for (Vec3& b : base) {
      b = rng.grid_point(-reach, reach, 2);
      b[k] = level;
    }
    if (rng.chance(0.25)) {
      switch (rng.integer(0, 2)) {
        case 0:
          base[1] = base[0];
          base[2] = base[0];
          break;  // a point
        case 1:
          base[2] = base[1];
          break;  // a segment
        default:
          base[2] = base[0] + Real(2) * (base[1] - base[0]);
          break;  // collinear
      }
    }
    s.prism.base = base;
    s.prism.axis = Vec3::Unit(k) * (rng.chance(0.5) ? 1 : -1);
    s.prism.height = half_or_zero(rng, 3, 0.3);
    for (const Vec3& c : corners(s.prism)) s.corner_list.push_back(c);
  }
  return s;
}

ExactShape random_exact_shape(Random& rng) {
  const int kind = rng.integer(0, 4);  // prisms twice as often: they have the general axes
  return random_exact_shape(rng, kind == 0 ? ExactShape::kAabb : kind == 1 ? ExactShape::kObb : ExactShape::kPrism);
}

// The kind-specific overlap functions that apply to this pair, each of which must agree with
// sat_overlap. (Aabb/Aabb and Aabb/Obb live in aabb.h and are tested in test_geometry.cpp.)
std::vector<bool> specialized_answers(const ExactShape& a, const ExactShape& b) {
  std::vector<bool> r;
  using K = ExactShape::Kind;
  if (a.kind == K::kObb && b.kind == K::kAabb) r.push_back(overlaps(a.obb, b.aabb));
  if (a.kind == K::kObb && b.kind == K::kObb) {
    r.push_back(overlaps(a.obb, b.obb));
    r.push_back(overlaps(a.obb, b.obb, RigidTransform::identity()));
  }
  if (a.kind == K::kPrism && b.kind == K::kAabb) r.push_back(overlaps(a.prism, b.aabb));
  if (a.kind == K::kPrism && b.kind == K::kObb) r.push_back(overlaps(a.prism, b.obb));
  if (a.kind == K::kPrism && b.kind == K::kPrism) r.push_back(overlaps(a.prism, b.prism, RigidTransform::identity()));
  return r;
}

// ------------------------------------------------------------------------------------------
// Independent membership (long double) and sampling of the volumes

using LD = long double;
using LVec3 = Eigen::Matrix<LD, 3, 1>;
LVec3 ld(const Vec3& v) { return v.cast<LD>(); }

// How far p is outside the volume (<= 0 inside): the largest excess over the box's slabs.
LD excess(const Obb& box, const LVec3& p) {
  const LVec3 x = box.axes.cast<LD>().transpose() * (p - ld(box.center));
  LD e = -std::numeric_limits<LD>::infinity();
  for (int i = 0; i < 3; ++i) e = std::max(e, std::abs(x[i]) - LD(box.half_extents[i]));
  return e;
}

// The same for a prism: excess over [0, h] along the axis and, in the base plane, over the
// triangle's edge lines (inward normals), or the distance to the longest edge if the base is a
// segment or a point.
LD excess(const Prism& prism, const LVec3& x) {
  const LVec3 a = ld(prism.axis);
  const LVec3 b[3] = {ld(prism.base[0]), ld(prism.base[1]), ld(prism.base[2])};
  const LD s = a.dot(x - b[0]);
  LD e = std::max(-s, s - LD(prism.height));
  const LVec3 q = x - s * a;
  const LVec3 n = (b[1] - b[0]).cross(b[2] - b[0]);
  LD longest = 0;
  for (int i = 0; i < 3; ++i) longest = std::max(longest, (b[(i + 1) % 3] - b[i]).norm());
  if (n.norm() > 1e-14L * longest * longest) {
    // Long double resolves the orientation of needles down to widths of ~1e-17 L.
    for (int i = 0; i < 3; ++i) {
      const LVec3 inward = n.cross(b[(i + 1) % 3] - b[i]).normalized();
      e = std::max(e, -inward.dot(q - b[i]));
    }
  } else {
    // A segment or a point: the union of its edges.
    LD distance = std::numeric_limits<LD>::infinity();
    for (int i = 0; i < 3; ++i) {
      const LVec3 s0 = b[i];
      const LVec3 s1 = b[(i + 1) % 3];
      const LD len2 = (s1 - s0).squaredNorm();
      const LD t = len2 > 0 ? std::clamp((q - s0).dot(s1 - s0) / len2, LD(0), LD(1)) : LD(0);
      distance = std::min(distance, (q - (s0 + t * (s1 - s0))).norm());
    }
    e = std::max(e, distance);
  }
  return e;
}

template <class S>
LD excess(const S& s, const Vec3& p) {
  return excess(s, ld(p));
}

// A typical magnitude of a volume's coordinates: tolerances are relative to it.
Real magnitude(const Obb& box) { return box.center.cwiseAbs().maxCoeff() + box.half_extents.sum() + 1e-300; }
Real magnitude(const Prism& prism) {
  Real m = 0;
  for (const Vec3& c : corners(prism)) m = std::max(m, c.cwiseAbs().maxCoeff());
  Real size = prism.height;
  for (int i = 0; i < 3; ++i) size += (prism.base[(i + 1) % 3] - prism.base[i]).norm();
  return m + size + 1e-300;
}

Vec3 sample_point(const Obb& box, Random& rng) {
  Vec3 s = rng.point(-1, 1);
  for (int k = 0; k < 3; ++k) {
    if (rng.chance(0.1)) s[k] = rng.chance(0.5) ? 1 : -1;  // on a face
  }
  return box.center + box.axes * s.cwiseProduct(box.half_extents);
}
Vec3 sample_point(const Prism& prism, Random& rng) {
  Real u = rng.uniform(0, 1), v = rng.uniform(0, 1);
  if (u + v > 1) {
    u = 1 - u;
    v = 1 - v;
  }
  if (rng.chance(0.1)) v = 0;  // on a side
  Real w = rng.uniform(0, 1);
  if (rng.chance(0.1)) w = rng.chance(0.5) ? 0 : 1;  // on a cap
  return prism.base[0] + u * (prism.base[1] - prism.base[0]) + v * (prism.base[2] - prism.base[0]) +
         (w * prism.height) * prism.axis;
}

// Grid samples such that every point of the volume is within `spacing` of one of them.
std::vector<Vec3> grid_samples(const Obb& box, int n, Real& spacing) {
  std::vector<Vec3> out;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      for (int k = 0; k <= n; ++k) {
        const Vec3 s(Real(2 * i) / n - 1, Real(2 * j) / n - 1, Real(2 * k) / n - 1);
        out.push_back(box.center + box.axes * s.cwiseProduct(box.half_extents));
      }
    }
  }
  spacing = (box.half_extents / n).norm();
  return out;
}
std::vector<Vec3> grid_samples(const Prism& prism, int n, Real& spacing) {
  std::vector<Vec3> out;
  const Vec3& a = prism.base[0];
  const Vec3 ab = prism.base[1] - a;
  const Vec3 ac = prism.base[2] - a;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      for (int k = 0; k <= n; ++k) {
        out.push_back(a + (Real(i) / n) * ab + (Real(j) / n) * ac + (Real(k) / n * prism.height) * prism.axis);
      }
    }
  }
  const Real longest = std::max({ab.norm(), ac.norm(), (ac - ab).norm()});
  spacing = longest / n + prism.height / (2 * n);
  return out;
}

Real point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const Real len2 = d.squaredNorm();
  const Real t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, Real(0), Real(1)) : Real(0);
  return (p - (a + t * d)).norm();
}

// ------------------------------------------------------------------------------------------
// Typed access to the seven oriented volume kinds

template <PrincipalAxis K>
const Obb& shape_of(const OrientedBox<K>& v) {
  return v.box;
}
template <PrincipalAxis K, TriangleRule R>
const Prism& shape_of(const PieSlice<K, R>& v) {
  return v.prism;
}
template <PrincipalAxis K>
OrientedBox<K> moved(const OrientedBox<K>& v, const RigidTransform& t) {
  return {Obb{t.apply(v.box.center), t.rotation * v.box.axes, v.box.half_extents}};
}
template <PrincipalAxis K, TriangleRule R>
PieSlice<K, R> moved(const PieSlice<K, R>& v, const RigidTransform& t) {
  PieSlice<K, R> r = v;
  for (Vec3& b : r.prism.base) b = t.apply(b);
  r.prism.axis = t.rotation * v.prism.axis;
  return r;
}

// A volume of kind V over `leaves` random facets near `center` (leaves merged in random pairs).
template <class V>
V random_volume(Random& rng, int leaves, const Vec3& center, Real size, Real degenerate = 0.2) {
  std::vector<V> level;
  for (int i = 0; i < leaves; ++i) {
    const Real triangle_size = size * rng.uniform(0.05, 1);  // the last argument first: see tests/support/random.h
    const auto t = random_triangle(rng, center + size * rng.point(-1, 1), triangle_size, degenerate);
    level.push_back(V::from_triangle(t[0], t[1], t[2]));
  }
  while (level.size() > 1) {
    rng.shuffle(level.begin(), level.end());
    const V merged = V::enclosing(level[level.size() - 2], level.back());
    level.pop_back();
    level.back() = merged;
  }
  return level.front();
}

template <class V>
class VolumeKinds : public testing::Test {};
using OrientedKinds = testing::Types<ObbAll, ObbMax, ObbMin, PieMax, PieMin, PieMaxGeneral, PieMinGeneral>;
struct KindNames {
  template <class V>
  static std::string GetName(int) {
    std::string name = V::kind_name;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
  }
};
TYPED_TEST_SUITE(VolumeKinds, OrientedKinds, KindNames);

// ==========================================================================================
// Fits (paper 3.2, 3.3)

TYPED_TEST(VolumeKinds, FromTriangleContainsTheFacet) {
  // Every corner (and sampled point) of the facet is inside the leaf, by contains() with no
  // tolerance and by the independent test within 1e-12 of the magnitude; degenerate facets give
  // finite volumes; leaves are flat.
  using V = TypeParam;
  Random rng(11);
  int degenerate = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const Vec3 center = rng.chance(0.2) ? rng.point(-1e4, 1e4) : rng.point(-2, 2);
    const auto t = random_triangle(rng, center, rng.uniform(1e-3, 3), 0.3);
    const V v = V::from_triangle(t[0], t[1], t[2]);
    const auto& s = shape_of(v);
    const Real tol = 1e-12 * magnitude(s);
    ASSERT_TRUE(std::isfinite(surface_area(v)) && std::isfinite(mean_width(v))) << i;
    for (int k = 0; k < 3; ++k) {
      ASSERT_TRUE(contains(v, t[k], 0)) << i << " corner " << k << " " << str(t[k]);
      ASSERT_LE(excess(s, t[k]), tol) << i << " corner " << k;
    }
    for (int k = 0; k < 5; ++k) {
      const Real u = rng.uniform(0, 1), w = rng.uniform(0, 1 - u);
      const Vec3 p = t[0] + u * (t[1] - t[0]) + w * (t[2] - t[0]);
      ASSERT_TRUE(contains(v, p, 1e-13 * magnitude(s))) << i;
    }
    // Zero thickness: the box's smallest extent / the prism's height.
    if constexpr (std::is_same_v<std::decay_t<decltype(s)>, Obb>) {
      EXPECT_LE(s.half_extents.minCoeff(), 1e-14 * magnitude(s)) << i;
    } else {
      EXPECT_EQ(s.height, 0) << i;
      EXPECT_NEAR(s.axis.norm(), 1, 1e-15) << i;
    }
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (n.squaredNorm() == 0) {
      ++degenerate;
      // A segment or a point: zero area (a box of zero extents across the segment).
      EXPECT_LE(surface_area(v), 1e-12 * magnitude(s) * magnitude(s)) << i;
    }
  }
  EXPECT_GT(degenerate, scaled(3000) / 20);
}

TEST(VolumeFit, ObbLeafIsTheMinimumAreaRectangle) {
  // An optimal enclosing rectangle of a triangle has a side along one of its edges: the least of
  // the three flush rectangles (computed here directly) is the minimum.
  Random rng(12);
  for (int i = 0; i < scaled(2000); ++i) {
    const Real triangle_size = rng.uniform(0.1, 3);  // the last argument first: see tests/support/random.h
    const auto t = random_triangle(rng, rng.point(-3, 3), triangle_size, 0);
    const Obb box = obb_from_triangle(t[0], t[1], t[2]);
    Real best = kInf;
    for (int e = 0; e < 3; ++e) {
      const Vec3 edge = t[(e + 1) % 3] - t[e];
      const Real length = edge.norm();
      const Real height = (t[(e + 2) % 3] - t[e]).cross(edge).norm() / length;
      Real lo = 0, hi = 0;
      for (const Vec3& p : t) {
        lo = std::min(lo, (p - t[e]).dot(edge) / length);
        hi = std::max(hi, (p - t[e]).dot(edge) / length);
      }
      best = std::min(best, (hi - lo) * height);
    }
    // The box's in-plane area: the product of its two largest full extents.
    Vec3 h = box.half_extents;
    std::sort(h.data(), h.data() + 3);
    EXPECT_NEAR(4 * h[1] * h[2], best, 1e-9 * best) << i;
    // Its thin axis is the facet normal.
    int thin = 0;
    box.half_extents.minCoeff(&thin);
    const Vec3 normal = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    EXPECT_NEAR(std::abs(box.axes.col(thin).dot(normal)), 1, 1e-9) << i;
    EXPECT_NEAR((box.axes.transpose() * box.axes - Mat3::Identity()).norm(), 0, 1e-14) << i;
  }
}

TEST(VolumeFit, PrismLeafIsTheFacet) {
  const Prism p = prism_from_triangle(Vec3(0, 0, 1), Vec3(2, 0, 1), Vec3(0, 3, 1));
  EXPECT_EQ(p.base[1], Vec3(2, 0, 1));
  EXPECT_EQ(p.height, 0);
  EXPECT_NEAR(std::abs(p.axis.z()), 1, 1e-15);
  // Degenerate facets: a unit axis normal to the segment, never NaN.
  const Prism segment = prism_from_triangle(Vec3(1, 1, 1), Vec3(3, 2, 1), Vec3(5, 3, 1));
  EXPECT_NEAR(segment.axis.norm(), 1, 1e-15);
  EXPECT_NEAR(segment.axis.dot(Vec3(2, 1, 0).normalized()), 0, 1e-15);
  const Prism point = prism_from_triangle(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3));
  EXPECT_NEAR(point.axis.norm(), 1, 1e-15);
  const Obb box_point = obb_from_triangle(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3));
  EXPECT_TRUE(box_point.axes.allFinite());
  EXPECT_LE(box_point.half_extents.maxCoeff(), 1e-14);
  EXPECT_TRUE(contains(box_point, Vec3(1, 2, 3)));
  const Obb box_segment = obb_from_triangle(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(1, 0, 0));
  EXPECT_NEAR(box_segment.half_extents.maxCoeff(), 2, 1e-14);
  EXPECT_NEAR(box_segment.half_extents.sum(), 2, 1e-14);
}

TYPED_TEST(VolumeKinds, EnclosingContainsBothChildren) {
  // Random bottom-up merges: every parent contains every corner of both children, by
  // contains(parent, child) with no tolerance (what validate_tree checks) and, independently,
  // within 1e-12 of the coordinates' magnitude. Far-off positions, tiny and degenerate facets,
  // identical and nested children included.
  using V = TypeParam;
  Random rng(13);
  int checked = 0;
  for (int scene = 0; scene < scaled(150); ++scene) {
    const Vec3 offset = rng.chance(0.3) ? rng.point(-1e5, 1e5) : Vec3::Zero();
    const Real size = std::pow(10.0, rng.uniform(-3, 2));
    std::vector<V> level;
    for (int i = 0; i < 16; ++i) {
      const Real triangle_size = size * rng.uniform(0.01, 1);  // the last argument first: see tests/support/random.h
      const auto t = random_triangle(rng, offset + size * rng.point(-1, 1), triangle_size, 0.2);
      level.push_back(V::from_triangle(t[0], t[1], t[2]));
      if (rng.chance(0.1)) level.push_back(level.back());  // identical children
    }
    while (level.size() > 1) {
      rng.shuffle(level.begin(), level.end());
      const V& x = level[level.size() - 2];
      const V& y = level.back();
      const V parent = V::enclosing(x, y);
      const Real tol = 1e-12 * magnitude(shape_of(parent));
      for (const V* child : {&x, &y}) {
        ASSERT_TRUE(contains(parent, *child, 0)) << "scene " << scene;
        const ConvexPolytope poly = polytope_of(*child);
        for (int k = 0; k < poly.vertex_count; ++k) {
          ASSERT_LE(excess(shape_of(parent), poly.vertices[k]), tol) << "scene " << scene << " corner " << k;
        }
        ++checked;
      }
      // Enclosing a box and a copy of itself gives the box again (its axes are the principal axes
      // of its corners, and a rectangle is its own minimum-area rectangle). Not so for prisms:
      // the sweep axis is a principal axis of a prism's corners but not always the max (min) one.
      const V again = V::enclosing(parent, parent);
      ASSERT_TRUE(contains(again, parent, 0));
      if constexpr (std::is_same_v<std::decay_t<decltype(shape_of(parent))>, Obb>) {
        // (Mean width: linear in the padding of a few hundred ulps of the coordinates. Where two
        // extents are nearly equal the principal axes in their plane are ill-conditioned, so
        // the all-rule box may turn a little: 1e-4.)
        EXPECT_LE(mean_width(again), mean_width(parent) * (1 + 1e-4) + 1e-12 * magnitude(shape_of(parent)));
      }
      level.pop_back();
      level.back() = parent;
    }
  }
  EXPECT_GT(checked, scaled(150) * 20);
}

TYPED_TEST(VolumeKinds, EnclosingDegenerateChildrenIsValid) {
  // Collinear facets, a single point, coincident children: a finite volume that contains them.
  using V = TypeParam;
  const Vec3 a(1, 2, 3), d(0.3, -0.2, 0.9);
  const V s1 = V::from_triangle(a, a + d, a + 2 * d);
  const V s2 = V::from_triangle(a + 3 * d, a + 5 * d, a + 4 * d);
  const V p1 = V::from_triangle(a, a, a);
  for (const V& parent : {V::enclosing(s1, s2), V::enclosing(p1, p1), V::enclosing(s1, p1)}) {
    EXPECT_TRUE(std::isfinite(surface_area(parent)));
    EXPECT_TRUE(std::isfinite(volume(parent)));
    EXPECT_TRUE(contains(parent, a, 0));
    EXPECT_LE(volume(parent), 1e-12);
  }
  EXPECT_TRUE(contains(V::enclosing(s1, s2), a + 5 * d, 0));
}

TYPED_TEST(VolumeKinds, PointsInAChildAreInItsParent) {
  // What a stabbing query relies on: every point that contains() accepts for a child (corners,
  // sampled points, points a rounding away from its boundary) it accepts for the parent and for
  // the child's bounding box (the upper levels of hybrid trees), far from the origin too.
  using V = TypeParam;
  Random rng(19);
  int checked = 0;
  for (int scene = 0; scene < scaled(200); ++scene) {
    const Vec3 offset = rng.chance(0.5) ? rng.point(-1e6, 1e6) : rng.point(-1, 1);
    const Real size = std::pow(10.0, rng.uniform(-3, 1));
    std::vector<V> level;
    for (int i = 0; i < 8; ++i) {
      const Real triangle_size = size * rng.uniform(0.01, 1);  // the last argument first: see tests/support/random.h
      const auto t = random_triangle(rng, offset + size * rng.point(-1, 1), triangle_size, 0.2);
      level.push_back(V::from_triangle(t[0], t[1], t[2]));
    }
    while (level.size() > 1) {
      rng.shuffle(level.begin(), level.end());
      const V& x = level[level.size() - 2];
      const V& y = level.back();
      const V parent = V::enclosing(x, y);
      for (const V* child : {&x, &y}) {
        const ConvexPolytope poly = polytope_of(*child);
        const Aabb bounds = bounding_aabb(*child);
        const Real m = magnitude(shape_of(*child));
        for (int k = 0; k < 40; ++k) {
          Vec3 p = k < poly.vertex_count ? poly.vertices[k] : sample_point(shape_of(*child), rng);
          if (rng.chance(0.5)) p += 1e-15 * m * rng.unit_vector();
          if (!contains(*child, p, 0)) continue;
          ++checked;
          ASSERT_TRUE(contains(parent, p, 0)) << "scene " << scene << " point " << k;
          ASSERT_TRUE(contains(bounds, p)) << "scene " << scene << " point " << k;
        }
      }
      level.pop_back();
      level.back() = parent;
    }
  }
  EXPECT_GT(checked, scaled(200) * 7 * 2 * 20);
}

template <class V>
void check_coplanar_parents_are_flat() {
  // Paper 3.2/3.3, the point of the min rule: children in one plane give a parent of (nearly)
  // zero thickness whose thin direction is the plane's normal. Nearly: each level pads its
  // children by a few hundred ulps (see fit_box and prism_enclosing), so after the up to 11
  // levels here the thickness is below 1e-11 of the coordinates' magnitude.
  Random rng(14);
  for (int scene = 0; scene < scaled(100); ++scene) {
    const Mat3 frame = rng.rotation();
    const Vec3 origin = rng.point(-10, 10);
    const Real size = std::pow(10.0, rng.uniform(-2, 2));
    const auto in_plane = [&](Real x, Real y) { return Vec3(origin + size * (x * frame.col(0) + y * frame.col(1))); };
    std::vector<V> level;
    for (int i = 0; i < 12; ++i) {
      const Real cx = rng.uniform(-1, 1), cy = rng.uniform(-1, 1);
      std::array<Vec3, 3> corners;
      for (int k = 2; k >= 0; --k) {  // the last corner first, y before x: see tests/support/random.h
        const Real y = cy + rng.uniform(-0.3, 0.3);
        const Real x = cx + rng.uniform(-0.3, 0.3);
        corners[k] = in_plane(x, y);
      }
      level.push_back(V::from_triangle(corners[0], corners[1], corners[2]));
    }
    while (level.size() > 1) {
      rng.shuffle(level.begin(), level.end());
      const V parent = V::enclosing(level[level.size() - 2], level.back());
      const auto& s = shape_of(parent);
      const Real tol = 1e-11 * magnitude(s);
      if constexpr (std::is_same_v<std::decay_t<decltype(s)>, Obb>) {
        int thin = 0;
        ASSERT_LE(s.half_extents.minCoeff(&thin), tol) << scene;
        EXPECT_NEAR(std::abs(s.axes.col(thin).dot(frame.col(2))), 1, 1e-9) << scene;
      } else {
        ASSERT_LE(s.height, tol) << scene;
        EXPECT_NEAR(std::abs(s.axis.dot(frame.col(2))), 1, 1e-9) << scene;
      }
      level.pop_back();
      level.back() = parent;
    }
  }
}

TEST(VolumeFit, MinRuleParentsOfCoplanarChildrenAreFlat) {
  check_coplanar_parents_are_flat<ObbMin>();
  check_coplanar_parents_are_flat<PieMin>();
  check_coplanar_parents_are_flat<PieMinGeneral>();
}

// The 16 (or 12) child corners a parent is fitted to.
template <class S>
std::vector<Vec3> child_corners(const S& x, const S& y) {
  std::vector<Vec3> pts;
  for (const Vec3& c : corners(x)) pts.push_back(c);
  for (const Vec3& c : corners(y)) pts.push_back(c);
  return pts;
}

// |cos| of the angle between two directions.
Real alignment(const Vec3& a, const Vec3& b) { return std::abs(a.normalized().dot(b.normalized())); }

TEST(VolumeFit, ObbRulesUseThePrincipalAxes) {
  // all: the axes are the principal axes of the 16 corners and the box is tight along them;
  // max/min: one axis is the max/min principal axis and the cross-section is the minimum-area
  // rectangle of the corners projected along it.
  Random rng(15);
  for (int i = 0; i < scaled(300); ++i) {
    const ObbAll x = random_volume<ObbAll>(rng, rng.integer(1, 4), Vec3::Zero(), 2, 0.1);
    const Vec3 center = rng.point(-2, 2);  // the last argument first: see tests/support/random.h
    const ObbAll y = random_volume<ObbAll>(rng, rng.integer(1, 4), center, 2, 0.1);
    const std::vector<Vec3> pts = child_corners(x.box, y.box);
    const Mat3 principal = detail::principal_axes(pts.data(), pts.size());

    const Obb all = obb_enclosing(x.box, y.box, PrincipalAxis::all);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(alignment(all.axes.col(k), principal.col(k)), 1, 1e-12) << i;
      Real lo = kInf, hi = -kInf;
      for (const Vec3& p : pts) {
        lo = std::min(lo, principal.col(k).dot(p));
        hi = std::max(hi, principal.col(k).dot(p));
      }
      EXPECT_NEAR(2 * all.half_extents[k], hi - lo, 1e-12 * (1 + hi - lo)) << i;  // tight: center mid-range
    }

    for (const PrincipalAxis rule : {PrincipalAxis::max, PrincipalAxis::min}) {
      const Obb box = obb_enclosing(x.box, y.box, rule);
      const Vec3 fixed = principal.col(rule == PrincipalAxis::max ? 0 : 2);
      int match = 0;
      for (int k = 1; k < 3; ++k) {
        if (alignment(box.axes.col(k), fixed) > alignment(box.axes.col(match), fixed)) match = k;
      }
      EXPECT_NEAR(alignment(box.axes.col(match), fixed), 1, 1e-12) << i;
      const Vec3 u = principal.col(rule == PrincipalAxis::max ? 1 : 0);
      const Vec3 v = principal.col(rule == PrincipalAxis::max ? 2 : 1);
      std::vector<Vec2> planar;
      for (const Vec3& p : pts) planar.emplace_back(u.dot(p), v.dot(p));
      const Real area = detail::min_area_rectangle(planar).area();
      const Real box_area = 4 * box.half_extents[(match + 1) % 3] * box.half_extents[(match + 2) % 3];
      EXPECT_NEAR(box_area, area, 1e-9 * (1 + area)) << i;
    }
  }
}

TEST(VolumeFit, PieRulesUseThePrincipalAxisAndTheMinimumTriangles) {
  // The sweep axis is the max/min principal axis of the 12 corners; the base is the enclosing
  // triangle of the rule, placed at the lowest corner; the height is the corners' extent.
  Random rng(16);
  for (int i = 0; i < scaled(200); ++i) {
    const PieMax x = random_volume<PieMax>(rng, rng.integer(1, 3), Vec3::Zero(), 2, 0.1);
    const Vec3 center = rng.point(-2, 2);  // the last argument first: see tests/support/random.h
    const PieMax y = random_volume<PieMax>(rng, rng.integer(1, 3), center, 2, 0.1);
    const std::vector<Vec3> pts = child_corners(x.prism, y.prism);
    const Mat3 principal = detail::principal_axes(pts.data(), pts.size());
    for (const PrincipalAxis axis : {PrincipalAxis::max, PrincipalAxis::min}) {
      for (const TriangleRule rule : {TriangleRule::isosceles, TriangleRule::general}) {
        const Prism p = prism_enclosing(x.prism, y.prism, axis, rule);
        const Vec3 a = principal.col(axis == PrincipalAxis::max ? 0 : 2);
        EXPECT_NEAR(alignment(p.axis, a), 1, 1e-12) << i;
        EXPECT_NEAR(p.axis.norm(), 1, 1e-14);
        Real lo = kInf, hi = -kInf;
        for (const Vec3& q : pts) {
          lo = std::min(lo, p.axis.dot(q));
          hi = std::max(hi, p.axis.dot(q));
        }
        EXPECT_NEAR(p.height, hi - lo, 1e-9 * (1 + hi - lo)) << i;
        const Vec3 u = principal.col(axis == PrincipalAxis::max ? 1 : 0);
        const Vec3 v = principal.col(axis == PrincipalAxis::max ? 2 : 1);
        std::vector<Vec2> planar;
        for (const Vec3& q : pts) planar.emplace_back(u.dot(q), v.dot(q));
        const Real expected = rule == TriangleRule::isosceles ? detail::min_area_isosceles_triangle(planar).area()
                                                              : detail::min_area_triangle(planar).area();
        const Real base = 0.5 * (p.base[1] - p.base[0]).cross(p.base[2] - p.base[0]).norm();
        EXPECT_NEAR(base, expected, 1e-9 * (1 + expected)) << i;
      }
    }
  }
}

// ==========================================================================================
// Measures

TEST(VolumeMeasures, HandComputedObb) {
  const Obb box{Vec3(1, 2, 3), Eigen::AngleAxisd(0.7, Vec3(1, 2, 2).normalized()).toRotationMatrix(), Vec3(1, 2, 3)};
  EXPECT_DOUBLE_EQ(surface_area(box), 8 * (2 + 6 + 3));  // 2(2a*2b + 2b*2c + 2c*2a)
  EXPECT_DOUBLE_EQ(volume(box), 48);
  EXPECT_DOUBLE_EQ(mean_width(box), 6);  // (2 + 4 + 6) / 2
  EXPECT_EQ(center(box), Vec3(1, 2, 3));
  const Aabb bounds = bounding_aabb(box);
  for (const Vec3& c : corners(box)) EXPECT_TRUE(contains(bounds, c)) << str(c);
  Aabb tight;
  for (const Vec3& c : corners(box)) tight.expand(c);
  EXPECT_LE((bounds.min - tight.min).cwiseAbs().maxCoeff(), 1e-12);  // rounded outward, slightly
  EXPECT_LE((bounds.max - tight.max).cwiseAbs().maxCoeff(), 1e-12);
  // Degenerate: a rectangle has area but no volume, a segment neither.
  EXPECT_DOUBLE_EQ(surface_area(Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 2, 0)}), 16);
  EXPECT_DOUBLE_EQ(volume(Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 2, 0)}), 0);
  EXPECT_DOUBLE_EQ(surface_area(Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 0, 0)}), 0);
  EXPECT_DOUBLE_EQ(mean_width(Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 0, 0)}), 1);
}

TEST(VolumeMeasures, HandComputedPrism) {
  // Right triangle with legs 3 and 4 (hypotenuse 5), height 2: A = 6, P = 12.
  Prism p;
  p.base = {Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 4, 0)};
  p.axis = Vec3(0, 0, -1);
  p.height = 2;
  EXPECT_DOUBLE_EQ(surface_area(p), 2 * 6 + 12 * 2);
  EXPECT_DOUBLE_EQ(volume(p), 12);
  EXPECT_DOUBLE_EQ(mean_width(p), 1 + 3);
  EXPECT_LE((center(p) - Vec3(1, 4.0 / 3, -1)).norm(), 1e-15);
  const Aabb bounds = bounding_aabb(p);
  EXPECT_LE((bounds.min - Vec3(0, 0, -2)).norm(), 1e-12);  // rounded outward, slightly
  EXPECT_LE((bounds.max - Vec3(3, 4, 0)).norm(), 1e-12);
  for (const Vec3& c : corners(p)) EXPECT_TRUE(contains(bounds, c));
  p.height = 0;  // the facet itself: two faces of area 6
  EXPECT_DOUBLE_EQ(surface_area(p), 12);
  EXPECT_DOUBLE_EQ(volume(p), 0);
  EXPECT_DOUBLE_EQ(mean_width(p), 3);
}

TEST(VolumeMeasures, AxisAlignedObbMatchesAabb) {
  Random rng(17);
  for (int i = 0; i < scaled(200); ++i) {
    const Vec3 q = rng.point(-3, 3);  // the second corner first: see tests/support/random.h
    const Aabb a = Aabb::from_points(rng.point(-3, 3), q);
    const Obb b{a.center(), Mat3::Identity(), a.extent() / 2};
    EXPECT_NEAR(surface_area(b), surface_area(a), 1e-12 * surface_area(a));
    EXPECT_NEAR(volume(b), volume(a), 1e-12 * volume(a));
    EXPECT_NEAR(mean_width(b), mean_width(a), 1e-12 * mean_width(a));
    // Half a box: a prism on half of a face.
    Prism p;
    p.base = {a.min, Vec3(a.max.x(), a.min.y(), a.min.z()), Vec3(a.min.x(), a.max.y(), a.min.z())};
    p.axis = Vec3::UnitZ();
    p.height = a.extent().z();
    EXPECT_NEAR(volume(p), volume(a) / 2, 1e-12 * volume(a));
  }
}

TYPED_TEST(VolumeKinds, MeasuresAreInvariantUnderRigidMotion) {
  using V = TypeParam;
  Random rng(18);
  for (int i = 0; i < scaled(100); ++i) {
    const V v = random_volume<V>(rng, 4, Vec3::Zero(), 2);
    const RigidTransform t = rng.motion(50);
    const V w = moved(v, t);
    EXPECT_NEAR(surface_area(w), surface_area(v), 1e-12 * (1 + surface_area(v)));
    EXPECT_NEAR(volume(w), volume(v), 1e-12 * (1 + surface_area(v)));
    EXPECT_NEAR(mean_width(w), mean_width(v), 1e-12 * (1 + mean_width(v)));
    EXPECT_LE((center(w) - t.apply(center(v))).norm(), 1e-12 * 100);
    EXPECT_GE(surface_area(v), 0);
    EXPECT_GE(volume(v), 0);
    const Aabb bounds = bounding_aabb(v);
    for (int k = 0; k < polytope_of(v).vertex_count; ++k) EXPECT_TRUE(contains(bounds, polytope_of(v).vertices[k]));
  }
}

// ==========================================================================================
// Separating axes: exact scenes

TEST(SatExact, MatchesExactLpOnGridPolytopes) {
  // Boxes, oriented boxes and prisms with half-integer corners (flat and degenerate ones often):
  // every answer is exact on both sides, touching included.
  Random rng(21);
  int positives = 0, negatives = 0, touching = 0, flat_pairs = 0, failures = 0;
  for (int i = 0; i < scaled(4000); ++i) {
    const ExactShape a = random_exact_shape(rng);
    const ExactShape b = random_exact_shape(rng);
    const bool expected = hulls_intersect(a.exact_corners(), b.exact_corners());
    (expected ? positives : negatives)++;
    if (expected && !hulls_intersect(a.exact_corners(), shrunk(b.exact_corners(), Rational::of(1, 64)))) ++touching;
    flat_pairs += a.flat() && b.flat();
    std::vector<bool> got = {sat_overlap(a.polytope(), b.polytope()), sat_overlap(b.polytope(), a.polytope())};
    for (bool s : specialized_answers(a, b)) got.push_back(s);
    for (bool s : specialized_answers(b, a)) got.push_back(s);
    for (std::size_t k = 0; k < got.size(); ++k) {
      if (got[k] != expected && failures++ < 10) {
        ADD_FAILURE() << "case " << i << " answer " << k << ": expected " << expected << " kinds " << a.kind << "/"
                      << b.kind;
      }
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(positives, scaled(4000) / 10);
  EXPECT_GT(negatives, scaled(4000) / 10);
  EXPECT_GT(touching, scaled(4000) / 50);
  EXPECT_GT(flat_pairs, scaled(4000) / 20);
}

TEST(SatExact, FlatAndCoplanarShapes) {
  // Coplanar flat shapes need the in-plane edge normals; collinear segments need the direction
  // along them; points need any basis.
  const auto rect = [](Real x0, Real y0, Real x1, Real y1) {
    return polytope_of(
        Obb{Vec3((x0 + x1) / 2, (y0 + y1) / 2, 0), Mat3::Identity(), Vec3((x1 - x0) / 2, (y1 - y0) / 2, 0)});
  };
  const auto tri = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return polytope_of(prism_from_triangle(a, b, c));
  };
  // Rectangles in z = 0.
  EXPECT_TRUE(sat_overlap(rect(0, 0, 1, 1), rect(1, 0, 2, 1)));       // sharing an edge
  EXPECT_TRUE(sat_overlap(rect(0, 0, 1, 1), rect(1, 1, 2, 2)));       // sharing a corner
  EXPECT_FALSE(sat_overlap(rect(0, 0, 1, 1), rect(1.001, 0, 2, 1)));  // gap along x
  EXPECT_TRUE(sat_overlap(rect(0, 0, 2, 2), rect(0.5, 0.5, 1, 1)));   // one inside the other
  EXPECT_TRUE(sat_overlap(rect(0, 0, 1, 1), rect(0, 0, 1, 1)));       // identical
  // Triangles in z = 0.
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
  EXPECT_TRUE(sat_overlap(tri(o, x, y), tri(x, y, Vec3(1, 1, 0))));  // sharing the hypotenuse
  EXPECT_FALSE(sat_overlap(tri(o, x, y), tri(Vec3(0.6, 0.6, 0), Vec3(2, 0.6, 0), Vec3(0.6, 2, 0))));  // beyond it
  EXPECT_TRUE(sat_overlap(tri(o, x, y), tri(Vec3(0.5, 0.5, 0), Vec3(2, 0.5, 0), Vec3(0.5, 2, 0))));   // touching it
  EXPECT_TRUE(sat_overlap(tri(o, x, y), tri(x, Vec3(2, 0, 0), Vec3(2, 1, 0))));  // sharing a corner
  EXPECT_FALSE(sat_overlap(tri(o, x, y), tri(Vec3(1.01, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0))));
  // A flat triangle and a flat rectangle, coplanar, near a corner (the separating line is the
  // triangle's hypotenuse, not a box axis).
  EXPECT_FALSE(sat_overlap(tri(Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)), rect(-1, -1, 0.49, 0.49)));
  EXPECT_TRUE(sat_overlap(tri(Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)), rect(-1, -1, 0.5, 0.5)));
  // Segments (degenerate prisms): collinear apart, collinear touching, coplanar T apart, crossing.
  EXPECT_FALSE(sat_overlap(tri(o, x, x), tri(Vec3(2, 0, 0), Vec3(3, 0, 0), Vec3(3, 0, 0))));
  EXPECT_TRUE(sat_overlap(tri(o, x, x), tri(x, Vec3(3, 0, 0), Vec3(3, 0, 0))));
  EXPECT_FALSE(sat_overlap(tri(o, Vec3(2, 0, 0), o), tri(Vec3(1.5, 1, 0), Vec3(3.5, -1, 0), Vec3(3.5, -1, 0))));
  EXPECT_TRUE(sat_overlap(tri(o, Vec3(2, 0, 0), o), tri(Vec3(1, 1, 0), Vec3(3, -1, 0), Vec3(3, -1, 0))));
  EXPECT_FALSE(sat_overlap(tri(o, x, o), tri(Vec3(0, 1, 1), Vec3(1, 1, 1), Vec3(0, 1, 1))));  // parallel apart
  // Points.
  EXPECT_TRUE(sat_overlap(tri(x, x, x), tri(x, x, x)));
  EXPECT_FALSE(sat_overlap(tri(x, x, x), tri(Vec3(1, 0, 1e-6), Vec3(1, 0, 1e-6), Vec3(1, 0, 1e-6))));
  EXPECT_FALSE(sat_overlap(tri(x, x, x), tri(Vec3(1, 1e-6, 0), Vec3(1, 1e-6, 0), Vec3(1, 1e-6, 0))));
  EXPECT_TRUE(sat_overlap(tri(Vec3(0.5, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0, 0)), tri(o, x, y)));
  EXPECT_FALSE(sat_overlap(tri(Vec3(0.5, 0.51, 0), Vec3(0.5, 0.51, 0), Vec3(0.5, 0.51, 0)), tri(Vec3(1, 0, 0), y, o)));
  // A point inside a box; a box inside a prism.
  EXPECT_TRUE(sat_overlap(tri(Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0.5, 0.5)),
                          polytope_of(Obb{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)})));
  Prism big;
  big.base = {Vec3(-10, -10, -10), Vec3(30, -10, -10), Vec3(-10, 30, -10)};
  big.axis = Vec3::UnitZ();
  big.height = 20;
  EXPECT_TRUE(sat_overlap(polytope_of(big), polytope_of(Obb{Vec3(1, 1, 1), Mat3::Identity(), Vec3(1, 2, 3)})));
  // Empty boxes and NaN coordinates overlap nothing.
  EXPECT_FALSE(sat_overlap(polytope_of(Aabb::empty()), polytope_of(big)));
  RigidTransform bad;
  bad.translation.x() = std::nan("");
  EXPECT_FALSE(sat_overlap(polytope_of(big), polytope_of(big).transformed(bad)));
  EXPECT_FALSE(overlaps(big, big, bad));
  const Obb unit{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)};
  EXPECT_FALSE(overlaps(unit, unit, bad));
}

// ==========================================================================================
// Separating axes: float scenes outside a band

struct Band {
  bool outer;  // b grown by the cube [-tau, tau]^3 meets a
  bool inner;  // b shrunk about its centroid by 1/64 meets a
  bool decided() const { return outer == inner; }
};

Band band_of(const ExactShape& a, const ExactShape& b) {
  const auto pa = a.exact_corners();
  const auto pb = b.exact_corners();
  return {hulls_intersect(pa, grown(pb, Rational::of(1, 64))), hulls_intersect(pa, shrunk(pb, Rational::of(1, 64)))};
}

TEST(SatFloat, MatchesExactLpUnderRandomRigidMotionOutsideBand) {
  // The exact scenes moved by a random rigid motion, and b sometimes tilted about its centroid by
  // up to 1e-5 (which moves it by less than 1e-4): parallel edges become nearly parallel,
  // coplanar faces nearly coplanar. Asserted where the exact answer is the same for b grown by
  // tau = 1/64 and shrunk by 1/64 about its centroid (rounding moves things by ~1e-14, far inside
  // the band). The tilt is applied only where it cannot change the answer: when b is apart (by
  // more than tau), or when b is solid (then the shrunk b meeting a means a point of a at depth
  // >= 1/256 inside b). A flat b overlapping a may be tilted off it.
  Random rng(22);
  int asserted = 0, positives = 0, negatives = 0, failures = 0;
  for (int i = 0; i < scaled(2500); ++i) {
    const ExactShape a = random_exact_shape(rng);
    const ExactShape b = random_exact_shape(rng);
    const Band band = band_of(a, b);
    if (!band.decided()) continue;
    ++asserted;
    (band.inner ? positives : negatives)++;
    const RigidTransform motion = rng.motion(100);
    ConvexPolytope pb = b.polytope();
    if ((!band.inner || !b.flat()) && rng.chance(0.5)) {
      Vec3 centroid = Vec3::Zero();
      for (const Vec3& c : b.corner_list) centroid += c;
      centroid /= Real(b.corner_list.size());
      const Real angle = std::pow(10.0, rng.uniform(-15, -5));
      const Mat3 tilt = Eigen::AngleAxisd(angle, rng.unit_vector()).toRotationMatrix();
      pb = pb.transformed(RigidTransform{tilt, centroid - tilt * centroid});
    }
    const bool got = sat_overlap(a.polytope().transformed(motion), pb.transformed(motion));
    if (got != band.inner && failures++ < 10) ADD_FAILURE() << "case " << i << ": expected " << band.inner;
    // The kind-specific tests on the moved shapes.
    if (a.kind == ExactShape::kObb && b.kind != ExactShape::kPrism) {
      const Obb ma{motion.apply(a.obb.center), motion.rotation * a.obb.axes, a.obb.half_extents};
      const Obb mb = b.kind == ExactShape::kObb
                         ? Obb{motion.apply(b.obb.center), motion.rotation * b.obb.axes, b.obb.half_extents}
                         : Obb{motion.apply(b.aabb.center()), motion.rotation, b.aabb.extent() / 2};
      if (overlaps(ma, mb) != band.inner && failures++ < 10) ADD_FAILURE() << "obb case " << i;
    }
    if (a.kind == ExactShape::kPrism && b.kind == ExactShape::kPrism) {
      // b given in its own frame B = motion^-1 (the polytope test must undo it).
      Prism pb_local = b.prism;
      const RigidTransform inverse = motion.inverse();
      for (Vec3& c : pb_local.base) c = inverse.apply(c);
      pb_local.axis = inverse.rotation * pb_local.axis;
      if (overlaps(a.prism, pb_local, motion) != band.inner && failures++ < 10) ADD_FAILURE() << "prism case " << i;
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(asserted, scaled(2500) / 2);
  EXPECT_GT(positives, scaled(2500) / 20);
  EXPECT_GT(negatives, scaled(2500) / 10);
}

TEST(SatFloat, NearlyCoplanarFlatShapesAreSeparatedByInPlaneGaps) {
  // A flat shape A in z = 0 whose rightmost point is at x = 1, and a flat shape B in the same
  // plane whose leftmost point p is at x = 1 + g (B apart by g) or 1 - g (p inside A, depth g);
  // then B is tilted by theta about the line through p along y. That rotation keeps x - p.x of
  // every point of B non-negative (x' - p.x = (x - p.x) cos theta for points of z = 0), so B stays
  // beyond the line x = 1 + g, or keeps touching A at p: the answer is known exactly whatever
  // theta. Then both are moved rigidly. Gaps down to 1e-6 must be resolved at every tilt from
  // 1e-15 to 1e-2, which is where the in-plane axes of polytope.cpp matter.
  Random rng(23);
  int failures = 0;
  for (int i = 0; i < scaled(4000); ++i) {
    // A: a unit rectangle, a triangle with a vertex at (1, 0.5), or a segment ending there.
    const int kind_a = rng.integer(0, 2);
    ConvexPolytope a;
    if (kind_a == 0) {
      a = polytope_of(Obb{Vec3(0.5, 0.5, 0), Mat3::Identity(), Vec3(0.5, 0.5, 0)});
    } else if (kind_a == 1) {
      a = polytope_of(prism_from_triangle(Vec3(0, 0, 0), Vec3(1, 0.5, 0), Vec3(0, 1, 0)));
    } else {
      a = polytope_of(prism_from_triangle(Vec3(rng.uniform(0, 0.9), 0.5, 0), Vec3(1, 0.5, 0), Vec3(1, 0.5, 0)));
    }
    const bool apart = rng.chance(0.5);
    const Real gap = std::pow(10.0, rng.uniform(-6, -2));
    const Vec3 p(apart ? 1 + gap : 1 - gap, kind_a == 0 ? rng.uniform(0.2, 0.8) : 0.5, 0);
    // B: a rectangle whose left edge is centred on p, a triangle or a segment with a corner at p.
    const int kind_b = rng.integer(0, 2);
    ConvexPolytope b;
    if (kind_b == 0) {
      const Real w = rng.uniform(0.1, 1);
      b = polytope_of(Obb{p + Vec3(w, 0, 0), Mat3::Identity(), Vec3(w, rng.uniform(0, 0.1), 0)});
    } else if (kind_b == 1) {
      // The last corner first, y before x: see tests/support/random.h.
      const Real y2 = rng.uniform(-1, 1);
      const Real x2 = rng.uniform(0.1, 1);
      const Real y1 = rng.uniform(-1, 1);
      const Real x1 = rng.uniform(0.1, 1);
      b = polytope_of(prism_from_triangle(p, p + Vec3(x1, y1, 0), p + Vec3(x2, y2, 0)));
    } else {
      const Real y = rng.uniform(-1, 1);  // y first: see tests/support/random.h
      const Real x = rng.uniform(0.1, 1);
      b = polytope_of(prism_from_triangle(p, p + Vec3(x, y, 0), p));
    }
    const Real angle = std::pow(10.0, rng.uniform(-15, -2));
    const Real theta = angle * (rng.chance(0.5) ? 1 : -1);
    const Mat3 tilt = Eigen::AngleAxisd(theta, Vec3::UnitY()).toRotationMatrix();
    b = b.transformed(RigidTransform{tilt, p - tilt * p});
    const RigidTransform motion = rng.motion(10);
    const bool got = sat_overlap(a.transformed(motion), b.transformed(motion));
    const bool got_reversed = sat_overlap(b.transformed(motion), a.transformed(motion));
    if ((got != !apart || got_reversed != !apart) && failures++ < 10) {
      ADD_FAILURE() << "case " << i << " kinds " << kind_a << "/" << kind_b << " apart " << apart << " gap " << gap
                    << " tilt " << theta;
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(SatFloat, NearlyCoplanarSegmentAgainstAVertex) {
  // A flat triangle A in z = 0 with a vertex at (1, 0.5) and no face normal along x (no edge is
  // vertical), and a segment B along y at x = 1 + g (apart) or 1 - g (through A near the vertex),
  // tilted by theta about the x axis through p = (x_B, 0.5, 0): it stays in the plane x = x_B,
  // and keeps p. The only separating directions are close to x = n x (direction of B), which no
  // face normal of either provides: B's face normals are two arbitrary directions normal to it,
  // each of which mixes in the heights of B (up to theta * |B|). The in-plane axes of
  // polytope.cpp (n x e for a direction n along which both are thin) resolve it.
  Random rng(25);
  const ConvexPolytope a = polytope_of(prism_from_triangle(Vec3(0, 0.2, 0), Vec3(1, 0.5, 0), Vec3(0.1, 1, 0)));
  int failures = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const bool apart = rng.chance(0.5);
    const Real gap = std::pow(10.0, rng.uniform(-6, -2));
    const Vec3 p(apart ? 1 + gap : 1 - gap, 0.5, 0);
    const Real up = rng.uniform(0.5, 2);  // the second corner first: see tests/support/random.h
    const Real down = rng.uniform(0.5, 2);
    ConvexPolytope b = polytope_of(prism_from_triangle(p - Vec3(0, down, 0), p + Vec3(0, up, 0), p));
    const Real angle = std::pow(10.0, rng.uniform(-12, -1));
    const Real theta = angle * (rng.chance(0.5) ? 1 : -1);
    const Mat3 tilt = Eigen::AngleAxisd(theta, Vec3::UnitX()).toRotationMatrix();
    b = b.transformed(RigidTransform{tilt, p - tilt * p});
    const RigidTransform motion = rng.motion(10);
    const bool got = sat_overlap(a.transformed(motion), b.transformed(motion));
    const bool got_reversed = sat_overlap(b.transformed(motion), a.transformed(motion));
    if ((got != !apart || got_reversed != !apart) && failures++ < 10) {
      ADD_FAILURE() << "case " << i << " apart " << apart << " gap " << gap << " tilt " << theta;
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(SatFloat, NeverMissesASharedPoint) {
  // Random boxes and prisms built to share a point (a corner of one on the boundary or inside of
  // the other), in random orientations: never reported apart.
  Random rng(24);
  for (int i = 0; i < scaled(4000); ++i) {
    const Obb box{rng.point(-5, 5), rng.rotation(), rng.point(0, 2).cwiseProduct(Vec3(1, 1, rng.chance(0.3) ? 0 : 1))};
    const Vec3 shared = sample_point(box, rng);
    const Vec3 to_third = rng.point(-2, 2);  // the last corner first: see tests/support/random.h
    const Vec3 to_second = rng.point(-2, 2);
    Prism prism = prism_from_triangle(shared, shared + to_second, shared + to_third);
    prism.height = rng.chance(0.5) ? 0 : rng.uniform(0, 2);
    if (rng.chance(0.5)) {  // put the shared point on the top face instead
      for (Vec3& c : prism.base) c -= prism.height * prism.axis;
    }
    ASSERT_TRUE(sat_overlap(polytope_of(box), polytope_of(prism))) << i;
    ASSERT_TRUE(overlaps(prism, box)) << i;
    const RigidTransform t = rng.motion(50);
    ASSERT_TRUE(sat_overlap(polytope_of(box).transformed(t), polytope_of(prism).transformed(t))) << i;
    // A second box with a corner at the shared point.
    const Mat3 r = rng.rotation();
    const Vec3 h = rng.point(0, 1);
    const Obb other{shared + r * h, r, h};
    ASSERT_TRUE(overlaps(box, other)) << i;
    ASSERT_TRUE(overlaps(other, box)) << i;
    ASSERT_TRUE(overlaps(box, other, RigidTransform::identity())) << i;
  }
}

// ==========================================================================================
// Transformed overlaps

TEST(SatTransform, ExactTransformsMatchExplicitCorners) {
  // b given in frame B, a_from_b a signed permutation plus a half-integer shift: exact, so
  // overlaps(a, b, T), sat_overlap(polytope(a), polytope(b).transformed(T)) and the LP on the
  // exactly transformed corners of b agree everywhere, touching included.
  Random rng(31);
  int failures = 0, positives = 0;
  for (int i = 0; i < scaled(2500); ++i) {
    const bool boxes = rng.chance(0.5);
    const ExactShape a = random_exact_shape(rng, boxes ? ExactShape::kObb : ExactShape::kPrism);
    const ExactShape b = random_exact_shape(rng, boxes ? ExactShape::kObb : ExactShape::kPrism);
    const RigidTransform t{signed_permutation(rng), rng.grid_point(-2, 2, 2)};
    std::vector<RPoint> moved_b;
    for (const Vec3& c : b.corner_list) moved_b.push_back(exact(t.apply(c)));  // exact: permutation + dyadics
    const bool expected = hulls_intersect(a.exact_corners(), moved_b);
    positives += expected;
    const bool direct = boxes ? overlaps(a.obb, b.obb, t) : overlaps(a.prism, b.prism, t);
    const bool via_polytope = sat_overlap(a.polytope(), b.polytope().transformed(t));
    if ((direct != expected || via_polytope != expected) && failures++ < 10) {
      ADD_FAILURE() << "case " << i << " boxes " << boxes << " expected " << expected;
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(positives, scaled(2500) / 20);
  EXPECT_LT(positives, scaled(2500) * 9 / 10);
}

TYPED_TEST(VolumeKinds, TransformedOverlapsAgree) {
  // Fitted volumes, random rigid transforms: overlaps(a, b, T) == sat_overlap(polytope(a),
  // polytope(b).transformed(T)) == the overlap of a with b actually moved by T (its geometry
  // transformed, then tested in one frame). The three differ only in rounding, so they could
  // disagree only within ~1e-12 of touching, which these fixed seeds do not hit.
  using V = TypeParam;
  Random rng(32);
  int positives = 0;
  for (int i = 0; i < scaled(1500); ++i) {
    const V a = random_volume<V>(rng, rng.integer(1, 6), Vec3::Zero(), 2);
    const V b = random_volume<V>(rng, rng.integer(1, 6), Vec3::Zero(), 2);
    const RigidTransform t{rng.rotation(), rng.point(-4, 4)};
    const bool direct = overlaps(a, b, t);
    const bool via_polytope = sat_overlap(polytope_of(a), polytope_of(b).transformed(t));
    const bool explicit_move = overlaps(a, moved(b, t), RigidTransform::identity());
    ASSERT_EQ(direct, via_polytope) << i;
    ASSERT_EQ(direct, explicit_move) << i;
    positives += direct;
    // Symmetry: b against a through the inverse transform.
    ASSERT_EQ(overlaps(b, a, t.inverse()), direct) << i;
  }
  EXPECT_GT(positives, scaled(1500) / 10);
  EXPECT_LT(positives, scaled(1500) * 9 / 10);
}

// ==========================================================================================
// Queries: points, boxes, spheres, capsules, planes

TYPED_TEST(VolumeKinds, ContainsPointMatchesIndependentTest) {
  using V = TypeParam;
  Random rng(41);
  int outside = 0;
  for (int i = 0; i < scaled(300); ++i) {
    const Real size = std::pow(10.0, rng.uniform(-2, 1));  // the last argument first: see tests/support/random.h
    const Vec3 center = rng.point(-50, 50);
    const V v = random_volume<V>(rng, rng.integer(1, 6), center, size);
    const auto& s = shape_of(v);
    const Real m = magnitude(s);
    for (int k = 0; k < 20; ++k) {
      // Inside or on the boundary, up to the rounding of its coordinates.
      const Vec3 p = sample_point(s, rng);
      ASSERT_TRUE(contains(v, p, 1e-14 * m)) << i << " " << str(p);
      // Points around: the answer must match the independent one outside a 1e-9 band.
      const Vec3 direction = rng.unit_vector();  // first: see tests/support/random.h
      const Vec3 q = p + std::pow(10.0, rng.uniform(-8, 0)) * m * direction;
      const LD e = excess(s, q);
      if (e > 1e-9 * m) {
        ASSERT_FALSE(contains(v, q, 0)) << i;
        ++outside;
      } else if (e < -1e-9 * m) {
        ASSERT_TRUE(contains(v, q, 0)) << i;
      }
      // A tolerance is (at most) a distance: q is within |q - p| of a point of the volume.
      ASSERT_TRUE(contains(v, q, (q - p).norm() * (1 + 1e-9) + 1e-12 * m)) << i;
    }
  }
  EXPECT_GT(outside, scaled(300));
  // Invalid points are in nothing.
  const V v = random_volume<V>(rng, 2, Vec3::Zero(), 1);
  EXPECT_FALSE(contains(v, Vec3(std::nan(""), 0, 0)));
}

TYPED_TEST(VolumeKinds, OverlapsBoxesNeverMissesAndMatchesSat) {
  // Query boxes and oriented boxes that contain a point of the volume always overlap; those
  // beyond a supporting plane by a margin never do; and the answer is sat_overlap's.
  using V = TypeParam;
  Random rng(42);
  int hits = 0, misses = 0;
  for (int i = 0; i < scaled(1500); ++i) {
    const V v = random_volume<V>(rng, rng.integer(1, 6), Vec3::Zero(), 2);
    const auto& s = shape_of(v);
    const Vec3 p = sample_point(s, rng);
    const Aabb box{p - rng.point(0, 1).cwiseProduct(Vec3(1, rng.chance(0.3) ? 0 : 1, 1)), p + rng.point(0, 1)};
    ASSERT_TRUE(overlaps(v, box)) << i;
    const Mat3 r = rng.rotation();
    const Vec3 h = rng.point(0, 1);
    const Vec3 corner_sign = test::vec3_z_first([&] { return rng.chance(0.5) ? 1 : -1; });
    ASSERT_TRUE(overlaps(v, Obb{p + r * h.cwiseProduct(corner_sign), r, h})) << i;
    // Beyond the support plane along w by delta.
    const Vec3 w = rng.unit_vector();
    Real support = -kInf;
    const ConvexPolytope poly = polytope_of(v);
    for (int k = 0; k < poly.vertex_count; ++k) support = std::max(support, w.dot(poly.vertices[k]));
    const Real delta = std::pow(10.0, rng.uniform(-8, 0));
    const Vec3 hq = rng.point(0, 1);
    const Mat3 rq = rng.rotation();
    const Real reach = (rq.transpose() * w).cwiseAbs().dot(hq);
    const Vec3 cq = rng.point(-3, 3);
    const Obb far{cq + w * (support + delta + reach - w.dot(cq)), rq, hq};
    ASSERT_FALSE(overlaps(v, far)) << i << " delta " << delta;
    // Random boxes: same answer as the polytope test.
    const Vec3 box_corner = rng.point(-3, 3);  // the second corner first: see tests/support/random.h
    const Aabb random_box = Aabb::from_points(rng.point(-3, 3), box_corner);
    const bool got = overlaps(v, random_box);
    ASSERT_EQ(got, sat_overlap(poly, polytope_of(random_box))) << i;
    const Obb random_obb{rng.point(-3, 3), rng.rotation(), rng.point(0, 1.5)};
    ASSERT_EQ(overlaps(v, random_obb), sat_overlap(poly, polytope_of(random_obb))) << i;
    (got ? hits : misses)++;
  }
  EXPECT_GT(hits, scaled(1500) / 10);
  EXPECT_GT(misses, scaled(1500) / 10);
  // Invalid query boxes overlap nothing.
  const V v = random_volume<V>(rng, 2, Vec3::Zero(), 1);
  EXPECT_FALSE(overlaps(v, Aabb::empty()));
  EXPECT_FALSE(overlaps(v, Obb{Vec3::Zero(), Mat3::Identity(), Vec3(std::nan(""), 1, 1)}));
  EXPECT_FALSE(overlaps(v, Obb{Vec3::Zero(), Mat3::Identity(), Vec3(-1, 1, 1)}));
}

TYPED_TEST(VolumeKinds, SphereMatchesSamplingReference) {
  // The sampled minimum distance d bounds the true distance within [d - spacing, d]: a sphere
  // reaching d overlaps; one short of d - spacing does not. Spheres centred on sampled points
  // with radius 0 touch.
  using V = TypeParam;
  Random rng(43);
  int asserted = 0, hits = 0;
  for (int i = 0; i < scaled(300); ++i) {
    const V v = random_volume<V>(rng, rng.integer(1, 4), Vec3::Zero(), 2);
    const auto& s = shape_of(v);
    Real spacing = 0;
    const std::vector<Vec3> samples = grid_samples(s, 12, spacing);
    for (int k = 0; k < 10; ++k) {
      const Vec3 c = rng.point(-5, 5);
      Real d = kInf;
      for (const Vec3& q : samples) d = std::min(d, (q - c).norm());
      const Real r = rng.uniform(0, 5);
      const Real tol = 1e-12 * 10;
      if (r >= d + tol) {
        ASSERT_TRUE(overlaps(v, Sphere{c, r})) << i;
        ++asserted;
        ++hits;
      } else if (r < d - spacing - tol) {
        ASSERT_FALSE(overlaps(v, Sphere{c, r})) << i;
        ++asserted;
      }
    }
    ASSERT_TRUE(overlaps(v, Sphere{sample_point(s, rng), 0})) << i;
  }
  EXPECT_GT(asserted, scaled(300) * 8);
  EXPECT_GT(hits, scaled(300));
  const V v = random_volume<V>(rng, 2, Vec3::Zero(), 1);
  EXPECT_FALSE(overlaps(v, Sphere{Vec3::Zero(), -1}));
  EXPECT_FALSE(overlaps(v, Sphere{Vec3(std::nan(""), 0, 0), 1}));
}

TYPED_TEST(VolumeKinds, CapsuleMatchesSamplingReference) {
  using V = TypeParam;
  Random rng(44);
  int asserted = 0, hits = 0;
  for (int i = 0; i < scaled(300); ++i) {
    const V v = random_volume<V>(rng, rng.integer(1, 4), Vec3::Zero(), 2);
    const auto& s = shape_of(v);
    Real spacing = 0;
    const std::vector<Vec3> samples = grid_samples(s, 12, spacing);
    for (int k = 0; k < 6; ++k) {
      const Vec3 p0 = rng.point(-5, 5);
      const Vec3 p1 = rng.chance(0.2) ? p0 : Vec3(p0 + rng.point(-4, 4));
      Real d = kInf;
      for (const Vec3& q : samples) d = std::min(d, point_segment_distance(q, p0, p1));
      const Real r = rng.uniform(0, 4);
      const Real tol = 1e-12 * 10;
      if (r >= d + tol) {
        ASSERT_TRUE(overlaps(v, Capsule{p0, p1, r})) << i;
        ++asserted;
        ++hits;
      } else if (r < d - spacing - tol) {
        ASSERT_FALSE(overlaps(v, Capsule{p0, p1, r})) << i;
        ++asserted;
      }
    }
    // A segment through a point of the volume, radius 0.
    const Vec3 p = sample_point(s, rng);
    const Vec3 d = rng.unit_vector();
    ASSERT_TRUE(overlaps(v, Capsule{p - d, p + 2 * d, 0})) << i;
    ASSERT_TRUE(overlaps(v, Capsule{p, p + d, 0})) << i;
  }
  EXPECT_GT(asserted, scaled(300) * 4);
  EXPECT_GT(hits, scaled(300) / 2);
  const V v = random_volume<V>(rng, 2, Vec3::Zero(), 1);
  EXPECT_FALSE(overlaps(v, Capsule{Vec3::Zero(), Vec3::Zero(), -1}));
}

TYPED_TEST(VolumeKinds, PlaneMatchesCornerSigns) {
  // Closed: the plane meets the volume iff the corners' signed distances bracket zero. Planes
  // through a corner (or a sampled point) always touch.
  using V = TypeParam;
  Random rng(45);
  int hits = 0, misses = 0;
  for (int i = 0; i < scaled(500); ++i) {
    const Vec3 center = rng.point(-20, 20);  // the last argument first: see tests/support/random.h
    const V v = random_volume<V>(rng, rng.integer(1, 4), center, 2);
    const ConvexPolytope poly = polytope_of(v);
    const Real length = rng.uniform(0.1, 10);   // first: see tests/support/random.h
    const Vec3 n = rng.unit_vector() * length;  // not unit length
    const Real offset = n.dot(rng.point(-25, 25));
    LD lo = std::numeric_limits<LD>::infinity(), hi = -lo;
    for (int k = 0; k < poly.vertex_count; ++k) {
      const LD d = ld(n).dot(ld(poly.vertices[k])) - offset;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    const Real band = 1e-9 * 30 * n.norm();
    const Plane plane{n, offset};
    if (lo > band || hi < -band) {
      ASSERT_FALSE(overlaps(v, plane)) << i;
      ++misses;
    } else if (lo < -band && hi > band) {
      ASSERT_TRUE(overlaps(v, plane)) << i;
      ++hits;
    }
    const Vec3 corner = poly.vertices[rng.integer(0, poly.vertex_count - 1)];
    ASSERT_TRUE(overlaps(v, Plane{n, n.dot(corner)})) << i;
    const Vec3 p = sample_point(shape_of(v), rng);
    ASSERT_TRUE(overlaps(v, Plane{n, n.dot(p)})) << i;
  }
  EXPECT_GT(hits, scaled(500) / 20);
  EXPECT_GT(misses, scaled(500) / 2);
}

// ==========================================================================================
// Rays

// Where the ray enters the volume grown by `tol` (the independent membership test, on ray
// points computed in long double), by bisection between 0 and `inside`, a parameter known to be
// inside; NaN if `inside` is not (the exact ray can miss a flat volume by a rounding).
template <class S>
Real reference_entry(const S& s, const Ray& ray, Real inside, Real tol) {
  const auto in = [&](Real t) { return excess(s, LVec3(ld(ray.origin) + LD(t) * ld(ray.direction))) <= tol; };
  if (!in(inside)) return std::numeric_limits<Real>::quiet_NaN();
  if (in(0)) return 0;
  Real lo = 0, hi = inside;
  for (int k = 0; k < 200 && hi - lo > 1e-15 * inside; ++k) {
    const Real mid = (lo + hi) / 2;
    (in(mid) ? hi : lo) = mid;
  }
  return hi;
}

TYPED_TEST(VolumeKinds, RayNeverMissesAndEntersNoLaterThanTheTruth) {
  // Rays through sampled points of the volume (flat leaves included) always hit, with an entry
  // no later than the true one (to the bisection's 1e-15) and no earlier than the entry into the
  // volume grown by 1e-9 of its magnitude.
  using V = TypeParam;
  Random rng(51);
  int exact_entries = 0;
  for (int i = 0; i < scaled(300); ++i) {
    const Real size = std::pow(10.0, rng.uniform(-1, 1));  // the last argument first: see tests/support/random.h
    const Vec3 center = rng.point(-100, 100);
    const V v = random_volume<V>(rng, rng.integer(1, 6), center, size);
    const auto& s = shape_of(v);
    const Real m = magnitude(s);
    for (int k = 0; k < 10; ++k) {
      const Vec3 p = sample_point(s, rng);
      const Real length = std::pow(10.0, rng.uniform(-2, 2));  // first: see tests/support/random.h
      const Vec3 d = rng.unit_vector() * length;
      const Real t0 = rng.uniform(0, 5) * m / d.norm();
      const Ray ray{p - t0 * d, d};
      const Real scale_t = m / d.norm();
      Real t_enter = -1;
      ASSERT_TRUE(intersect_ray(v, RayPrecomputed(ray), 0, kInf, &t_enter)) << i << " " << k;
      ASSERT_LE(t_enter, t0 + 1e-12 * scale_t) << i << " " << k;
      const Real truth = reference_entry(s, ray, t0, 0);
      if (!std::isnan(truth)) {
        ASSERT_LE(t_enter, truth) << i << " " << k;
        ++exact_entries;
      }
      const Real loose = reference_entry(s, ray, t0, 1e-9 * m);
      ASSERT_FALSE(std::isnan(loose)) << i;
      ASSERT_GE(t_enter, loose - 1e-12 * scale_t) << i << " " << k;
      // The segment ending at the sampled point still reaches it; one ending well before the
      // entry does not.
      ASSERT_TRUE(intersect_ray(v, RayPrecomputed(ray), 0, t0, nullptr)) << i;
      if (loose > 1e-6 * scale_t) {
        ASSERT_FALSE(intersect_ray(v, RayPrecomputed(ray), 0, loose - 1e-6 * scale_t, nullptr)) << i;
      }
      // Started past the point, pointing away: a miss unless the start is still inside.
      const Ray away{p + t0 * d, d};
      if (excess(s, away.origin) > 1e-9 * m) {
        ASSERT_FALSE(intersect_ray(v, RayPrecomputed(away), 0, kInf)) << i;
      }
    }
  }
  EXPECT_GT(exact_entries, scaled(300));
}

TYPED_TEST(VolumeKinds, RayTouchingACornerOrLyingInAFlatVolumeHits) {
  using V = TypeParam;
  Random rng(52);
  for (int i = 0; i < scaled(500); ++i) {
    const Vec3 center = rng.point(-10, 10);  // the last argument first: see tests/support/random.h
    const V v = random_volume<V>(rng, rng.integer(1, 3), center, 2, 0.3);
    const ConvexPolytope poly = polytope_of(v);
    const Vec3 corner = poly.vertices[rng.integer(0, poly.vertex_count - 1)];
    const Vec3 d = rng.unit_vector();
    Real t = -1;
    ASSERT_TRUE(intersect_ray(v, RayPrecomputed(Ray{corner - 3 * d, d}), 0, kInf, &t)) << i;
    EXPECT_LE(t, 3 + 1e-9) << i;
    ASSERT_TRUE(intersect_ray(v, RayPrecomputed(Ray{corner, d}), 0, kInf, &t)) << i;  // starting there
    EXPECT_EQ(t, 0) << i;
    // Leaves are flat: a ray in the facet's plane through an in-plane point hits it.
    const auto t3 = random_triangle(rng, rng.point(-10, 10), 2, 0);
    const V leaf = V::from_triangle(t3[0], t3[1], t3[2]);
    const Vec3 inside = (t3[0] + t3[1] + t3[2]) / 3;
    const Real along_second = rng.uniform(-1, 1);  // first: see tests/support/random.h
    const Vec3 in_plane = (t3[1] - t3[0]) * rng.uniform(-1, 1) + (t3[2] - t3[0]) * along_second;
    if (in_plane.norm() > 1e-3) {
      ASSERT_TRUE(intersect_ray(leaf, RayPrecomputed(Ray{inside - 5 * in_plane, in_plane}), 0, kInf, &t)) << i;
      EXPECT_LE(t, 5 + 1e-9) << i;
      // Parallel to the facet but off its plane by 1e-6: a miss.
      const Vec3 normal = (t3[1] - t3[0]).cross(t3[2] - t3[0]).normalized();
      ASSERT_FALSE(intersect_ray(leaf, RayPrecomputed(Ray{inside + 1e-6 * normal - 5 * in_plane, in_plane}), 0, kInf))
          << i;
    }
  }
}

TEST(VolumeRay, ExactCasesOnAxisAlignedShapes) {
  // Exact geometry: rays grazing faces and edges, lying in a flat box, clipped by [t_min, t_max].
  // Entries are exact up to the tests' conservative margins (~64 ulps of the distances).
  const Obb box{Vec3(1, 1, 1), Mat3::Identity(), Vec3(1, 1, 1)};   // [0, 2]^3
  const Obb flat{Vec3(1, 1, 0), Mat3::Identity(), Vec3(1, 1, 0)};  // [0, 2]^2 x {0}
  Real t = -1;
  const auto hit = [&](const auto& v, const Vec3& o, const Vec3& d, Real t_min = 0, Real t_max = kInf) {
    return intersect_ray(v, RayPrecomputed(Ray{o, d}), t_min, t_max, &t);
  };
  EXPECT_TRUE(hit(box, Vec3(-1, 1, 1), Vec3(1, 0, 0)));
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(hit(box, Vec3(-1, 2, 1), Vec3(1, 0, 0)));    // along a face
  EXPECT_TRUE(hit(box, Vec3(-1, 2, 2), Vec3(1, 0, 0)));    // along an edge
  EXPECT_TRUE(hit(box, Vec3(-1, -1, -1), Vec3(1, 1, 1)));  // through a corner
  EXPECT_FALSE(hit(box, Vec3(-1, 2.001, 1), Vec3(1, 0, 0)));
  EXPECT_FALSE(hit(box, Vec3(-1, 1, 1), Vec3(1, 0, 0), 0, 0.999));
  EXPECT_TRUE(hit(box, Vec3(-1, 1, 1), Vec3(1, 0, 0), 0, 1));
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(hit(box, Vec3(-1, 1, 1), Vec3(1, 0, 0), 2, 10));  // starting inside the range
  EXPECT_NEAR(t, 2, 1e-12);
  EXPECT_FALSE(hit(box, Vec3(-1, 1, 1), Vec3(-1, 0, 0)));
  EXPECT_TRUE(hit(flat, Vec3(-1, 1, 0), Vec3(1, 0.1, 0)));  // lying in the flat box
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(hit(flat, Vec3(1, 1, 5), Vec3(0, 0, -1)));  // through it
  EXPECT_NEAR(t, 5, 1e-12);
  EXPECT_FALSE(hit(flat, Vec3(-1, 1, 1e-9), Vec3(1, 0, 0)));

  Prism p;  // the triangle (0,0), (2,0), (0,2) swept from z = 0 to z = 1
  p.base = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)};
  p.axis = Vec3::UnitZ();
  p.height = 1;
  EXPECT_TRUE(hit(p, Vec3(3, 3, 0.5), Vec3(-1, -1, 0)));  // enters through the hypotenuse
  EXPECT_NEAR(t, 2, 1e-12);
  EXPECT_TRUE(hit(p, Vec3(-1, 3, 0.5), Vec3(1, -1, 0)));  // along the hypotenuse
  EXPECT_FALSE(hit(p, Vec3(-1, 3.001, 0.5), Vec3(1, -1, 0)));
  EXPECT_TRUE(hit(p, Vec3(2, 0, 5), Vec3(0, 0, -1)));  // down a vertical edge
  EXPECT_NEAR(t, 4, 1e-12);
  EXPECT_TRUE(hit(p, Vec3(0.5, 0.5, 3), Vec3(0, 0, -1)));
  EXPECT_NEAR(t, 2, 1e-12);
  EXPECT_FALSE(hit(p, Vec3(1.001, 1.001, 3), Vec3(0, 0, -1)));
  p.height = 0;                                        // the facet
  EXPECT_TRUE(hit(p, Vec3(-1, 1, 0), Vec3(1, 0, 0)));  // in its plane
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_FALSE(hit(p, Vec3(-1, 1, 1e-9), Vec3(1, 0, 0)));
  // A segment and a point.
  const Prism segment = prism_from_triangle(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 0, 0));
  EXPECT_TRUE(hit(segment, Vec3(-1, 0, 0), Vec3(1, 0, 0)));
  EXPECT_NEAR(t, 1, 1e-12);
  EXPECT_TRUE(hit(segment, Vec3(1, -1, -1), Vec3(0, 1, 1)));
  EXPECT_FALSE(hit(segment, Vec3(3, -1, -1), Vec3(0, 1, 1)));  // past the segment's end
  EXPECT_FALSE(hit(segment, Vec3(2.001, -1, 0), Vec3(0, 1, 0)));
  const Prism point = prism_from_triangle(Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1));
  EXPECT_TRUE(hit(point, Vec3(0, 0, 0), Vec3(1, 1, 1)));
  EXPECT_FALSE(hit(point, Vec3(0, 0, 0), Vec3(1, 1, 1.001)));
  // Invalid rays miss.
  EXPECT_FALSE(hit(box, Vec3(std::nan(""), 1, 1), Vec3(1, 0, 0)));
  EXPECT_FALSE(hit(box, Vec3(std::nan(""), 1, 1), Vec3(1, 1, 1)));
  EXPECT_FALSE(hit(p, Vec3(std::nan(""), 1, 1), Vec3(1, 1, 1)));
  EXPECT_FALSE(hit(p, Vec3(0, 0, 0), Vec3(std::nan(""), 1, 1)));
}

TEST(VolumeQueries, ExactShapesMatchAabbReference) {
  // Boxes with signed-permutation axes are AABBs: every query must give the AABB's answer
  // (exact integer geometry, touching cases frequent).
  Random rng(53);
  for (int i = 0; i < scaled(3000); ++i) {
    const ExactShape s = random_exact_shape(rng, ExactShape::kObb);
    Aabb a;
    for (const Vec3& c : s.corner_list) a.expand(c);
    const Vec3 c = rng.grid_point(-4, 4, 2);
    const Real r = rng.grid(0, 3, 2);
    ASSERT_EQ(overlaps(s.obb, Sphere{c, r}), overlaps(a, Sphere{c, r})) << i;
    const Vec3 c1 = rng.grid_point(-4, 4, 2);
    ASSERT_EQ(overlaps(s.obb, Capsule{c, c1, r}), overlaps(a, Capsule{c, c1, r})) << i;
    const Plane plane{rng.grid_point(-2, 2), rng.grid(-6, 6)};
    ASSERT_EQ(overlaps(s.obb, plane), overlaps(a, plane)) << i;
    ASSERT_EQ(contains(s.obb, c), contains(a, c)) << i;
    const Vec3 q_corner = rng.grid_point(-4, 4, 2);  // the second corner first: see tests/support/random.h
    const Aabb q = Aabb::from_points(rng.grid_point(-4, 4, 2), q_corner);
    ASSERT_EQ(overlaps(s.obb, q), overlaps(a, q)) << i;
    const Vec3 o = rng.grid_point(-5, 5, 2);
    const Vec3 d = rng.grid_point(-2, 2);
    if (!d.isZero()) {
      Real t1 = -1, t2 = -1;
      const bool h1 = intersect_ray(s.obb, RayPrecomputed(Ray{o, d}), 0, kInf, &t1);
      const bool h2 = intersect_ray(a, RayPrecomputed(Ray{o, d}), 0, kInf, &t2);
      ASSERT_EQ(h1, h2) << i << " " << str(o) << " " << str(d);
      if (h1) {
        EXPECT_NEAR(t1, t2, 1e-12) << i;
      }
    }
  }
}

TEST(VolumeQueries, PrismSphereAndCapsuleAreExactOnGridPrisms) {
  // Axis-aligned grid prisms: the distance is the in-plane distance to the triangle combined with
  // the axial one; check spheres against that formula in long double, touching included, and
  // capsules of radius 0 against the exact segment/polytope LP.
  Random rng(54);
  int touching = 0;
  for (int i = 0; i < scaled(3000); ++i) {
    const ExactShape s = random_exact_shape(rng, ExactShape::kPrism);
    const Vec3 c = rng.grid_point(-4, 4, 2);
    // The axis is a coordinate axis, so the distance separates exactly into the in-plane one
    // (to the grid triangle) and the axial one.
    const Prism& p = s.prism;
    const Real height = std::clamp(p.axis.dot(c - p.base[0]), Real(0), p.height);
    const Vec3 q = c - height * p.axis;
    const Real closest = (closest_point_on_triangle(q, p.base[0], p.base[1], p.base[2]) - q).norm();
    const Real r = rng.grid(0, 3, 2);
    if (std::abs(closest - r) < 1e-9) ++touching;
    if (closest <= r + 1e-12) {
      ASSERT_TRUE(overlaps(p, Sphere{c, r})) << i;
    } else if (closest > r + 1e-9) {
      ASSERT_FALSE(overlaps(p, Sphere{c, r})) << i;
    }
    const Vec3 c1 = rng.grid_point(-4, 4, 2);
    const bool segment_meets = hulls_intersect(s.exact_corners(), {exact(c), exact(c1)});
    ASSERT_EQ(overlaps(p, Capsule{c, c1, 0}), segment_meets) << i << " " << str(c) << " " << str(c1);
    ASSERT_EQ(contains(p, c), hulls_intersect(s.exact_corners(), {exact(c)})) << i;
  }
  EXPECT_GT(touching, scaled(3000) / 300);
}

}  // namespace
}  // namespace boxtree
