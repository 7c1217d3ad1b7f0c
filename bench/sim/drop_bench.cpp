// SPDX-License-Identifier: MIT
// The drop scene (the demo's: mixed bodies falling into a terrain bowl) in Bullet and ODE, with
// each engine's built-in triangle-mesh midphase and with boxtree's, in one process on the same
// scene (demos/src/scene.h, sim.h: the demo's own worlds, without rendering).
//
// Per engine, terrain size and body count, the built-in run is the peer of every boxtree method:
//   contacts_per_step       contact points in the step (Bullet: manifold points; ODE: joints);
//                           trajectories diverge between runs (contact is chaotic), so the ratio
//                           is statistical agreement, not identity;
//   narrowphase_triangles_per_step   triangles handed to per-triangle contact routines (sim.h);
//   collision_ms_per_step   collision detection (Bullet: performDiscreteCollisionDetection;
//                           ODE: dSpaceCollide with the near callback);
//   terrain_collide_ms_per_step   ODE only: the time of the dCollide calls between the terrain
//                           and a body (the near callback times every call; sim.h
//                           collision_breakdown), the measure for ODE; the markdown also
//                           splits it by the body's shape;
//   step_ms                 the whole step (collision, solver, integration);
//   bodies_fallen_through   bodies whose centre ended more than 1 m below the terrain's lowest
//                           point: lost through the terrain (their pairs with it stop, so a
//                           world that loses bodies also has less collision work left);
//   build_seconds           creating the world, the terrain's hierarchy included.
// Per-step figures are means over the steps after the first third (most bodies have landed).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/method.h"
#include "scene.h"
#include "sim.h"

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kTimeStep = 1.0 / 60;

struct Config {
  int cells = 128;  // terrain cells per side: 2 * cells^2 facets
  int bodies = 100;
  bool all_methods = true;  // oriented builds are slow on the largest terrains: aabb only there
};

struct Measure {
  double contacts = 0, triangles = 0, collision_ms = 0, step_ms = 0, build_seconds = 0;
  // Bodies whose centre ended more than 1 m below the terrain's lowest point: lost through it.
  int fell_through = 0;
  // Per pair kind, over the measured steps, per step (empty for Bullet).
  std::vector<demo::Simulation::PairKindTime> breakdown;
  double terrain_ms = 0;  // the breakdown's terrain-* entries, ms per step
  double measured_steps = 1;
};

// after - before over the measured steps: seconds per step; calls and contacts summed (Measure::measured_steps divides
// them).
std::vector<demo::Simulation::PairKindTime> per_step(const std::vector<demo::Simulation::PairKindTime>& before,
                                                     const std::vector<demo::Simulation::PairKindTime>& after,
                                                     double steps) {
  std::vector<demo::Simulation::PairKindTime> out;
  for (const auto& a : after) {
    demo::Simulation::PairKindTime d = a;
    for (const auto& b : before)
      if (b.kind == a.kind) {
        d.seconds -= b.seconds;
        d.calls -= b.calls;
        d.contacts -= b.contacts;
        d.triangles -= b.triangles;
      }
    d.seconds /= steps;
    out.push_back(d);
  }
  return out;
}

Measure run(const demo::Scene& scene, const std::string& engine, bool boxtree, const std::string& method, int steps) {
  demo::SimOptions options;
  options.boxtree_midphase = boxtree;
  options.method = method;
  const auto build_start = Clock::now();
  std::unique_ptr<demo::Simulation> sim = demo::make_simulation(engine, scene, options);
  Measure m;
  m.build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count();
  const int first_measured = steps / 3;
  double collision_before = 0, contacts = 0, step_seconds = 0;
  std::uint64_t triangles_before = 0;
  std::vector<demo::Simulation::PairKindTime> breakdown_before;
  for (int i = 0; i < steps; ++i) {
    if (i == first_measured) {
      collision_before = sim->collision_seconds();
      triangles_before = sim->narrowphase_triangles();
      breakdown_before = sim->collision_breakdown();
    }
    const auto start = Clock::now();
    sim->step(kTimeStep);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (i >= first_measured) {
      step_seconds += seconds;
      contacts += sim->contacts();
    }
  }
  const double measured = steps - first_measured;
  m.contacts = contacts / measured;
  m.triangles = double(sim->narrowphase_triangles() - triangles_before) / measured;
  m.collision_ms = 1e3 * (sim->collision_seconds() - collision_before) / measured;
  m.step_ms = 1e3 * step_seconds / measured;
  m.measured_steps = measured;
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& v : scene.terrain->vertices) lowest = std::min(lowest, v.z());
  for (const demo::Pose& pose : sim->poses()) m.fell_through += pose.position.z() < lowest - 1;
  // ODE's only: this program's rows and tables predate Bullet's breakdown (bench/sim/scene_matrix.cpp
  // reports both engines').
  if (engine == "ode") m.breakdown = per_step(breakdown_before, sim->collision_breakdown(), measured);
  for (const auto& k : m.breakdown)
    if (k.kind.rfind("terrain-", 0) == 0) m.terrain_ms += 1e3 * k.seconds;
  return m;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

// One scene's table: a row per pair kind, a column group per engine run (the built-in first).
void write_breakdown(std::ostringstream& md, const std::string& engine, const Config& config,
                     const std::vector<std::pair<std::string, Measure>>& runs) {
  md << "\n" << engine << ", terrain " << config.cells << "^2, " << config.bodies << " bodies:\n\n| pair kind |";
  for (const auto& [name, m] : runs) md << " " << name << ": ms (calls, contacts, triangles) |";
  for (std::size_t r = 1; r < runs.size(); ++r) md << " " << runs[r].first << " / built-in |";
  md << "\n|---|";
  for (std::size_t r = 0; r < 2 * runs.size() - 1; ++r) md << "---:|";
  md << "\n";
  std::vector<std::string> kinds;
  for (const auto& [name, m] : runs)
    for (const auto& k : m.breakdown)
      if (std::find(kinds.begin(), kinds.end(), k.kind) == kinds.end()) kinds.push_back(k.kind);
  auto find = [](const Measure& m, const std::string& kind) -> const demo::Simulation::PairKindTime* {
    for (const auto& k : m.breakdown)
      if (k.kind == kind) return &k;
    return nullptr;
  };
  char buf[160];
  for (const std::string& kind : kinds) {
    md << "| " << kind << " |";
    for (const auto& [name, m] : runs) {
      const auto* k = find(m, kind);
      if (!k) {
        md << " |";
        continue;
      }
      std::snprintf(buf, sizeof buf, " %.3f (%.0f, %.0f, %.0f) |", 1e3 * k->seconds,
                    double(k->calls) / m.measured_steps, double(k->contacts) / m.measured_steps,
                    double(k->triangles) / m.measured_steps);
      md << buf;
    }
    const auto* base = find(runs[0].second, kind);
    for (std::size_t r = 1; r < runs.size(); ++r) {
      const auto* k = find(runs[r].second, kind);
      if (base && k && base->seconds > 0) {
        std::snprintf(buf, sizeof buf, " %.2f |", k->seconds / base->seconds);
        md << buf;
      } else {
        md << " |";
      }
    }
    md << "\n";
  }
  md << "| **terrain total** |";
  for (const auto& [name, m] : runs) {
    std::snprintf(buf, sizeof buf, " **%.3f** |", m.terrain_ms);
    md << buf;
  }
  for (std::size_t r = 1; r < runs.size(); ++r) {
    std::snprintf(buf, sizeof buf, " **%.2f** |",
                  runs[0].second.terrain_ms > 0 ? runs[r].second.terrain_ms / runs[0].second.terrain_ms : 0.0);
    md << buf;
  }
  md << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Drop scene in Bullet and ODE: built-in mesh midphase vs boxtree, in one run"};
  bool quick = false;
  std::string json_path, markdown_path;
  std::vector<std::string> methods = {"aabb", "obb-min-tight"};
  std::vector<std::string> engines = {"bullet", "ode"};
  int steps = 240;
  std::uint64_t seed = 1;
  std::vector<int> only_bodies;
  app.add_flag("--quick", quick, "One small scene, aabb and obb-min only, 90 steps (CI)");
  app.add_option("--json", json_path, "Write the rows (bench/results.json schema) here");
  app.add_option("--markdown", markdown_path, "Write the tables as a markdown fragment here");
  app.add_option("--methods", methods, "Comma-separated boxtree methods (small terrains; aabb only on large ones)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->capture_default_str();
  app.add_option("--engines", engines, "bullet, ode or both")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->capture_default_str();
  app.add_option("--steps", steps, "Steps per run (the last two thirds are measured)")->capture_default_str();
  app.add_option("--seed", seed, "Scene seed")->capture_default_str();
  app.add_option("--bodies", only_bodies, "Run only the scenes with these body counts (100, 500, 1000, 2000)")
      ->delimiter(',');
  CLI11_PARSE(app, argc, argv);
  std::vector<Config> configs = {{128, 100, true}, {256, 500, true}, {512, 1000, false}, {1024, 2000, false}};
  if (quick) {
    configs = {{64, 60, true}};
    methods = {"aabb", "obb-min"};
    steps = std::min(steps, 90);
  }
  if (!only_bodies.empty()) {
    std::vector<Config> chosen;
    for (const Config& config : configs)
      if (std::find(only_bodies.begin(), only_bodies.end(), config.bodies) != only_bodies.end())
        chosen.push_back(config);
    if (chosen.empty()) {
      std::fprintf(stderr, "drop_bench: --bodies matches no scene (100, 500, 1000, 2000; 60 with --quick)\n");
      return 2;
    }
    configs = chosen;
  }
  try {
    for (const std::string& m : methods) boxtree::parse_method(m);
    for (const std::string& e : engines)
      if (e != "bullet" && e != "ode") throw boxtree::Error("unknown engine '" + e + "' (bullet, ode)");
  } catch (const boxtree::Error& e) {
    std::fprintf(stderr, "drop_bench: %s\n", e.what());
    return 2;
  }

  nlohmann::json rows = nlohmann::json::array();
  std::ostringstream md;
  md << "Scene: the demo's (`demos/src/scene.h`): a fractal terrain in a bowl, 40 m across, mixed bodies (spheres, "
        "boxes, capsules, cylinders, convex hulls, small meshes) dropped in layers; "
     << steps << " steps of 1/60 s, means over the last two thirds. CPU: " << cpu_model() << ".\n\n";
  md << "| engine | terrain | bodies | midphase | contacts/step | narrowphase tri/step | collision ms/step | step ms | "
        "build s | fell through | collision ratio | step ratio | contacts ratio | triangles ratio |\n";
  md << "|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  // ODE's collision time by pair kind, one table per scene, appended after the main table.
  std::ostringstream breakdown_md;
  char buf[512];
  for (const std::string& engine : engines) {
    const std::string peer = engine == "bullet" ? "bullet btBvhTriangleMeshShape" : "ode dTriMesh (OPCODE)";
    for (const Config& config : configs) {
      demo::TerrainOptions terrain;
      terrain.cells = config.cells;
      const demo::Scene scene = demo::make_scene(terrain, config.bodies, seed);
      const std::string case_name = engine + " terrain " + std::to_string(config.cells) + "^2 (" +
                                    std::to_string(scene.terrain->facet_count()) + " facets), " +
                                    std::to_string(config.bodies) + " bodies";
      const Measure builtin = run(scene, engine, false, "", steps);
      std::snprintf(buf, sizeof buf, "| %s | %d^2 | %d | %s | %.1f | %.0f | %.3f | %.3f | %.2f | %d | | | | |\n",
                    engine.c_str(), config.cells, config.bodies, peer.c_str(), builtin.contacts, builtin.triangles,
                    builtin.collision_ms, builtin.step_ms, builtin.build_seconds, builtin.fell_through);
      md << buf;
      std::printf("%s: %s contacts %.1f triangles %.0f collision %.3f ms step %.3f ms build %.2f s fell through %d\n",
                  case_name.c_str(), peer.c_str(), builtin.contacts, builtin.triangles, builtin.collision_ms,
                  builtin.step_ms, builtin.build_seconds, builtin.fell_through);
      std::fflush(stdout);
      const std::vector<std::string> run_methods = config.all_methods ? methods : std::vector<std::string>{"aabb"};
      std::vector<std::pair<std::string, Measure>> breakdowns;
      if (!builtin.breakdown.empty()) breakdowns.push_back({peer, builtin});
      for (const std::string& method : run_methods) {
        const Measure ours = run(scene, engine, true, method, steps);
        if (!ours.breakdown.empty()) breakdowns.push_back({"boxtree " + method, ours});
        auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        const struct {
          const char* metric;
          double ours, theirs;
        } metrics[] = {{"contacts_per_step", ours.contacts, builtin.contacts},
                       {"narrowphase_triangles_per_step", ours.triangles, builtin.triangles},
                       {"collision_ms_per_step", ours.collision_ms, builtin.collision_ms},
                       {"terrain_collide_ms_per_step", ours.terrain_ms, builtin.terrain_ms},
                       {"step_ms", ours.step_ms, builtin.step_ms},
                       {"bodies_fallen_through", double(ours.fell_through), double(builtin.fell_through)},
                       {"build_seconds", ours.build_seconds, builtin.build_seconds}};
        for (const auto& m : metrics) {
          if (std::string(m.metric) == "terrain_collide_ms_per_step" &&
              (ours.breakdown.empty() || builtin.breakdown.empty()))
            continue;
          rows.push_back({{"section", "simulation"},
                          {"case", case_name},
                          {"metric", m.metric},
                          {"boxtree_method", method},
                          {"boxtree", m.ours},
                          {"peer", peer},
                          {"peer_value", m.theirs},
                          {"ratio", ratio(m.ours, m.theirs)}});
        }
        std::snprintf(
            buf, sizeof buf,
            "| %s | %d^2 | %d | boxtree %s | %.1f | %.0f | %.3f | %.3f | %.2f | %d | %.2f | %.2f | %.2f | %.2f |\n",
            engine.c_str(), config.cells, config.bodies, method.c_str(), ours.contacts, ours.triangles,
            ours.collision_ms, ours.step_ms, ours.build_seconds, ours.fell_through,
            ratio(ours.collision_ms, builtin.collision_ms), ratio(ours.step_ms, builtin.step_ms),
            ratio(ours.contacts, builtin.contacts), ratio(ours.triangles, builtin.triangles));
        md << buf;
        std::printf(
            "%s: boxtree %s contacts %.1f triangles %.0f collision %.3f ms (%.2fx) step %.3f ms (%.2fx) build %.2f s "
            "fell "
            "through %d\n",
            case_name.c_str(), method.c_str(), ours.contacts, ours.triangles, ours.collision_ms,
            ratio(ours.collision_ms, builtin.collision_ms), ours.step_ms, ratio(ours.step_ms, builtin.step_ms),
            ours.build_seconds, ours.fell_through);
        std::fflush(stdout);
      }
      if (breakdowns.size() > 1) write_breakdown(breakdown_md, engine, config, breakdowns);
    }
  }
  if (!breakdown_md.str().empty()) {
    md << "\n**Where ODE's collision time goes**: ms per step in the near callback's `dCollide` calls, by the "
          "kind of pair (a body with the terrain, by the body's shape, or two bodies); calls and contacts per "
          "step, and triangles handed to the narrowphase per step (ODE: OPCODE's triangle callback, which not every "
          "collider calls; boxtree: the adapter's candidate facets). `terrain_collide_ms_per_step` in "
          "`bench/results.json` is the sum of the terrain rows. ODE's hash "
          "space (finding the pairs) is in the collision time above but in none of these rows.\n"
       << breakdown_md.str();
  }
  if (!json_path.empty()) std::ofstream(json_path) << rows.dump(1) << '\n';
  if (!markdown_path.empty()) std::ofstream(markdown_path) << md.str();
  return 0;
}
