// SPDX-License-Identifier: MIT
#pragma once
// FCL 0.7 (Debian's libfcl-dev) as a peer for mesh-vs-mesh collision: the same two meshes, the
// same relative pose, exhaustive contact enumeration, and FCL's own counters.
//
// Counting differs slightly from ours: FCL tests the volumes of every node pair it reaches
// except leaf-leaf pairs, which go straight to the triangle test (num_leaf_tests); we test the
// volumes of every pair, leaf pairs included, before any triangle test.
#include <string>
#include <utility>
#include <vector>

#include "boxtree/mesh.h"
#include "boxtree/shapes.h"

namespace boxtree::peers {

struct FclResult {
  std::uint64_t bv_tests = 0;
  std::uint64_t leaf_tests = 0;
  std::uint64_t pairs = 0;  // intersecting triangle pairs found
  double seconds = 0;       // the collision query alone: fcl_collide, median of the repeats; fcl_collide_poses: below
  double build_seconds = 0;
};

// bv: "AABB", "OBB", "RSS", "OBBRSS", "kIOS". b is placed by a_from_b.
FclResult fcl_collide(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b,
                      const std::string& bv, int repeats);

// Many poses of b against a (bench/mesh_mesh): both models are built once (build_seconds: the
// mean of the two builds); counters and pairs are summed over the poses; seconds = the sum over
// the poses of each pose's fastest query time of `repeats` runs. FCL's AABB traversal works in a single frame: for a
// pose that is not the identity it transforms b's vertices and rebuilds b's tree in a's frame
// (fcl::detail::initialize, what fcl::collide does for AABB models, on a copy of the model).
// That rebuild is part of the timed query; copying the model is not. The oriented volumes'
// traversals only take the relative pose. pairs_per_pose (optional): per pose, the intersecting
// (facet of a, facet of b) pairs FCL reports, sorted.
FclResult fcl_collide_poses(const TriangleMesh& a, const TriangleMesh& b, const std::vector<RigidTransform>& a_from_b,
                            const std::string& bv, int repeats,
                            std::vector<std::vector<std::pair<FacetId, FacetId>>>* pairs_per_pose = nullptr);

std::vector<std::string> fcl_bv_names();

}  // namespace boxtree::peers
