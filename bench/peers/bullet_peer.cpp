// SPDX-License-Identifier: MIT
#include "peers/bullet_peer.h"

#include <chrono>
#include <limits>
#include <string>
#include <vector>

#include "boxtree/error.h"

#if BOXTREE_BENCH_HAVE_BULLET
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <btBulletCollisionCommon.h>
#endif

namespace boxtree::peers {

#if BOXTREE_BENCH_HAVE_BULLET
namespace {

using Clock = std::chrono::steady_clock;

// Reads the arrays btQuantizedBvh keeps protected, through pointers to members formed in a
// derived class (reading only; no object of this type is ever made).
struct BvhArrays : btQuantizedBvh {
  static std::size_t retained_bytes(const btQuantizedBvh& bvh) {
    constexpr auto leaf = &BvhArrays::m_leafNodes;
    constexpr auto contiguous = &BvhArrays::m_contiguousNodes;
    constexpr auto quantized_leaf = &BvhArrays::m_quantizedLeafNodes;
    return std::size_t((bvh.*leaf).capacity()) * sizeof(btOptimizedBvhNode) +
           std::size_t((bvh.*contiguous).capacity()) * sizeof(btOptimizedBvhNode) +
           std::size_t((bvh.*quantized_leaf).capacity()) * sizeof(btQuantizedBvhNode);
  }
};

// Keeps the closest hit: returning the hit fraction makes it the new limit, so farther
// triangles are rejected by btTriangleRaycastCallback's own test (leaves are still visited).
struct ClosestHit final : btTriangleRaycastCallback {
  using btTriangleRaycastCallback::btTriangleRaycastCallback;
  bool hit = false;
  btScalar reportHit(const btVector3&, btScalar fraction, int, int) override {
    hit = true;
    return fraction;
  }
};

}  // namespace

struct BulletBvhMesh::Impl {
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;
  std::unique_ptr<btBvhTriangleMeshShape> shape;
  double build_seconds = 0;
};

bool bullet_available() { return true; }
const char* bullet_version() {
  static const std::string v = "Bullet " + std::to_string(btGetVersion() / 100) + "." +
                               std::to_string(btGetVersion() % 100) +
                               (sizeof(btScalar) == 8 ? " (double precision)" : " (single precision)");
  return v.c_str();
}

BulletBvhMesh::BulletBvhMesh(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.vertices.reserve(3 * mesh.vertices.size());
  for (const Vec3& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) m.vertices.push_back(btScalar(v[k]));
  m.indices.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles)
    for (VertexId v : t) m.indices.push_back(int(v));
  m.array = std::make_unique<btTriangleIndexVertexArray>(int(mesh.triangles.size()), m.indices.data(),
                                                         3 * int(sizeof(int)), int(mesh.vertices.size()),
                                                         m.vertices.data(), 3 * int(sizeof(btScalar)));
  const auto start = Clock::now();
  m.shape = std::make_unique<btBvhTriangleMeshShape>(m.array.get(), /*useQuantizedAabbCompression=*/true);
  m.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
}

BulletBvhMesh::~BulletBvhMesh() = default;

double BulletBvhMesh::build_seconds() const { return impl_->build_seconds; }

BulletBvhBytes BulletBvhMesh::bytes() const {
  const btOptimizedBvh* bvh = impl_->shape->getOptimizedBvh();
  auto& mutable_bvh = const_cast<btOptimizedBvh&>(*bvh);  // Bullet's getters are non-const
  BulletBvhBytes b;
  b.quantized_nodes = std::size_t(mutable_bvh.getQuantizedNodeArray().capacity()) * sizeof(btQuantizedBvhNode);
  b.subtree_headers = std::size_t(mutable_bvh.getSubtreeInfoArray().capacity()) * sizeof(btBvhSubtreeInfo);
  b.retained_build_arrays = BvhArrays::retained_bytes(*bvh);
  return b;
}

std::size_t BulletBvhMesh::node_count() const {
  auto& bvh = const_cast<btOptimizedBvh&>(*impl_->shape->getOptimizedBvh());
  return std::size_t(bvh.getQuantizedNodeArray().size());
}

std::size_t BulletBvhMesh::mesh_copy_bytes() const {
  return impl_->vertices.size() * sizeof(btScalar) + impl_->indices.size() * sizeof(int);
}

double BulletBvhMesh::ray_closest(const Vec3& origin, const Vec3& direction, double t_max) {
  const Vec3 end = origin + t_max * direction;
  const btVector3 from(btScalar(origin.x()), btScalar(origin.y()), btScalar(origin.z()));
  const btVector3 to(btScalar(end.x()), btScalar(end.y()), btScalar(end.z()));
  ClosestHit callback(from, to);
  impl_->shape->performRaycast(&callback, from, to);
  return callback.hit ? double(callback.m_hitFraction) * t_max : std::numeric_limits<double>::infinity();
}

namespace {
struct CollectNodes final : btNodeOverlapCallback {
  std::vector<int>* out = nullptr;
  void processNode(int, int triangle) override { out->push_back(triangle); }
};
}  // namespace

void BulletBvhMesh::box_candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out) {
  CollectNodes collect;
  collect.out = &out;
  const btVector3 min(btScalar(lo.x()), btScalar(lo.y()), btScalar(lo.z()));
  const btVector3 max(btScalar(hi.x()), btScalar(hi.y()), btScalar(hi.z()));
  impl_->shape->getOptimizedBvh()->reportAabbOverlappingNodex(&collect, min, max);
}

#else  // no Bullet

struct BulletBvhMesh::Impl {};
bool bullet_available() { return false; }
const char* bullet_version() { return "Bullet: not built"; }
BulletBvhMesh::BulletBvhMesh(const TriangleMesh&) { throw Error("the bench was built without Bullet"); }
BulletBvhMesh::~BulletBvhMesh() = default;
double BulletBvhMesh::build_seconds() const { return 0; }
BulletBvhBytes BulletBvhMesh::bytes() const { return {}; }
std::size_t BulletBvhMesh::node_count() const { return 0; }
std::size_t BulletBvhMesh::mesh_copy_bytes() const { return 0; }
double BulletBvhMesh::ray_closest(const Vec3&, const Vec3&, double) { return 0; }
void BulletBvhMesh::box_candidates(const Vec3&, const Vec3&, std::vector<int>&) {}

#endif

}  // namespace boxtree::peers
