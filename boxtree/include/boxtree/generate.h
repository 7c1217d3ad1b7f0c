// SPDX-License-Identifier: MIT
#pragma once
// Procedural meshes shared by the tests, the CLI's `generate`, the benchmarks and the demos.
// All are deterministic functions of their arguments (own random-number mapping, so the same
// seed gives the same mesh on every platform).
#include <cstdint>

#include "boxtree/mesh.h"

namespace boxtree {

// Closed UV sphere: 2 poles plus (rings-1) rings of `segments` vertices; 2*segments*(rings-1)
// facets. segments >= 3, rings >= 2.
TriangleMesh make_uv_sphere(int segments, int rings, Real radius = 1, const Vec3& center = Vec3::Zero());

// A closed, star-shaped, non-convex mesh: a UV sphere whose vertices are moved radially by a
// random factor in [1 - roughness, 1 + roughness].
TriangleMesh make_bumpy_sphere(int segments, int rings, Real roughness, std::uint64_t seed);

// Closed torus around the z axis, wound outward: `segments` around the axis times `sides`
// around the tube, 2 facets per quad. segments, sides >= 3; 0 < minor < major.
TriangleMesh make_torus(Real major, Real minor, int segments, int sides);

// Fractal terrain (sum of octaves of value noise) over [0, size]^2 in x, y with heights in
// about [0, height]; cells_x * cells_y grid cells, 2 facets each.
TriangleMesh make_terrain(int cells_x, int cells_y, std::uint64_t seed, Real size = 100, Real height = 10);

// `count` independent random triangles with corners in a cube of side `extent`, each with edges
// up to about `triangle_size`.
TriangleMesh make_triangle_soup(std::size_t count, std::uint64_t seed, Real extent = 1, Real triangle_size = 0.1);

// Deterministic random numbers (splitmix64): the same sequence everywhere.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  Real uniform() { return Real(next() >> 11) * (1.0 / 9007199254740992.0); }
  Real uniform(Real lo, Real hi) { return lo + (hi - lo) * uniform(); }
  Vec3 uniform_vec3(Real lo, Real hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  // Uniform on the unit sphere.
  Vec3 unit_vector();

 private:
  std::uint64_t state_;
};

}  // namespace boxtree
