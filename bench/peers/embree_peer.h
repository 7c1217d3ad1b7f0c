// SPDX-License-Identifier: MIT
#pragma once
// Embree 3 (Debian's libembree-dev) as a peer: one triangle geometry in a static scene, default
// build quality (medium), built by a device created with "threads=1" so that builds and rays are
// single-threaded like every other engine here. Embree works in single precision: the caller's
// mesh is copied to float vertex and index buffers that the geometry shares (the user's copy,
// not counted as Embree's memory).
//
// Memory: the bytes Embree itself reports through rtcSetDeviceMemoryMonitorFunction for the
// scene (allocations minus frees from rtcNewScene to the end of rtcCommitScene): the BVH nodes
// and Embree's primitive blocks (which hold their own copies of the triangles' vertices).
#include <cstddef>
#include <memory>

#include "boxtree/mesh.h"

namespace boxtree::peers {

// False when the bench was built without Embree (then EmbreeScene throws).
bool embree_available();
// "Embree 3.13.5 (...)" or "Embree: not built".
const char* embree_version();

class EmbreeScene {
 public:
  // Copies the mesh to float buffers (not timed), then builds (timed: build_seconds(), from
  // rtcNewScene to rtcCommitScene).
  explicit EmbreeScene(const TriangleMesh& mesh);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  double build_seconds() const;
  std::size_t bytes() const;            // held by the scene after the build (memory monitor)
  std::size_t peak_bytes() const;       // the most held at once during the build
  std::size_t mesh_copy_bytes() const;  // the shared float vertex / uint32 index buffers

  // Closest hit of origin + t * direction for t in [0, t_max] (rtcIntersect1): t, or +infinity.
  double ray_closest(const Vec3& origin, const Vec3& direction, double t_max) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace boxtree::peers
