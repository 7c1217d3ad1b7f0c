// SPDX-License-Identifier: MIT
#include "boxtree/generate.h"

#include <cmath>

#include "boxtree/error.h"

namespace boxtree {

Vec3 Random::unit_vector() {
  for (;;) {
    const Vec3 v = uniform_vec3(-1, 1);
    const Real n2 = v.squaredNorm();
    if (n2 > 1e-6 && n2 <= 1) return v / std::sqrt(n2);
  }
}

TriangleMesh make_uv_sphere(int segments, int rings, Real radius, const Vec3& center) {
  if (segments < 3 || rings < 2) throw Error("make_uv_sphere: need segments >= 3 and rings >= 2");
  const Real pi = std::acos(Real(-1));
  TriangleMesh mesh;
  mesh.vertices.push_back(center + Vec3(0, 0, radius));
  for (int r = 1; r < rings; ++r) {
    const Real theta = pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const Real phi = 2 * pi * s / segments;
      mesh.vertices.push_back(
          center + radius * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
  }
  mesh.vertices.push_back(center - Vec3(0, 0, radius));
  const VertexId south = VertexId(mesh.vertices.size() - 1);
  auto ring_vertex = [&](int r, int s) { return VertexId(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back({0, ring_vertex(1, s), ring_vertex(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      mesh.triangles.push_back({ring_vertex(r, s), ring_vertex(r + 1, s), ring_vertex(r + 1, s + 1)});
      mesh.triangles.push_back({ring_vertex(r, s), ring_vertex(r + 1, s + 1), ring_vertex(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s)
    mesh.triangles.push_back({ring_vertex(rings - 1, s), south, ring_vertex(rings - 1, s + 1)});
  return mesh;
}

TriangleMesh make_bumpy_sphere(int segments, int rings, Real roughness, std::uint64_t seed) {
  TriangleMesh mesh = make_uv_sphere(segments, rings);
  Random random(seed);
  for (Vec3& v : mesh.vertices) v *= random.uniform(1 - roughness, 1 + roughness);
  return mesh;
}

TriangleMesh make_torus(Real major, Real minor, int segments, int sides) {
  if (segments < 3 || sides < 3) throw Error("make_torus: need segments >= 3 and sides >= 3");
  if (!(minor > 0) || !(minor < major)) throw Error("make_torus: need 0 < minor < major");
  const Real pi = std::acos(Real(-1));
  TriangleMesh mesh;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      const Real u = 2 * pi * i / segments, v = 2 * pi * j / sides;
      const Real r = major + minor * std::cos(v);
      mesh.vertices.emplace_back(r * std::cos(u), r * std::sin(u), minor * std::sin(v));
    }
  auto id = [&](int i, int j) { return VertexId((i % segments) * sides + j % sides); };
  // (i, j) -> (i + 1, j) -> (i + 1, j + 1) turns along u then v, and du x dv points away from
  // the tube's core circle: outward.
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < sides; ++j) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

namespace {
// Value noise on an integer lattice, smoothly interpolated.
Real lattice_value(std::uint64_t seed, std::int64_t x, std::int64_t y) {
  Random r(seed ^ (std::uint64_t(x) * 0x9E3779B185EBCA87ULL) ^ (std::uint64_t(y) * 0xC2B2AE3D27D4EB4FULL));
  return r.uniform();
}
Real value_noise(std::uint64_t seed, Real x, Real y) {
  const Real fx = std::floor(x), fy = std::floor(y);
  const std::int64_t ix = std::int64_t(fx), iy = std::int64_t(fy);
  auto smooth = [](Real t) { return t * t * (3 - 2 * t); };
  const Real tx = smooth(x - fx), ty = smooth(y - fy);
  const Real a = lattice_value(seed, ix, iy), b = lattice_value(seed, ix + 1, iy);
  const Real c = lattice_value(seed, ix, iy + 1), d = lattice_value(seed, ix + 1, iy + 1);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}
}  // namespace

TriangleMesh make_terrain(int cells_x, int cells_y, std::uint64_t seed, Real size, Real height) {
  if (cells_x < 1 || cells_y < 1) throw Error("make_terrain: need at least one cell in each direction");
  if (std::uint64_t(cells_x) * std::uint64_t(cells_y) * 2 > 0x7fffffffULL) throw Error("make_terrain: too many cells");
  TriangleMesh mesh;
  mesh.vertices.reserve(std::size_t(cells_x + 1) * std::size_t(cells_y + 1));
  const int octaves = 6;
  for (int j = 0; j <= cells_y; ++j)
    for (int i = 0; i <= cells_x; ++i) {
      const Real x = size * i / cells_x, y = size * j / cells_y;
      Real z = 0, amplitude = 0.5, frequency = 4.0 / size;
      for (int o = 0; o < octaves; ++o) {
        z += amplitude * value_noise(seed + std::uint64_t(o), x * frequency, y * frequency);
        amplitude *= 0.5;
        frequency *= 2;
      }
      mesh.vertices.emplace_back(x, y, z * height);
    }
  auto id = [&](int i, int j) { return VertexId(j * (cells_x + 1) + i); };
  mesh.triangles.reserve(std::size_t(cells_x) * std::size_t(cells_y) * 2);
  for (int j = 0; j < cells_y; ++j)
    for (int i = 0; i < cells_x; ++i) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

TriangleMesh make_triangle_soup(std::size_t count, std::uint64_t seed, Real extent, Real triangle_size) {
  TriangleMesh mesh;
  Random random(seed);
  mesh.vertices.reserve(3 * count);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 base = random.uniform_vec3(0, extent);
    const VertexId first = VertexId(mesh.vertices.size());
    mesh.vertices.push_back(base);
    mesh.vertices.push_back(base + random.uniform_vec3(-triangle_size, triangle_size));
    mesh.vertices.push_back(base + random.uniform_vec3(-triangle_size, triangle_size));
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  return mesh;
}

}  // namespace boxtree
