// SPDX-License-Identifier: MIT
#pragma once
// An indexed triangle mesh: the input a boxtree is built over.
// Facet ids are indices into `triangles`, in the order of the source file (polygons are
// fan-triangulated in order), so that the ids a query reports mean something to the user.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "boxtree/math.h"

namespace boxtree {

using FacetId = std::uint32_t;
using VertexId = std::uint32_t;
using Triangle = std::array<VertexId, 3>;

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;

  std::size_t facet_count() const { return triangles.size(); }
  const Vec3& corner(FacetId facet, int k) const { return vertices[triangles[facet][k]]; }
};

// What validation found that is legal but worth reporting.
struct MeshStats {
  std::size_t facets = 0;
  std::size_t vertices = 0;
  std::size_t degenerate_facets = 0;  // zero area: repeated index or collinear corners
  std::size_t unused_vertices = 0;    // referenced by no facet
  Vec3 bounds_min = Vec3::Zero();     // over the vertices that facets use
  Vec3 bounds_max = Vec3::Zero();
  Real total_area = 0;
};

// Throws boxtree::Error, naming `source` (a file name or "mesh") and the offending facet or
// vertex, when: there are no facets, an index is out of range, or a used vertex has a NaN/Inf
// coordinate or, with `for_tree` (what build_tree checks), one beyond +-1e50, where the exact
// triangle tests would overflow (load_mesh reads such files, the builder refuses them).
// Degenerate facets are accepted (counted by compute_mesh_stats).
void validate_mesh(const TriangleMesh& mesh, const std::string& source = "mesh", bool for_tree = true);

// Assumes a valid mesh.
MeshStats compute_mesh_stats(const TriangleMesh& mesh);

// The area of a facet's triangle, |(b-a)x(c-a)|/2; zero means degenerate.
Real facet_area(const TriangleMesh& mesh, FacetId facet);

}  // namespace boxtree
