// SPDX-License-Identifier: MIT
// Fitting primitives (detail/fit.h): principal axes, 2D convex hull, minimum-area enclosing
// rectangle, minimum-area enclosing triangle (general and isosceles).
//
// Shared conventions:
//  * The hull is exact: its orientation predicate is Shewchuk's filtered orient2d with an exact
//    fallback ("Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//    Predicates", 1997), so a hull vertex is exactly an extreme point of the input (for inputs
//    whose products neither overflow nor underflow).
//  * The optimizers work in coordinates relative to a hull vertex, so large offsets cost no
//    precision, on the hull less the vertices whose turn is lost in rounding noise (HullFrame:
//    near-duplicates, as in the corners of a box seen along its own axis). Their answer is a set
//    of side directions; the final shape is rebuilt from those directions and the support
//    values of *all* input points, checked point by point, and pushed outward until every point
//    is inside by a margin that any double evaluation of the containment test sees (see
//    enclosing_triangle / enclosing_rectangle).
//  * A triangle is handled through its three unit outward side normals n_k in counter-clockwise
//    order and offsets h_k (side k is the line n_k . x = h_k). With s_k = n_{k+1} x n_{k+2} (the
//    sine of the angle between the other two normals; all three positive iff the normals bound a
//    triangle), its area is (sum_k s_k h_k)^2 / (2 s_0 s_1 s_2).
// Cost on 12 points all on the hull (tests/test_fit.cpp, FitPerformance): principal axes 0.5 us,
// hull 0.2 us, rectangle 0.6 us, triangle 4 us, isosceles triangle 13 us; a third of that for
// the triangles when only ~7 of the 12 points are on the hull.
#include "boxtree/detail/fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "boxtree/error.h"
#include "internal.h"

namespace boxtree::detail {
namespace {

constexpr Real kPi = 3.14159265358979323846;
constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr Real kUlp = std::numeric_limits<Real>::epsilon();  // 2^-52
constexpr Real kRoundoff = kUlp / 2;                         // 2^-53, Shewchuk's epsilon
// Relative error bound of the plain double evaluation of orient2d (Shewchuk 1997, ccwerrboundA).
constexpr Real kOrientErrorBound = (3 + 16 * kRoundoff) * kRoundoff;
// Padding added to enclosing shapes, in units of the input's largest coordinate magnitude.
constexpr Real kPaddingUlps = 4;
// Smallest sine of an angle of a returned triangle: below it, rounding the corners to doubles
// moves the sides by more than the padding can absorb (a corner of angle alpha moves by
// (side shift) / sin(alpha)).
constexpr Real kMinSine = 1e-8;

Real cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
Vec2 perp(const Vec2& v) { return Vec2(-v.y(), v.x()); }  // rotated by +90 degrees

bool all_finite(const std::vector<Vec2>& points) {
  return std::all_of(points.begin(), points.end(),
                     [](const Vec2& p) { return std::isfinite(p.x()) && std::isfinite(p.y()); });
}

Real coordinate_scale(const std::vector<Vec2>& points) {
  Real scale = 0;
  for (const Vec2& p : points) scale = std::max(scale, p.cwiseAbs().maxCoeff());
  return scale;
}

// ---- Exact orientation (Shewchuk 1997) ----

void two_sum(Real a, Real b, Real& sum, Real& error) {
  sum = a + b;
  const Real b_virtual = sum - a;
  const Real a_virtual = sum - b_virtual;
  error = (a - a_virtual) + (b - b_virtual);
}

// Sign of (a - c) x (b - c) from its six-product expansion, each product split exactly by fma
// into a double and its rounding error, summed into a non-overlapping expansion (Shewchuk's
// Grow-Expansion with zero elimination): the sign of the largest component is the exact sign.
int orient_sign_exact(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Real factors[6][2] = {{a.x(), b.y()},  {-a.x(), c.y()}, {-c.x(), b.y()},
                              {-a.y(), b.x()}, {a.y(), c.x()},  {c.y(), b.x()}};
  Real expansion[13];
  int length = 0;
  auto grow = [&](Real term) {
    Real q = term;
    int out = 0;
    for (int i = 0; i < length; ++i) {
      Real sum;
      Real error;
      two_sum(q, expansion[i], sum, error);
      if (error != 0) expansion[out++] = error;
      q = sum;
    }
    expansion[out++] = q;
    length = out;
  };
  for (const auto& f : factors) {
    const Real product = f[0] * f[1];
    grow(std::fma(f[0], f[1], -product));
    grow(product);
  }
  for (int i = length - 1; i >= 0; --i)
    if (expansion[i] != 0) return expansion[i] > 0 ? 1 : -1;
  return 0;
}

// +1 if (a, b, c) turn counter-clockwise, -1 clockwise, 0 collinear; exact.
int orient_sign(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Real left = (a.x() - c.x()) * (b.y() - c.y());
  const Real right = (a.y() - c.y()) * (b.x() - c.x());
  const Real det = left - right;
  const Real bound = kOrientErrorBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orient_sign_exact(a, b, c);
}

// True when p is on the left of the directed line a -> b by a margin larger than twice the
// rounding error of the plain double orientation test, so that this test evaluated in any
// order (or in higher precision) also finds p inside.
bool certainly_left(const Vec2& a, const Vec2& b, const Vec2& p) {
  const Real left = (a.x() - p.x()) * (b.y() - p.y());
  const Real right = (a.y() - p.y()) * (b.x() - p.x());
  return left - right >= 2 * kOrientErrorBound * (std::abs(left) + std::abs(right));
}

// ---- Enclosing shapes rebuilt from directions, checked and padded ----

// Intersection of the lines n0 . x = h0 and n1 . x = h1 (not parallel).
Vec2 line_intersection(const Vec2& n0, Real h0, const Vec2& n1, Real h1) {
  const Real det = cross2(n0, n1);
  return Vec2((h0 * n1.y() - h1 * n0.y()) / det, (n0.x() * h1 - n1.x() * h0) / det);
}

// The triangle with unit outward side normals `normals` (counter-clockwise, bounding a
// triangle) whose sides are the support lines of `points` pushed out by a padding, grown (per
// side, geometrically) until certainly_left holds for every point and side. Corner k is where
// side k - 1 meets side k, so side k runs from corner k to corner k + 1.
Triangle2 enclosing_triangle(const std::vector<Vec2>& points, const Vec2& origin, const std::array<Vec2, 3>& normals) {
  std::array<Real, 3> support{-kInf, -kInf, -kInf};
  for (const Vec2& p : points) {
    const Vec2 local = p - origin;
    for (int k = 0; k < 3; ++k) support[k] = std::max(support[k], normals[k].dot(local));
  }
  const Real scale = std::max(coordinate_scale(points), std::numeric_limits<Real>::min());
  std::array<Real, 3> pad;
  pad.fill(kPaddingUlps * kUlp * scale);
  Triangle2 t;
  for (int attempt = 0; attempt < 256; ++attempt) {
    for (int k = 0; k < 3; ++k) {
      const int prev = (k + 2) % 3;
      t.corners[k] =
          origin + line_intersection(normals[prev], support[prev] + pad[prev], normals[k], support[k] + pad[k]);
    }
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const Vec2& a = t.corners[k];
      const Vec2& b = t.corners[(k + 1) % 3];
      const bool side_ok =
          std::all_of(points.begin(), points.end(), [&](const Vec2& p) { return certainly_left(a, b, p); });
      if (!side_ok) {
        pad[k] *= 4;
        ok = false;
      }
    }
    if (ok) return t;
  }
  BOXTREE_ASSERT(false, "enclosing triangle: padding did not converge (non-finite or overflowing input?)");
  return t;
}

// The rectangle with axis `axis_u` (unit) that encloses `points`: extents measured exactly the
// way a caller tests containment, |(p - center) . axis| <= half, then padded.
Rectangle2 enclosing_rectangle(const std::vector<Vec2>& points, const Vec2& origin, const Vec2& axis_u) {
  Rectangle2 r;
  r.axis_u = axis_u;
  const Vec2 axis_v = r.axis_v();
  Real min_u = kInf, max_u = -kInf, min_v = kInf, max_v = -kInf;
  for (const Vec2& p : points) {
    const Vec2 local = p - origin;
    const Real u = local.dot(axis_u);
    const Real v = local.dot(axis_v);
    min_u = std::min(min_u, u);
    max_u = std::max(max_u, u);
    min_v = std::min(min_v, v);
    max_v = std::max(max_v, v);
  }
  r.center = origin + axis_u * ((min_u + max_u) / 2) + axis_v * ((min_v + max_v) / 2);
  Real half_u = 0, half_v = 0;
  for (const Vec2& p : points) {
    half_u = std::max(half_u, std::abs((p - r.center).dot(axis_u)));
    half_v = std::max(half_v, std::abs((p - r.center).dot(axis_v)));
  }
  const Real pad = kPaddingUlps * kUlp * coordinate_scale(points);
  r.half_u = half_u + pad;
  r.half_v = half_v + pad;
  return r;
}

// A hull of 0, 1 or 2 points as a degenerate triangle: the point, or the segment with its
// midpoint as third corner (so the isosceles contract |c2 - c0| = |c2 - c1| also holds). The
// rounded midpoint may lie off the segment by an ulp; the ends are then ordered so that the
// sliver is counter-clockwise.
Triangle2 degenerate_triangle(const std::vector<Vec2>& hull) {
  Triangle2 t;
  if (hull.empty()) {
    t.corners.fill(Vec2::Zero());
  } else if (hull.size() == 1) {
    t.corners.fill(hull[0]);
  } else {
    const Vec2 mid = hull[0] + (hull[1] - hull[0]) / 2;
    if (orient_sign(hull[0], hull[1], mid) >= 0) {
      t.corners = {hull[0], hull[1], mid};
    } else {
      t.corners = {hull[1], hull[0], mid};
    }
  }
  return t;
}

// The hull as the optimizers see it, in coordinates relative to its first vertex, with unit edge
// directions and outward normals. The exact hull may keep vertices that rounding cannot tell
// apart from their neighbours (near-duplicates: the corners of a box or prism projected along
// one of its own axes; nearly collinear runs): their edges have directions that are mostly
// rounding noise, which breaks the monotone turning of edge normals that the rotating calipers,
// the wedge scans and the hill climbing rely on. So vertices whose turn is not clearly larger
// than that noise are dropped (worst first), until every turn is: the vertices dropped lie
// outside the simplified polygon by a few ulps of its size, which costs nothing in optimality
// and nothing in containment (the final shapes are rebuilt from all input points). A hull
// that is a segment up to rounding ends with two vertices.
struct HullFrame {
  Vec2 origin;               // hull[0]
  std::vector<Vec2> vertex;  // hull[k] - origin, simplified
  std::vector<Vec2> edge;    // unit direction of vertex[k] -> vertex[k + 1]
  std::vector<Vec2> normal;  // unit outward normal of that edge
  std::vector<Real> offset;  // normal[k] . vertex[k]

  explicit HullFrame(const std::vector<Vec2>& hull) : origin(hull[0]) {
    vertex.reserve(hull.size());
    for (const Vec2& p : hull) vertex.push_back(p - origin);
    simplify();
    const std::size_t n = vertex.size();
    edge.resize(n);
    normal.resize(n);
    offset.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      edge[k] = (vertex[(k + 1) % n] - vertex[k]).normalized();
      normal[k] = Vec2(edge[k].y(), -edge[k].x());
      offset[k] = normal[k].dot(vertex[k]);
    }
  }
  std::size_t size() const { return vertex.size(); }

 private:
  // An edge e computed from coordinates of magnitude R has a direction error of about
  // eps R / |e|; the turn angle at a vertex (in (0, pi) for a convex polygon; a sharp turn is
  // as good as a wide one) must exceed 16 times the sum of its two edges' errors.
  void simplify() {
    Real radius = 0;
    for (const Vec2& v : vertex) radius = std::max(radius, v.norm());
    const Real noise = 16 * kUlp * radius;
    while (vertex.size() > 2) {
      const std::size_t n = vertex.size();
      std::size_t worst = n;
      Real worst_score = 1;
      for (std::size_t k = 0; k < n; ++k) {
        const Vec2 a = vertex[k] - vertex[(k + n - 1) % n];
        const Vec2 b = vertex[(k + 1) % n] - vertex[k];
        const Real la = a.norm(), lb = b.norm();
        const Real error = noise * (1 / la + 1 / lb);
        const Real cross = cross2(a, b), dot = a.dot(b);
        if (error < kPi / 2 && (dot <= 0 || cross >= error * la * lb)) continue;  // turn >= error
        const Real score = std::atan2(cross, dot) / error;
        if (!(score >= worst_score)) {
          worst_score = score;
          worst = k;
        }
      }
      if (worst == n) return;
      vertex.erase(vertex.begin() + static_cast<std::ptrdiff_t>(worst));
    }
  }
};

// Area of the triangle bounded by the support lines of the hull with these unit outward normals
// (counter-clockwise), infinite if they bound no triangle. The optimizers compute areas from
// their own contact points; a candidate that beats the best so far is re-scored here, so that
// a near-degenerate candidate misjudged by rounding (a side nearly parallel to another) can
// never win with a meaningless area.
Real support_triangle_area(const HullFrame& hull, const std::array<Vec2, 3>& normal) {
  Real s[3];
  for (int k = 0; k < 3; ++k) {
    s[k] = cross2(normal[(k + 1) % 3], normal[(k + 2) % 3]);
    if (!(s[k] > 0)) return kInf;
  }
  Real weighted = 0;
  for (int k = 0; k < 3; ++k) {
    Real support = -kInf;
    for (const Vec2& v : hull.vertex) support = std::max(support, normal[k].dot(v));
    weighted += s[k] * support;
  }
  return weighted * weighted / (2 * s[0] * s[1] * s[2]);
}

// ---- Real roots of a small polynomial on an interval ----

Real evaluate_polynomial(const Real* coefficient, int degree, Real x) {
  Real value = coefficient[degree];
  for (int i = degree - 1; i >= 0; --i) value = value * x + coefficient[i];
  return value;
}

// min |p0 + p1 x + p2 x^2| over [x1, x2] (zero where the quadratic changes sign).
Real quadratic_min_abs(Real p0, Real p1, Real p2, Real x1, Real x2) {
  const Real coefficient[3] = {p0, p1, p2};
  const Real f1 = evaluate_polynomial(coefficient, 2, x1), f2 = evaluate_polynomial(coefficient, 2, x2);
  if ((f1 < 0) != (f2 < 0)) return 0;
  Real lowest = std::min(std::abs(f1), std::abs(f2));
  if (p2 != 0) {
    const Real vertex = -p1 / (2 * p2);
    if (vertex > x1 && vertex < x2) {
      const Real fv = evaluate_polynomial(coefficient, 2, vertex);
      if ((fv < 0) != (f1 < 0)) return 0;
      lowest = std::min(lowest, std::abs(fv));
    }
  }
  return lowest;
}

// The points of the open interval (lo, hi) where a polynomial of degree <= 4 (coefficients low
// to high) changes sign, increasing; returns how many. Recursion on the derivative: between
// consecutive sign changes of the derivative the polynomial is monotone, so each such piece
// holds at most one root, found by Newton's method safeguarded by bisection. Roots without a
// sign change (even multiplicity) are skipped, which is harmless here: such a stationary point
// of the area is no minimum, and the interval ends are candidates of their own.
int sign_change_roots(const Real* coefficient, int degree, Real lo, Real hi, Real* roots) {
  while (degree > 0 && coefficient[degree] == 0) --degree;
  if (degree <= 0 || !(lo < hi)) return 0;
  if (degree == 1) {
    const Real x = -coefficient[0] / coefficient[1];
    if (!(x > lo && x < hi)) return 0;
    roots[0] = x;
    return 1;
  }
  // No root if the value at lo (less its rounding error) cannot be cancelled over the interval:
  // |P'| <= sum i |c_i| m^(i-1) with m = max(|lo|, |hi|).
  const Real m = std::max(std::abs(lo), std::abs(hi));
  Real slope = 0, magnitude = 0;
  for (int i = degree; i >= 1; --i) slope = slope * m + i * std::abs(coefficient[i]);
  for (int i = degree; i >= 0; --i) magnitude = magnitude * m + std::abs(coefficient[i]);
  if (std::abs(evaluate_polynomial(coefficient, degree, lo)) - 8 * kUlp * magnitude > slope * (hi - lo)) return 0;
  Real derivative[4];
  for (int i = 1; i <= degree; ++i) derivative[i - 1] = i * coefficient[i];
  Real split[6];
  split[0] = lo;
  int count = 1 + sign_change_roots(derivative, degree - 1, lo, hi, split + 1);
  split[count++] = hi;
  int found = 0;
  for (int i = 0; i + 1 < count; ++i) {
    Real a = split[i], b = split[i + 1];
    const Real fa = evaluate_polynomial(coefficient, degree, a);
    const Real fb = evaluate_polynomial(coefficient, degree, b);
    if (fa == 0 || fb == 0 || (fa < 0) == (fb < 0)) continue;
    Real x = (a + b) / 2;
    for (int iteration = 0; iteration < 100; ++iteration) {
      const Real fx = evaluate_polynomial(coefficient, degree, x);
      if (fx == 0) break;
      if ((fx < 0) == (fa < 0)) {
        a = x;
      } else {
        b = x;
      }
      Real next = x - fx / evaluate_polynomial(derivative, degree - 1, x);
      if (!(next > a && next < b)) next = (a + b) / 2;  // also when the derivative vanishes
      const bool converged = std::abs(next - x) <= 4 * kUlp * std::max<Real>(1, std::abs(x));
      x = next;
      if (converged) break;
    }
    roots[found++] = x;
  }
  return found;
}

// ---- Minimum-area enclosing triangle ----
//
// Characterization (Klamkin & Chakerian 1982; O'Rourke, Aggarwal, Maddila, Baldwin 1986): in a
// locally minimal enclosing triangle every side that is not flush with a hull edge touches the
// hull at one vertex, and that vertex is the side's midpoint (rotating the side about the
// vertex changes the area at rate (l1^2 - l2^2) / 2, l1 and l2 the two parts of the side).
// We strengthen "at least one side flush" to "at least two sides flush" for some minimum:
//  * no flush side: the three sides touch at their midpoints m_k; rotating every side by delta
//    about m_k maps the triangle by the spiral similarity about its circumcenter with ratio
//    cos(delta), so the area drops for either sign of delta -- not a local minimum;
//  * exactly one flush side C: the other two touch at vertices p, q that are their midpoints,
//    which forces q - p parallel to C; sliding the apex parallel to C (base corners X, Y and
//    apex Z with Z = 2p - X = 2q - Y) keeps the area and both midpoint contacts. It cannot go on
//    forever: in one direction side A's outward normal tends to C's, which is no support
//    direction at p, so first A or B turns flush with an edge at p or q -- an optimal triangle
//    with two flush sides.
// So we enumerate every pair of hull edges (i, j) whose outward normals turn counter-clockwise
// by less than pi: their lines form a wedge containing the hull, and the third side is the
// support line minimizing the area cut from the wedge. In the wedge's oblique coordinates
// (x = V + s r1 + t r2) a line is (1/s_0, 1/t_0) and "the triangle contains vertex (a, b)" is
// the linear constraint a/s_0 + b/t_0 <= 1, while area ~ s_0 t_0: maximizing the strictly
// concave log(1/s_0) + log(1/t_0) over a convex polygon has a unique optimum, and along the
// polygon's boundary the objective is unimodal. The polygon's vertices are the third side
// flush with a hull edge k, its edges are the third side turning about a hull vertex, optimal
// there when that vertex is the side's midpoint (s_0 = 2a, t_0 = 2b). So the exact optimum of
// a wedge is the best flush edge k* or the midpoint line of one of k*'s two endpoints (or, if
// no edge normal falls inside the wedge's range, of the one vertex facing it), and the best
// wedge is the global minimum: O(h^2) wedges of O(h) each, O(h^3), which for the h <= 16 of
// the pie-slice rule is a few thousand cheap steps. (O'Rourke et al. reach O(h) by walking the
// wedges with pointers over the same characterization; the plain enumeration is easier to
// verify, and every candidate that wins is re-scored from scratch by support_triangle_area.)

// The exact minimum over triangles with sides on the lines of hull edges i and j (outward
// normals turning counter-clockwise by less than pi) and a third side supporting the hull: its
// area from the wedge formulas, and the third side's unit outward normal -- if below `cutoff`
// (otherwise area == cutoff and no normal).
struct WedgeBest {
  Real area = kInf;
  Vec2 normal = Vec2::Zero();
};

WedgeBest wedge_minimum(const HullFrame& hull, std::size_t i, std::size_t j, Real cutoff) {
  const std::size_t n = hull.size();
  const Vec2& ni = hull.normal[i];
  const Vec2& nj = hull.normal[j];
  WedgeBest best;
  best.area = cutoff;
  if (!(cross2(ni, nj) > 0)) return best;  // need a counter-clockwise turn in (0, pi)
  const Vec2 apex = line_intersection(ni, hull.offset[i], nj, hull.offset[j]);
  const Vec2 r1 = -hull.edge[i];  // the wedge's rays from the apex, towards the hull
  const Vec2 r2 = hull.edge[j];
  const Real wedge_cross = cross2(r1, r2);
  const Real wedge_sine = std::abs(wedge_cross);

  // Third side flush with edge k, k on the far chain j+1 .. i-1 with its normal strictly
  // between -n_i and -n_j. Going counter-clockwise along the chain the normals pass -n_i, then
  // -n_j; `first_past` is the first edge beyond -n_i: if none lies in the range, the start
  // vertex of that edge is the one facing the whole range.
  std::size_t best_k = n, first_past = n;
  Real best_k_area = kInf;
  for (std::size_t k = (j + 1) % n; k != i; k = (k + 1) % n) {
    const Vec2& nk = hull.normal[k];
    if (!(cross2(nk, ni) > 0)) continue;
    if (first_past == n) first_past = k;
    if (!(cross2(nj, nk) > 0)) break;
    const Real gap = hull.offset[k] - nk.dot(apex);
    const Real s = gap / nk.dot(r1);
    const Real t = gap / nk.dot(r2);
    if (!(s > 0 && t > 0)) continue;
    const Real area = s * t * wedge_sine / 2;
    if (area < best_k_area) {
      best_k_area = area;
      best_k = k;
    }
  }
  if (best_k < n && best_k_area < best.area) {
    best.area = best_k_area;
    best.normal = hull.normal[best_k];
  }

  // Third side touching vertex m at its midpoint.
  auto try_midpoint = [&](std::size_t m) {
    if (m == i || m == (i + 1) % n || m == j || m == (j + 1) % n) return;  // on the wedge's sides
    const Vec2 w = hull.vertex[m] - apex;
    const Real a = cross2(w, r2) / wedge_cross;
    const Real b = cross2(r1, w) / wedge_cross;
    const Real area = 2 * a * b * wedge_sine;
    if (!(a > 0 && b > 0) || !(area < best.area)) return;
    // From X = apex + 2a r1 to Y = apex + 2b r2; (side.y, -side.x) . (m - apex) = 4ab (r1 x r2),
    // so the normal pointing away from the apex is that one times sign(r1 x r2).
    const Vec2 side = r2 * (2 * b) - r1 * (2 * a);
    const Vec2 outward = wedge_cross > 0 ? Vec2(side.y(), -side.x()) : Vec2(-side.y(), side.x());
    const Vec2& prev = hull.vertex[(m + n - 1) % n];
    const Vec2& next = hull.vertex[(m + 1) % n];
    if (outward.dot(prev - hull.vertex[m]) > 0 || outward.dot(next - hull.vertex[m]) > 0) return;
    best.area = area;
    best.normal = outward.normalized();
  };
  if (best_k < n) {
    try_midpoint(best_k);
    try_midpoint((best_k + 1) % n);
  } else if (first_past < n) {
    try_midpoint(first_past);
  }
  return best;
}

std::array<Vec2, 3> min_area_triangle_normals(const HullFrame& hull) {
  const std::size_t n = hull.size();
  Real best_area = kInf;
  std::array<Vec2, 3> best = {hull.normal[0], hull.normal[1], hull.normal[2]};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      const WedgeBest wedge = wedge_minimum(hull, i, j, best_area);
      if (!(wedge.area < best_area)) continue;
      const std::array<Vec2, 3> candidate = {hull.normal[i], hull.normal[j], wedge.normal};
      const Real area = support_triangle_area(hull, candidate);  // re-scored, see there
      if (area < best_area) {
        best_area = area;
        best = candidate;
      }
    }
  }
  return best;
}

// For every hull edge e, the minimum area of an enclosing triangle with a side on e's line:
// by the same argument as above (with e held flush, the other two sides still touch at their
// midpoints, and sliding ends at a second flush side) it is the best wedge containing e.
std::vector<Real> flush_minimum(const HullFrame& hull) {
  const std::size_t n = hull.size();
  std::vector<Real> minimum(n, kInf);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const Real area = wedge_minimum(hull, i, j, std::max(minimum[i], minimum[j])).area;
      minimum[i] = std::min(minimum[i], area);
      minimum[j] = std::min(minimum[j], area);
    }
  return minimum;
}

// ---- Minimum-area enclosing isosceles triangle ----
//
// Parametrization: axis direction d at angle theta (base towards apex) and base angle beta in
// (0, pi/2). The base has outward normal -d (angle theta + pi), the legs theta - beta (right)
// and theta + beta (left); any three support lines with these normals bound an isosceles
// triangle, whatever their offsets. Claim: some minimum has a side flush with a hull edge.
// Rotating all three sides together (theta += delta, beta fixed) keeps the shape, and while
// every side touches the hull at one vertex p_k its area is (sum_k lambda_k n_k(delta) . p_k)^2
// times a constant, i.e. proportional to cos^2(delta - delta_0): no local minimum unless a
// contact changes, i.e. a side is flush. So we try every hull edge as the base, as the right
// leg and as the left leg; each leaves the one-parameter family beta -> triangle, whose normal
// angles are phi_k(beta) = phi_k0 + c_k beta. Along it the contacts change only where some
// phi_k crosses an edge normal ("breakpoints"); between them the contacts are fixed vertices
// and the area is a closed-form function of beta whose stationary points we solve for:
//  * edge as base (frame: base on the x axis, hull above): with right/left contacts (x_R, y_R),
//    (x_L, y_L), w = x_R - x_L, s = y_R + y_L, t = tan(beta): A = (w t + s)^2 / (4 t), convex
//    in t, minimal at t = s / w;
//  * edge as right leg (frame: leg on the x axis, hull above; the left-leg case is its mirror
//    image, x -> -x): base contact b, left-leg contact l, u = cot(beta):
//    A = N(u)^2 / (4 u (1 + u^2)), N = k u^2 + 2 D u + l_y, k = 2 b_y - l_y, D = l_x - b_x, and
//    dA/du = N Q / (4 u^2 (1 + u^2)^2) with Q = k u^4 - 2 D u^3 + 3 (k - l_y) u^2 + 2 D u - l_y
//    (N = 0 would be zero area); the roots of Q are found on u in [0, 1] and, as Q(1/t) t^4, on
//    t = tan(beta) in [0, 1].
// Evaluating every breakpoint and every stationary point of every piece gives the exact
// minimum (up to rounding): h edges x 3 roles x O(h) pieces, contacts found by hill climbing
// from the previous piece's. Angles are carried as tangents, breakpoints included (a crossing
// at relative angle r has beta = r or r / 2, tan(r / 2) = sin r / (1 + cos r)), so the loops
// need no trigonometric calls. Two prunings keep this fast without losing exactness: edges are
// visited by increasing flush_minimum (a lower bound for all their triangles) and skipped once
// it reaches the best area, and a piece's root finding is skipped when a lower bound of its
// area cannot win.
struct IsoscelesSide {
  Vec2 normal0;  // unit outward normal at beta = 0
  int rate;      // d(angle) / d(beta), in {-2, -1, 0, 1, 2}
};

// An angle beta in [0, pi/2] as its cosine and sine (or any positive multiple of them, where
// only a direction matters).
struct BaseAngle {
  Real cos = 1;
  Real sin = 0;
  static BaseAngle from_tan(Real t) {
    const Real c = 1 / std::sqrt(1 + t * t);
    return {c, t * c};
  }
  static BaseAngle from_vector(Real c, Real s) {  // (c, s) with c >= 0, s >= 0, not both zero
    const Real norm = std::sqrt(c * c + s * s);   // O(1) values: no overflow
    return {c / norm, s / norm};
  }
};

// Rotation of v by rate * beta.
Vec2 rotated(const Vec2& v, int rate, const BaseAngle& beta) {
  Real c = 1, s = 0;
  if (rate == 1 || rate == -1) {
    c = beta.cos;
    s = beta.sin;
  } else if (rate == 2 || rate == -2) {
    c = beta.cos * beta.cos - beta.sin * beta.sin;
    s = 2 * beta.sin * beta.cos;
  }
  if (rate < 0) s = -s;
  return Vec2(c * v.x() - s * v.y(), s * v.x() + c * v.y());
}

struct IsoscelesBest {
  Real area = kInf;
  Vec2 axis0 = Vec2::UnitY();  // d at beta = 0
  int axis_rate = 0;
  BaseAngle beta = BaseAngle::from_tan(1);
};

// The hull vertex extreme in `direction`, by hill climbing from `start`: the support function
// along a convex polygon is unimodal, and consecutive pieces move the contact by a vertex or
// two, so this is O(1) per piece instead of O(h).
std::size_t support_vertex(const HullFrame& hull, const Vec2& direction, std::size_t start) {
  const std::size_t n = hull.size();
  std::size_t best = start;
  Real best_value = direction.dot(hull.vertex[best]);
  for (std::size_t step = 0; step < n; ++step) {
    const std::size_t next = best + 1 == n ? 0 : best + 1, prev = best == 0 ? n - 1 : best - 1;
    const Real next_value = direction.dot(hull.vertex[next]), prev_value = direction.dot(hull.vertex[prev]);
    if (next_value > best_value && next_value >= prev_value) {
      best = next;
      best_value = next_value;
    } else if (prev_value > best_value) {
      best = prev;
      best_value = prev_value;
    } else {
      break;
    }
  }
  return best;
}

enum class FlushRole { base, right_leg, left_leg };

void minimize_isosceles_with_flush_edge(const HullFrame& hull, std::size_t edge, FlushRole role,
                                        std::vector<Real>& breakpoints, IsoscelesBest& best) {
  const Vec2& out = hull.normal[edge];
  // Sides in counter-clockwise order of their normals, and d(beta) = rotated(axis0, axis_rate).
  std::array<IsoscelesSide, 3> side;
  Vec2 axis0 = out;
  int axis_rate;
  switch (role) {
    case FlushRole::base:  // base, right leg, left leg
      side = {IsoscelesSide{out, 0}, IsoscelesSide{-out, -1}, IsoscelesSide{-out, 1}};
      axis0 = -out;
      axis_rate = 0;
      break;
    case FlushRole::right_leg:  // right leg, left leg, base
      side = {IsoscelesSide{out, 0}, IsoscelesSide{out, 2}, IsoscelesSide{-out, 1}};
      axis_rate = 1;
      break;
    default:  // left leg flush: right leg, left leg, base
      side = {IsoscelesSide{out, -2}, IsoscelesSide{out, 0}, IsoscelesSide{-out, -1}};
      axis_rate = -1;
      break;
  }

  // Breakpoints, as tan(beta) for beta in (0, pi/2), where a moving side's normal crosses an
  // edge normal. With (c, s) the cosine and sine of the edge normal's angle r relative to the
  // side's start (s mirrored for clockwise sides), beta is r (|rate| 1, needs c > 0) or r / 2,
  // whose tangent is s / (1 + c).
  breakpoints.clear();
  for (const IsoscelesSide& s : side) {
    if (s.rate == 0) continue;
    for (const Vec2& normal : hull.normal) {
      const Real c = s.normal0.dot(normal);
      const Real sine = s.rate > 0 ? cross2(s.normal0, normal) : -cross2(s.normal0, normal);
      if (!(sine > 0)) continue;
      if (s.rate == 1 || s.rate == -1) {
        if (c > 0) breakpoints.push_back(sine / c);
      } else {
        breakpoints.push_back(sine / (1 + c));
      }
    }
  }
  breakpoints.push_back(0);     // beta = 0
  breakpoints.push_back(kInf);  // beta = pi/2
  std::sort(breakpoints.begin(), breakpoints.end());

  // The flush edge's frame: x along the edge, y towards the hull (mirrored for the left leg).
  const Vec2& q0 = hull.vertex[edge];
  const Vec2 x_axis = role == FlushRole::left_leg ? Vec2(-hull.edge[edge]) : hull.edge[edge];
  const Vec2 y_axis = perp(hull.edge[edge]);
  auto frame = [&](const Vec2& p) { return Vec2((p - q0).dot(x_axis), (p - q0).dot(y_axis)); };

  std::array<std::size_t, 3> contact_index = {edge, edge, edge};
  for (std::size_t piece = 0; piece + 1 < breakpoints.size(); ++piece) {
    const Real lo = breakpoints[piece], hi = breakpoints[piece + 1];
    if (!(hi > lo)) continue;
    // Any beta inside the piece gives its contacts; support directions need no normalization.
    const Real t_mid = hi < kInf ? (lo + hi) / 2 : 2 * lo + 1;
    const BaseAngle mid{1, t_mid};
    std::array<Vec2, 3> contact;
    for (int k = 0; k < 3; ++k) {
      if (side[k].rate == 0) {
        contact[k] = q0;
      } else {
        contact_index[k] = support_vertex(hull, rotated(side[k].normal0, side[k].rate, mid), contact_index[k]);
        contact[k] = hull.vertex[contact_index[k]];
      }
    }

    // Candidates as tan(beta), scored first by the piece's closed-form area; only a candidate
    // that beats the best so far gets its normals built and its area re-scored exactly.
    Real candidates[12];
    int count = 0;
    if (lo > 0) candidates[count++] = lo;
    Real area_form[3] = {0, 0, 0};  // the piece's closed-form area: base (w, s, -), legs (k, d, ly)
    if (role == FlushRole::base) {
      const Vec2 right = frame(contact[1]), left = frame(contact[2]);
      const Real w = right.x() - left.x(), s = right.y() + left.y();
      area_form[0] = w;
      area_form[1] = s;
      if (w > 0 && s > 0 && s / w > lo && s / w < hi) candidates[count++] = s / w;
    } else {
      // In the (mirrored) frame the flush leg is the right one and the moving leg the left one.
      const Vec2 base = frame(contact[2]);
      const Vec2 left = frame(contact[role == FlushRole::right_leg ? 1 : 0]);
      const Real k = 2 * base.y() - left.y(), d = left.x() - base.x(), ly = left.y();
      area_form[0] = k;
      area_form[1] = d;
      area_form[2] = ly;
      // A = N(u)^2 / (4 u (1 + u^2)) = M(t)^2 / (4 t (1 + t^2)) with N = k u^2 + 2 d u + ly and
      // M = ly t^2 + 2 d t + k: the same form in t = tan(beta) <= 1 and in u = cot(beta) <= 1.
      // On [x1, x2] it is at least min |P|^2 / (4 x2 (1 + x2^2)); the root finding is skipped
      // where that bound cannot beat the best area so far.
      const Real in_u[5] = {-ly, 2 * d, 3 * (k - ly), -2 * d, k};  // Q(u), u = cot(beta)
      const Real in_t[5] = {k, -2 * d, 3 * (k - ly), 2 * d, -ly};  // t^4 Q(1/t), t = tan(beta)
      auto search = [&](const Real* q, Real p0, Real p2, Real x1, Real x2, bool is_tan) {
        if (!(x1 < x2)) return;
        const Real lower = quadratic_min_abs(p0, 2 * d, p2, x1, x2);
        if (lower * lower / (4 * x2 * (1 + x2 * x2)) * (1 - 1e-9) >= best.area) return;
        Real roots[4];
        const int found = sign_change_roots(q, 4, x1, x2, roots);
        for (int r = 0; r < found; ++r) candidates[count++] = is_tan ? roots[r] : 1 / roots[r];
      };
      if (lo < 1) search(in_t, k, ly, lo, std::min<Real>(1, hi), true);
      if (hi > 1) search(in_u, ly, k, 1 / hi, std::min<Real>(1, 1 / lo), false);
    }

    for (int i = 0; i < count; ++i) {
      const Real t = candidates[i];
      if (!(t > 0 && t < kInf)) continue;
      Real estimate;
      if (role == FlushRole::base) {
        const Real m = area_form[0] * t + area_form[1];
        estimate = m * m / (4 * t);
      } else {
        const Real x = t <= 1 ? t : 1 / t;  // M(t) in t, or N(u) in u = 1/t: the same form
        const Real p0 = t <= 1 ? area_form[0] : area_form[2], p2 = t <= 1 ? area_form[2] : area_form[0];
        const Real m = p0 + 2 * area_form[1] * x + p2 * x * x;
        estimate = m * m / (4 * x * (1 + x * x));
      }
      if (!(estimate * (1 - 1e-9) < best.area)) continue;
      const BaseAngle beta = BaseAngle::from_tan(t);
      std::array<Vec2, 3> normal;
      for (int k = 0; k < 3; ++k) normal[k] = rotated(side[k].normal0, side[k].rate, beta);
      const Real area = support_triangle_area(hull, normal);
      if (area < best.area) {
        best.area = area;
        best.axis0 = axis0;
        best.axis_rate = axis_rate;
        best.beta = beta;
      }
    }
  }
}

// For a hull that is a segment up to rounding (HullFrame kept two vertices): the isosceles
// triangle around the strip of the points, length L and width W, base along it and base angle
// atan(2 W / L) (the optimum for a rectangle, area 2 L W), clamped away from a needle.
Triangle2 thin_triangle(const std::vector<Vec2>& points, const HullFrame& frame) {
  const Vec2 along = frame.edge[0];
  const Vec2 d = perp(along);
  Real lo = kInf, hi = -kInf;
  for (const Vec2& p : points) {
    lo = std::min(lo, d.dot(p - frame.origin));
    hi = std::max(hi, d.dot(p - frame.origin));
  }
  const Real length = (frame.vertex[1] - frame.vertex[0]).norm();
  BaseAngle beta = BaseAngle::from_vector(length, 2 * (hi - lo));
  if (!(beta.sin >= kMinSine)) beta = BaseAngle::from_vector(1, kMinSine);
  const Vec2 across = perp(d);
  const std::array<Vec2, 3> normals = {Vec2(-d), Vec2(beta.cos * d - beta.sin * across),
                                       Vec2(beta.cos * d + beta.sin * across)};
  return enclosing_triangle(points, frame.origin, normals);
}

}  // namespace

// ---- Public entry points ----

// Principal components (paper, Section 3.2): eigenvectors of the scatter matrix about the
// centroid. Centered coordinates are divided by their largest magnitude first, so neither tiny
// nor huge spreads under- or overflow; the eigenvectors do not depend on that scale.
Mat3 principal_axes(const Vec3* points, std::size_t count) {
  if (count == 0) return Mat3::Identity();
  for (std::size_t i = 0; i < count; ++i) BOXTREE_ASSERT(points[i].allFinite(), "principal_axes: non-finite point");
  Vec3 mean = Vec3::Zero();
  for (std::size_t i = 0; i < count; ++i) mean += points[i] / static_cast<Real>(count);
  Real spread = 0;
  for (std::size_t i = 0; i < count; ++i) spread = std::max(spread, (points[i] - mean).cwiseAbs().maxCoeff());
  if (!(spread > 0)) return Mat3::Identity();  // all points coincide

  Mat3 scatter = Mat3::Zero();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 d = (points[i] - mean) / spread;
    scatter.noalias() += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(scatter);
  if (solver.info() != Eigen::Success) return Mat3::Identity();

  // Eigen sorts eigenvalues increasingly; we want decreasing. Sign convention: the component of
  // largest magnitude (the first one on ties) is positive, for col(0) and col(1); col(2) then
  // follows from the right-hand rule so the frame is a rotation.
  auto canonical_sign = [](Vec3 v) {
    int largest = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(v[k]) > std::abs(v[largest])) largest = k;
    return v[largest] < 0 ? Vec3(-v) : v;
  };
  Mat3 axes;
  axes.col(0) = canonical_sign(solver.eigenvectors().col(2)).normalized();
  // Re-orthogonalize against col(0) (the solver's vectors are orthonormal only to rounding).
  Vec3 second = solver.eigenvectors().col(1);
  second -= axes.col(0) * axes.col(0).dot(second);
  if (!(second.norm() > 0.5)) second = axes.col(0).unitOrthogonal();
  axes.col(1) = canonical_sign(second).normalized();
  axes.col(2) = axes.col(0).cross(axes.col(1)).normalized();
  return axes;
}

// Andrew's monotone chain (Andrew 1979) with the exact orientation predicate: pops every
// non-left turn, so collinear points and duplicates never survive.
int convex_hull_2d(Vec2* points, int count, Vec2* hull) {
  std::sort(points, points + count,
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  count = int(std::unique(points, points + count) - points);
  if (count <= 2) {
    std::copy(points, points + count, hull);
    return count;
  }
  int size = 0;
  for (int i = 0; i < count; ++i) {  // lower chain, left to right
    while (size >= 2 && orient_sign(hull[size - 2], hull[size - 1], points[i]) <= 0) --size;
    hull[size++] = points[i];
  }
  const int lower_size = size;
  for (int i = count - 1; i-- > 0;) {  // upper chain, right to left
    while (size > lower_size && orient_sign(hull[size - 2], hull[size - 1], points[i]) <= 0) --size;
    hull[size++] = points[i];
  }
  return size - 1;  // the last point repeats the first
}

std::vector<Vec2> convex_hull_2d(std::vector<Vec2> points) {
  BOXTREE_ASSERT(all_finite(points), "convex_hull_2d: non-finite point");
  std::vector<Vec2> hull(2 * points.size());
  hull.resize(std::size_t(convex_hull_2d(points.data(), int(points.size()), hull.data())));
  return hull;
}

// Rotating calipers (Toussaint 1983): an optimal rectangle has a side flush with a hull edge
// (Freeman & Shapira 1975); for edge i the extreme vertices along the edge, across it and
// against it move monotonically counter-clockwise, so all h edges cost O(h) together.
Rectangle2 min_area_rectangle(const std::vector<Vec2>& points) {
  const std::vector<Vec2> hull = convex_hull_2d(points);
  if (hull.empty()) return Rectangle2{};
  if (hull.size() == 1) return enclosing_rectangle(points, hull[0], Vec2::UnitX());
  if (hull.size() == 2) return enclosing_rectangle(points, hull[0], (hull[1] - hull[0]).normalized());

  const HullFrame frame(hull);
  if (frame.size() == 2) return enclosing_rectangle(points, hull[0], frame.edge[0]);
  const std::size_t n = frame.size();
  const auto& p = frame.vertex;
  auto next = [n](std::size_t k) { return (k + 1) % n; };
  std::size_t far_u = 1, far_v = 1, near_u = 1;  // argmax u, argmax v, argmin u
  Real best_area = kInf;
  std::size_t best_edge = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& u = frame.edge[i];
    const Vec2 v = perp(u);
    // Each pointer advances at most n times over the whole loop; the bounds guard rounding.
    for (std::size_t step = 0; step < n && (p[next(far_u)] - p[far_u]).dot(u) > 0; ++step) far_u = next(far_u);
    if (i == 0) far_v = far_u;
    for (std::size_t step = 0; step < n && (p[next(far_v)] - p[far_v]).dot(v) > 0; ++step) far_v = next(far_v);
    if (i == 0) near_u = far_v;
    for (std::size_t step = 0; step < n && (p[next(near_u)] - p[near_u]).dot(u) < 0; ++step) near_u = next(near_u);
    const Real length = (p[far_u] - p[near_u]).dot(u);
    const Real width = (p[far_v] - p[i]).dot(v);
    const Real area = length * width;
    if (area < best_area) {
      best_area = area;
      best_edge = i;
    }
  }
  return enclosing_rectangle(points, hull[0], frame.edge[best_edge]);
}

Real Triangle2::area() const { return std::abs(cross2(corners[1] - corners[0], corners[2] - corners[0])) / 2; }

Triangle2 min_area_triangle(const std::vector<Vec2>& points) {
  const std::vector<Vec2> hull = convex_hull_2d(points);
  if (hull.size() <= 2) return degenerate_triangle(hull);
  const HullFrame frame(hull);
  if (frame.size() == 2) return thin_triangle(points, frame);
  const std::array<Vec2, 3> normals = min_area_triangle_normals(frame);
  // A needle (an angle below kMinSine, for a hull that is a segment up to rounding) cannot be
  // represented by its corners: fall back to the isosceles fit, clamped away from needles; the
  // two areas differ by a negligible amount on such input.
  for (int k = 0; k < 3; ++k)
    if (!(cross2(normals[(k + 1) % 3], normals[(k + 2) % 3]) >= kMinSine)) return min_area_isosceles_triangle(points);
  return enclosing_triangle(points, frame.origin, normals);
}

Triangle2 min_area_isosceles_triangle(const std::vector<Vec2>& points) {
  const std::vector<Vec2> hull = convex_hull_2d(points);
  if (hull.size() <= 2) return degenerate_triangle(hull);
  const HullFrame frame(hull);
  if (frame.size() == 2) return thin_triangle(points, frame);
  IsoscelesBest best;
  std::vector<Real> breakpoints;
  breakpoints.reserve(4 * frame.size() + 2);
  // Edges in increasing order of the smallest enclosing triangle (of any shape) flush with
  // them: a lower bound for all three families of the edge, so once it reaches the best
  // isosceles area the remaining edges cannot win (typically two thirds of them).
  const std::vector<Real> lower_bound = flush_minimum(frame);
  std::vector<std::size_t> order(frame.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lower_bound[a] < lower_bound[b]; });
  for (const std::size_t k : order) {
    if (lower_bound[k] * (1 - 1e-9) >= best.area) break;
    for (const FlushRole role : {FlushRole::base, FlushRole::right_leg, FlushRole::left_leg})
      minimize_isosceles_with_flush_edge(frame, k, role, breakpoints, best);
  }
  // Keep every angle of the triangle above kMinSine (base angles beta, apex angle pi - 2 beta):
  // a needle cannot be represented by its corners. Only a hull that is a segment up to
  // rounding has its optimum there.
  BaseAngle beta = best.beta;
  if (!(beta.sin >= kMinSine)) beta = BaseAngle::from_vector(1, kMinSine);
  if (!(beta.cos >= kMinSine)) beta = BaseAngle::from_vector(kMinSine, 1);
  // Mirror-symmetric normals built from (d, beta), so the result is isosceles whatever offsets
  // the padding gives the sides: base, right leg, left leg; corner 2 is the apex.
  const Vec2 d = rotated(best.axis0, best.axis_rate, best.beta);
  const Vec2 across = perp(d);
  const std::array<Vec2, 3> normals = {Vec2(-d), Vec2(beta.cos * d - beta.sin * across),
                                       Vec2(beta.cos * d + beta.sin * across)};
  return enclosing_triangle(points, frame.origin, normals);
}

}  // namespace boxtree::detail
