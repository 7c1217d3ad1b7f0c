// SPDX-License-Identifier: MIT
#include "peers/fcl_peer.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>

#include <fcl/fcl.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include "boxtree/error.h"

namespace boxtree::peers {
namespace {

using Clock = std::chrono::steady_clock;

template <class BV>
std::shared_ptr<fcl::BVHModel<BV>> make_model(const TriangleMesh& mesh) {
  std::vector<fcl::Vector3d> vertices(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<fcl::BVHModel<BV>>();
  model->beginModel();
  model->addSubModel(vertices, triangles);
  model->endModel();
  return model;
}

template <class BV, class Node>
FclResult run(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b, int repeats) {
  FclResult r;
  const auto build_start = Clock::now();
  auto model_a = make_model<BV>(a);
  auto model_b = make_model<BV>(b);
  r.build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count() / 2;
  fcl::Transform3d tf_a = fcl::Transform3d::Identity();
  fcl::Transform3d tf_b = fcl::Transform3d::Identity();
  tf_b.linear() = a_from_b.rotation;
  tf_b.translation() = a_from_b.translation;
  const fcl::CollisionRequestd request(std::numeric_limits<int>::max(), false);
  std::vector<double> times;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    fcl::CollisionResultd result;
    Node node;
    bool ready = false;
    if constexpr (std::is_same_v<Node, fcl::detail::MeshCollisionTraversalNode<BV>>) {
      ready = fcl::detail::initialize(node, *model_a, tf_a, *model_b, tf_b, request, result);
    } else {  // the oriented volumes' own node types take const models
      ready = fcl::detail::initialize(node, std::as_const(*model_a), std::as_const(tf_a), std::as_const(*model_b),
                                      std::as_const(tf_b), request, result);
    }
    if (!ready) throw Error("fcl: traversal initialisation failed");
    node.enable_statistics = true;  // FCL counts volume and leaf tests only when asked
    const auto start = Clock::now();
    fcl::detail::collide(&node);
    times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    r.bv_tests = std::uint64_t(node.num_bv_tests);
    r.leaf_tests = std::uint64_t(node.num_leaf_tests);
    r.pairs = result.numContacts();
  }
  std::sort(times.begin(), times.end());
  r.seconds = times[times.size() / 2];
  return r;
}

template <class BV, class Node>
FclResult run_poses(const TriangleMesh& a, const TriangleMesh& b, const std::vector<RigidTransform>& poses, int repeats,
                    std::vector<std::vector<std::pair<FacetId, FacetId>>>* pairs_per_pose) {
  FclResult r;
  const auto build_start = Clock::now();
  auto model_a = make_model<BV>(a);
  auto model_b = make_model<BV>(b);
  r.build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count() / 2;
  const fcl::CollisionRequestd request(std::numeric_limits<int>::max(), false);
  if (pairs_per_pose) pairs_per_pose->assign(poses.size(), {});
  r.seconds = 0;
  for (std::size_t p = 0; p < poses.size(); ++p) {
    std::vector<double> times;
    for (int i = 0; i < std::max(1, repeats); ++i) {
      fcl::Transform3d tf_a = fcl::Transform3d::Identity();
      fcl::Transform3d tf_b = fcl::Transform3d::Identity();
      tf_b.linear() = poses[p].rotation;
      tf_b.translation() = poses[p].translation;
      fcl::CollisionResultd result;
      Node node;
      bool ready = false;
      auto start = Clock::now();
      if constexpr (std::is_same_v<Node, fcl::detail::MeshCollisionTraversalNode<BV>>) {
        // initialize() rewrites a non-identity model in place: give it a copy (not timed).
        std::shared_ptr<fcl::BVHModel<BV>> b_copy = model_b;
        if (!tf_b.matrix().isIdentity()) b_copy = std::make_shared<fcl::BVHModel<BV>>(*model_b);
        start = Clock::now();
        ready = fcl::detail::initialize(node, *model_a, tf_a, *b_copy, tf_b, request, result);
        if (!ready) throw Error("fcl: traversal initialisation failed");
        node.enable_statistics = true;
        fcl::detail::collide(&node);
      } else {
        ready = fcl::detail::initialize(node, std::as_const(*model_a), std::as_const(tf_a), std::as_const(*model_b),
                                        std::as_const(tf_b), request, result);
        if (!ready) throw Error("fcl: traversal initialisation failed");
        node.enable_statistics = true;
        fcl::detail::collide(&node);
      }
      times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
      if (i > 0) continue;
      r.bv_tests += std::uint64_t(node.num_bv_tests);
      r.leaf_tests += std::uint64_t(node.num_leaf_tests);
      r.pairs += result.numContacts();
      if (pairs_per_pose) {
        auto& pairs = (*pairs_per_pose)[p];
        for (std::size_t k = 0; k < result.numContacts(); ++k) {
          const fcl::Contactd& c = result.getContact(k);
          pairs.emplace_back(FacetId(c.b1), FacetId(c.b2));
        }
        std::sort(pairs.begin(), pairs.end());
      }
    }
    r.seconds += *std::min_element(times.begin(), times.end());
  }
  return r;
}

}  // namespace

FclResult fcl_collide_poses(const TriangleMesh& a, const TriangleMesh& b, const std::vector<RigidTransform>& a_from_b,
                            const std::string& bv, int repeats,
                            std::vector<std::vector<std::pair<FacetId, FacetId>>>* pairs_per_pose) {
  using namespace fcl::detail;
  if (bv == "AABB")
    return run_poses<fcl::AABBd, MeshCollisionTraversalNode<fcl::AABBd>>(a, b, a_from_b, repeats, pairs_per_pose);
  if (bv == "OBB")
    return run_poses<fcl::OBBd, MeshCollisionTraversalNodeOBB<double>>(a, b, a_from_b, repeats, pairs_per_pose);
  if (bv == "RSS")
    return run_poses<fcl::RSSd, MeshCollisionTraversalNodeRSS<double>>(a, b, a_from_b, repeats, pairs_per_pose);
  if (bv == "OBBRSS")
    return run_poses<fcl::OBBRSSd, MeshCollisionTraversalNodeOBBRSS<double>>(a, b, a_from_b, repeats, pairs_per_pose);
  if (bv == "kIOS")
    return run_poses<fcl::kIOSd, MeshCollisionTraversalNodekIOS<double>>(a, b, a_from_b, repeats, pairs_per_pose);
  throw Error("fcl: unknown bounding volume '" + bv + "'");
}

std::vector<std::string> fcl_bv_names() { return {"AABB", "OBB", "RSS", "OBBRSS", "kIOS"}; }

FclResult fcl_collide(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b,
                      const std::string& bv, int repeats) {
  using namespace fcl::detail;
  if (bv == "AABB") return run<fcl::AABBd, MeshCollisionTraversalNode<fcl::AABBd>>(a, b, a_from_b, repeats);
  if (bv == "OBB") return run<fcl::OBBd, MeshCollisionTraversalNodeOBB<double>>(a, b, a_from_b, repeats);
  if (bv == "RSS") return run<fcl::RSSd, MeshCollisionTraversalNodeRSS<double>>(a, b, a_from_b, repeats);
  if (bv == "OBBRSS") return run<fcl::OBBRSSd, MeshCollisionTraversalNodeOBBRSS<double>>(a, b, a_from_b, repeats);
  if (bv == "kIOS") return run<fcl::kIOSd, MeshCollisionTraversalNodekIOS<double>>(a, b, a_from_b, repeats);
  throw Error("fcl: unknown bounding volume '" + bv + "'");
}

}  // namespace boxtree::peers
