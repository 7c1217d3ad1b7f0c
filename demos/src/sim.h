// SPDX-License-Identifier: MIT
#pragma once
// One physics world built from a Scene: Bullet or ODE, with the engine's own triangle-mesh
// midphase or the boxtree adapter's. Both step with a fixed time step, single-threaded, so the
// same scene gives the same motion on every run.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene.h"

namespace demo {

struct SimOptions {
  bool boxtree_midphase = false;
  std::string method = "aabb";  // the boxtree hierarchy method (boxtree/method.h)
  std::uint64_t seed = 1;       // for engines that randomise their solver (ODE's quickstep)
  // ODE: the contact buffer handed to dCollide per pair (its `flags`). OPCODE's capsule and
  // cylinder colliders stop visiting triangles once that many raw contacts are found (measured:
  // 16.0 and 10.0 triangles per call with 8, 24.0 and 15.7 with 64); boxtree's visit them all and
  // keep the best. 1 to 64.
  int max_contacts_per_pair = 8;
  // Mesh-vs-mesh contact policy of the boxtree adapters (boxtree/collider.h): "triangle-pairs",
  // "face-normals", or empty for each adapter's default.
  std::string mesh_contacts;
  // Mesh vs mesh with temporal coherence in the boxtree adapters (Bullet's
  // AlgorithmSettings::meshCoherence, ODE's GeomSettings::mesh_coherence; both off by default).
  bool mesh_coherence = false;
  // Convex bodies vs meshes with temporal coherence in the boxtree adapters (ODE's
  // GeomSettings::convex_coherence, Bullet's AlgorithmSettings::convexCoherence; both on by
  // default): a pair at rest gets its last contacts again while neither body moves.
  bool convex_coherence = true;
  // Bullet with the boxtree adapter: convex hulls get their polyhedral features
  // (btPolyhedralConvexShape::initializePolyhedralFeatures) and boxtree's exact separating axes
  // (AlgorithmSettings::hullFaces) instead of Bullet's GJK per triangle. Off: the adapter's default.
  bool hull_faces = false;
  // Bodies at rest may sleep (Bullet's deactivation, ODE's auto-disable), after which their pairs
  // are not collided. Off: every body stays awake (benchmarks of resting piles).
  bool sleeping = true;
};

class Simulation {
 public:
  virtual ~Simulation() = default;
  virtual void step(Real dt) = 0;
  // One pose per scene body, in scene order.
  virtual std::vector<Pose> poses() const = 0;
  // Contact points in the last step (Bullet: points in the persistent manifolds; ODE: contact
  // joints made).
  virtual int contacts() const = 0;
  // Seconds spent in collision detection so far (Bullet: performDiscreteCollisionDetection, i.e.
  // AABB update, broadphase, midphase and narrowphase; ODE: dSpaceCollide with the near callback).
  virtual double collision_seconds() const = 0;
  // Triangles handed to the narrowphase so far, for the benchmarks (bench/sim). Bullet builtin:
  // the terrain's convex-triangle callbacks (btConvexTriangleCallback; GImpact's mesh-mesh work is
  // not counted); boxtree: the adapter's counters of every mesh shape (narrowphase triangles).
  // ODE builtin: the triangles OPCODE hands to the colliders (dGeomTriMeshSetCallback); boxtree:
  // the candidate facets of every boxtree geom.
  virtual std::uint64_t narrowphase_triangles() const = 0;
  // Volume pairs tested so far by the boxtree adapters' mesh-vs-mesh tree walks (0 for the
  // built-in midphase).
  virtual std::uint64_t mesh_volume_tests() const { return 0; }
  // The boxtree adapter's per-pair coherence state kept now, where the adapter can tell (ODE's
  // registries: convex_pair_cache_info and mesh_pair_cache_info; Bullet keeps it in each pair's
  // algorithm and reports nothing here).
  struct PairState {
    std::size_t pairs = 0, bytes = 0;
  };
  virtual PairState pair_state() const { return {}; }
  // Collision time split by the kind of pair, for the benchmarks: one entry per pair kind seen so
  // far ("terrain-box", ..., "body-body"), in a fixed order. ODE: the time of each dCollide call
  // made by the near callback (the hash space's own work is outside all of them). Bullet: the time
  // of the dispatcher's default near callback per broadphase pair (the pair's algorithm: midphase
  // and narrowphase; the broadphase and the AABB update are outside all of them); contacts are the
  // points in the pair's manifolds after the call.
  struct PairKindTime {
    std::string kind;
    double seconds = 0;
    std::uint64_t calls = 0, contacts = 0;
    std::uint64_t triangles = 0;  // handed to the narrowphase (as narrowphase_triangles())
  };
  virtual std::vector<PairKindTime> collision_breakdown() const { return {}; }
  // For the pair benchmark (bench/sim/pair_replay.cpp).
  // Puts every body at `poses` (scene order), at rest. False if not supported.
  virtual bool set_poses(const std::vector<Pose>& poses) {
    (void)poses;
    return false;
  }
  // Collides the terrain with every body (of shape `only`, if given) `repeats` times at the
  // current poses, making no joints; the time per kind, as collision_breakdown. ODE: every
  // terrain-body pair; Bullet: every broadphase pair of the terrain or of a mesh body with a body
  // (kinds terrain-<shape> and mesh-<shape>), each by its own collision algorithm.
  virtual std::vector<PairKindTime> replay_terrain_pairs(int repeats, const Shape* only = nullptr) {
    (void)repeats, (void)only;
    return {};
  }
  // What handles the triangle meshes, for the summary.
  virtual std::string midphase_description() const = 0;
};

// Throw boxtree::Error when the boxtree midphase is asked for but the adapter was not built.
std::unique_ptr<Simulation> make_bullet_simulation(const Scene& scene, const SimOptions& options);
std::unique_ptr<Simulation> make_ode_simulation(const Scene& scene, const SimOptions& options);
// The engine by name: "bullet" or "ode" (boxtree::Error otherwise, and as above).
std::unique_ptr<Simulation> make_simulation(const std::string& engine, const Scene& scene, const SimOptions& options);

bool have_bullet_adapter();
bool have_ode_adapter();

}  // namespace demo
