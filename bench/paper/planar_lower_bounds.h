// SPDX-License-Identifier: MIT
#pragma once
// The paper's Section 5 constructions (bench-only: the exact hull needs Boost.Multiprecision).
#include <cstdint>

#include "boxtree/mesh.h"

namespace boxtree::bench {

// The boundary of a cone: apex (0, 0, 1) joined to a regular (n-1)-gon of radius 1 in z = 0,
// the base fan-triangulated from its first vertex: 2n - 4 facets. n >= 4.
TriangleMesh make_cone(int n);

// Section 5's convex polytope: the segments p_k q_k, p_k = (3^k, 9^k), q_k = (-3^n,
// -2*3^(k+n) - 9^k), 0 <= k < n, lifted onto the paraboloid z = x^2 + y^2, and the convex
// hull of the 2n lifted points (computed exactly with big integers on the coordinates as
// rounded to double, then fan-triangulated). `segments_are_edges` reports, exactly, whether every
// lifted segment is an edge of that hull (the lower bound's premise).
struct TangentPolytope {
  TriangleMesh mesh;
  bool segments_are_edges = false;
  bool exact_in_double = false;  // every coordinate is an integer below 2^53 (no rounding)
};
TangentPolytope make_tangent_polytope(int n);

}  // namespace boxtree::bench
