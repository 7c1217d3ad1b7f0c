// SPDX-License-Identifier: MIT
// The drop scene's terrain pairs, replayed (ODE, or with --engine bullet Bullet: there the pairs
// of the terrain and of the mesh bodies): the scene settles for some steps (the engine's built-in
// midphase), then both the built-in world and boxtree's world are put at those very poses
// and every terrain-body pair is collided again and again, without stepping. The same pairs at the
// same poses for both, so the time per call of each body shape compares directly, and a profiler
// can be pointed at one shape (--only) without the rest of the step around it.
//
//   pair_replay --bodies 500 --cells 256 --settle 160 --repeats 50
//   perf record pair_replay --midphase boxtree --only cylinder --repeats 2000
//   pair_replay --terrain rough --mix hull64 --only convex   (scene_matrix's hull64 scene)
#include <CLI/CLI.hpp>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "scene.h"
#include "sim.h"

int main(int argc, char** argv) {
  CLI::App app{"Drop scene: the terrain-body pairs at one moment, replayed, built-in vs boxtree"};
  int bodies = 500, cells = 256, settle = 160, repeats = 50, rounds = 3;
  std::uint64_t seed = 1;
  std::string only_name, midphase = "both", method = "aabb", engine = "ode", terrain_name = "bowl", mix_name = "mixed";
  app.add_option("--bodies", bodies, "Bodies in the scene")->capture_default_str();
  app.add_option("--cells", cells, "Terrain cells per side")->capture_default_str();
  app.add_option("--settle", settle, "Steps before the replay (the built-in world)")->capture_default_str();
  app.add_option("--repeats", repeats, "Times every pair is collided")->capture_default_str();
  app.add_option("--rounds", rounds, "Replays per world, alternating; the fastest is kept")->capture_default_str();
  app.add_option("--seed", seed, "Scene seed")->capture_default_str();
  app.add_option("--terrain", terrain_name, "bowl, rough or flat (scene_matrix's terrains)")
      ->capture_default_str()
      ->check(CLI::IsMember({"bowl", "rough", "flat"}));
  app.add_option("--mix", mix_name,
                 "Bodies of the scene (scene.h's BodyMix: mixed, hull8 ... hull64 for hulls of 8 to 64 points, ...)")
      ->capture_default_str();
  app.add_option("--only", only_name,
                 "Replay only the bodies of this shape (sphere, box, capsule, cylinder, convex, mesh)");
  app.add_option("--engine", engine, "ode or bullet")->capture_default_str()->check(CLI::IsMember({"ode", "bullet"}));
  app.add_option("--midphase", midphase, "builtin, boxtree or both")->capture_default_str();
  app.add_option("--method", method, "boxtree hierarchy method")->capture_default_str();
  int max_contacts = 8;
  app.add_option("--max-contacts", max_contacts,
                 "Contact buffer per dCollide call, both worlds (OPCODE's capsule and cylinder colliders stop "
                 "visiting triangles when it is full)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  CLI11_PARSE(app, argc, argv);
  try {
    demo::Shape only_shape{};
    bool only = false;
    if (!only_name.empty()) {
      for (int s = 0; s <= int(demo::Shape::mesh); ++s)
        if (only_name == demo::shape_name(demo::Shape(s))) {
          only_shape = demo::Shape(s);
          only = true;
        }
      if (!only) throw boxtree::Error("unknown shape '" + only_name + "'");
    }
    if (midphase != "builtin" && midphase != "boxtree" && midphase != "both")
      throw boxtree::Error("--midphase: builtin, boxtree or both");
    demo::TerrainOptions terrain;
    terrain.cells = cells;
    for (demo::TerrainKind kind : {demo::TerrainKind::bowl, demo::TerrainKind::rough, demo::TerrainKind::flat})
      if (terrain_name == demo::terrain_kind_name(kind)) terrain.kind = kind;
    demo::SceneOptions scene_options;
    scene_options.terrain = terrain;
    scene_options.bodies = bodies;
    if (!demo::parse_body_mix(mix_name, &scene_options.mix)) throw boxtree::Error("unknown mix '" + mix_name + "'");
    const demo::Scene scene = demo::make_scene(scene_options, seed);
    demo::SimOptions builtin_options;
    builtin_options.max_contacts_per_pair = max_contacts;
    demo::SimOptions boxtree_options = builtin_options;
    boxtree_options.boxtree_midphase = true;
    boxtree_options.method = method;
    // Every replay collides the same poses again: with convex coherence the adapter would answer
    // them from its pair state (SimOptions::convex_coherence) instead of colliding.
    boxtree_options.convex_coherence = false;
    std::vector<demo::Pose> poses;
    {
      // Settled by the built-in world, so that the poses do not depend on the boxtree code under
      // test (A/B runs of two versions replay the very same pairs).
      auto settling = demo::make_simulation(engine, scene, demo::SimOptions{});
      for (int i = 0; i < settle; ++i) settling->step(1.0 / 60);
      poses = settling->poses();
    }
    // kind -> (built-in, boxtree)
    std::map<std::string, std::pair<demo::Simulation::PairKindTime, demo::Simulation::PairKindTime>> rows;
    // Both worlds exist at once; the replays alternate between them and each kind keeps its
    // fastest round (the machine is noisy; the counts are the same every round).
    std::unique_ptr<demo::Simulation> worlds[2];
    for (const bool use_boxtree : {false, true}) {
      if (midphase != "both" && use_boxtree != (midphase == "boxtree")) continue;
      worlds[use_boxtree] = demo::make_simulation(engine, scene, use_boxtree ? boxtree_options : builtin_options);
      if (!worlds[use_boxtree]->set_poses(poses)) throw boxtree::Error("the simulation cannot be posed");
    }
    for (int round = 0; round < rounds; ++round) {
      for (const bool use_boxtree : {false, true}) {
        if (!worlds[use_boxtree]) continue;
        for (const auto& k : worlds[use_boxtree]->replay_terrain_pairs(repeats, only ? &only_shape : nullptr)) {
          auto& kept = use_boxtree ? rows[k.kind].second : rows[k.kind].first;
          if (round == 0 || k.seconds < kept.seconds) kept = k;
        }
      }
    }
    std::printf(
        "%s drop scene, %s terrain %d^2, %d %s bodies, poses after %d steps, every terrain pair x %d, fastest of %d "
        "rounds, %d contacts per call at most\n",
        engine == "bullet" ? "Bullet" : "ODE", terrain_name.c_str(), cells, bodies, mix_name.c_str(), settle, repeats,
        rounds, max_contacts);
    std::printf("%-18s %8s | %10s %9s %9s | %10s %9s %9s | %7s\n", "pair kind", "pairs",
                engine == "bullet" ? "Bullet us" : "OPCODE us", "contacts", "triangles", "boxtree us", "contacts",
                "triangles", "ratio");
    double total[2] = {0, 0};
    for (const auto& [kind, both] : rows) {
      const auto per_call = [](const demo::Simulation::PairKindTime& t, double value) {
        return t.calls ? value / double(t.calls) : 0.0;
      };
      const auto& [a, b] = both;
      total[0] += a.seconds;
      total[1] += b.seconds;
      std::printf("%-18s %8.0f | %10.2f %9.2f %9.2f | %10.2f %9.2f %9.2f | %7.2f\n", kind.c_str(),
                  double(std::max(a.calls, b.calls)) / repeats, 1e6 * per_call(a, a.seconds),
                  per_call(a, double(a.contacts)), per_call(a, double(a.triangles)), 1e6 * per_call(b, b.seconds),
                  per_call(b, double(b.contacts)), per_call(b, double(b.triangles)),
                  a.seconds > 0 ? b.seconds / a.seconds : 0.0);
    }
    std::printf("%-18s %8s | %10.3f ms/replay %28s %10.3f ms/replay | %7.2f\n", "total", "", 1e3 * total[0] / repeats,
                "", 1e3 * total[1] / repeats, total[0] > 0 ? total[1] / total[0] : 0.0);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pair_replay: %s\n", e.what());
    return 2;
  }
  return 0;
}
