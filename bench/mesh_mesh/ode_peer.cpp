// SPDX-License-Identifier: MIT
#include <algorithm>
#include <chrono>
#include <cstdarg>

#include "boxtree/error.h"
#include "mesh_peers.h"

#ifdef BOXTREE_MM_HAVE_ODE
#include <ode/ode.h>
#endif

namespace boxtree::peers {

#ifdef BOXTREE_MM_HAVE_ODE

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::uint64_t ode_messages = 0;  // ODE's warnings (e.g. its contact hash table overflowing)
void count_message(int, const char*, va_list) { ++ode_messages; }

void init_ode() {
  static const bool done = [] {
    dInitODE2(0);
    dSetMessageHandler(count_message);
    return true;
  }();
  (void)done;
}

// The fastest of the repeated runs: on a shared machine the least disturbed one.
double fastest(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// ODE reads the mesh from the caller's arrays: they live here as long as the geom.
struct OdeMesh {
  std::vector<dReal> vertices;
  std::vector<dTriIndex> indices;
  dTriMeshDataID data = nullptr;
  dGeomID geom = nullptr;
  double build_seconds = 0;

  explicit OdeMesh(const TriangleMesh& mesh) {
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(dReal(v[k]));
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) indices.push_back(dTriIndex(t[k]));
    const auto start = Clock::now();
    data = dGeomTriMeshDataCreate();
    dGeomTriMeshDataBuildDouble(data, vertices.data(), 3 * int(sizeof(dReal)), int(mesh.vertices.size()),
                                indices.data(), int(indices.size()), 3 * int(sizeof(dTriIndex)));
    geom = dCreateTriMesh(nullptr, data, nullptr, nullptr, nullptr);
    build_seconds = since(start);
  }
  ~OdeMesh() {
    dGeomDestroy(geom);
    dGeomTriMeshDataDestroy(data);
  }
  OdeMesh(const OdeMesh&) = delete;
  OdeMesh& operator=(const OdeMesh&) = delete;
};
}  // namespace

struct OdeTriMeshPair::Impl {
  OdeMesh a, b;
  std::vector<dContactGeom> contacts;
  Impl(const TriangleMesh& a_, const TriangleMesh& b_) : a((init_ode(), a_)), b(b_) {}
};

bool ode_available() { return true; }
std::string ode_configuration() {
  init_ode();
  return dGetConfiguration();
}

OdeTriMeshPair::OdeTriMeshPair(const TriangleMesh& a, const TriangleMesh& b) : impl_(std::make_unique<Impl>(a, b)) {}
OdeTriMeshPair::~OdeTriMeshPair() = default;

OdeResult OdeTriMeshPair::run(const std::vector<RigidTransform>& a_from_b, int repeats, int max_contacts) {
  const std::uint64_t messages_before = ode_messages;
  max_contacts = std::max(1, std::min(max_contacts, 0xffff));
  OdeResult r;
  r.build_seconds = (impl_->a.build_seconds + impl_->b.build_seconds) / 2;
  impl_->contacts.resize(std::size_t(max_contacts));
  dGeomSetPosition(impl_->a.geom, 0, 0, 0);
  dMatrix3 identity;
  dRSetIdentity(identity);
  dGeomSetRotation(impl_->a.geom, identity);
  for (const RigidTransform& pose : a_from_b) {
    dMatrix3 rotation;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) rotation[4 * i + j] = dReal(pose.rotation(i, j));
      rotation[4 * i + 3] = 0;
    }
    dGeomSetRotation(impl_->b.geom, rotation);
    dGeomSetPosition(impl_->b.geom, dReal(pose.translation.x()), dReal(pose.translation.y()),
                     dReal(pose.translation.z()));
    std::vector<double> times;
    int n = 0;
    for (int rep = 0; rep < std::max(1, repeats); ++rep) {
      const auto start = Clock::now();
      n = dCollide(impl_->a.geom, impl_->b.geom, max_contacts, impl_->contacts.data(), int(sizeof(dContactGeom)));
      times.push_back(since(start));
    }
    r.seconds += fastest(times);
    r.contacts += std::uint64_t(n);
    if (n >= max_contacts) ++r.poses_at_cap;
  }
  r.messages = ode_messages - messages_before;
  return r;
}

#else  // no ODE

struct OdeTriMeshPair::Impl {};
bool ode_available() { return false; }
std::string ode_configuration() { return "ODE: not built"; }
OdeTriMeshPair::OdeTriMeshPair(const TriangleMesh&, const TriangleMesh&) { throw Error("ode: not built"); }
OdeTriMeshPair::~OdeTriMeshPair() = default;
OdeResult OdeTriMeshPair::run(const std::vector<RigidTransform>&, int, int) { return {}; }

#endif

}  // namespace boxtree::peers
