#pragma once
// FCL 0.7 (Debian's libfcl-dev) as a peer for mesh-vs-mesh collision: the same two meshes, the
// same relative pose, exhaustive contact enumeration, and FCL's own counters.
//
// Counting differs slightly from ours: FCL tests the volumes of every node pair it reaches
// except leaf-leaf pairs, which go straight to the triangle test (num_leaf_tests); we test the
// volumes of every pair, leaf pairs included, before any triangle test.
#include <string>
#include <vector>

#include "boxtree/mesh.h"
#include "boxtree/shapes.h"

namespace boxtree::peers {

struct FclResult {
  std::uint64_t bv_tests = 0;
  std::uint64_t leaf_tests = 0;
  std::uint64_t pairs = 0;  // intersecting triangle pairs found
  double seconds = 0;       // median of the repeats, the collision query alone
  double build_seconds = 0;
};

// bv: "AABB", "OBB", "RSS", "OBBRSS", "kIOS". b is placed by a_from_b.
FclResult fcl_collide(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b, const std::string& bv,
                      int repeats);

std::vector<std::string> fcl_bv_names();

}  // namespace boxtree::peers
