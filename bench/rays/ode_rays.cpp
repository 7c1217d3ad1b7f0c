// SPDX-License-Identifier: MIT
#include "ode_rays.h"

#include <chrono>
#include <limits>
#include <vector>

#include "boxtree/error.h"

#if BOXTREE_BENCH_HAVE_ODE
#include <ode/ode.h>
#endif

namespace boxtree::peers {

#if BOXTREE_BENCH_HAVE_ODE

struct OdeTriMeshRays::Impl {
  std::vector<dReal> vertices;
  std::vector<dTriIndex> indices;
  dTriMeshDataID data = nullptr;
  dGeomID mesh = nullptr;
  dGeomID ray = nullptr;
  double build_seconds = 0;
  ~Impl() {
    if (ray) dGeomDestroy(ray);
    if (mesh) dGeomDestroy(mesh);
    if (data) dGeomTriMeshDataDestroy(data);
    dCloseODE();
  }
};

bool ode_available() { return true; }
const char* ode_version() {
  return dCheckConfiguration("ODE_double_precision") ? "ODE dTriMesh (OPCODE), double precision"
                                                     : "ODE dTriMesh (OPCODE), single precision";
}

OdeTriMeshRays::OdeTriMeshRays(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  dInitODE2(0);
  m.vertices.reserve(3 * mesh.vertices.size());
  for (const Vec3& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) m.vertices.push_back(dReal(v[k]));
  m.indices.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (VertexId v : t) m.indices.push_back(dTriIndex(v));
  const auto start = std::chrono::steady_clock::now();
  m.data = dGeomTriMeshDataCreate();
  dGeomTriMeshDataBuildDouble(m.data, m.vertices.data(), 3 * int(sizeof(dReal)), int(mesh.vertices.size()),
                              m.indices.data(), int(m.indices.size()), 3 * int(sizeof(dTriIndex)));
  m.mesh = dCreateTriMesh(nullptr, m.data, nullptr, nullptr, nullptr);
  m.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m.ray = dCreateRay(nullptr, 1);
  dGeomRaySetFirstContact(m.ray, 0);
  dGeomRaySetBackfaceCull(m.ray, 0);
  dGeomRaySetClosestHit(m.ray, 1);
}

OdeTriMeshRays::~OdeTriMeshRays() = default;

double OdeTriMeshRays::build_seconds() const { return impl_->build_seconds; }

double OdeTriMeshRays::ray_closest(const Vec3& origin, const Vec3& direction, double t_max) {
  dGeomRaySetLength(impl_->ray, dReal(t_max));
  dGeomRaySet(impl_->ray, origin.x(), origin.y(), origin.z(), direction.x(), direction.y(), direction.z());
  dContactGeom contact;
  const int n = dCollide(impl_->ray, impl_->mesh, 1, &contact, int(sizeof(dContactGeom)));
  return n > 0 ? double(contact.depth) : std::numeric_limits<double>::infinity();
}

#else  // no ODE

struct OdeTriMeshRays::Impl {};
bool ode_available() { return false; }
const char* ode_version() { return "ODE: not built"; }
OdeTriMeshRays::OdeTriMeshRays(const TriangleMesh&) { throw Error("the bench was built without ODE"); }
OdeTriMeshRays::~OdeTriMeshRays() = default;
double OdeTriMeshRays::build_seconds() const { return 0; }
double OdeTriMeshRays::ray_closest(const Vec3&, const Vec3&, double) { return 0; }

#endif

}  // namespace boxtree::peers
