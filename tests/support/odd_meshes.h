// SPDX-License-Identifier: MIT
#pragma once
// A terrain with the oddities of real-world meshes added on top of a closed height field, for the
// engines' robustness tests (tests/bullet, tests/ode): every fourth facet duplicated, zero-area
// facets (a repeated corner, three collinear corners along a grid edge) and needle slivers
// (a grid edge with a third corner 1e-9 above its middle). The surface itself stays whole, so
// no body may fall through it, and none of the extras may give a NaN.
#include <cstdint>

#include "boxtree/generate.h"

namespace boxtree::test {

inline TriangleMesh make_odd_terrain(int cells, std::uint64_t seed, Real size, Real height) {
  TriangleMesh mesh = make_terrain(cells, cells, seed, size, height);
  const std::size_t facets = mesh.triangles.size();
  for (std::size_t f = 0; f < facets; ++f) {
    const Triangle t = mesh.triangles[f];
    if (f % 4 == 0) mesh.triangles.push_back(t);                   // duplicate
    if (f % 4 == 1) mesh.triangles.push_back({t[0], t[1], t[1]});  // repeated corner
    if (f % 4 == 2 || f % 4 == 3) {
      const Vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]];
      const VertexId mid = VertexId(mesh.vertices.size());
      mesh.vertices.push_back(0.5 * (a + b));                     // collinear: on the edge
      mesh.vertices.push_back(0.5 * (a + b) + Vec3(0, 0, 1e-9));  // needle apex
      mesh.triangles.push_back({t[0], t[1], f % 4 == 2 ? mid : mid + 1});
    }
  }
  return mesh;
}

}  // namespace boxtree::test
