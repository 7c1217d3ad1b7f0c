// SPDX-License-Identifier: MIT
#pragma once
// Bullet GImpact and ODE's trimesh as mesh-vs-mesh peers (bench/mesh_mesh): the same two meshes
// as boxtree's trees, b placed in a's frame by a rigid pose, a at the identity.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "boxtree/mesh.h"
#include "boxtree/shapes.h"

namespace boxtree::peers {

// Bullet GImpact: one btGImpactMeshShape per mesh over a btScalar (single precision) copy of
// it; its part's btGImpactQuantizedBvh holds one box per triangle (the triangle's box grown by
// the shape's margin, quantized to 16 bits). A query is what btGImpactCollisionAlgorithm runs
// for two GImpact meshes before its narrowphase: btGImpactQuantizedBvh::find_collision between
// the two box sets (the candidate pairs), then here the same exact triangle test boxtree uses
// (boxtree::triangles_intersect, double precision, on the caller's meshes) on every candidate,
// so that the pair counts compare.
bool gimpact_available();
const char* gimpact_version();

struct GImpactResult {
  std::uint64_t candidates = 0;  // triangle pairs whose boxes overlap (find_collision)
  std::uint64_t pairs = 0;       // candidates that intersect (triangles_intersect)
  double midphase_seconds = 0;   // find_collision, summed over poses
  double exact_seconds = 0;      // the exact tests, summed over poses
  double build_seconds = 0;      // mean of the two shapes' updateBound()
};

class GImpactPair {
 public:
  // margin: the shape margin (absolute units) added around every triangle box.
  GImpactPair(const TriangleMesh& a, const TriangleMesh& b, double margin);
  ~GImpactPair();
  GImpactPair(const GImpactPair&) = delete;
  GImpactPair& operator=(const GImpactPair&) = delete;

  // Totals over the poses; the times are sums over the poses of each pose's fastest of
  // `repeats` runs. pairs_per_pose (optional): per pose the exact pairs (facet of a, facet of
  // b), sorted.
  GImpactResult run(const std::vector<RigidTransform>& a_from_b, int repeats,
                    std::vector<std::vector<std::pair<FacetId, FacetId>>>* pairs_per_pose = nullptr);
  double build_seconds() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ODE trimesh-trimesh: dCreateTriMesh for both meshes (ODE's own build, OPCODE trees in
// Debian's libode), one dCollide per pose with room for `max_contacts` (at most 0xffff, the
// flags' limit). ODE returns contact points (position, normal, depth), not facet pairs.
bool ode_available();
std::string ode_configuration();

struct OdeResult {
  std::uint64_t contacts = 0;      // summed over poses
  std::uint64_t poses_at_cap = 0;  // poses where ODE filled the whole contact array
  std::uint64_t messages = 0;      // ODE's warnings during the queries (silenced, counted)
  double seconds = 0;              // dCollide: sum over poses of each pose's fastest time
  double build_seconds = 0;        // mean of the two dGeomTriMeshDataBuildDouble + dCreateTriMesh
};

class OdeTriMeshPair {
 public:
  OdeTriMeshPair(const TriangleMesh& a, const TriangleMesh& b);
  ~OdeTriMeshPair();
  OdeTriMeshPair(const OdeTriMeshPair&) = delete;
  OdeTriMeshPair& operator=(const OdeTriMeshPair&) = delete;

  OdeResult run(const std::vector<RigidTransform>& a_from_b, int repeats, int max_contacts = 0xffff);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace boxtree::peers
