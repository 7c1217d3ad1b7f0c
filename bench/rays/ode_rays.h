// SPDX-License-Identifier: MIT
#pragma once
// ODE as a ray peer: a dGeomRay against a dTriMesh (ODE's OPCODE-based trimesh), one dCollide
// per ray with closest-hit mode on (dGeomRaySetClosestHit), first-contact mode and back-face
// culling off, i.e. what an ODE program pays per ray cast at a mesh outside a space.
#include <memory>

#include "boxtree/mesh.h"

namespace boxtree::peers {

bool ode_available();
const char* ode_version();

class OdeTriMeshRays {
 public:
  // Copies the mesh into dReal / dTriIndex arrays that ODE reads, then builds the trimesh data
  // and geom (OPCODE's tree).
  explicit OdeTriMeshRays(const TriangleMesh& mesh);
  ~OdeTriMeshRays();
  OdeTriMeshRays(const OdeTriMeshRays&) = delete;
  OdeTriMeshRays& operator=(const OdeTriMeshRays&) = delete;

  double build_seconds() const;
  // Closest hit of origin + t * direction for t in [0, t_max] (direction unit length): t, or +infinity.
  double ray_closest(const Vec3& origin, const Vec3& direction, double t_max);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace boxtree::peers
