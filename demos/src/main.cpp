// SPDX-License-Identifier: MIT
// boxtree-demo: drops a few hundred mixed bodies onto a meshed terrain in Bullet or ODE, with
// the engine's own triangle-mesh midphase or boxtree's, and renders PNG frames off-screen
// (OSMesa). With --overlay-level it instead draws the hierarchy's volumes over the mesh.
// Errors: one line on stderr starting with "boxtree-demo: error:", exit code 1 (2 for usage).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/method.h"
#include "boxtree/version.h"
#include "overlay.h"
#include "render.h"
#include "scene.h"
#include "sim.h"

namespace {

using namespace demo;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Resident set size in kB (VmRSS of /proc/self/status), 0 where unavailable.
long resident_kb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return 0;
}

struct Options {
  std::string engine = "bullet";
  std::string midphase;  // empty: boxtree if the engine's adapter was built, else builtin
  std::string method = "aabb";
  int bodies = 300;
  int terrain_size = 128;
  std::string mesh;
  std::string up = "z";
  int steps = 300;
  int every = 10;
  int width = 640, height = 480;
  std::string out;
  std::uint64_t seed = 1;
  std::string json_path;
  int overlay_level = -1;
  bool soak = false;
  std::string mesh_contacts;
};

constexpr Real kTimeStep = 1.0 / 60;

// Frames of an earlier run in the same folder would mix with ours: remove just those.
void remove_old_frames(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("frame-", 0) == 0 && entry.path().extension() == ".png") fs::remove(entry.path());
  }
}

void write_json(const std::string& path, const json& summary) {
  if (path.empty()) return;
  std::ofstream out(path);
  out << summary.dump(2) << "\n";
  if (!out) throw boxtree::Error("cannot write " + path);
}

int run_overlay(const Options& o, const TerrainOptions& terrain_options) {
  const fs::path dir = o.out.empty() ? fs::path("out/demo-overlay") : fs::path(o.out);
  fs::create_directories(dir);
  std::string name;
  const auto mesh = make_demo_terrain(terrain_options, o.seed, &name);
  Renderer renderer(o.width, o.height);
  const std::string file =
      (dir / ("overlay-" + o.method + "-level" + std::to_string(o.overlay_level) + ".png")).string();
  const auto start = Clock::now();
  const OverlayResult result = render_overlay(renderer, mesh, o.method, o.overlay_level, file);
  std::cout << "boxtree-demo: overlay of " << name << " (" << mesh->facet_count() << " facets), method " << o.method
            << ", tree height " << result.height << ": " << result.volumes << " volumes at level " << o.overlay_level
            << " in " << file << " (" << seconds_since(start) << " s)\n";
  write_json(o.json_path, {{"mode", "overlay"},
                           {"mesh", name},
                           {"facets", mesh->facet_count()},
                           {"method", o.method},
                           {"level", o.overlay_level},
                           {"tree_height", result.height},
                           {"volumes", result.volumes},
                           {"image", file}});
  return 0;
}

// --soak: a long run without rendering that watches for the failures a long simulation can
// show: non-finite poses, bodies sinking below the terrain, memory growth. Every --every steps it
// samples the number of non-finite poses, the lowest body centre relative to the terrain under
// it, and the resident set size; it prints one line per sample and the summary (also to --json).
// Exit code 1 if any pose went non-finite or any body on the terrain ended below it.
int run_soak(const Options& o, const TerrainOptions& terrain_options) {
  const bool bullet = o.engine == "bullet";
  const bool adapter = bullet ? have_bullet_adapter() : have_ode_adapter();
  const std::string midphase = o.midphase.empty() ? (adapter ? "boxtree" : "builtin") : o.midphase;
  if (midphase == "boxtree") boxtree::parse_method(o.method);
  const auto start = Clock::now();
  const Scene scene = make_scene(terrain_options, o.bodies, o.seed);
  SimOptions sim_options;
  sim_options.boxtree_midphase = midphase == "boxtree";
  sim_options.method = o.method;
  sim_options.seed = o.seed;
  sim_options.mesh_contacts = o.mesh_contacts;
  auto sim = make_simulation(o.engine, scene, sim_options);
  constexpr Real kAllowance = 0.05;  // as in the simulation summary
  const TerrainProbe& probe = *scene.probe;
  json samples = json::array();
  int worst_nan = 0, worst_below = 0;
  std::size_t worst_pair_bytes = 0;
  std::vector<bool> reported(scene.bodies.size(), false);  // bodies already named as below the terrain
  Real lowest = std::numeric_limits<Real>::infinity();
  const long rss_start = resident_kb();
  std::printf("boxtree-demo soak: %s, %s midphase, %zu bodies, %d steps; RSS at start %ld kB\n", o.engine.c_str(),
              midphase.c_str(), scene.bodies.size(), o.steps, rss_start);
  for (int step = 1; step <= o.steps; ++step) {
    sim->step(kTimeStep);
    if (step % o.every != 0 && step != o.steps) continue;
    int nan = 0, below = 0;
    Real min_clearance = std::numeric_limits<Real>::infinity();
    const std::vector<Pose> poses = sim->poses();
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const Vec3& p = poses[i].position;
      if (!p.allFinite() || !poses[i].orientation.coeffs().allFinite()) {
        ++nan;
        continue;
      }
      Real ground = 0;
      if (!probe.height_at(p.x(), p.y(), &ground)) continue;
      min_clearance = std::min(min_clearance, p.z() - ground);
      if (p.z() < ground - kAllowance) {
        ++below;
        if (!reported[i]) {
          reported[i] = true;
          std::printf("  body %zu (%s) below the terrain at step %d: (%.3f, %.3f, %.3f), terrain at %.3f\n", i,
                      shape_name(scene.bodies[i].shape), step, p.x(), p.y(), p.z(), ground);
        }
      }
    }
    const long rss = resident_kb();
    const Simulation::PairState pair_state = sim->pair_state();
    worst_pair_bytes = std::max(worst_pair_bytes, pair_state.bytes);
    worst_nan = std::max(worst_nan, nan);
    worst_below = std::max(worst_below, below);
    lowest = std::min(lowest, min_clearance);
    std::printf(
        "  step %d: %.0f s, %d non-finite, %d below the terrain, lowest centre %.4f m above it, %d contacts, RSS %ld "
        "kB, pair state %zu pairs %zu bytes\n",
        step, seconds_since(start), nan, below, min_clearance, sim->contacts(), rss, pair_state.pairs,
        pair_state.bytes);
    std::fflush(stdout);
    samples.push_back({{"step", step},
                       {"wall_seconds", seconds_since(start)},
                       {"non_finite", nan},
                       {"below", below},
                       {"min_clearance", min_clearance},
                       {"contacts", sim->contacts()},
                       {"rss_kb", rss},
                       {"pair_state_pairs", pair_state.pairs},
                       {"pair_state_bytes", pair_state.bytes}});
  }
  const double wall = seconds_since(start);
  const long rss_middle = samples.empty() ? 0 : samples[samples.size() / 2]["rss_kb"].get<long>();
  const long rss_end = resident_kb();
  std::printf(
      "boxtree-demo soak: %d steps in %.0f s; non-finite poses at most %d, bodies below the terrain at most %d, "
      "lowest centre %.4f m above the terrain; RSS start %ld kB, middle %ld kB, end %ld kB\n",
      o.steps, wall, worst_nan, worst_below, lowest, rss_start, rss_middle, rss_end);
  write_json(o.json_path, {{"mode", "soak"},
                           {"engine", o.engine},
                           {"midphase", midphase},
                           {"method", o.method},
                           {"seed", o.seed},
                           {"bodies", scene.bodies.size()},
                           {"steps", o.steps},
                           {"wall_seconds", wall},
                           {"collision_seconds", sim->collision_seconds()},
                           {"max_non_finite", worst_nan},
                           {"max_below_terrain", worst_below},
                           {"min_clearance", lowest},
                           {"rss_kb_start", rss_start},
                           {"rss_kb_middle", rss_middle},
                           {"rss_kb_end", rss_end},
                           {"max_pair_state_bytes", worst_pair_bytes},
                           {"samples", samples}});
  return worst_nan == 0 && worst_below == 0 ? 0 : 1;
}

int run_simulation(const Options& o, const TerrainOptions& terrain_options) {
  const bool bullet = o.engine == "bullet";
  const bool adapter = bullet ? have_bullet_adapter() : have_ode_adapter();
  const std::string midphase = o.midphase.empty() ? (adapter ? "boxtree" : "builtin") : o.midphase;
  if (midphase == "boxtree") boxtree::parse_method(o.method);  // a bad name fails before any work
  const fs::path dir = o.out.empty() ? fs::path("out") / ("demo-" + o.engine + "-" + midphase) : fs::path(o.out);
  fs::create_directories(dir);
  remove_old_frames(dir);

  const auto start = Clock::now();
  const Scene scene = make_scene(terrain_options, o.bodies, o.seed);
  SimOptions sim_options;
  sim_options.boxtree_midphase = midphase == "boxtree";
  sim_options.method = o.method;
  sim_options.seed = o.seed;
  sim_options.mesh_contacts = o.mesh_contacts;
  auto sim = make_simulation(o.engine, scene, sim_options);
  const double setup_seconds = seconds_since(start);

  Renderer renderer(o.width, o.height);
  const DrawMesh terrain_draw = make_terrain_draw_mesh(*scene.terrain);
  std::vector<DrawMesh> body_draws;
  body_draws.reserve(scene.bodies.size());
  for (const BodySpec& b : scene.bodies) body_draws.push_back(make_draw_mesh(render_mesh_of(b), b.colour));
  // A fixed camera on where the action is: the bodies' starting column and the ground under it.
  Vec3 lo = scene.bounds_min, hi = scene.bounds_max;
  if (!scene.bodies.empty()) {
    lo.head<2>() = hi.head<2>() = scene.bodies.front().position.head<2>();
    for (const BodySpec& b : scene.bodies) {
      lo.head<2>() = lo.head<2>().cwiseMin(b.position.head<2>());
      hi.head<2>() = hi.head<2>().cwiseMax(b.position.head<2>());
      hi.z() = std::max(hi.z(), b.position.z());
    }
    lo.head<2>().array() -= 3;
    hi.head<2>().array() += 3;
  }
  const Camera camera = frame_box(lo, hi, Real(o.width) / o.height);

  std::vector<std::string> images;
  double render_seconds = 0;
  auto render = [&](int step) {
    const auto t0 = Clock::now();
    renderer.begin_frame(camera);
    renderer.draw(terrain_draw);
    const std::vector<Pose> poses = sim->poses();
    for (std::size_t i = 0; i < poses.size(); ++i) renderer.draw(body_draws[i], poses[i]);
    char name[32];
    std::snprintf(name, sizeof name, "frame-%05d.png", step);
    images.push_back((dir / name).string());
    renderer.write_png(images.back());
    render_seconds += seconds_since(t0);
  };

  const bool progress = isatty(STDERR_FILENO) != 0;
  long long contacts_total = 0;
  int contacts_max = 0;
  const auto sim_start = Clock::now();
  auto last_progress = sim_start;
  render(0);
  for (int step = 1; step <= o.steps; ++step) {
    sim->step(kTimeStep);
    contacts_total += sim->contacts();
    contacts_max = std::max(contacts_max, sim->contacts());
    if (step % o.every == 0 || step == o.steps) render(step);
    if (progress && (seconds_since(last_progress) > 0.2 || step == o.steps)) {
      last_progress = Clock::now();
      std::fprintf(stderr, "\rboxtree-demo: step %d/%d, %.1f s, %d contacts, %zu frames   ", step, o.steps,
                   seconds_since(sim_start), sim->contacts(), images.size());
      std::fflush(stderr);
    }
  }
  if (progress) std::fprintf(stderr, "\r%*s\r", 70, "");
  const double wall = seconds_since(start);

  // Where the bodies ended: how deep each body's bottom (scene.h, bottom_points) is in the
  // terrain under it; `above_terrain` unless deeper than the allowance, null with no terrain under
  // it. Allowance 5 cm. Deepest measured on the default scene (300 bodies, 300 steps, seeds 1-3,
  // boxtree midphase): 2.9 cm, a closed mesh in Bullet (ODE 0.5 cm; bench/results/mesh_contacts.txt
  // and the cylinder change after it); on the tests' scene (tests/demo, which holds it to 2.5 cm)
  // 0.5 cm in Bullet and 1.1 cm in ODE with boxtree, 1.3 and 0.9 cm with the builtin midphases.
  constexpr Real kDepthAllowance = 0.05;
  const TerrainProbe& probe = *scene.probe;
  const std::vector<Pose> final_poses = sim->poses();
  json final_bodies = json::array();
  int above = 0, below = 0, off = 0;
  Real deepest = -std::numeric_limits<Real>::infinity();
  for (std::size_t i = 0; i < final_poses.size(); ++i) {
    const Vec3& p = final_poses[i].position;
    Real ground = 0;
    const bool centre_on = std::isfinite(p.squaredNorm()) && probe.height_at(p.x(), p.y(), &ground);
    const std::optional<Real> depth = depth_below_terrain(probe, scene.bodies[i], final_poses[i]);
    json body = {{"shape", shape_name(scene.bodies[i].shape)}, {"position", {p.x(), p.y(), p.z()}}};
    body["terrain_z"] = centre_on ? json(ground) : json(nullptr);
    if (depth) {
      body["depth"] = *depth;
      body["above_terrain"] = *depth < kDepthAllowance;
      ++(*depth < kDepthAllowance ? above : below);
      deepest = std::max(deepest, *depth);
    } else {
      body["depth"] = nullptr;
      body["above_terrain"] = nullptr;
      ++off;
    }
    final_bodies.push_back(body);
  }

  const double contacts_mean = o.steps > 0 ? double(contacts_total) / o.steps : 0;
  std::printf("boxtree-demo: %s, %s midphase (%s), %zu bodies on %s (%zu facets)\n", o.engine.c_str(), midphase.c_str(),
              sim->midphase_description().c_str(), scene.bodies.size(), scene.terrain_name.c_str(),
              scene.terrain->facet_count());
  std::printf(
      "  %d steps (%.2f s simulated) in %.1f s wall: setup %.1f s, collision detection %.1f s, rendering %.1f s\n",
      o.steps, o.steps * kTimeStep, wall, setup_seconds, sim->collision_seconds(), render_seconds);
  std::printf(
      "  contacts per step: %.0f on average, %d at most; bodies at the end: %d above the terrain, %d below, %d off "
      "it; the deepest %.3f m in it\n",
      contacts_mean, contacts_max, above, below, off, deepest);
  std::printf("  %zu images: %s/frame-*.png\n", images.size(), dir.string().c_str());

  json summary = {{"mode", "simulation"},
                  {"engine", o.engine},
                  {"midphase", midphase},
                  {"midphase_shapes", sim->midphase_description()},
                  {"method", o.method},
                  {"seed", o.seed},
                  {"bodies", scene.bodies.size()},
                  {"terrain", scene.terrain_name},
                  {"terrain_facets", scene.terrain->facet_count()},
                  {"steps", o.steps},
                  {"dt", kTimeStep},
                  {"width", o.width},
                  {"height", o.height},
                  {"wall_seconds", wall},
                  {"setup_seconds", setup_seconds},
                  {"collision_seconds", sim->collision_seconds()},
                  {"render_seconds", render_seconds},
                  {"contacts_per_step", contacts_mean},
                  {"contacts_max", contacts_max},
                  {"bodies_above_terrain", above},
                  {"bodies_below_terrain", below},
                  {"bodies_off_terrain", off},
                  {"max_depth", std::isfinite(deepest) ? json(deepest) : json(nullptr)},
                  {"out_dir", dir.string()},
                  {"images", images},
                  {"final_bodies", final_bodies}};
  write_json(o.json_path, summary);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"boxtree-demo: bodies dropped onto a meshed terrain (Bullet or ODE), rendered off-screen to PNG"};
  app.set_version_flag("--version", std::string("boxtree-demo ") + BOXTREE_VERSION_STRING + " (library " +
                                        boxtree::library_version() + "; Bullet adapter " +
                                        (have_bullet_adapter() ? "built" : "not built") + ", ODE adapter " +
                                        (have_ode_adapter() ? "built" : "not built") + ")");
  app.add_option("--engine", o.engine, "Physics engine")
      ->check(CLI::IsMember({"bullet", "ode"}))
      ->capture_default_str();
  app.add_option("--midphase", o.midphase,
                 "Triangle-mesh midphase: boxtree (the adapter) or builtin (btBvhTriangleMeshShape + "
                 "btGImpactMeshShape, or ODE's OPCODE trimesh) [default: boxtree if the adapter is built]")
      ->check(CLI::IsMember({"boxtree", "builtin"}));
  app.add_option("--method", o.method,
                 "Hierarchy method of the boxtree midphase and of the overlay (see `boxtree --help`)")
      ->capture_default_str();
  app.add_option("--mesh-contacts", o.mesh_contacts,
                 "Mesh-vs-mesh contacts of the boxtree midphase: triangle-pairs or face-normals [default: the "
                 "adapter's]")
      ->check(CLI::IsMember({"triangle-pairs", "face-normals"}));
  app.add_option("--bodies", o.bodies, "Number of bodies dropped")->check(CLI::Range(0, 100000))->capture_default_str();
  app.add_option("--terrain-size", o.terrain_size, "Terrain grid cells per side (2 x size^2 facets)")
      ->check(CLI::Range(2, 4096))
      ->capture_default_str();
  app.add_option("--mesh", o.mesh, "Use this mesh file (.obj/.stl/.ply/.off) as the terrain, scaled to 40 m across");
  app.add_option("--up", o.up, "The --mesh file's up axis")->check(CLI::IsMember({"z", "y"}))->capture_default_str();
  app.add_option("--steps", o.steps, "Simulation steps of 1/60 s")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
  app.add_option("--every", o.every, "Write a frame every K steps (and the first and last)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--width", o.width, "Image width")->check(CLI::Range(16, 16384))->capture_default_str();
  app.add_option("--height", o.height, "Image height")->check(CLI::Range(16, 16384))->capture_default_str();
  app.add_option("--out", o.out, "Output folder [default: out/demo-ENGINE-MIDPHASE, or out/demo-overlay]");
  app.add_option("--seed", o.seed, "Seed of the terrain and the scene")->capture_default_str();
  app.add_option("--json", o.json_path, "Also write the summary as JSON to this file");
  app.add_option("--overlay-level", o.overlay_level,
                 "Overlay mode: no simulation; draw the tree's volumes at this level (0 = leaves) over the terrain "
                 "or --mesh, into OUT/overlay-METHOD-levelL.png")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--soak", o.soak,
               "Soak mode: no rendering; every --every steps report non-finite poses, the lowest body relative to "
               "the terrain and the resident memory (exit 1 on a non-finite pose or a body below the terrain)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help or the usage error
    return code == 0 ? 0 : 2;
  }

  try {
    TerrainOptions terrain;
    terrain.cells = o.terrain_size;
    terrain.mesh_path = o.mesh;
    terrain.up_axis = o.up[0];
    if (o.soak) return run_soak(o, terrain);
    return o.overlay_level >= 0 ? run_overlay(o, terrain) : run_simulation(o, terrain);
  } catch (const std::exception& e) {
    std::cerr << "boxtree-demo: error: " << e.what() << "\n";
    return 1;
  }
}
