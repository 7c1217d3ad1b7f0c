// SPDX-License-Identifier: MIT
#include <algorithm>
#include <chrono>

#include "boxtree/error.h"
#include "boxtree/geometry.h"
#include "mesh_peers.h"

#ifdef BOXTREE_MM_HAVE_BULLET
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactQuantizedBvh.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btScalar.h>
#endif

namespace boxtree::peers {

#ifdef BOXTREE_MM_HAVE_BULLET

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
// The fastest of the repeated runs: on a shared machine the least disturbed one.
double fastest(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// A mesh as Bullet reads it (its own btScalar copy) and its GImpact shape.
struct GImpactMesh {
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;
  std::unique_ptr<btGImpactMeshShape> shape;
  double build_seconds = 0;

  GImpactMesh(const TriangleMesh& mesh, double margin) {
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(btScalar(v[k]));
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) indices.push_back(int(t[k]));
    array = std::make_unique<btTriangleIndexVertexArray>(int(mesh.triangles.size()), indices.data(),
                                                         3 * int(sizeof(int)), int(mesh.vertices.size()),
                                                         vertices.data(), 3 * int(sizeof(btScalar)));
    const auto start = Clock::now();
    shape = std::make_unique<btGImpactMeshShape>(array.get());
    shape->setMargin(btScalar(margin));
    shape->updateBound();  // builds the part's quantized box tree
    build_seconds = since(start);
    if (shape->getMeshPartCount() != 1) throw Error("gimpact: expected one mesh part");
  }
  const btGImpactBoxSet* box_set() const { return shape->getMeshPart(0)->getBoxSet(); }
};

btTransform to_bullet(const RigidTransform& t) {
  const Mat3& r = t.rotation;
  return btTransform(
      btMatrix3x3(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)), btScalar(r(1, 0)), btScalar(r(1, 1)),
                  btScalar(r(1, 2)), btScalar(r(2, 0)), btScalar(r(2, 1)), btScalar(r(2, 2))),
      btVector3(btScalar(t.translation.x()), btScalar(t.translation.y()), btScalar(t.translation.z())));
}
}  // namespace

struct GImpactPair::Impl {
  const TriangleMesh& a;
  const TriangleMesh& b;
  GImpactMesh ga, gb;
  Impl(const TriangleMesh& a_, const TriangleMesh& b_, double margin) : a(a_), b(b_), ga(a_, margin), gb(b_, margin) {}
};

bool gimpact_available() { return true; }
const char* gimpact_version() {
  static const std::string v = "Bullet " + std::to_string(BT_BULLET_VERSION / 100) + "." +
                               std::to_string(BT_BULLET_VERSION % 100) +
                               (sizeof(btScalar) == 8 ? " (double precision)" : " (single precision)");
  return v.c_str();
}

GImpactPair::GImpactPair(const TriangleMesh& a, const TriangleMesh& b, double margin)
    : impl_(std::make_unique<Impl>(a, b, margin)) {}
GImpactPair::~GImpactPair() = default;
double GImpactPair::build_seconds() const { return (impl_->ga.build_seconds + impl_->gb.build_seconds) / 2; }

GImpactResult GImpactPair::run(const std::vector<RigidTransform>& a_from_b, int repeats,
                               std::vector<std::vector<std::pair<FacetId, FacetId>>>* pairs_per_pose) {
  GImpactResult r;
  r.build_seconds = build_seconds();
  if (pairs_per_pose) pairs_per_pose->assign(a_from_b.size(), {});
  const btTransform identity = btTransform::getIdentity();
  btPairSet candidates;
  for (std::size_t p = 0; p < a_from_b.size(); ++p) {
    const RigidTransform& pose = a_from_b[p];
    const btTransform b_world = to_bullet(pose);
    std::vector<double> mid, exact;
    std::uint64_t found = 0;
    for (int rep = 0; rep < std::max(1, repeats); ++rep) {
      candidates.resizeNoInitialize(0);
      auto start = Clock::now();
      btGImpactQuantizedBvh::find_collision(impl_->ga.box_set(), identity, impl_->gb.box_set(), b_world, candidates);
      mid.push_back(since(start));
      start = Clock::now();
      found = 0;
      const TriangleMesh& a = impl_->a;
      const TriangleMesh& b = impl_->b;
      for (int i = 0; i < candidates.size(); ++i) {
        const FacetId fa = FacetId(candidates[i].m_index1), fb = FacetId(candidates[i].m_index2);
        if (triangles_intersect(a.corner(fa, 0), a.corner(fa, 1), a.corner(fa, 2), pose.apply(b.corner(fb, 0)),
                                pose.apply(b.corner(fb, 1)), pose.apply(b.corner(fb, 2)))) {
          ++found;
          if (pairs_per_pose && rep == 0) (*pairs_per_pose)[p].emplace_back(fa, fb);
        }
      }
      exact.push_back(since(start));
    }
    r.midphase_seconds += fastest(mid);
    r.exact_seconds += fastest(exact);
    r.candidates += std::uint64_t(candidates.size());
    r.pairs += found;
    if (pairs_per_pose) std::sort((*pairs_per_pose)[p].begin(), (*pairs_per_pose)[p].end());
  }
  return r;
}

#else  // no Bullet

struct GImpactPair::Impl {};
bool gimpact_available() { return false; }
const char* gimpact_version() { return "Bullet: not built"; }
GImpactPair::GImpactPair(const TriangleMesh&, const TriangleMesh&, double) { throw Error("gimpact: Bullet not built"); }
GImpactPair::~GImpactPair() = default;
double GImpactPair::build_seconds() const { return 0; }
GImpactResult GImpactPair::run(const std::vector<RigidTransform>&, int,
                               std::vector<std::vector<std::pair<FacetId, FacetId>>>*) {
  return {};
}

#endif

}  // namespace boxtree::peers
