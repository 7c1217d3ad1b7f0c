// SPDX-License-Identifier: MIT
// Mesh validation and statistics (contracts in boxtree/mesh.h).
#include "boxtree/mesh.h"

#include <Eigen/Geometry>  // cross()
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "boxtree/error.h"

namespace boxtree {
namespace {

// Facet ids are reported through signed 32-bit counters in places (stats, engine adapters), so
// the library promises at most 2^31-1 facets, not the full FacetId range.
constexpr std::size_t kMaxFacets = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());

bool is_finite(const Vec3& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

// The exact triangle tests form products of up to six coordinates (squared norms of cross
// products, triple products of differences); beyond 1e50 these overflow to infinity and the
// answers become meaningless, so such meshes are refused rather than answered wrongly.
constexpr Real kMaxCoordinate = 1e50;

Vec3 facet_cross(const TriangleMesh& mesh, FacetId facet) {
  const Vec3& a = mesh.corner(facet, 0);
  return (mesh.corner(facet, 1) - a).cross(mesh.corner(facet, 2) - a);
}

}  // namespace

void validate_mesh(const TriangleMesh& mesh, const std::string& source, bool for_tree) {
  const std::size_t facet_count = mesh.triangles.size();
  const std::size_t vertex_count = mesh.vertices.size();
  if (facet_count == 0) {
    throw Error(source + ": no facets (" + std::to_string(vertex_count) + " vertices, 0 triangles)");
  }
  if (facet_count > kMaxFacets) {
    throw Error(source + ": too many facets (" + std::to_string(facet_count) + "; at most 2^31-1 are supported)");
  }
  for (std::size_t f = 0; f < facet_count; ++f) {
    for (int k = 0; k < 3; ++k) {
      const VertexId v = mesh.triangles[f][k];
      if (v >= vertex_count) {
        throw Error(source + ": facet " + std::to_string(f) + " corner " + std::to_string(k) + ": vertex index " +
                    std::to_string(v) + " out of range (mesh has " + std::to_string(vertex_count) + " vertices)");
      }
      const Vec3& p = mesh.vertices[v];
      if (!is_finite(p)) {
        std::ostringstream message;
        message << source << ": facet " << f << " uses vertex " << v << " with a non-finite coordinate (" << p.x()
                << ", " << p.y() << ", " << p.z() << ")";
        throw Error(message.str());
      }
      if (for_tree && p.cwiseAbs().maxCoeff() > kMaxCoordinate) {
        std::ostringstream message;
        message << source << ": facet " << f << " uses vertex " << v << " with a coordinate beyond +-1e50 (" << p.x()
                << ", " << p.y() << ", " << p.z() << "): too large for the triangle tests";
        throw Error(message.str());
      }
    }
  }
}

MeshStats compute_mesh_stats(const TriangleMesh& mesh) {
  MeshStats stats;
  stats.facets = mesh.triangles.size();
  stats.vertices = mesh.vertices.size();

  std::vector<bool> used(mesh.vertices.size(), false);
  for (const Triangle& t : mesh.triangles) {
    for (VertexId v : t) {
      BOXTREE_ASSERT(v < mesh.vertices.size(), "compute_mesh_stats needs a valid mesh (see validate_mesh)");
      used[v] = true;
    }
  }

  bool any_used = false;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) {
      ++stats.unused_vertices;
      continue;
    }
    const Vec3& p = mesh.vertices[v];
    if (!any_used) {
      stats.bounds_min = stats.bounds_max = p;
      any_used = true;
    } else {
      stats.bounds_min = stats.bounds_min.cwiseMin(p);
      stats.bounds_max = stats.bounds_max.cwiseMax(p);
    }
  }

  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    // A repeated index gives an exactly zero cross product too; testing it first keeps the
    // definition independent of the coordinates (meshinfo.py counts the same way).
    const Vec3 cross = facet_cross(mesh, static_cast<FacetId>(f));
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (cross.array() == 0.0).all()) {
      ++stats.degenerate_facets;
      continue;
    }
    stats.total_area += 0.5 * cross.norm();
  }
  return stats;
}

Real facet_area(const TriangleMesh& mesh, FacetId facet) {
  BOXTREE_ASSERT(facet < mesh.triangles.size(), "facet_area: facet id out of range");
  return 0.5 * facet_cross(mesh, facet).norm();
}

}  // namespace boxtree
