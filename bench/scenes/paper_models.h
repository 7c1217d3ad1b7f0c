// SPDX-License-Identifier: MIT
#pragma once
// The models of the paper's experiments (Section 4, Figure 2), generated: random-point spheres
// and concentric sphere pairs, interleaved combs, and rook- and banana-like stand-ins.
#include <cstdint>

#include "boxtree/mesh.h"

namespace boxtree::scenes {

// Convex hull of `points` random points on a sphere: 2*points - 4 facets (280 points -> the
// paper's 556-facet sphere; 1000 -> 1996; 5000 -> 9996). Outward-oriented.
TriangleMesh random_sphere(int points, std::uint64_t seed, Real radius = 1);

// Convex hull of arbitrary points (Qhull), outward-oriented triangles.
TriangleMesh convex_hull(const std::vector<Vec3>& points);

// The paper's comb: a 24-corner comb polygon (a spine and 6 teeth) extruded: 48 vertices,
// 92 facets, closed. Spine [0,16] x [0,1], teeth 1 wide and 5 long every 3 units, depth 2.
TriangleMesh comb();

// The second comb of an interleaved pair: the comb turned by 180 degrees about z and moved so
// its teeth sit between the first comb's teeth, `gap` away from them and from the spine.
TriangleMesh interleaved_comb(Real gap);

// Surface of revolution of a rook-like profile: 8 profile points x 16 segments plus the two
// axis points, 256 facets (the paper's rook has 131 vertices and 256 facets).
TriangleMesh rook();

// A closed bent tube (a "banana"): 16 rings of 16 vertices along a circular arc, capped,
// 512 facets (the paper's banana: 273 vertices, 512 facets).
TriangleMesh banana();

}  // namespace boxtree::scenes
