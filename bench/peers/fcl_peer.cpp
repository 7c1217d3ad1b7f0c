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

}  // namespace

std::vector<std::string> fcl_bv_names() { return {"AABB", "OBB", "RSS", "OBBRSS", "kIOS"}; }

FclResult fcl_collide(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b, const std::string& bv,
                      int repeats) {
  using namespace fcl::detail;
  if (bv == "AABB") return run<fcl::AABBd, MeshCollisionTraversalNode<fcl::AABBd>>(a, b, a_from_b, repeats);
  if (bv == "OBB") return run<fcl::OBBd, MeshCollisionTraversalNodeOBB<double>>(a, b, a_from_b, repeats);
  if (bv == "RSS") return run<fcl::RSSd, MeshCollisionTraversalNodeRSS<double>>(a, b, a_from_b, repeats);
  if (bv == "OBBRSS") return run<fcl::OBBRSSd, MeshCollisionTraversalNodeOBBRSS<double>>(a, b, a_from_b, repeats);
  if (bv == "kIOS") return run<fcl::kIOSd, MeshCollisionTraversalNodekIOS<double>>(a, b, a_from_b, repeats);
  throw Error("fcl: unknown bounding volume '" + bv + "'");
}

}  // namespace boxtree::peers
