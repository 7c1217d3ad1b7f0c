// SPDX-License-Identifier: MIT
// The drop scene in many variants (issue 25): each body kind alone, mixes, three terrains, 100 to
// 2,000 bodies, each in Bullet and ODE with the engine's built-in triangle-mesh midphase and with
// boxtree's (method aabb, the adapters' defaults), in one process on the same scene
// (demos/src/scene.h, sim.h: the demo's own worlds). The two runs of a scene alternate their order
// from one scene to the next, so that slow drift of the machine falls on both sides. With
// --repeats N each scene runs N such pairs (the order alternating from pair to pair): the tables
// give each measure's median over the N runs of a midphase, their ratio, and the range of the N
// paired ratios (each pair's boxtree / built-in), which shows how far one run can be trusted.
//
// Each run has two measured phases, the same steps for both midphases:
//   falling   from the first step until the highest body has had time to fall to the ground and
//             land: sqrt(2 h / g) + 0.5 s, h the largest drop height over the terrain;
//   at rest   after a further settling time (1 s, not measured): the next 1 s.
// Per phase: collision ms per step (Bullet: performDiscreteCollisionDetection; ODE: dSpaceCollide
// with the near callback), contacts per step, and the collision time by pair kind (sim.h
// collision_breakdown: a body's pairs with the terrain by its shape, and body-body). At the end:
// bodies fallen through (centre over the terrain, more than 1 m below its lowest point), bodies off
// the terrain (rolled off the edge of a rough or flat terrain; in no other count), and bodies at
// rest (over the terrain, not fallen through, centre slower than 0.1 m/s over the last step).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "scene.h"
#include "sim.h"

namespace {

using Clock = std::chrono::steady_clock;
using PairKindTime = demo::Simulation::PairKindTime;
constexpr double kTimeStep = 1.0 / 60;
constexpr double kGravity = 9.81;
constexpr double kLandingSeconds = 0.5;  // after the highest body's free fall, still falling
constexpr double kAtRestSpeed = 0.1;     // m/s: slower bodies count as at rest at the end
constexpr double kKindFloorMs = 0.02;    // pair kinds below this (built-in, ms/step) are not ranked
constexpr const char* kMethod = "aabb";

struct Variant {
  std::string name;
  demo::SceneOptions options;
};

std::string variant_name(const demo::SceneOptions& o) {
  return std::string(demo::body_mix_name(o.mix)) + ", " + demo::terrain_kind_name(o.terrain.kind) + ", " +
         std::to_string(o.bodies);
}

Variant variant(demo::BodyMix mix, demo::TerrainKind terrain, int bodies, int cells) {
  Variant v;
  v.options.mix = mix;
  v.options.terrain.kind = terrain;
  v.options.terrain.cells = cells;
  v.options.bodies = bodies;
  v.name = variant_name(v.options);
  return v;
}

// The matrix (not a full factorial): each body kind alone on the rough terrain at 500 bodies;
// the mix without meshes on each terrain at 100, 500 and 2,000 bodies; the demo's mix in its bowl.
std::vector<Variant> matrix(int cells) {
  using demo::BodyMix;
  using demo::TerrainKind;
  std::vector<Variant> out;
  for (BodyMix mix : {BodyMix::sphere, BodyMix::box, BodyMix::capsule, BodyMix::cylinder, BodyMix::hull8,
                      BodyMix::hull16, BodyMix::hull32, BodyMix::hull64, BodyMix::mesh})
    out.push_back(variant(mix, TerrainKind::rough, 500, cells));
  for (TerrainKind terrain : {TerrainKind::flat, TerrainKind::rough, TerrainKind::bowl})
    for (int bodies : {100, 500, 2000}) out.push_back(variant(BodyMix::mixed_without_meshes, terrain, bodies, cells));
  out.push_back(variant(BodyMix::mixed, TerrainKind::bowl, 500, cells));
  return out;
}

struct Schedule {
  int falling = 0, settling = 0, resting = 0;
  int total() const { return falling + settling + resting; }
};

Schedule schedule_for(const demo::Scene& scene, double settle_seconds, double rest_seconds) {
  double highest = 0;
  for (const demo::BodySpec& body : scene.bodies) {
    demo::Real ground = scene.bounds_min.z();
    scene.probe->height_at(body.position.x(), body.position.y(), &ground);
    highest = std::max(highest, body.position.z() - ground);
  }
  Schedule s;
  s.falling = int(std::ceil((std::sqrt(2 * highest / kGravity) + kLandingSeconds) / kTimeStep));
  s.settling = int(std::lround(settle_seconds / kTimeStep));
  s.resting = std::max(1, int(std::lround(rest_seconds / kTimeStep)));
  return s;
}

struct Phase {
  double collision_ms = 0, contacts = 0;
  std::vector<PairKindTime> kinds;  // seconds per step; calls, contacts, triangles per step
};

struct Run {
  Phase falling, resting;
  int fell_through = 0, off_terrain = 0, at_rest = 0;
  double build_seconds = 0, seconds = 0;
};

// The breakdown between two snapshots, per step.
std::vector<PairKindTime> per_step(const std::vector<PairKindTime>& before, const std::vector<PairKindTime>& after,
                                   int steps) {
  std::vector<PairKindTime> out;
  for (const PairKindTime& a : after) {
    PairKindTime d = a;
    for (const PairKindTime& b : before)
      if (b.kind == a.kind) d.seconds -= b.seconds, d.calls -= b.calls, d.contacts -= b.contacts;
    d.seconds /= steps;
    out.push_back(d);
  }
  return out;
}

Run run(const demo::Scene& scene, const std::string& engine, bool boxtree, bool hull_faces, bool convex_coherence,
        const Schedule& schedule) {
  demo::SimOptions options;
  options.boxtree_midphase = boxtree;
  options.method = kMethod;
  options.hull_faces = hull_faces;
  options.convex_coherence = convex_coherence;
  const auto start = Clock::now();
  std::unique_ptr<demo::Simulation> sim = demo::make_simulation(engine, scene, options);
  Run r;
  r.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  struct Snapshot {
    double collision = 0;
    std::vector<PairKindTime> kinds;
  };
  auto snapshot = [&] { return Snapshot{sim->collision_seconds(), sim->collision_breakdown()}; };
  auto close_phase = [&](Phase& phase, const Snapshot& from, int steps) {
    phase.collision_ms = 1e3 * (sim->collision_seconds() - from.collision) / steps;
    phase.contacts /= steps;
    phase.kinds = per_step(from.kinds, sim->collision_breakdown(), steps);
  };
  const int rest_start = schedule.falling + schedule.settling;
  Snapshot from = snapshot();
  std::vector<demo::Pose> before_last;
  for (int i = 0; i < schedule.total(); ++i) {
    if (i == schedule.falling) close_phase(r.falling, from, schedule.falling);
    if (i == rest_start) from = snapshot();
    if (i == schedule.total() - 1) before_last = sim->poses();
    sim->step(kTimeStep);
    if (i < schedule.falling) r.falling.contacts += sim->contacts();
    if (i >= rest_start) r.resting.contacts += sim->contacts();
  }
  close_phase(r.resting, from, schedule.resting);
  double lowest = std::numeric_limits<double>::infinity();
  for (const demo::Vec3& v : scene.terrain->vertices) lowest = std::min(lowest, v.z());
  const std::vector<demo::Pose> last = sim->poses();
  for (std::size_t b = 0; b < last.size(); ++b) {
    const demo::Vec3& p = last[b].position;
    if (!p.allFinite() || !demo::over_terrain(scene, p)) {
      ++r.off_terrain;
    } else if (p.z() < lowest - 1) {
      ++r.fell_through;
    } else if ((p - before_last[b].position).norm() / kTimeStep < kAtRestSpeed) {
      ++r.at_rest;
    }
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

double ratio(double ours, double theirs) { return theirs > 0 ? ours / theirs : std::nan(""); }

std::string fixed(double value, int digits) {
  if (!std::isfinite(value)) return "n/a";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

const PairKindTime* find_kind(const Phase& phase, const std::string& kind) {
  for (const PairKindTime& k : phase.kinds)
    if (k.kind == kind) return &k;
  return nullptr;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

// One cell of the matrix: a scene in one engine, both midphases.
struct Cell {
  Variant variant;
  std::string engine;
  std::size_t facets = 0;
  Schedule schedule;
  Run builtin, ours;  // each measure's median over the repeats
  // Per phase, each run's collision ms per step, in run order (a pair's two runs at one index).
  std::vector<double> builtin_ms[2], our_ms[2];
  bool end_counts_vary = false;  // the repeats disagreed on the end counts (the medians are shown)
};

double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2;
}

// Each measure's median over `runs` (at least one); pair kinds by name.
Run median_run(const std::vector<Run>& runs) {
  Run m = runs.front();
  const auto over = [&](auto&& get) {
    std::vector<double> v;
    for (const Run& r : runs) v.push_back(double(get(r)));
    return median(v);
  };
  m.fell_through = int(std::lround(over([](const Run& r) { return r.fell_through; })));
  m.off_terrain = int(std::lround(over([](const Run& r) { return r.off_terrain; })));
  m.at_rest = int(std::lround(over([](const Run& r) { return r.at_rest; })));
  m.build_seconds = over([](const Run& r) { return r.build_seconds; });
  m.seconds = 0;
  for (const Run& r : runs) m.seconds += r.seconds;
  for (Phase Run::*phase : {&Run::falling, &Run::resting}) {
    (m.*phase).collision_ms = over([&](const Run& r) { return (r.*phase).collision_ms; });
    (m.*phase).contacts = over([&](const Run& r) { return (r.*phase).contacts; });
    for (PairKindTime& k : (m.*phase).kinds) {
      std::vector<double> seconds, calls, contacts, triangles;
      for (const Run& r : runs)
        for (const PairKindTime& x : (r.*phase).kinds)
          if (x.kind == k.kind) {
            seconds.push_back(x.seconds);
            calls.push_back(double(x.calls));
            contacts.push_back(double(x.contacts));
            triangles.push_back(double(x.triangles));
          }
      k.seconds = median(seconds);
      k.calls = std::uint64_t(std::llround(median(calls)));
      k.contacts = std::uint64_t(std::llround(median(contacts)));
      k.triangles = std::uint64_t(std::llround(median(triangles)));
    }
  }
  return m;
}

bool same_end_counts(const Run& a, const Run& b) {
  return a.fell_through == b.fell_through && a.off_terrain == b.off_terrain && a.at_rest == b.at_rest;
}

// The range of a cell's paired ratios in one phase, "(lo-hi)", or "" for a single run.
std::string ratio_range(const Cell& c, int phase) {
  std::vector<double> r;
  for (std::size_t i = 0; i < c.our_ms[phase].size(); ++i)
    r.push_back(ratio(c.our_ms[phase][i], c.builtin_ms[phase][i]));
  if (r.size() < 2) return "";
  const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
  return " (" + fixed(*lo, 2) + "–" + fixed(*hi, 2) + ")";
}

// The worst and best ratio of a set of (ratio, where) pairs.
struct Extremes {
  double worst = -1, best = std::numeric_limits<double>::infinity();
  std::string worst_at, best_at;
  int count = 0;
  void add(double r, const std::string& at) {
    if (!std::isfinite(r)) return;
    ++count;
    if (r > worst) worst = r, worst_at = at;
    if (r < best) best = r, best_at = at;
  }
};

const char* kPhaseNames[2] = {"falling", "at rest"};
const Phase& phase_of(const Run& r, int phase) { return phase == 0 ? r.falling : r.resting; }

std::string thousands(std::size_t n) {
  std::string digits = std::to_string(n);
  for (int i = int(digits.size()) - 3; i > 0; i -= 3) digits.insert(std::size_t(i), ",");
  return digits;
}

std::string markdown(const std::vector<Cell>& cells, const std::vector<std::string>& engines, int cells_per_side,
                     bool hull_faces, bool convex_coherence, int repeats, double settle_seconds, double rest_seconds,
                     double seconds) {
  std::ostringstream md;
  md << "Generated by `bash bench/sim/run_scene_matrix` (`bench/sim/scene_matrix.cpp`): the demo's drop scene "
        "(`demos/src/scene.h`) in variants, each in both engines with the built-in midphase (Bullet: "
        "`btBvhTriangleMeshShape`, GImpact for mesh bodies; ODE: `dTriMesh`, OPCODE) and with boxtree `"
     << kMethod << "` ("
     << (hull_faces ? "the adapters' defaults but for Bullet's hulls, which get boxtree's separating axes: "
                      "`AlgorithmSettings::hullFaces`, `--hull-faces`"
                    : "the adapters' defaults")
     << (convex_coherence ? "" : ", but without convex-vs-mesh coherence: `--no-convex-coherence`") << "), "
     << (repeats == 1
             ? std::string("one run each")
             : std::to_string(repeats) + " runs each (each measure is the median of its " + std::to_string(repeats) +
                   " runs; beside a ratio, in brackets, the range of the runs' paired ratios)")
     << ", alternating which goes first. Terrains " << cells_per_side << "x" << cells_per_side << " cells ("
     << thousands(2 * std::size_t(cells_per_side) * std::size_t(cells_per_side))
     << " facets), 40 m across: `bowl` (the demo's), `rough` (the same fractal without the bowl), `flat`. Phases: "
        "*falling* = from the drop until the highest body has fallen and landed (sqrt(2h/g) + 0.5 s); *at rest* = "
     << fixed(rest_seconds, 2) << " s after a further " << fixed(settle_seconds, 2)
     << " s of settling."
        " Ratios are boxtree / built-in (below 1: boxtree faster). "
        "Collision: Bullet `performDiscreteCollisionDetection`, ODE `dSpaceCollide` with the near callback. "
        "End counts (built-in / boxtree): bodies fallen through the terrain, bodies at rest (centre slower than "
     << kAtRestSpeed << " m/s), bodies off the terrain's edge (counted in neither). CPU: " << cpu_model()
     << "; whole matrix " << fixed(seconds / 60, 1) << " min.\n\n";

  // The summary first: per engine, the extremes over scenes x phases, and by pair kind.
  md << "| engine | scene x phase cases | worst collision ratio | best collision ratio | pair kinds where boxtree is "
        "slower "
        "(worst ratio) |\n|---|---:|---|---|---|\n";
  for (const std::string& engine : engines) {
    Extremes total;
    std::map<std::string, Extremes> by_kind;
    for (const Cell& c : cells) {
      if (c.engine != engine) continue;
      for (int p = 0; p < 2; ++p) {
        const std::string at = c.variant.name + ", " + kPhaseNames[p];
        total.add(ratio(phase_of(c.ours, p).collision_ms, phase_of(c.builtin, p).collision_ms), at);
        for (const PairKindTime& k : phase_of(c.builtin, p).kinds) {
          const PairKindTime* o = find_kind(phase_of(c.ours, p), k.kind);
          if (o && 1e3 * k.seconds >= kKindFloorMs) by_kind[k.kind].add(ratio(o->seconds, k.seconds), at);
        }
      }
    }
    if (total.count == 0) continue;
    std::string slower;
    for (const auto& [kind, e] : by_kind)
      if (e.worst > 1)
        slower += (slower.empty() ? "" : "; ") + kind + " **" + fixed(e.worst, 2) + "** (" + e.worst_at + ")";
    md << "| " << engine << " | " << total.count << " | **" << fixed(total.worst, 2) << "**: " << total.worst_at
       << " | **" << fixed(total.best, 2) << "**: " << total.best_at << " | " << (slower.empty() ? "none" : slower)
       << " |\n";
  }

  md << "\n| scene (bodies, terrain, count) | engine | falling: collision ms/step, built-in → boxtree | ratio | "
        "at rest: collision ms/step, built-in → boxtree | ratio | contacts ratio, falling / at rest | fell through | "
        "at rest at end | off terrain |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Cell& c : cells) {
    const Run &b = c.builtin, &o = c.ours;
    md << "| " << c.variant.name << " | " << c.engine << " | " << fixed(b.falling.collision_ms, 2) << " → "
       << fixed(o.falling.collision_ms, 2) << " | " << fixed(ratio(o.falling.collision_ms, b.falling.collision_ms), 2)
       << ratio_range(c, 0) << " | " << fixed(b.resting.collision_ms, 2) << " → " << fixed(o.resting.collision_ms, 2)
       << " | " << fixed(ratio(o.resting.collision_ms, b.resting.collision_ms), 2) << ratio_range(c, 1) << " | "
       << fixed(ratio(o.falling.contacts, b.falling.contacts), 2) << " / "
       << fixed(ratio(o.resting.contacts, b.resting.contacts), 2) << " | " << b.fell_through << " / " << o.fell_through
       << " | " << b.at_rest << " / " << o.at_rest << " | " << b.off_terrain << " / " << o.off_terrain
       << (c.end_counts_vary ? " (medians: the runs differ)" : "") << " |\n";
  }

  md << "\n**By pair kind**: collision ms per step of each kind of pair (a body with the terrain, by the body's "
        "shape; two bodies), built-in → boxtree (ratio). Bullet: the dispatcher's near callback per pair; ODE: "
        "`dCollide` per pair; the broadphase is in neither. The summary ranks kinds from "
     << kKindFloorMs << " ms/step (built-in) up.\n\n"
     << "| scene | engine | pair kind | falling | at rest |\n|---|---|---|---:|---:|\n";
  for (const Cell& c : cells) {
    std::vector<std::string> kinds;
    for (const Run* r : {&c.builtin, &c.ours})
      for (const Phase* p : {&r->falling, &r->resting})
        for (const PairKindTime& k : p->kinds)
          if (std::find(kinds.begin(), kinds.end(), k.kind) == kinds.end()) kinds.push_back(k.kind);
    std::sort(kinds.begin(), kinds.end());
    for (const std::string& kind : kinds) {
      md << "| " << c.variant.name << " | " << c.engine << " | " << kind << " |";
      for (int p = 0; p < 2; ++p) {
        const PairKindTime* b = find_kind(phase_of(c.builtin, p), kind);
        const PairKindTime* o = find_kind(phase_of(c.ours, p), kind);
        const double bm = b ? 1e3 * b->seconds : 0, om = o ? 1e3 * o->seconds : 0;
        md << " " << fixed(bm, 3) << " → " << fixed(om, 3) << " (" << fixed(ratio(om, bm), 2) << ") |";
      }
      md << "\n";
    }
  }
  return md.str();
}

nlohmann::json rows(const std::vector<Cell>& cells, bool hull_faces, bool convex_coherence, int repeats) {
  nlohmann::json out = nlohmann::json::array();
  auto row = [&](const Cell& c, const std::string& phase, const std::string& metric, const std::string& kind,
                 double ours, double theirs) {
    const std::string peer = c.engine == "bullet" ? "bullet btBvhTriangleMeshShape" : "ode dTriMesh (OPCODE)";
    nlohmann::json r = {{"section", "scene_matrix"},
                        {"case", c.engine + " " + c.variant.name + ", " + phase},
                        {"engine", c.engine},
                        {"scene", c.variant.name},
                        {"bodies", c.variant.options.bodies},
                        {"mix", demo::body_mix_name(c.variant.options.mix)},
                        {"terrain", demo::terrain_kind_name(c.variant.options.terrain.kind)},
                        {"terrain_facets", c.facets},
                        {"phase", phase},
                        {"metric", metric},
                        {"boxtree_method", kMethod},
                        {"bullet_hull_faces", hull_faces},
                        {"convex_coherence", convex_coherence},
                        {"repeats", repeats},
                        {"boxtree", ours},
                        {"peer", peer},
                        {"peer_value", theirs}};
    const double q = ratio(ours, theirs);
    r["ratio"] = std::isfinite(q) ? nlohmann::json(q) : nlohmann::json(nullptr);
    if (!kind.empty()) r["pair_kind"] = kind;
    out.push_back(r);
  };
  for (const Cell& c : cells) {
    for (int p = 0; p < 2; ++p) {
      const Phase &b = phase_of(c.builtin, p), &o = phase_of(c.ours, p);
      const std::string phase = p == 0 ? "falling" : "at_rest";
      const int steps = p == 0 ? c.schedule.falling : c.schedule.resting;
      row(c, phase, "collision_ms_per_step", "", o.collision_ms, b.collision_ms);
      if (c.our_ms[p].size() > 1) {
        nlohmann::json paired = nlohmann::json::array();
        for (std::size_t i = 0; i < c.our_ms[p].size(); ++i)
          paired.push_back(ratio(c.our_ms[p][i], c.builtin_ms[p][i]));
        out.back()["paired_ratios"] = paired;
        out.back()["boxtree_runs"] = c.our_ms[p];
        out.back()["peer_runs"] = c.builtin_ms[p];
      }
      row(c, phase, "contacts_per_step", "", o.contacts, b.contacts);
      for (const PairKindTime& k : b.kinds) {
        const PairKindTime* ok = find_kind(o, k.kind);
        row(c, phase, "pair_kind_ms_per_step", k.kind, ok ? 1e3 * ok->seconds : 0, 1e3 * k.seconds);
        row(c, phase, "pair_kind_contacts_per_step", k.kind, ok ? double(ok->contacts) / steps : 0,
            double(k.contacts) / steps);
      }
    }
    row(c, "end", "bodies_fallen_through", "", c.ours.fell_through, c.builtin.fell_through);
    row(c, "end", "bodies_at_rest", "", c.ours.at_rest, c.builtin.at_rest);
    row(c, "end", "bodies_off_terrain", "", c.ours.off_terrain, c.builtin.off_terrain);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The drop scene in many variants, Bullet and ODE: built-in mesh midphase vs boxtree, in one run"};
  std::string json_path, markdown_path, only;
  std::vector<std::string> engines = {"bullet", "ode"};
  int cells = 256;
  double settle_seconds = 1, rest_seconds = 1;
  std::uint64_t seed = 1;
  int repeats = 1;
  bool quick = false, list = false, hull_faces = false, convex_coherence = true;
  app.add_option("--json", json_path, "Write the rows here");
  app.add_option("--markdown", markdown_path, "Write the tables as a markdown fragment here");
  app.add_option("--engines", engines, "bullet, ode or both")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->capture_default_str();
  app.add_option("--only", only, "Run only the scenes whose name contains this text (see --list)");
  app.add_option("--cells", cells, "Terrain cells per side (2 x cells^2 facets)")->capture_default_str();
  app.add_option("--settle-seconds", settle_seconds, "Unmeasured steps between the phases")->capture_default_str();
  app.add_option("--rest-seconds", rest_seconds, "Length of the at-rest phase")->capture_default_str();
  app.add_option("--seed", seed, "Scene seed")->capture_default_str();
  app.add_option("--repeats", repeats, "Runs per scene and midphase (medians and the paired ratios' range)")
      ->check(CLI::Range(1, 99))
      ->capture_default_str();
  app.add_flag("--quick", quick, "A smoke run: 64x64 terrains, 40 bodies, short phases");
  app.add_flag("--list", list, "Print the scenes' names and exit");
  app.add_flag("--hull-faces", hull_faces,
               "Bullet with boxtree: hulls by boxtree's separating axes (AlgorithmSettings::hullFaces) instead of "
               "Bullet's GJK per triangle");
  app.add_flag("!--no-convex-coherence", convex_coherence,
               "boxtree without convex-vs-mesh coherence (ODE's GeomSettings::convex_coherence, Bullet's "
               "AlgorithmSettings::convexCoherence): every pair collided afresh, as the built-in midphases do");
  CLI11_PARSE(app, argc, argv);
  for (const std::string& e : engines)
    if (e != "bullet" && e != "ode") {
      std::fprintf(stderr, "scene_matrix: unknown engine '%s' (bullet, ode)\n", e.c_str());
      return 2;
    }
  if (quick) cells = 64, settle_seconds = 0.25, rest_seconds = 0.25;
  std::vector<Variant> variants;
  for (Variant v : matrix(cells)) {
    if (quick) v.options.bodies = 40;
    v.name = variant_name(v.options);
    if (only.empty() || v.name.find(only) != std::string::npos) variants.push_back(v);
  }
  if (list) {
    for (const Variant& v : variants) std::printf("%s\n", v.name.c_str());
    return 0;
  }
  if (variants.empty()) {
    std::fprintf(stderr, "scene_matrix: --only '%s' matches no scene (--list)\n", only.c_str());
    return 2;
  }

  const auto start = Clock::now();
  std::vector<Cell> results;
  int order = 0;
  try {
    for (const Variant& v : variants) {
      const demo::Scene scene = demo::make_scene(v.options, seed);
      for (const std::string& engine : engines) {
        Cell c{v,  engine, scene.terrain->facet_count(), schedule_for(scene, settle_seconds, rest_seconds), {}, {}, {},
               {}, false};
        std::vector<Run> builtin_runs, our_runs;
        for (int repeat = 0; repeat < repeats; ++repeat) {
          // Alternate which midphase runs first, so that drift of the machine falls on both.
          if (order++ % 2 == 0) {
            builtin_runs.push_back(run(scene, engine, false, hull_faces, convex_coherence, c.schedule));
            our_runs.push_back(run(scene, engine, true, hull_faces, convex_coherence, c.schedule));
          } else {
            our_runs.push_back(run(scene, engine, true, hull_faces, convex_coherence, c.schedule));
            builtin_runs.push_back(run(scene, engine, false, hull_faces, convex_coherence, c.schedule));
          }
          for (int p = 0; p < 2; ++p) {
            c.our_ms[p].push_back(phase_of(our_runs.back(), p).collision_ms);
            c.builtin_ms[p].push_back(phase_of(builtin_runs.back(), p).collision_ms);
          }
          c.end_counts_vary = c.end_counts_vary || !same_end_counts(builtin_runs.back(), builtin_runs.front()) ||
                              !same_end_counts(our_runs.back(), our_runs.front());
        }
        c.builtin = median_run(builtin_runs);
        c.ours = median_run(our_runs);
        std::printf(
            "%s, %s (%d+%d+%d steps x %d, %.0f s): collision ms/step falling %.2f -> %.2f (%.2fx), at rest %.2f -> "
            "%.2f (%.2fx); fell through %d/%d, at rest %d/%d, off terrain %d/%d\n",
            v.name.c_str(), engine.c_str(), c.schedule.falling, c.schedule.settling, c.schedule.resting, repeats,
            c.builtin.seconds + c.ours.seconds, c.builtin.falling.collision_ms, c.ours.falling.collision_ms,
            ratio(c.ours.falling.collision_ms, c.builtin.falling.collision_ms), c.builtin.resting.collision_ms,
            c.ours.resting.collision_ms, ratio(c.ours.resting.collision_ms, c.builtin.resting.collision_ms),
            c.builtin.fell_through, c.ours.fell_through, c.builtin.at_rest, c.ours.at_rest, c.builtin.off_terrain,
            c.ours.off_terrain);
        std::fflush(stdout);
        results.push_back(std::move(c));
      }
    }
  } catch (const boxtree::Error& e) {
    std::fprintf(stderr, "scene_matrix: %s\n", e.what());
    return 1;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (!json_path.empty())
    std::ofstream(json_path) << rows(results, hull_faces, convex_coherence, repeats).dump(1) << '\n';
  if (!markdown_path.empty())
    std::ofstream(markdown_path) << markdown(results, engines, cells, hull_faces, convex_coherence, repeats,
                                             settle_seconds, rest_seconds, seconds);
  std::printf("scene_matrix: %zu scenes x %zu engines in %.0f s\n", variants.size(), engines.size(), seconds);
  return 0;
}
