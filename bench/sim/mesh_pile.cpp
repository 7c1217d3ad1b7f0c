// SPDX-License-Identifier: MIT
// Mesh-vs-mesh temporal coherence (issue 25, item 3): a pile of small closed meshes (the drop
// scene's bumpy spheres and tori, demos/src/scene.h BodyMix::mesh) dropped in tight columns onto
// the bowl, settled, then measured at rest, in Bullet and ODE with the boxtree adapters, once with
// the per-pair fronts (collide_front.h) and once with a fresh descent every step, in one process
// on the same scene; the two runs of an engine alternate their order. Bodies never sleep, so that
// the resting pairs are collided on every step (with sleeping, a resting pile costs nothing either
// way).
//
// Per engine and mode, over the measured steps: the mesh-vs-mesh walks' volume tests per step
// (sim.h mesh_volume_tests: body-body and body-terrain pairs, all boxtree meshes), the collision
// time per step (Bullet: performDiscreteCollisionDetection; ODE: dSpaceCollide with its near
// callback), contacts per step, and whether the two runs' final poses are bit-identical (they
// must be: the fronts change the work, not the answer).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "scene.h"
#include "sim.h"

namespace {

using Clock = std::chrono::steady_clock;
using demo::Real;
using demo::Vec3;
constexpr double kTimeStep = 1.0 / 60;

struct Run {
  double volume_tests = 0;  // per measured step
  double collision_ms = 0;  // per measured step
  double contacts = 0;      // per measured step
  double seconds = 0;       // the whole run, wall
  std::vector<demo::Pose> poses;
};

// The scene's mesh bodies re-placed in a 3 x 3 grid of columns over the middle of the terrain,
// `spacing` apart and layered `spacing` apart, so that they land on each other.
demo::Scene pile_scene(int bodies, int cells, std::uint64_t seed) {
  demo::SceneOptions options;
  options.mix = demo::BodyMix::mesh;
  options.bodies = bodies;
  options.terrain.kind = demo::TerrainKind::bowl;
  options.terrain.cells = cells;
  demo::Scene scene = demo::make_scene(options, seed);
  const Vec3 mid = (scene.bounds_min + scene.bounds_max) / 2;
  Real ground = scene.bounds_max.z();
  if (Real z = 0; scene.probe->height_at(mid.x(), mid.y(), &z)) ground = z;
  constexpr Real kSpacing = 1.1;  // bodies are 0.5 to 1.1 m across
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const int column = int(i % 9), layer = int(i / 9);
    scene.bodies[i].position = Vec3(mid.x() + kSpacing * (column % 3 - 1), mid.y() + kSpacing * (column / 3 - 1),
                                    ground + 1.5 + kSpacing * layer);
  }
  return scene;
}

Run run(const demo::Scene& scene, const std::string& engine, bool coherence, int settle_steps, int steps) {
  const auto start = Clock::now();
  demo::SimOptions options;
  options.boxtree_midphase = true;
  options.mesh_coherence = coherence;
  options.sleeping = false;
  std::unique_ptr<demo::Simulation> sim = demo::make_simulation(engine, scene, options);
  for (int i = 0; i < settle_steps; ++i) sim->step(kTimeStep);
  const std::uint64_t tests = sim->mesh_volume_tests();
  const double collision = sim->collision_seconds();
  double contacts = 0;
  for (int i = 0; i < steps; ++i) {
    sim->step(kTimeStep);
    contacts += sim->contacts();
  }
  Run r;
  r.volume_tests = double(sim->mesh_volume_tests() - tests) / steps;
  r.collision_ms = 1e3 * (sim->collision_seconds() - collision) / steps;
  r.contacts = contacts / steps;
  r.poses = sim->poses();
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

bool same_poses(const std::vector<demo::Pose>& a, const std::vector<demo::Pose>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].position != b[i].position || a[i].orientation.coeffs() != b[i].orientation.coeffs()) return false;
  return true;
}

double ratio(double x, double y) { return y > 0 ? x / y : std::nan(""); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A resting pile of meshes, Bullet and ODE with boxtree: mesh-vs-mesh fronts vs fresh descents"};
  std::string json_path, markdown_path;
  std::vector<std::string> engines = {"bullet", "ode"};
  int bodies = 50, cells = 128;
  double settle_seconds = 6, rest_seconds = 2;
  std::uint64_t seed = 1;
  bool quick = false;
  app.add_option("--json", json_path, "Write the rows here (bench/report.py's row format)");
  app.add_option("--markdown", markdown_path, "Write the table as a markdown fragment here");
  app.add_option("--engines", engines, "bullet, ode or both")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->capture_default_str();
  app.add_option("--bodies", bodies, "Mesh bodies in the pile")->capture_default_str();
  app.add_option("--cells", cells, "Terrain cells per side (2 x cells^2 facets)")->capture_default_str();
  app.add_option("--settle-seconds", settle_seconds, "Unmeasured fall and settling")->capture_default_str();
  app.add_option("--rest-seconds", rest_seconds, "Measured steps at rest")->capture_default_str();
  app.add_option("--seed", seed, "Scene seed")->capture_default_str();
  app.add_flag("--quick", quick, "A smoke run: 18 bodies, short phases");
  CLI11_PARSE(app, argc, argv);
  if (quick) bodies = 18, settle_seconds = 1, rest_seconds = 0.25;
  const int settle_steps = int(std::lround(settle_seconds / kTimeStep));
  const int steps = std::max(1, int(std::lround(rest_seconds / kTimeStep)));

  nlohmann::json rows = nlohmann::json::array();
  std::ostringstream md;
  md << "Mesh pile at rest: " << bodies << " closed meshes (bumpy spheres and tori, 250-290 facets) settled "
     << settle_seconds << " s on the bowl (" << 2 * cells * cells << " facets), then " << steps
     << " steps measured, bodies kept awake; boxtree `aabb` with the per-pair fronts vs a fresh descent every "
        "step (bench/sim/mesh_pile.cpp).\n\n"
     << "| engine | mesh volume tests / step: fresh → fronts (ratio) | collision ms / step: fresh → fronts "
        "(ratio) | contacts / step | final poses |\n|---|---|---|---|---|\n";
  try {
    const demo::Scene scene = pile_scene(bodies, cells, seed);
    int order = 0;
    for (const std::string& engine : engines) {
      Run fresh, fronts;
      if (order++ % 2 == 0) {
        fresh = run(scene, engine, false, settle_steps, steps);
        fronts = run(scene, engine, true, settle_steps, steps);
      } else {
        fronts = run(scene, engine, true, settle_steps, steps);
        fresh = run(scene, engine, false, settle_steps, steps);
      }
      const bool identical = same_poses(fresh.poses, fronts.poses);
      std::printf(
          "%s: mesh volume tests/step %.0f -> %.0f (%.3fx), collision ms/step %.3f -> %.3f (%.2fx), contacts/step "
          "%.1f / %.1f, final poses %s (%.0f s)\n",
          engine.c_str(), fresh.volume_tests, fronts.volume_tests, ratio(fronts.volume_tests, fresh.volume_tests),
          fresh.collision_ms, fronts.collision_ms, ratio(fronts.collision_ms, fresh.collision_ms), fresh.contacts,
          fronts.contacts, identical ? "bit-identical" : "DIFFER", fresh.seconds + fronts.seconds);
      std::fflush(stdout);
      md << "| " << engine << " | " << std::lround(fresh.volume_tests) << " → " << std::lround(fronts.volume_tests)
         << " (" << ratio(fronts.volume_tests, fresh.volume_tests) << ") | " << fresh.collision_ms << " → "
         << fronts.collision_ms << " (" << ratio(fronts.collision_ms, fresh.collision_ms) << ") | " << fronts.contacts
         << " | " << (identical ? "bit-identical" : "differ") << " |\n";
      const auto row = [&](const std::string& metric, double ours, double theirs) {
        const double q = ratio(ours, theirs);
        rows.push_back({{"section", "coherence"},
                        {"case", engine + " mesh pile at rest, " + std::to_string(bodies) + " meshes"},
                        {"engine", engine},
                        {"metric", metric},
                        {"boxtree_method", "aabb, fronts"},
                        {"boxtree", ours},
                        {"peer", "aabb, fresh descent"},
                        {"peer_value", theirs},
                        {"ratio", std::isfinite(q) ? nlohmann::json(q) : nlohmann::json(nullptr)}});
      };
      row("mesh_volume_tests_per_step", fronts.volume_tests, fresh.volume_tests);
      row("collision_ms_per_step", fronts.collision_ms, fresh.collision_ms);
      row("contacts_per_step", fronts.contacts, fresh.contacts);
      row("poses_disagree", identical ? 0 : 1, 0);
      if (!identical) {
        std::fprintf(stderr, "mesh_pile: %s: the runs with and without fronts ended in different poses\n",
                     engine.c_str());
        return 1;
      }
    }
  } catch (const boxtree::Error& e) {
    std::fprintf(stderr, "mesh_pile: %s\n", e.what());
    return 1;
  }
  if (!json_path.empty()) std::ofstream(json_path) << rows.dump(1) << '\n';
  if (!markdown_path.empty()) std::ofstream(markdown_path) << md.str();
  return 0;
}
