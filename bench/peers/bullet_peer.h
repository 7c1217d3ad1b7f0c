// SPDX-License-Identifier: MIT
#pragma once
// Bullet's static-mesh midphase as a peer: btBvhTriangleMeshShape with quantized AABB
// compression (Bullet's recommended setting for static meshes, 16-byte nodes), over a
// btTriangleIndexVertexArray that reads the caller's btScalar copy of the mesh (Bullet reads
// the mesh through that interface, so the copy is the user's data, not the hierarchy's).
// Precision is that of the Bullet the adapter links (pkg-config `bullet`: single).
//
// Ray path: btBvhTriangleMeshShape::performRaycast (the quantized tree's stackless ray walk,
// then btTriangleRaycastCallback's triangle test per leaf), i.e. exactly what
// btCollisionWorld::rayTest runs for a triangle-mesh object once the broadphase has found it,
// without the broadphase and the world's bookkeeping. Bullet's walk does not shorten the ray as
// hits are found: every leaf box the segment crosses is tested.
#include <cstddef>
#include <memory>
#include <vector>

#include "boxtree/mesh.h"

namespace boxtree::peers {

// False when the bench was built without Bullet (then BulletBvhMesh throws).
bool bullet_available();
// "Bullet 3.24 (single precision)" or "Bullet: not built".
const char* bullet_version();

struct BulletBvhBytes {
  std::size_t quantized_nodes = 0;        // m_quantizedContiguousNodes: the tree walked by queries
  std::size_t subtree_headers = 0;        // m_SubtreeHeaders: cache-friendly subtree bounds
  std::size_t retained_build_arrays = 0;  // leaf (and unquantized) node arrays still held after the build
  std::size_t total() const { return quantized_nodes + subtree_headers + retained_build_arrays; }
};

class BulletBvhMesh {
 public:
  // Converts the mesh to btScalar (not timed) and builds the BVH (timed: build_seconds()).
  explicit BulletBvhMesh(const TriangleMesh& mesh);
  ~BulletBvhMesh();
  BulletBvhMesh(const BulletBvhMesh&) = delete;
  BulletBvhMesh& operator=(const BulletBvhMesh&) = delete;

  double build_seconds() const;
  BulletBvhBytes bytes() const;
  std::size_t node_count() const;  // quantized nodes
  // Bytes of the btScalar vertex and int index arrays Bullet reads (the user's mesh copy).
  std::size_t mesh_copy_bytes() const;

  // Closest hit of origin + t * direction for t in [0, t_max] (direction unit length): t, or
  // +infinity on a miss.
  double ray_closest(const Vec3& origin, const Vec3& direction, double t_max);

  // Midphase only: the triangles whose quantized leaf box overlaps the box [lo, hi]
  // (btQuantizedBvh::reportAabbOverlappingNodex, the walk under processAllTriangles, without
  // fetching the triangles' vertices). Appends their indices to `out`.
  void box_candidates(const Vec3& lo, const Vec3& hi, std::vector<int>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace boxtree::peers
