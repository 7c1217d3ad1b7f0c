// SPDX-License-Identifier: MIT
// The paper's Section 5 lower-bound constructions.
//
// The polytope's coordinates grow like 3^(4n): no floating type holds them exactly beyond
// n = 8 (double) or 10 (long double). We therefore compute each coordinate exactly as an
// integer, round it once to double (the mesh the trees are built on), and do every geometric
// decision -- the hull, and whether each lifted segment is a hull edge -- in exact integer
// arithmetic on those rounded values (doubles above 2^53 are integers), so the mesh we measure
// is exactly a convex polytope and the premise of the lower bound is checked, not assumed.
#include "planar_lower_bounds.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <boost/multiprecision/cpp_int.hpp>

#include "boxtree/error.h"

namespace boxtree::bench {
namespace {

constexpr Real kPi = 3.14159265358979323846;
using Int = boost::multiprecision::cpp_int;

struct IVec {
  Int x, y, z;
};
IVec operator-(const IVec& a, const IVec& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
IVec cross(const IVec& a, const IVec& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Int dot(const IVec& a, const IVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
bool is_zero(const IVec& a) { return a.x == 0 && a.y == 0 && a.z == 0; }

// The double nearest to an integer, and that double back as an exact integer.
Int rounded(const Int& v) {
  const double d = v.convert_to<double>();
  return Int(d);
}

// Segment ab is an edge of conv(points) iff, projected along b - a, the other points lie in an
// open half-plane around the image of a (then a plane through a and b supports the hull there).
bool is_hull_edge(const std::vector<IVec>& points, std::size_t i, std::size_t j) {
  const IVec d = points[j] - points[i];
  std::vector<IVec> w;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (k == i || k == j) continue;
    w.push_back(cross(points[k] - points[i], d));
    if (is_zero(w.back())) return false;  // collinear with the segment
  }
  for (const IVec& first : w) {
    bool all_after = true;
    for (const IVec& other : w) {
      const Int turn = dot(d, cross(first, other));
      if (turn > 0 || (turn == 0 && dot(first, other) > 0)) continue;
      all_after = false;
      break;
    }
    if (all_after) return true;
  }
  return false;
}

}  // namespace

TriangleMesh make_cone(int n) {
  if (n < 4) throw Error("make_cone: n must be at least 4");
  TriangleMesh mesh;
  const int m = n - 1;
  mesh.vertices.push_back(Vec3(0, 0, 1));
  for (int i = 0; i < m; ++i) mesh.vertices.push_back(Vec3(std::cos(2 * kPi * i / m), std::sin(2 * kPi * i / m), 0));
  for (int i = 0; i < m; ++i) mesh.triangles.push_back({0, VertexId(1 + i), VertexId(1 + (i + 1) % m)});
  for (int i = 1; i + 1 < m; ++i) mesh.triangles.push_back({1, VertexId(1 + i + 1), VertexId(1 + i)});
  return mesh;
}

TangentPolytope make_tangent_polytope(int n) {
  if (n < 2) throw Error("make_tangent_polytope: n must be at least 2");
  std::vector<IVec> points;  // p_0..p_{n-1}, q_0..q_{n-1}
  const Int three_n = boost::multiprecision::pow(Int(3), unsigned(n));
  TangentPolytope out;
  out.exact_in_double = true;
  auto lift = [&](const Int& x, const Int& y) {
    const Int z = x * x + y * y;
    const IVec exact{x, y, z};
    const IVec r{rounded(x), rounded(y), rounded(z)};
    if (r.x != exact.x || r.y != exact.y || r.z != exact.z) out.exact_in_double = false;
    points.push_back(r);
  };
  for (int k = 0; k < n; ++k) {
    const Int three_k = boost::multiprecision::pow(Int(3), unsigned(k));
    lift(three_k, three_k * three_k);
  }
  for (int k = 0; k < n; ++k) {
    const Int three_k = boost::multiprecision::pow(Int(3), unsigned(k));
    lift(-three_n, -2 * three_k * three_n - three_k * three_k);
  }
  const std::size_t count = points.size();

  // The hull by brute force (fine for the few dozen points the exponents allow): every plane
  // through three points with all others on one side is a face; its points in convex position
  // are ordered around the face and fan-triangulated, outward.
  std::set<std::vector<std::size_t>> faces_seen;
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t j = i + 1; j < count; ++j)
      for (std::size_t k = j + 1; k < count; ++k) {
        IVec normal = cross(points[j] - points[i], points[k] - points[i]);
        if (is_zero(normal)) continue;
        int side = 0;
        bool supporting = true;
        std::vector<std::size_t> on_plane;
        for (std::size_t q = 0; q < count && supporting; ++q) {
          const Int s = dot(normal, points[q] - points[i]);
          if (s == 0) {
            on_plane.push_back(q);
            continue;
          }
          const int sign = s > 0 ? 1 : -1;
          if (side == 0) side = sign;
          if (sign != side) supporting = false;
        }
        if (!supporting || !faces_seen.insert(on_plane).second) continue;
        if (side > 0) normal = IVec{-normal.x, -normal.y, -normal.z};  // outward: others behind
        const std::size_t pivot = on_plane.front();
        std::vector<std::size_t> ring(on_plane.begin() + 1, on_plane.end());
        std::sort(ring.begin(), ring.end(), [&](std::size_t a, std::size_t b) {
          return dot(normal, cross(points[a] - points[pivot], points[b] - points[pivot])) > 0;
        });
        for (std::size_t s = 0; s + 1 < ring.size(); ++s)
          out.mesh.triangles.push_back({VertexId(pivot), VertexId(ring[s]), VertexId(ring[s + 1])});
      }
  for (const IVec& p : points)
    out.mesh.vertices.push_back(Vec3(p.x.convert_to<double>(), p.y.convert_to<double>(), p.z.convert_to<double>()));
  out.segments_are_edges = true;
  for (int k = 0; k < n; ++k)
    out.segments_are_edges = out.segments_are_edges && is_hull_edge(points, std::size_t(k), std::size_t(n + k));
  return out;
}

}  // namespace boxtree::bench
