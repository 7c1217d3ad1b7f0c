// SPDX-License-Identifier: MIT
// The paper's theory made executable (Sections 2, 3.1, 5): planar boxtrees on rectangular
// partitions up to millions of cells, the terrain merge rule against the greedy builder on the
// demo's terrain, and the stabbing number on the lower-bound constructions.
//
//   planar_bench --out bench/paper/results/planar [--max-n 1000000] [--quick]
//
// Writes planar.csv, terrain.csv, lower_bounds.csv (plotted by planar_plot.py).
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "boxtree/build.h"
#include "boxtree/generate.h"
#include "boxtree/method.h"
#include "boxtree/planar/partition.h"
#include "boxtree/planar/planar_tree.h"
#include "boxtree/planar/terrain.h"
#include "boxtree/query.h"
#include "planar_lower_bounds.h"
#include "scenes/paper_models.h"

using namespace boxtree;
using Clock = std::chrono::steady_clock;

namespace {

// Several random draws never share one call: the order of a call's arguments is unspecified (gcc
// evaluates them last first, clang first first). They are drawn one per statement in the order
// gcc gave the former one-call forms, last argument first, so the inputs are the ones measured
// before, now on both compilers.

// A point of `box`, z first, then y, then x (see above).
Vec3 random_point_in(Random& random, const Aabb& box) {
  const Real z = random.uniform(box.min.z(), box.max.z());
  const Real y = random.uniform(box.min.y(), box.max.y());
  const Real x = random.uniform(box.min.x(), box.max.x());
  return {x, y, z};
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// ---------------------------------------------------------------- planar (Section 2)
void run_planar(std::ofstream& csv, std::size_t max_n, bool quick) {
  csv << "generator,n,height,rounds,stabbing,two_height,log2n,min_pair_fraction,mean_pair_fraction,fallback_rounds,"
         "validate_s,build_s,locate_ns,locate_nodes_mean,locate_nodes_max\n";
  std::vector<std::size_t> sizes;
  for (std::size_t n = 100; n <= max_n; n = n * 10 / 3 < max_n && n * 10 / 3 > n ? (n * 10) / 3 : n * 3)
    sizes.push_back(n);
  if (sizes.empty() || sizes.back() != max_n) sizes.push_back(max_n);
  for (const std::string& generator : planar::partition_generator_names()) {
    for (std::size_t n : sizes) {
      if (quick && n > 100000) continue;
      const std::vector<planar::Rect> cells = planar::make_partition(generator, n, 42);
      planar::PlanarBuildStats stats;
      const planar::PlanarTree tree = planar::build_planar_tree(cells, {}, &stats);
      double min_fraction = 1e9, mean_fraction = 0;
      for (const auto& r : stats.rounds) {
        const double f = 12.0 * double(r.pairs) / double(r.cells + 3);  // >= 1: Theorem 2.2's guarantee
        min_fraction = std::min(min_fraction, f);
        mean_fraction += double(r.pairs) / double(r.cells);
      }
      mean_fraction /= double(std::max<std::size_t>(1, stats.rounds.size()));
      const std::size_t stabbing = planar::stabbing_number(tree);
      // Point location: random points, after a warm-up pass.
      Random random(7);
      const int queries = 200000;
      std::vector<Vec2> points(queries);
      for (auto& p : points) {
        const Real y = random.uniform();  // y first: see the top of the file
        p = Vec2(random.uniform(), y);
      }
      std::size_t checksum = 0;
      for (int i = 0; i < queries / 10; ++i) checksum += *planar::locate_point(tree, points[std::size_t(i)]);
      planar::PlanarQueryStats qstats;
      std::uint64_t max_nodes = 0;
      const auto t = Clock::now();
      for (const auto& p : points) {
        planar::PlanarQueryStats one;
        checksum += *planar::locate_point(tree, p, &one);
        qstats.nodes_visited += one.nodes_visited;
        max_nodes = std::max(max_nodes, one.nodes_visited);
      }
      const double ns = seconds_since(t) * 1e9 / queries;
      csv << generator << "," << cells.size() << "," << tree.height() << "," << stats.rounds.size() << "," << stabbing
          << "," << 2 * tree.height() << "," << std::log2(double(cells.size())) << "," << min_fraction << ","
          << mean_fraction << "," << stats.fallback_rounds << "," << stats.validate_seconds << ","
          << stats.build_seconds << "," << ns << "," << double(qstats.nodes_visited) / queries << "," << max_nodes
          << "\n";
      csv.flush();
      std::printf(
          "planar %-10s n=%8zu height=%3d rounds=%3zu stabbing=%3zu min12p/(m+3)=%.2f build=%.3fs locate=%.0fns "
          "(%zu)\n",
          generator.c_str(), cells.size(), tree.height(), stats.rounds.size(), stabbing, min_fraction,
          stats.build_seconds, ns, checksum % 10);
      std::fflush(stdout);
    }
  }
}

// ---------------------------------------------------------------- 3D stabbing (Section 5)
// Our 3D stabbing number: the largest number of nodes whose volume a line meets (closed
// volumes; exactly the nodes the all-hits ray walk enters, the paper's Section 1 count), over a
// family of lines: the construction's witness lines plus random lines and axis-parallel lines
// through the mesh's bounding box.
struct Line {
  Vec3 origin, direction;
};

std::vector<Line> probe_lines(const TriangleMesh& mesh, const std::vector<Line>& witnesses, int random_count,
                              std::uint64_t seed) {
  Aabb box;
  for (const Vec3& v : mesh.vertices) box.expand(v);
  const Vec3 c = box.center();
  const Real r = box.extent().norm();
  std::vector<Line> lines = witnesses;
  Random random(seed);
  for (int i = 0; i < random_count; ++i) {
    const Vec3 inside = random_point_in(random, box);
    if (i % 2 == 0) {
      const Vec3 from = c + r * random.unit_vector();
      lines.push_back({from, (inside - from).normalized()});
    } else {
      const int axis = (i / 2) % 3;
      Vec3 from = inside;
      from[axis] = box.min[axis] - r;
      lines.push_back({from, Vec3::Unit(axis)});
    }
  }
  return lines;
}

struct StabbingResult {
  std::uint64_t max_all = 0, max_witness = 0;
  double mean_random = 0;
  int height = 0;
};

template <class V>
StabbingResult stabbing(const Tree<V>& tree, const std::vector<Line>& lines, std::size_t witness_count) {
  StabbingResult out;
  out.height = tree.height();
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    Ray ray;
    ray.origin = lines[i].origin;
    ray.direction = lines[i].direction;
    QueryStats stats;
    ray_all_hits(
        tree, ray, [](const RayHit&) { return true; }, &stats);
    out.max_all = std::max(out.max_all, stats.nodes_visited);
    if (i < witness_count)
      out.max_witness = std::max(out.max_witness, stats.nodes_visited);
    else
      sum += stats.nodes_visited;
  }
  out.mean_random = double(sum) / double(std::max<std::size_t>(1, lines.size() - witness_count));
  return out;
}

const std::vector<std::string> kPaperMethods = {"aabb", "obb-all", "obb-max", "obb-min", "pie-max", "pie-min"};

void measure_all_methods(std::ofstream& csv, const std::string& construction, int n, const TriangleMesh& mesh,
                         const std::vector<Line>& witnesses, const std::string& note) {
  const std::vector<Line> lines = probe_lines(mesh, witnesses, 400, 11);
  const auto shared = std::make_shared<const TriangleMesh>(mesh);
  for (const std::string& name : kPaperMethods) {
    const StabbingResult r = with_method(parse_method(name), [&](auto tag) {
      using V = typename decltype(tag)::type;
      return stabbing(build_tree<V>(shared), lines, witnesses.size());
    });
    csv << construction << "," << n << "," << mesh.facet_count() << "," << name << "," << r.height << "," << r.max_all
        << "," << r.max_witness << "," << r.mean_random << "," << note << "\n";
    std::printf("lower %-9s n=%4d facets=%6zu %-8s height=%3d stab=%5llu witness=%5llu mean=%.1f %s\n",
                construction.c_str(), n, mesh.facet_count(), name.c_str(), r.height, (unsigned long long)r.max_all,
                (unsigned long long)r.max_witness, r.mean_random, note.c_str());
  }
  csv.flush();
  std::fflush(stdout);
}

void run_lower_bounds(std::ofstream& csv, bool quick) {
  csv << "construction,n,facets,method,height,stabbing,witness,mean_random_line,note\n";
  for (int n : {8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096}) {
    if (quick && n > 512) continue;
    // Vertical lines just off the apex, one per quadrant: inside Omega(n) leaf boxes each.
    std::vector<Line> witnesses;
    for (int q = 0; q < 4; ++q)
      witnesses.push_back({Vec3((q & 1 ? 1 : -1) * 1e-3, (q & 2 ? 1 : -1) * 1e-3, -1), Vec3::UnitZ()});
    measure_all_methods(csv, "cone", n, bench::make_cone(n), witnesses, "");
  }
  for (int n : {2, 3, 4, 6, 8, 10, 12, 16, 20, 24, 28, 32}) {
    if (quick && n > 12) continue;
    const bench::TangentPolytope p = bench::make_tangent_polytope(n);
    const std::vector<Line> witnesses = {{Vec3(0, 0, -1), Vec3::UnitZ()}};  // the paper's: through the origin
    const std::string note = std::string(p.segments_are_edges ? "segments are hull edges" : "SEGMENTS NOT ALL EDGES") +
                             (p.exact_in_double ? "; exact in double" : "; rounded to double");
    measure_all_methods(csv, "polytope", n, p.mesh, witnesses, note);
  }
  // Surfaces without a bad construction: random-point spheres (the paper's sphere model) and
  // fractal terrains, with the same line family (no witness lines).
  for (int points : {32, 128, 512, 2048, 8192}) {
    if (quick && points > 2048) continue;
    measure_all_methods(csv, "sphere", points, scenes::random_sphere(points, 5), {}, "");
  }
  for (int cells : {4, 8, 16, 32, 64}) {
    if (quick && cells > 32) continue;
    measure_all_methods(csv, "terrain", cells * cells, make_terrain(cells, cells, 3), {}, "");
  }
}

// ---------------------------------------------------------------- terrain rule (Section 3.1)
// The demo's default terrain (demos/src/scene.cpp, make_demo_terrain with --terrain-size 128,
// --seed 1): a 128 x 128 fractal terrain 40 m wide, with a rim raised into a bowl.
TriangleMesh demo_terrain() {
  const Real width = 40, noise = 4;
  TriangleMesh mesh = make_terrain(128, 128, 1, width, noise);
  const Real half = width / 2;
  for (Vec3& v : mesh.vertices) {
    v.x() -= half;
    v.y() -= half;
    const Real u = v.x() / half, w = v.y() / half;
    const Real r = std::min(Real(1), std::pow(u * u * u * u + w * w * w * w, Real(0.25)));
    const Real rim = std::max(Real(0), r - Real(0.55)) / Real(0.45);
    v.z() += 7 * rim * rim;
  }
  return mesh;
}

template <class V>
void compare_on_terrain(std::ofstream& csv, const std::string& method, const std::string& strategy_name,
                        const std::shared_ptr<const TriangleMesh>& mesh, const BuildSettings& settings) {
  BuildStats build;
  const auto t = Clock::now();
  const Tree<V> tree = build_tree<V>(mesh, settings, &build);
  const double build_s = seconds_since(t);
  Aabb box;
  for (const Vec3& v : mesh->vertices) box.expand(v);
  auto report = [&](const std::string& query, const std::vector<QueryStats>& all) {
    double nodes = 0, tests = 0;
    std::uint64_t max_nodes = 0;
    for (const QueryStats& s : all) {
      nodes += double(s.nodes_visited);
      tests += double(s.volume_tests);
      max_nodes = std::max(max_nodes, s.nodes_visited);
    }
    csv << method << "," << strategy_name << "," << query << "," << tree.height() << "," << build_s << ","
        << nodes / double(all.size()) << "," << max_nodes << "," << tests / double(all.size()) << "\n";
    std::printf("terrain %-8s %-7s %-16s height=%3d nodes=%8.1f max=%6llu volume_tests=%8.1f\n", method.c_str(),
                strategy_name.c_str(), query.c_str(), tree.height(), nodes / double(all.size()),
                (unsigned long long)max_nodes, tests / double(all.size()));
  };
  Random random(99);
  const int count = 4000;
  // Vertical rays from above (all hits: the whole stab), random rays through the box (all hits),
  // and the drop scene's midphase: boxes of bodies resting on the ground in the middle.
  std::vector<QueryStats> vertical(count), random_rays(count), closest(count), midphase(count);
  for (int i = 0; i < count; ++i) {
    Ray ray;
    const Real origin_y = random.uniform(box.min.y(), box.max.y());  // y first: see the top of the file
    ray.origin = Vec3(random.uniform(box.min.x(), box.max.x()), origin_y, box.max.z() + 1);
    ray.direction = -Vec3::UnitZ();
    ray_all_hits(
        tree, ray, [](const RayHit&) { return true; }, &vertical[std::size_t(i)]);
    ray_closest_hit(tree, ray, &closest[std::size_t(i)]);
    Ray any;
    const Vec3 inside = random_point_in(random, box);
    any.origin = box.center() + box.extent().norm() * random.unit_vector();
    any.direction = (inside - any.origin).normalized();
    ray_all_hits(
        tree, any, [](const RayHit&) { return true; }, &random_rays[std::size_t(i)]);
    // Bodies of the drop scene are 0.25-0.55 m, dropped over the middle |x|, |y| <= 11 m.
    const Real size = random.uniform(0.25, 0.55);
    const Real half_z = random.uniform(0.5, 1);  // z first: see the top of the file
    const Real half_y = random.uniform(0.5, 1);
    const Real half_x = random.uniform(0.5, 1);
    const Vec3 half = Vec3(half_x, half_y, half_z) * size;
    const Real c_y = random.uniform(-11, 11);  // y first
    const Vec3 c(random.uniform(-11, 11), c_y, 0);
    Ray down;
    down.origin = Vec3(c.x(), c.y(), box.max.z() + 1);
    down.direction = -Vec3::UnitZ();
    const auto hit = ray_closest_hit(tree, down);
    const Vec3 centre(c.x(), c.y(), (hit ? down.origin.z() - hit->t : 0) + half.z() * random.uniform(-0.2, 1));
    query_overlap(
        tree, Aabb::from_points(centre - half, centre + half), [](FacetId) { return true; }, &midphase[std::size_t(i)],
        FacetTest::leaf_volume);
  }
  report("vertical_all_hits", vertical);
  report("vertical_closest", closest);
  report("random_all_hits", random_rays);
  report("drop_midphase", midphase);
  csv.flush();
  std::fflush(stdout);
}

void run_terrain(std::ofstream& csv) {
  csv << "method,strategy,query,height,build_s,nodes_mean,nodes_max,volume_tests_mean\n";
  const auto mesh = std::make_shared<const TriangleMesh>(demo_terrain());
  for (const std::string& name : kPaperMethods) {
    with_method(parse_method(name), [&](auto tag) {
      using V = typename decltype(tag)::type;
      BuildSettings greedy;
      BuildSettings terrain;
      terrain.merge_rule = planar::terrain_merge_order;
      compare_on_terrain<V>(csv, name, "greedy", mesh, greedy);
      compare_on_terrain<V>(csv, name, "terrain", mesh, terrain);
      return 0;
    });
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("The paper's Sections 2, 3.1 and 5: planar boxtrees, the terrain rule, lower bounds");
  std::string out = "bench/paper/results/planar";
  std::size_t max_n = 1000000;
  bool quick = false;
  std::string only;
  app.add_option("--out", out, "Output directory")->capture_default_str();
  app.add_option("--max-n", max_n, "Largest planar partition")->capture_default_str();
  app.add_flag("--quick", quick, "Small sizes only");
  app.add_option("--only", only, "Run one part: planar, terrain or lower_bounds");
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(out);
  const auto t = Clock::now();
  if (only.empty() || only == "planar") {
    std::ofstream csv(out + "/planar.csv");
    run_planar(csv, max_n, quick);
  }
  if (only.empty() || only == "terrain") {
    std::ofstream csv(out + "/terrain.csv");
    run_terrain(csv);
  }
  if (only.empty() || only == "lower_bounds") {
    std::ofstream csv(out + "/lower_bounds.csv");
    run_lower_bounds(csv, quick);
  }
  std::printf("total %.1f s\n", seconds_since(t));
  return 0;
}
