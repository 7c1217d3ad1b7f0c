// SPDX-License-Identifier: MIT
#include "peers/embree_peer.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <string>
#include <vector>

#include "boxtree/error.h"

#if BOXTREE_BENCH_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

namespace boxtree::peers {

#if BOXTREE_BENCH_HAVE_EMBREE
namespace {

using Clock = std::chrono::steady_clock;

// Embree reports each allocation (+bytes, before it) and each free (-bytes, after it); a failed
// allocation is reported again with -bytes. The running sum is what the device holds.
struct MemoryCounter {
  std::atomic<long long> current{0};
  std::atomic<long long> peak{0};
};

bool on_memory(void* user, ssize_t bytes, bool /*post*/) {
  auto& c = *static_cast<MemoryCounter*>(user);
  const long long now = c.current += bytes;
  long long peak = c.peak.load();
  while (now > peak && !c.peak.compare_exchange_weak(peak, now)) {
  }
  return true;
}

// Keeps the first error; the constructor throws it after the call (never through Embree's frames).
void on_error(void* user, RTCError code, const char* message) {
  auto& first = *static_cast<std::string*>(user);
  if (first.empty()) first = "embree: error " + std::to_string(int(code)) + ": " + (message ? message : "");
}

}  // namespace

struct EmbreeScene::Impl {
  MemoryCounter memory;
  std::string error;
  std::vector<float> vertices;  // x, y, z per vertex, plus padding: Embree reads 16 bytes at a time
  std::vector<unsigned> indices;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  double build_seconds = 0;
  std::size_t bytes = 0;
  std::size_t peak_bytes = 0;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

bool embree_available() { return true; }
const char* embree_version() {
  return "Embree " RTC_VERSION_STRING " (Debian libembree-dev, threads=1, build quality medium)";
}

EmbreeScene::EmbreeScene(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.vertices.reserve(3 * mesh.vertices.size() + 4);
  for (const Vec3& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) m.vertices.push_back(float(v[k]));
  m.vertices.resize(m.vertices.size() + 4, 0.0f);
  m.indices.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (VertexId v : t) m.indices.push_back(v);

  m.device = rtcNewDevice("threads=1");
  if (!m.device)
    throw Error("embree: rtcNewDevice failed (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(m.device, on_error, &m.error);
  rtcSetDeviceMemoryMonitorFunction(m.device, on_memory, &m.memory);
  {  // one-time initialisation (task arena, kernels) on a one-triangle scene, not timed or counted
    static const float corners[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0};
    static const unsigned triangle[3] = {0, 1, 2};
    RTCScene warm = rtcNewScene(m.device);
    RTCGeometry g = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, corners, 0, 3 * sizeof(float), 3);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, triangle, 0, 3 * sizeof(unsigned), 1);
    rtcCommitGeometry(g);
    rtcAttachGeometry(warm, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(warm);
    rtcReleaseScene(warm);
  }
  const long long before = m.memory.current.load();
  m.memory.peak = before;

  const auto start = Clock::now();
  m.scene = rtcNewScene(m.device);
  RTCGeometry geometry = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m.vertices.data(), 0,
                             3 * sizeof(float), mesh.vertices.size());
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m.indices.data(), 0,
                             3 * sizeof(unsigned), mesh.triangles.size());
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(m.scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(m.scene);
  m.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (!m.error.empty()) throw Error(m.error);
  m.bytes = std::size_t(std::max(0LL, m.memory.current.load() - before));
  m.peak_bytes = std::size_t(std::max(0LL, m.memory.peak.load() - before));
}

EmbreeScene::~EmbreeScene() = default;

double EmbreeScene::build_seconds() const { return impl_->build_seconds; }
std::size_t EmbreeScene::bytes() const { return impl_->bytes; }
std::size_t EmbreeScene::peak_bytes() const { return impl_->peak_bytes; }
std::size_t EmbreeScene::mesh_copy_bytes() const {
  return impl_->vertices.size() * sizeof(float) + impl_->indices.size() * sizeof(unsigned);
}

double EmbreeScene::ray_closest(const Vec3& origin, const Vec3& direction, double t_max) const {
  RTCRayHit rh;
  rh.ray.org_x = float(origin.x());
  rh.ray.org_y = float(origin.y());
  rh.ray.org_z = float(origin.z());
  rh.ray.dir_x = float(direction.x());
  rh.ray.dir_y = float(direction.y());
  rh.ray.dir_z = float(direction.z());
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = float(t_max);
  rh.ray.time = 0.0f;
  rh.ray.mask = ~0u;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(impl_->scene, &context, &rh);
  return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? std::numeric_limits<double>::infinity() : double(rh.ray.tfar);
}

#else  // no Embree

struct EmbreeScene::Impl {};
bool embree_available() { return false; }
const char* embree_version() { return "Embree: not built (Debian: libembree-dev)"; }
EmbreeScene::EmbreeScene(const TriangleMesh&) { throw Error("the bench was built without Embree"); }
EmbreeScene::~EmbreeScene() = default;
double EmbreeScene::build_seconds() const { return 0; }
std::size_t EmbreeScene::bytes() const { return 0; }
std::size_t EmbreeScene::peak_bytes() const { return 0; }
std::size_t EmbreeScene::mesh_copy_bytes() const { return 0; }
double EmbreeScene::ray_closest(const Vec3&, const Vec3&, double) const { return 0; }

#endif

}  // namespace boxtree::peers
