// SPDX-License-Identifier: MIT
// Box-query benchmark (issue 10, "axis-aligned box queries on terrains"): the midphase alone,
// as an engine calls it once per body and step, boxtree against Bullet's quantized BVH in one
// process on the same boxes.
//
// Terrains: make_terrain with 128², 512² and 1024² cells (32k, 524k, 2M facets; --quick: 128²).
// Boxes: centred on the terrain's surface at uniform random (x, y) (the height found by a ray,
// not timed), half sizes of 0.75-2.25 cells across and 0.2-2 cells in height: a body's box
// resting on the ground, about 30 candidate facets.
//
// Each engine reports the facets whose leaf box overlaps the query box, with no triangle test:
//  - boxtree: query_overlap(tree, Aabb, visit, nullptr, FacetTest::leaf_volume) on the packed tree
//    that AnyTree and the adapters hold (method `aabb`), and on the exact Tree<Aabb> beside it
//    (`aabb-exact`), for the record;
//  - Bullet: btQuantizedBvh::reportAabbOverlappingNodex of a btBvhTriangleMeshShape with
//    quantized AABB compression, i.e. what processAllTriangles walks, without fetching vertices.
// Both append the facet ids to a reused vector. Time: the engines take turns, one pass over all
// boxes each, for --rounds rounds (default 5); an engine's time is its fastest pass (the machine
// is shared: the minimum is the least disturbed), µs per query. Candidates: mean per query; a boxtree method
// "misses" a query when a facet whose triangle meets the box is not among its candidates
// (on the first 1,000 boxes, against boxtree's exact triangle query, itself cross-checked with
// brute force in the tests: must be 0).
#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench_report.h"
#include "boxtree/build.h"
#include "boxtree/generate.h"
#include "boxtree/geometry.h"
#include "boxtree/packed_tree.h"
#include "boxtree/query.h"
#include "peers/bullet_peer.h"

namespace {

using boxtree::Aabb;
using boxtree::FacetId;
using boxtree::Real;
using boxtree::Vec3;
using boxtree::bench::Clock;
using boxtree::bench::format;
using boxtree::bench::Row;
using boxtree::bench::table;
using boxtree::bench::with_commas;

constexpr const char* kTimeMetric = "us_per_query (midphase only)";
constexpr const char* kCandidateMetric = "candidates_per_query (facets whose leaf box overlaps)";
constexpr const char* kMissedMetric =
    "missed_queries (of the first 1,000 boxes, those missing a facet whose triangle meets the box; must be 0)";
constexpr const char* kBulletPeer = "bullet btQuantizedBvh reportAabbOverlappingNodex";

std::vector<Aabb> resting_boxes(const boxtree::PackedAabbTree& tree, int cells, Real size, std::size_t count,
                                std::uint64_t seed) {
  boxtree::Random random(seed);
  const Real cell = size / cells;
  const Aabb bounds = tree.bounds();
  std::vector<Aabb> boxes;
  boxes.reserve(count);
  while (boxes.size() < count) {
    const Real x = random.uniform(bounds.min.x() + 2 * cell, bounds.max.x() - 2 * cell);
    const Real y = random.uniform(bounds.min.y() + 2 * cell, bounds.max.y() - 2 * cell);
    boxtree::Ray down{Vec3(x, y, bounds.max.z() + 1), Vec3(0, 0, -1)};
    const auto hit = boxtree::ray_closest_hit(tree, down);
    if (!hit) continue;
    const Vec3 center(x, y, bounds.max.z() + 1 - hit->t);
    // z first, then y, then x: gcc's order for the former Vec3 of three draws (a call's arguments
    // are evaluated in an unspecified order; this keeps the boxes measured before, on any compiler).
    const Real half_z = cell * random.uniform(0.2, 2);
    const Real half_y = cell * random.uniform(0.75, 2.25);
    const Real half_x = cell * random.uniform(0.75, 2.25);
    const Vec3 half(half_x, half_y, half_z);
    boxes.push_back(Aabb{center - half, center + half});
  }
  return boxes;
}

struct Run {
  std::string label;
  double seconds = 0;
  std::size_t candidates = 0;
  std::size_t missed_queries = 0;
  double us_per_query(std::size_t n) const { return seconds * 1e6 / double(n); }
};

using QueryFn = std::function<void(const Aabb&, std::vector<int>&)>;

// Checks the first boxes' candidates against `touching` (the facets whose triangle meets them).
Run check_queries(const std::string& label, const std::vector<Aabb>& boxes,
                  const std::vector<std::vector<FacetId>>& touching, const QueryFn& query) {
  Run run{label};
  run.seconds = std::numeric_limits<double>::infinity();
  std::vector<int> out;
  for (std::size_t i = 0; i < touching.size(); ++i) {
    out.clear();
    query(boxes[i], out);
    std::sort(out.begin(), out.end());
    if (!std::all_of(touching[i].begin(), touching[i].end(),
                     [&](FacetId f) { return std::binary_search(out.begin(), out.end(), int(f)); }))
      ++run.missed_queries;
  }
  return run;
}

// One timed pass over every box; keeps the fastest pass in `run`.
void time_pass(Run& run, const std::vector<Aabb>& boxes, const QueryFn& query) {
  std::vector<int> out;
  out.reserve(4096);
  std::size_t candidates = 0;
  const auto start = Clock::now();
  for (const Aabb& box : boxes) {
    out.clear();
    query(box, out);
    candidates += out.size();
  }
  run.seconds = std::min(run.seconds, boxtree::bench::seconds_since(start));
  run.candidates = candidates;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"box-query benchmark: boxtree vs Bullet's quantized BVH, midphase only (issue 10)"};
  bool quick = false;
  std::string json_path, markdown_path;
  std::size_t query_count = 0;
  std::vector<int> cell_counts;
  int rounds = 5;
  app.add_flag("--quick", quick, "small run for CI: 128² cells, 2,000 boxes");
  app.add_option("--json", json_path, "write the result rows (JSON array) here");
  app.add_option("--markdown", markdown_path, "write the section's markdown fragment here");
  app.add_option("--queries", query_count, "boxes per terrain (default 10,000; --quick 2,000)");
  app.add_option("--rounds", rounds, "timed passes per engine, taking turns; the fastest counts (default 5)");
  app.add_option("--terrain-cells", cell_counts, "terrain cells per side, one run each (default 128 512 1024)");
  CLI11_PARSE(app, argc, argv);
  if (query_count == 0) query_count = quick ? 2000 : 10000;
  if (cell_counts.empty()) cell_counts = quick ? std::vector<int>{128} : std::vector<int>{128, 512, 1024};

  try {
    if (!boxtree::peers::bullet_available()) {
      std::fprintf(stderr, "query_bench: built without Bullet, nothing to compare with\n");
      return 1;
    }
    std::vector<Row> rows;
    std::vector<std::vector<std::string>> cells{{"terrain", "facets", "engine", "µs / query", "candidates / query",
                                                 "missed", "ratio time", "ratio candidates"}};
    constexpr Real kSize = 100;
    for (const int n : cell_counts) {
      auto mesh = std::make_shared<const boxtree::TriangleMesh>(boxtree::make_terrain(n, n, 7, kSize));
      const std::string case_name = "terrain-" + std::to_string(mesh->facet_count() / 1000) + "k";
      std::printf("== %s: %s facets, %s boxes\n", case_name.c_str(), with_commas(mesh->facet_count()).c_str(),
                  with_commas(query_count).c_str());
      const boxtree::Tree<Aabb> exact = boxtree::build_tree<Aabb>(mesh);
      const boxtree::PackedAabbTree packed(exact);
      boxtree::peers::BulletBvhMesh bullet(*mesh);
      const std::vector<Aabb> boxes = resting_boxes(packed, n, kSize, query_count, 11);
      // The facets whose triangle meets each of the first boxes (check_queries compares).
      std::vector<std::vector<FacetId>> touching(std::min<std::size_t>(1000, boxes.size()));
      for (std::size_t i = 0; i < touching.size(); ++i) touching[i] = boxtree::query_overlap(exact, boxes[i]);

      const auto boxtree_query = [](const auto& tree) {
        return [&tree](const Aabb& box, std::vector<int>& out) {
          boxtree::query_overlap(
              tree, box,
              [&](FacetId f) {
                out.push_back(int(f));
                return true;
              },
              nullptr, boxtree::FacetTest::leaf_volume);
        };
      };
      const QueryFn queries[] = {
          [&](const Aabb& box, std::vector<int>& out) { bullet.box_candidates(box.min, box.max, out); },
          boxtree_query(packed), boxtree_query(exact)};
      Run runs[] = {check_queries("bullet", boxes, touching, queries[0]),
                    check_queries("boxtree aabb", boxes, touching, queries[1]),
                    check_queries("boxtree aabb-exact", boxes, touching, queries[2])};
      for (int round = 0; round < std::max(1, rounds); ++round)
        for (int e = 0; e < 3; ++e) time_pass(runs[e], boxes, queries[e]);
      const Run& bullet_run = runs[0];
      const Run& packed_run = runs[1];
      const Run& exact_run = runs[2];

      const double n_boxes = double(boxes.size());
      for (const Run* run : {&bullet_run, &packed_run, &exact_run}) {
        const bool peer = run == &bullet_run;
        cells.push_back({case_name, with_commas(mesh->facet_count()), run->label,
                         format("%.3f", run->us_per_query(boxes.size())),
                         format("%.1f", double(run->candidates) / n_boxes), std::to_string(run->missed_queries),
                         peer ? "" : format("%.2f", run->seconds / bullet_run.seconds),
                         peer ? "" : format("%.2f", double(run->candidates) / double(bullet_run.candidates))});
        if (peer) continue;
        const std::string method = run == &packed_run ? "aabb" : "aabb-exact";
        rows.push_back(boxtree::bench::compare("box_queries", case_name, kTimeMetric, method,
                                               run->us_per_query(boxes.size()), kBulletPeer,
                                               bullet_run.us_per_query(boxes.size())));
        rows.push_back(boxtree::bench::compare("box_queries", case_name, kCandidateMetric, method,
                                               double(run->candidates) / n_boxes, kBulletPeer,
                                               double(bullet_run.candidates) / n_boxes));
        Row missed =
            boxtree::bench::compare("box_queries", case_name, kMissedMetric, method, double(run->missed_queries),
                                    kBulletPeer, double(bullet_run.missed_queries));
        missed.ratio.reset();  // a count that must be 0 (bench/report.py --check), not a ratio
        rows.push_back(missed);
      }
    }
    std::printf("%s", table(cells, false).c_str());
    std::ostringstream md;
    md << "## Box queries: midphase only, boxtree vs Bullet's quantized BVH\n\n"
       << boxtree::bench::machine_markdown(boxtree::peers::bullet_version())
       << "\n- Boxes resting on a fractal terrain (100 x 100 units, `make_terrain`), " << with_commas(query_count)
       << " per terrain, half sizes 0.75-2.25 cells across and 0.2-2 cells high. Each engine appends the ids of the "
          "facets whose leaf box overlaps the box to a vector (no triangle test). boxtree `aabb`: the packed tree "
          "the adapters hold (16-bit boxes, 22 B/facet); `aabb-exact`: the exact `Tree<Aabb>` (double boxes). "
          "Bullet: `reportAabbOverlappingNodex` of a quantized `btBvhTriangleMeshShape`.\n"
          "- *missed*: of the first 1,000 boxes, those where a facet whose triangle meets the box was not reported "
          "(must be 0). Time: the fastest of "
       << rounds
       << " passes per engine, the engines taking turns. Ratios: boxtree / Bullet (time: lower is better).\n\n"
       << table(cells, true) << "\n";
    if (!json_path.empty()) boxtree::bench::write_json(json_path, rows);
    if (!markdown_path.empty()) boxtree::bench::write_text(markdown_path, md.str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "query_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
