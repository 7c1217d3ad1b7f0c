// SPDX-License-Identifier: MIT
// Ray benchmark (issue 7, section 3): closest-hit throughput of boxtree's ray_closest_hit for
// several hierarchy methods against Bullet (btBvhTriangleMeshShape::performRaycast), Embree 3
// (rtcIntersect1) and ODE (dGeomRay vs dTriMesh), all single-threaded, in one process on the
// same rays, and how many rays each engine answers differently from boxtree.
//
// Meshes: a fractal terrain (make_terrain 512 x 512 cells, 524,288 facets), the Stanford bunny
// and a UV sphere of 10,000 facets. Two ray sets per mesh, same seed for every engine:
//  - outside: origins on a sphere of twice the mesh's bounding radius around its box centre,
//    aimed at a uniform point of the bounding box (most rays hit, from every side);
//  - volume: origins uniform in the bounding box, directions uniform on the sphere (random rays
//    through the volume; for closed meshes, many start inside).
// Every ray is a segment: unit direction, t in [0, t_max] with t_max past the far side of the
// box, the same for every engine (Bullet needs an end point).
//
// Timing: a warm-up pass over the first rays is excluded; then one pass over all rays per
// engine, recording t (or a miss) for every ray. Rays/s = rays / seconds of that pass.
// Agreement: a ray disagrees when one engine hits and the other misses, or both hit and the
// distances differ by more than 1e-5 relative. Bullet and Embree work in single precision,
// boxtree in double (watertight test), ODE's OPCODE in single.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench_report.h"
#include "boxtree/build.h"
#include "boxtree/generate.h"
#include "boxtree/io.h"
#include "boxtree/method.h"
#include "boxtree/packed_prism_tree.h"
#include "boxtree/packed_tree.h"
#include "boxtree/query.h"
#include "ode_rays.h"
#include "peers/bullet_peer.h"
#include "peers/embree_peer.h"

namespace {

using boxtree::Real;
using boxtree::Vec3;
using boxtree::bench::Clock;
using boxtree::bench::format;
using boxtree::bench::Row;
using boxtree::bench::table;
using boxtree::bench::with_commas;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kRelativeTolerance = 1e-5;
constexpr const char* kThroughputMetric = "rays_per_second (higher is better)";
constexpr const char* kDisagreeMetric =
    "disagreeing_rays (count: hit/miss differs or t beyond 1e-5 relative; boxtree = this method vs boxtree aabb, "
    "peer_value = peer vs this method)";

struct RaySet {
  std::string name;  // "outside", "volume"
  std::vector<Vec3> origins;
  std::vector<Vec3> directions;  // unit length
  double t_max = 0;
};

struct Bounds {
  Vec3 lo, hi;
  Vec3 center() const { return (lo + hi) / 2; }
  double radius() const { return (hi - lo).norm() / 2; }
};

Bounds bounds_of(const boxtree::TriangleMesh& mesh) {
  Bounds b{mesh.vertices.front(), mesh.vertices.front()};
  for (const Vec3& v : mesh.vertices) b.lo = b.lo.cwiseMin(v), b.hi = b.hi.cwiseMax(v);
  return b;
}

// A point of `box`, z first, then y, then x: gcc's order for the former Vec3 of three draws (a
// call's arguments are evaluated in an unspecified order; this keeps the rays measured before, on
// any compiler).
Vec3 random_point_in(boxtree::Random& random, const Bounds& box) {
  const Real z = random.uniform(box.lo.z(), box.hi.z());
  const Real y = random.uniform(box.lo.y(), box.hi.y());
  const Real x = random.uniform(box.lo.x(), box.hi.x());
  return {x, y, z};
}

RaySet outside_rays(const Bounds& box, std::size_t n, std::uint64_t seed) {
  boxtree::Random random(seed);
  RaySet s{"outside", {}, {}, 4 * box.radius()};  // from distance 2r to past the far side (<= 3r)
  s.origins.reserve(n), s.directions.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 origin = box.center() + 2 * box.radius() * random.unit_vector();
    const Vec3 target = random_point_in(random, box);
    s.origins.push_back(origin);
    s.directions.push_back((target - origin).normalized());
  }
  return s;
}

RaySet volume_rays(const Bounds& box, std::size_t n, std::uint64_t seed) {
  boxtree::Random random(seed);
  RaySet s{"volume", {}, {}, 2 * box.radius()};  // the box's diagonal: every origin leaves the box
  s.origins.reserve(n), s.directions.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.origins.push_back(random_point_in(random, box));
    s.directions.push_back(random.unit_vector());
  }
  return s;
}

struct EngineRun {
  std::string engine;  // "boxtree", "bullet", ...
  std::string method;  // boxtree method; empty for peers
  double build_seconds = 0;
  double seconds = 0;
  std::vector<double> t;  // per ray: hit distance or +inf
  std::size_t hits = 0;
  boxtree::QueryStats stats;  // boxtree only
  EngineRun(std::string e, std::string m) : engine(std::move(e)), method(std::move(m)) {}
  double rays_per_second() const { return seconds > 0 ? double(t.size()) / seconds : 0; }
  std::string label() const { return method.empty() ? engine : engine + " " + method; }
};

// Warm-up over the first rays (excluded; `after_warmup` resets counters), then one timed pass
// over all of them.
template <class Cast, class AfterWarmup>
void time_rays(const RaySet& rays, Cast&& cast, EngineRun& run, AfterWarmup&& after_warmup) {
  const std::size_t n = rays.origins.size();
  const std::size_t warm = std::min<std::size_t>(n, 2000);
  for (std::size_t i = 0; i < warm; ++i) cast(i);
  after_warmup();
  run.t.assign(n, kInf);
  const auto start = Clock::now();
  for (std::size_t i = 0; i < n; ++i) run.t[i] = cast(i);
  run.seconds = boxtree::bench::seconds_since(start);
  run.hits = std::size_t(std::count_if(run.t.begin(), run.t.end(), [](double t) { return std::isfinite(t); }));
}

// One engine built over one mesh, run on every ray set of that mesh.
class RayEngine {
 public:
  RayEngine(std::string engine, std::string method) : engine_(std::move(engine)), method_(std::move(method)) {}
  virtual ~RayEngine() = default;
  double build_seconds() const { return build_seconds_; }
  EngineRun run(const RaySet& rays) {
    EngineRun r(engine_, method_);
    r.build_seconds = build_seconds_;
    cast_all(rays, r);
    return r;
  }

 protected:
  virtual void cast_all(const RaySet& rays, EngineRun& run) = 0;
  double build_seconds_ = 0;

 private:
  std::string engine_, method_;
};

// boxtree's typed query (no virtual call per ray or per node). TreeType: Tree<V>, or the packed
// forms AnyTree and so the engine adapters hold: PackedAabbTree for `aabb`, PackedPrismTree for
// the plain pie-slice methods. The bench-only names `aabb-exact` and a pie-slice method +
// `-exact` (e.g. `pie-min-exact`) run the exact trees beside them.
template <class TreeType>
class BoxtreeEngine final : public RayEngine {
 public:
  template <class Build>
  BoxtreeEngine(const std::string& name, Build&& build) : RayEngine("boxtree", name) {
    const auto start = Clock::now();
    tree_ = build();
    build_seconds_ = boxtree::bench::seconds_since(start);
  }

 private:
  void cast_all(const RaySet& rays, EngineRun& run) override {
    boxtree::QueryStats stats;
    time_rays(
        rays,
        [&](std::size_t i) {
          const boxtree::Ray ray{rays.origins[i], rays.directions[i], 0, rays.t_max};
          const auto hit = boxtree::ray_closest_hit(tree_, ray, &stats);
          return hit ? double(hit->t) : kInf;
        },
        run, [&] { stats = {}; });
    run.stats = stats;
  }
  TreeType tree_;
};

// `aabb-batch`: the packed tree's ray_closest_hits over all the rays in one call (the rays' walks
// take turns node by node, hiding memory latency); the same answers as `aabb`.
class BoxtreeBatchEngine final : public RayEngine {
 public:
  explicit BoxtreeBatchEngine(const std::shared_ptr<const boxtree::TriangleMesh>& mesh)
      : RayEngine("boxtree", "aabb-batch") {
    const auto start = Clock::now();
    tree_ = boxtree::PackedAabbTree(boxtree::build_tree<boxtree::Aabb>(mesh));
    build_seconds_ = boxtree::bench::seconds_since(start);
  }

 private:
  void cast_all(const RaySet& rays, EngineRun& run) override {
    const std::size_t n = rays.origins.size();
    std::vector<boxtree::Ray> list(n);
    for (std::size_t i = 0; i < n; ++i) list[i] = boxtree::Ray{rays.origins[i], rays.directions[i], 0, rays.t_max};
    std::vector<std::optional<boxtree::RayHit>> hits(n);
    boxtree::QueryStats stats;
    boxtree::ray_closest_hits(tree_, list.data(), std::min<std::size_t>(n, 2000), hits.data(), &stats);  // warm-up
    stats = {};
    const auto start = Clock::now();
    boxtree::ray_closest_hits(tree_, list.data(), n, hits.data(), &stats);
    run.seconds = boxtree::bench::seconds_since(start);
    run.t.assign(n, kInf);
    for (std::size_t i = 0; i < n; ++i)
      if (hits[i]) run.t[i] = double(hits[i]->t);
    run.hits = std::size_t(std::count_if(run.t.begin(), run.t.end(), [](double t) { return std::isfinite(t); }));
    run.stats = stats;
  }
  boxtree::PackedAabbTree tree_;
};

std::unique_ptr<RayEngine> make_boxtree_engine(const std::shared_ptr<const boxtree::TriangleMesh>& mesh,
                                               const std::string& name) {
  if (name == "aabb-batch") return std::make_unique<BoxtreeBatchEngine>(mesh);
  const boxtree::bench::ExactSuffix split = boxtree::bench::split_exact_suffix(name);
  const bool exact = split.exact;  // a plain variable: lambdas below capture it
  const boxtree::Method method = boxtree::parse_method(split.method);
  return boxtree::with_method(method, [&](auto tag) -> std::unique_ptr<RayEngine> {
    using V = typename decltype(tag)::type;
    if constexpr (std::is_same_v<V, boxtree::Aabb>) {
      if (exact)
        return std::make_unique<BoxtreeEngine<boxtree::Tree<V>>>(name, [&] { return boxtree::build_tree<V>(mesh); });
      return std::make_unique<BoxtreeEngine<boxtree::PackedAabbTree>>(
          name, [&] { return boxtree::PackedAabbTree(boxtree::build_tree<V>(mesh)); });
    } else if constexpr (boxtree::is_pie_slice_v<V>) {
      const auto build = [&] { return boxtree::build_tree<V>(mesh, boxtree::settings_for(method)); };
      if (exact) return std::make_unique<BoxtreeEngine<boxtree::Tree<V>>>(name, build);
      return std::make_unique<BoxtreeEngine<boxtree::PackedPrismTree>>(
          name, [&] { return boxtree::PackedPrismTree(build()); });
    } else {
      if (exact) throw std::runtime_error("'" + name + "': -exact applies to aabb and the plain pie-slice methods");
      return std::make_unique<BoxtreeEngine<boxtree::Tree<V>>>(
          name, [&] { return boxtree::build_tree<V>(mesh, boxtree::settings_for(method)); });
    }
  });
}

// A peer: any class with a constructor from the mesh, build_seconds() and
// ray_closest(origin, direction, t_max).
template <class Peer>
class PeerEngine final : public RayEngine {
 public:
  PeerEngine(const boxtree::TriangleMesh& mesh, const std::string& name)
      : RayEngine(name, ""), peer_(std::make_unique<Peer>(mesh)) {
    build_seconds_ = peer_->build_seconds();
  }

 private:
  void cast_all(const RaySet& rays, EngineRun& run) override {
    time_rays(
        rays, [&](std::size_t i) { return peer_->ray_closest(rays.origins[i], rays.directions[i], rays.t_max); }, run,
        [] {});
  }
  std::unique_ptr<Peer> peer_;
};

struct Disagreement {
  std::size_t hit_miss = 0;  // one hits, the other misses
  std::size_t distance = 0;  // both hit, t differs beyond the tolerance
  std::size_t total() const { return hit_miss + distance; }
};

Disagreement disagreement(const std::vector<double>& a, const std::vector<double>& b) {
  Disagreement d;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool ha = std::isfinite(a[i]), hb = std::isfinite(b[i]);
    if (ha != hb) {
      ++d.hit_miss;
    } else if (ha && std::abs(a[i] - b[i]) > kRelativeTolerance * std::max({std::abs(a[i]), std::abs(b[i]), 1e-30})) {
      ++d.distance;
    }
  }
  return d;
}

// The peer's name in the JSON rows: the engine and the call that was timed.
std::string json_peer(const std::string& engine) {
  if (engine == "bullet") return "bullet btBvhTriangleMeshShape::performRaycast";
  if (engine == "embree") return "embree rtcIntersect1";
  if (engine == "ode") return "ode dCollide(dGeomRay, dTriMesh)";
  return engine;
}

struct Case {
  std::string name;  // "terrain-524k"
  std::string description;
  std::shared_ptr<const boxtree::TriangleMesh> mesh;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Ray benchmark: boxtree closest hit vs Bullet, Embree, ODE (single thread, same rays)"};
  bool quick = false;
  std::string json_path, markdown_path, meshes_dir = "../shared/meshes";
  std::string methods_list;
  std::size_t ray_count = 0, volume_ray_count = 0;
  int terrain_cells = 0;
  std::uint64_t seed = 1;
  int dump = 0;
  app.add_option("--dump-disagreements", dump, "print this many disagreeing rays per peer (t of boxtree and peer)");
  app.add_flag("--quick", quick, "small run for CI: 20,000 rays, 128 x 128-cell terrain");
  app.add_option("--json", json_path, "write the result rows (JSON array) here");
  app.add_option("--markdown", markdown_path, "write the section's markdown fragment here");
  app.add_option("--meshes", meshes_dir, "directory of the shared meshes (stanford_bunny.obj)");
  app.add_option(
      "--methods", methods_list,
      "comma-separated boxtree methods (default aabb,aabb-batch,obb-min,obb-all+aabb@2; --quick "
      "aabb,aabb-batch,obb-all+aabb@2); the first is the reference of the agreement counts. Bench-only names: "
      "aabb-exact (the exact Tree<Aabb>), aabb-batch (ray_closest_hits over all rays in one call)");
  app.add_option("--rays", ray_count, "rays from outside (default 1,000,000; --quick 20,000)");
  app.add_option("--volume-rays", volume_ray_count, "rays through the volume (default a quarter of --rays)");
  app.add_option("--terrain-cells", terrain_cells, "terrain cells per side (default 512; --quick 128)");
  app.add_option("--seed", seed, "random seed of the terrain and the rays");
  CLI11_PARSE(app, argc, argv);
  if (ray_count == 0) ray_count = quick ? 20000 : 1000000;
  if (volume_ray_count == 0) volume_ray_count = std::max<std::size_t>(1, ray_count / 4);
  if (methods_list.empty())
    methods_list = quick ? "aabb,aabb-batch,obb-all+aabb@2" : "aabb,aabb-batch,obb-min,obb-all+aabb@2";
  if (terrain_cells == 0) terrain_cells = quick ? 128 : 512;
  std::vector<std::string> methods;
  {
    std::stringstream ss(methods_list);
    std::string m;
    while (std::getline(ss, m, ','))
      if (!m.empty()) methods.push_back(m);
  }
  if (methods.empty()) methods.push_back("aabb");
  try {
    for (const auto& m : methods)
      if (m != "aabb-batch") boxtree::parse_method(boxtree::bench::split_exact_suffix(m).method);  // bench-only names
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ray_bench: error: %s\n", e.what());
    return 2;
  }
  const auto total_start = Clock::now();

  std::vector<Case> cases;
  {
    auto terrain =
        std::make_shared<const boxtree::TriangleMesh>(boxtree::make_terrain(terrain_cells, terrain_cells, seed));
    const std::size_t facets = terrain->facet_count();
    cases.push_back({"terrain-" + std::to_string((facets + 500) / 1000) + "k",
                     "fractal terrain, make_terrain(" + std::to_string(terrain_cells) + ", " +
                         std::to_string(terrain_cells) + "), " + with_commas(facets) + " facets",
                     terrain});
  }
  const std::string bunny_path = meshes_dir + "/stanford_bunny.obj";
  try {
    auto bunny = std::make_shared<const boxtree::TriangleMesh>(boxtree::load_mesh(bunny_path));
    cases.push_back(
        {"bunny", "Stanford bunny (" + bunny_path + "), " + with_commas(bunny->facet_count()) + " facets", bunny});
  } catch (const std::exception& e) {
    std::printf("skipping the bunny: %s\n", e.what());
  }
  {
    auto sphere = std::make_shared<const boxtree::TriangleMesh>(boxtree::make_uv_sphere(100, 51, 1.0));
    cases.push_back(
        {"sphere-10k", "UV sphere make_uv_sphere(100, 51), " + with_commas(sphere->facet_count()) + " facets", sphere});
  }

  std::string peers = std::string(boxtree::peers::bullet_version()) + "; " + boxtree::peers::embree_version() + "; " +
                      boxtree::peers::ode_version();
  if (!boxtree::peers::embree_available())
    std::printf("Embree peer skipped: not found at configure time (Debian: libembree-dev)\n");
  std::vector<Row> rows;
  std::ostringstream md;
  md << "## Rays: closest hit, boxtree vs Bullet, Embree, ODE\n\n" << boxtree::bench::machine_markdown(peers);
  md << "- " << with_commas(ray_count) << " rays from outside, " << with_commas(volume_ray_count)
     << " through the volume. *outside*: origins on a sphere of twice the bounding radius, aimed at uniform points of "
        "the "
        "bounding box; *volume*: origins uniform in the bounding box, uniform directions. Unit directions, segments "
        "t in [0, t_max] past the box, the same for every engine; one warm-up pass over 2,000 rays excluded.\n"
        "- boxtree: `ray_closest_hit` on `Tree<V>`, and for `aabb` on `PackedAabbTree` (what the engine adapters hold; "
        "`aabb-exact` is the exact `Tree<Aabb>`), double precision, watertight triangle test; `aabb-batch`: "
        "`ray_closest_hits` on the same packed tree, all the rays in one call (eight rays' walks take turns node by "
        "node, so that one ray's loads overlap the others' work: the same answers; a batch against the peers' one-ray "
        "calls, Embree's own batch calls not measured). Bullet: "
        "`btBvhTriangleMeshShape::performRaycast` (quantized BVH, `btTriangleRaycastCallback` keeping the closest "
        "hit; the midphase + triangle path of `btCollisionWorld::rayTest` without its broadphase). Embree: "
        "`rtcIntersect1`, device \"threads=1\", static scene, default (medium) build quality. ODE: `dCollide` of a "
        "`dGeomRay` (closest-hit mode) with a `dTriMesh`.\n"
        "- *disagree*: rays where the engine and boxtree " +
            methods.front() +
            " differ (hit vs miss, or t beyond 1e-5 relative).\n"
            "- Ratio = boxtree rays/s / peer rays/s: above 1 boxtree is faster.\n\n";

  for (const Case& c : cases) {
    const Bounds box = bounds_of(*c.mesh);
    std::vector<std::unique_ptr<RayEngine>> boxtree_engines, peer_engines;
    for (const std::string& m : methods) boxtree_engines.push_back(make_boxtree_engine(c.mesh, m));
    if (boxtree::peers::bullet_available())
      peer_engines.push_back(std::make_unique<PeerEngine<boxtree::peers::BulletBvhMesh>>(*c.mesh, "bullet"));
    if (boxtree::peers::embree_available())
      peer_engines.push_back(std::make_unique<PeerEngine<boxtree::peers::EmbreeScene>>(*c.mesh, "embree"));
    if (boxtree::peers::ode_available())
      peer_engines.push_back(std::make_unique<PeerEngine<boxtree::peers::OdeTriMeshRays>>(*c.mesh, "ode"));
    for (int set = 0; set < 2; ++set) {
      const RaySet rays =
          set == 0 ? outside_rays(box, ray_count, seed + 17) : volume_rays(box, volume_ray_count, seed + 29);
      const std::string case_name = c.name + "/" + rays.name;
      std::vector<EngineRun> runs, peer_runs;
      for (auto& e : boxtree_engines) runs.push_back(e->run(rays));
      for (auto& e : peer_engines) peer_runs.push_back(e->run(rays));

      for (const auto& p : peer_runs) {
        int shown = 0;
        for (std::size_t i = 0; i < p.t.size() && shown < dump; ++i) {
          const double a = runs.front().t[i], b = p.t[i];
          const bool differ =
              std::isfinite(a) != std::isfinite(b) ||
              (std::isfinite(a) && std::abs(a - b) > kRelativeTolerance * std::max(std::abs(a), std::abs(b)));
          if (!differ) continue;
          ++shown;
          std::printf("  %s ray %zu: boxtree t %.9g, %s t %.9g\n", case_name.c_str(), i, a, p.engine.c_str(), b);
        }
      }
      // Absolute figures.
      const EngineRun& reference = runs.front();
      std::vector<std::vector<std::string>> abs{
          {"engine", "build s", "Mrays/s", "hits", "disagree (hit/miss + t)", "nodes/ray", "tri tests/ray"}};
      auto add_abs = [&](const EngineRun& r) {
        const Disagreement d = disagreement(reference.t, r.t);
        const double n = double(r.t.size());
        abs.push_back({r.label(), format("%.3f", r.build_seconds), format("%.3f", r.rays_per_second() / 1e6),
                       with_commas(r.hits),
                       with_commas(d.total()) + " (" + with_commas(d.hit_miss) + " + " + with_commas(d.distance) + ")",
                       r.engine == "boxtree" ? format("%.1f", double(r.stats.nodes_visited) / n) : "",
                       r.engine == "boxtree" ? format("%.1f", double(r.stats.leaf_tests) / n) : ""});
      };
      for (const auto& r : runs) add_abs(r);
      for (const auto& r : peer_runs) add_abs(r);
      // Ratios: boxtree method x peer.
      std::vector<std::vector<std::string>> ratios{{"boxtree method"}};
      for (const auto& p : peer_runs) ratios.front().push_back("/ " + p.engine);
      for (const auto& r : runs) {
        std::vector<std::string> line{r.method};
        const Disagreement self = disagreement(reference.t, r.t);
        for (const auto& p : peer_runs) {
          line.push_back(format("%.2fx", r.rays_per_second() / p.rays_per_second()));
          rows.push_back(boxtree::bench::compare("rays", case_name, kThroughputMetric, r.method, r.rays_per_second(),
                                                 json_peer(p.engine), p.rays_per_second()));
          Row agree = boxtree::bench::compare("rays", case_name, kDisagreeMetric, r.method, double(self.total()),
                                              json_peer(p.engine), double(disagreement(r.t, p.t).total()));
          agree.ratio.reset();
          rows.push_back(agree);
        }
        ratios.push_back(line);
      }
      const std::string title = c.name + ", " + rays.name + " rays: " + c.description + "; " +
                                with_commas(rays.origins.size()) + " rays, t_max " + format("%.4g", rays.t_max);
      std::printf("\n%s\n%s\nthroughput ratio boxtree / peer (higher: boxtree faster)\n%s", title.c_str(),
                  table(abs, false).c_str(), table(ratios, false).c_str());
      std::fflush(stdout);
      md << "### " << title << "\n\n"
         << table(abs, true) << "\nThroughput ratio boxtree / peer (above 1: boxtree faster):\n\n"
         << table(ratios, true) << "\n";
    }
  }
  const double total = boxtree::bench::seconds_since(total_start);
  std::printf("\nray_bench: %.1f s\n", total);
  md << "Whole ray benchmark: " << format("%.1f", total) << " s.\n";
  try {
    if (!json_path.empty()) boxtree::bench::write_json(json_path, rows);
    if (!markdown_path.empty()) boxtree::bench::write_text(markdown_path, md.str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ray_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
