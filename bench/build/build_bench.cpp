// SPDX-License-Identifier: MIT
// Build time and memory (issue 7, section 4): boxtree's build_tree for each hierarchy method
// against Bullet's quantized BVH, FCL's BVHModel (AABB, OBB, RSS, OBBRSS, kIOS) and Embree 3, on
// fractal terrains of about 10k, 100k, 1M and 4M facets, single-threaded, in one process on the
// same meshes. Reports seconds per build and hierarchy bytes per facet, and writes a CSV and
// (with --plot-dir) PNG plots of how both grow with n.
//
// What "bytes" counts (the hierarchy a user pays for beyond the mesh itself):
//  - boxtree: Tree::memory_bytes(): the node volumes and the 4-byte links (capacity). The tree
//    shares the caller's mesh (std::shared_ptr), no copy. For `aabb`: the PackedAabbTree that
//    AnyTree and the engine adapters hold (build_tree + packing, both timed); `aabb-exact` is
//    the exact Tree<Aabb> alone. Likewise for the plain pie-slice methods (`pie-max`, `pie-min`,
//    `pie-max-general`, `pie-min-general`): the PackedPrismTree AnyTree holds (float prisms,
//    48 B per inner node, leaves not stored); `pie-min-exact` (any pie name + `-exact`) is the
//    exact Tree<PieSlice> alone.
//  - Bullet: btQuantizedBvh's quantized node array (16 B per node) + subtree headers + the
//    arrays still held after the build (its quantized leaf-node array). Bullet reads the
//    caller's btScalar arrays through btTriangleIndexVertexArray.
//  - FCL: getNumBVs() x sizeof(BVNode<BV>) + the primitive index array (4 B per facet). FCL also
//    copies the mesh (double vertices, int triangles): listed apart, not in bytes/facet.
//  - Embree: what the device's memory monitor reports held after rtcCommitScene (BVH nodes and
//    primitive blocks, which store the triangles' vertices again). The float vertex/index
//    buffers it shares are the user's copy, listed apart.
// Build time: boxtree build_tree; Bullet the btBvhTriangleMeshShape constructor; FCL
// beginModel..endModel (includes FCL's own copy of the mesh); Embree rtcNewScene..rtcCommitScene
// (device "threads=1"). Small meshes are built several times and the fastest build is kept.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <fcl/fcl.h>
#include <CLI/CLI.hpp>

#include "bench_report.h"
#include "boxtree/build.h"
#include "boxtree/generate.h"
#include "boxtree/method.h"
#include "boxtree/packed_prism_tree.h"
#include "boxtree/packed_tree.h"
#include "peers/bullet_peer.h"
#include "peers/embree_peer.h"

#ifndef BOXTREE_BENCH_SOURCE_DIR
#define BOXTREE_BENCH_SOURCE_DIR "."
#endif

namespace {

using boxtree::bench::Clock;
using boxtree::bench::format;
using boxtree::bench::Row;
using boxtree::bench::table;
using boxtree::bench::with_commas;

constexpr const char* kTimeMetric = "build_seconds (lower is better)";
constexpr const char* kBytesMetric = "hierarchy_bytes_per_facet (lower is better)";

struct Measure {
  std::string engine;  // "boxtree aabb", "bullet", "fcl OBB", "embree"
  double seconds = 0;  // fastest build
  std::size_t bytes = 0;
  std::size_t nodes = 0;
  std::string note;
};

// Runs `build` `repeats` times (each returns a Measure with its seconds) and keeps the fastest.
template <class Build>
Measure fastest(int repeats, Build&& build) {
  Measure best = build();
  for (int i = 1; i < repeats; ++i) {
    Measure m = build();
    if (m.seconds < best.seconds) best = m;
  }
  return best;
}

// --ranking: "" keeps BuildSettings' default.
std::string g_ranking;

Measure build_boxtree(const std::shared_ptr<const boxtree::TriangleMesh>& mesh, const std::string& name) {
  if (name == "aabb") {
    Measure m;
    m.engine = "boxtree aabb";
    const auto start = Clock::now();
    const boxtree::PackedAabbTree packed(boxtree::build_tree<boxtree::Aabb>(mesh));
    m.seconds = boxtree::bench::seconds_since(start);
    m.bytes = packed.memory_bytes();
    m.nodes = packed.node_count();
    m.note = "packed: 64 B per 4-wide node, " + with_commas(packed.nodes().size()) + " nodes";
    return m;
  }
  // The bench-only names of the exact trees beside the packed forms AnyTree holds: `aabb-exact`,
  // and a pie-slice method + `-exact` (e.g. `pie-min-exact`, `pie-max-general-tight-exact`).
  const boxtree::bench::ExactSuffix split = boxtree::bench::split_exact_suffix(name);
  const bool exact = split.exact;  // a plain variable: lambdas below capture it
  const boxtree::Method method = boxtree::parse_method(split.method);
  boxtree::BuildSettings settings = boxtree::settings_for(method);
  if (g_ranking == "merged-volume") settings.ranking = boxtree::PairRanking::merged_volume;
  if (g_ranking == "bounding-box") settings.ranking = boxtree::PairRanking::bounding_box;
  return boxtree::with_method(method, [&](auto tag) {
    using V = typename decltype(tag)::type;
    Measure m;
    m.engine = "boxtree " + name;
    const auto start = Clock::now();
    const boxtree::Tree<V> tree = boxtree::build_tree<V>(mesh, settings);
    if constexpr (boxtree::is_pie_slice_v<V>) {
      if (!exact) {  // what AnyTree holds: the packed form, packing timed too
        const boxtree::PackedPrismTree packed(tree);
        m.seconds = boxtree::bench::seconds_since(start);
        m.bytes = packed.memory_bytes();
        m.nodes = packed.node_count();
        m.note = "packed: 48 B per inner node (" + with_commas(packed.nodes().size()) + "), leaves not stored";
        return m;
      }
    }
    m.seconds = boxtree::bench::seconds_since(start);
    m.bytes = tree.memory_bytes();
    m.nodes = tree.node_count();
    m.note = format("%.0f B/node", double(tree.memory_bytes()) / double(tree.node_count()));
    return m;
  });
}

Measure build_bullet(const boxtree::TriangleMesh& mesh) {
  const boxtree::peers::BulletBvhMesh bullet(mesh);
  const auto b = bullet.bytes();
  Measure m;
  m.engine = "bullet";
  m.seconds = bullet.build_seconds();
  m.bytes = b.total();
  m.nodes = bullet.node_count();
  m.note = "nodes " + with_commas(b.quantized_nodes) + " B + subtree headers " + with_commas(b.subtree_headers) +
           " B + retained leaf arrays " + with_commas(b.retained_build_arrays) + " B";
  return m;
}

template <class BV>
Measure build_fcl(const boxtree::TriangleMesh& mesh, const std::string& name) {
  std::vector<fcl::Vector3d> vertices(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const boxtree::Triangle& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  Measure m;
  m.engine = "fcl " + name;
  auto model = std::make_unique<fcl::BVHModel<BV>>();
  const auto start = Clock::now();
  model->beginModel(int(triangles.size()), int(vertices.size()));
  model->addSubModel(vertices, triangles);
  model->endModel();
  m.seconds = boxtree::bench::seconds_since(start);
  m.nodes = std::size_t(model->getNumBVs());
  m.bytes = m.nodes * sizeof(fcl::BVNode<BV>) + mesh.facet_count() * sizeof(unsigned);
  m.note = std::to_string(sizeof(fcl::BVNode<BV>)) + " B/node + 4 B/facet primitive indices; mesh copy " +
           with_commas(vertices.size() * sizeof(fcl::Vector3d) + triangles.size() * sizeof(fcl::Triangle)) +
           " B not counted";
  return m;
}

Measure build_fcl(const boxtree::TriangleMesh& mesh, const std::string& bv) {
  if (bv == "AABB") return build_fcl<fcl::AABBd>(mesh, bv);
  if (bv == "OBB") return build_fcl<fcl::OBBd>(mesh, bv);
  if (bv == "RSS") return build_fcl<fcl::RSSd>(mesh, bv);
  if (bv == "OBBRSS") return build_fcl<fcl::OBBRSSd>(mesh, bv);
  return build_fcl<fcl::kIOSd>(mesh, bv);
}

Measure build_embree(const boxtree::TriangleMesh& mesh) {
  const boxtree::peers::EmbreeScene embree(mesh);
  Measure m;
  m.engine = "embree";
  m.seconds = embree.build_seconds();
  m.bytes = embree.bytes();
  m.note = "peak during build " + with_commas(embree.peak_bytes()) + " B; shared float buffers " +
           with_commas(embree.mesh_copy_bytes()) + " B not counted";
  return m;
}

// "a,b,c": a list as the options take it.
std::string comma_list(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ",") + item;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Build time and memory: boxtree methods vs Bullet, FCL, Embree on terrains (single thread)"};
  bool quick = false;
  std::string json_path, markdown_path, plot_dir, csv_path, meshes_dir;
  std::vector<std::string> methods = {"aabb",    "aabb-exact", "obb-all",       "obb-max",         "obb-min",
                                      "pie-max", "pie-min",    "pie-min-exact", "pie-max-general", "pie-min-general"};
  std::vector<std::string> large_methods = {"aabb", "aabb-exact", "obb-all"};
  std::vector<std::size_t> sizes;
  std::size_t large_from = 500000;
  std::uint64_t seed = 1;
  int min_repeats = 1;
  bool skip_peers = false;
  std::vector<std::string> peer_names = {"bullet", "fcl", "embree"};
  app.add_flag("--skip-peers", skip_peers, "build boxtree trees only (for profiling)");
  app.add_option("--peers", peer_names, "which peers to build: comma-separated subset of bullet,fcl,embree")
      ->delimiter(',')
      ->allow_extra_args(false);
  app.add_flag("--quick", quick, "small run for CI: 10k and 100k facets, methods aabb and obb-all");
  app.add_option("--json", json_path, "write the result rows (JSON array) here");
  app.add_option("--markdown", markdown_path, "write the section's markdown fragment here");
  app.add_option("--csv", csv_path, "write one line per (size, engine) here");
  app.add_option("--plot-dir", plot_dir, "write the CSV and PNG plots (build time, bytes per facet vs n) here");
  app.add_option("--meshes", meshes_dir, "unused (terrains are generated); accepted for a uniform command line");
  app.add_option("--methods", methods, "boxtree methods below --large-from facets")
      ->delimiter(',')
      ->allow_extra_args(false);
  app.add_option("--large-methods", large_methods, "boxtree methods from --large-from facets up")
      ->delimiter(',')
      ->allow_extra_args(false);
  app.add_option("--large-from", large_from, "facet count from which only --large-methods are built");
  app.add_option("--sizes", sizes, "comma-separated facet counts (default 10000,100000,1000000,4000000)")
      ->delimiter(',')
      ->allow_extra_args(false);
  app.add_option("--seed", seed, "terrain seed");
  app.add_option("--ranking", g_ranking,
                 "candidate ranking of the oriented kinds (BuildSettings::ranking; default: the library's)")
      ->check(CLI::IsMember({"merged-volume", "bounding-box"}));
  app.add_option("--repeats", min_repeats, "build every mesh at least this many times and keep the fastest build");
  CLI11_PARSE(app, argc, argv);
  // An empty item reads as 0 and "-5" as 2^64 - 5: both refused, as is any terrain past 2^31 facets.
  constexpr std::size_t kMostFacets = std::size_t(1) << 31;
  if (std::any_of(sizes.begin(), sizes.end(), [](std::size_t n) { return n == 0 || n > kMostFacets; })) {
    std::fprintf(stderr, "build_bench: --sizes: every facet count must be from 1 to %zu\n", kMostFacets);
    return 2;
  }
  if (sizes.empty())
    sizes = quick ? std::vector<std::size_t>{10000, 100000} : std::vector<std::size_t>{10000, 100000, 1000000, 4000000};
  if (quick && app.count("--methods") == 0) methods = {"aabb", "obb-all"};
  const auto peer_wanted = [&](const char* name) {
    return !skip_peers && std::find(peer_names.begin(), peer_names.end(), name) != peer_names.end();
  };
  try {
    for (const auto& list : {methods, large_methods})
      for (const auto& m : list) {
        // aabb-exact, pie-...-exact: the bench-only exact trees
        const boxtree::bench::ExactSuffix split = boxtree::bench::split_exact_suffix(m);
        const boxtree::Method method = boxtree::parse_method(split.method);
        if (split.exact && !boxtree::bench::has_packed_form(method))
          throw std::runtime_error("'" + m + "': -exact applies to aabb and pie-slice methods");
      }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "build_bench: error: %s\n", e.what());
    return 2;
  }
  const auto total_start = Clock::now();
  const std::vector<std::string> fcl_bvs = {"AABB", "OBB", "RSS", "OBBRSS", "kIOS"};
  if (!boxtree::peers::embree_available())
    std::printf("Embree peer skipped: not found at configure time (Debian: libembree-dev)\n");

  std::vector<Row> rows;
  std::ostringstream md, csv;
  csv << "facets,engine,kind,build_seconds,bytes,bytes_per_facet,nodes\n";
  const std::string peers =
      std::string(boxtree::peers::bullet_version()) + "; FCL " FCL_VERSION "; " + boxtree::peers::embree_version();
  md << "## Build time and memory: boxtree vs Bullet, FCL, Embree\n\n" << boxtree::bench::machine_markdown(peers);
  md << "- Meshes: `make_terrain(c, c, " << seed
     << ")` with c = round(sqrt(n / 2)) cells per side (2 c^2 facets). Single-threaded builds; meshes under 50k facets "
        "are "
        "built 3 times (every mesh at least --repeats times, here "
     << min_repeats
     << ") and the fastest build is kept.\n"
        "- Bytes per facet: the hierarchy a user pays for beyond the mesh. boxtree: `Tree::memory_bytes()` (volumes + "
        "4-byte links; the mesh is shared, not copied). Bullet: quantized nodes (16 B) + subtree headers + the "
        "leaf-node "
        "array it keeps after the build (`btBvhTriangleMeshShape`, `useQuantizedAabbCompression = true`). FCL: "
        "`getNumBVs() x sizeof(BVNode<BV>)` + 4 B/facet primitive indices (FCL's own copy of the mesh not counted). "
        "Embree: bytes held after `rtcCommitScene` by its memory monitor (BVH nodes + primitive blocks, which hold "
        "vertex copies; the shared float buffers not counted).\n"
        "- Build time: boxtree `build_tree`; Bullet the shape constructor; FCL `beginModel`..`endModel`; Embree "
        "`rtcNewScene`..`rtcCommitScene` (device \"threads=1\", medium quality).\n"
        "- Ratios: boxtree / peer, lower is better for both (below 1: boxtree builds faster / uses less memory).\n"
        "- Methods built: "
     << comma_list(methods) << " below " << with_commas(large_from) << " facets, " << comma_list(large_methods)
     << " from there up (the others are too slow to build at that size within the suite's time budget; see the "
        "per-facet build times of the smaller sizes).\n\n";

  for (const std::size_t target : sizes) {
    const int cells = std::max(2, int(std::lround(std::sqrt(double(target) / 2))));
    auto mesh = std::make_shared<const boxtree::TriangleMesh>(boxtree::make_terrain(cells, cells, seed));
    const std::size_t facets = mesh->facet_count();
    const int repeats = std::max(min_repeats, facets < 50000 ? 3 : 1);
    const std::string case_name =
        "terrain-" + (target >= 1000000 ? std::to_string(target / 1000000) + "M" : std::to_string(target / 1000) + "k");
    std::vector<Measure> boxtree_runs, peer_runs;
    const auto& these_methods = facets >= large_from ? large_methods : methods;
    for (const auto& m : these_methods) {
      boxtree_runs.push_back(fastest(repeats, [&] { return build_boxtree(mesh, m); }));
      std::fflush(stdout);
    }
    if (peer_wanted("bullet") && boxtree::peers::bullet_available())
      peer_runs.push_back(fastest(repeats, [&] { return build_bullet(*mesh); }));
    if (peer_wanted("fcl"))
      for (const auto& bv : fcl_bvs) peer_runs.push_back(fastest(repeats, [&] { return build_fcl(*mesh, bv); }));
    if (peer_wanted("embree") && boxtree::peers::embree_available())
      peer_runs.push_back(fastest(repeats, [&] { return build_embree(*mesh); }));

    std::vector<std::vector<std::string>> abs{
        {"engine", "build s", "us/facet", "bytes", "B/facet", "nodes", "what is counted"}};
    auto add = [&](const Measure& m, const char* kind) {
      abs.push_back({m.engine, format("%.3f", m.seconds), format("%.2f", 1e6 * m.seconds / double(facets)),
                     with_commas(m.bytes), format("%.1f", double(m.bytes) / double(facets)),
                     m.nodes ? with_commas(m.nodes) : "", m.note});
      csv << facets << "," << m.engine << "," << kind << "," << m.seconds << "," << m.bytes << ","
          << double(m.bytes) / double(facets) << "," << m.nodes << "\n";
    };
    for (const auto& m : boxtree_runs) add(m, "boxtree");
    for (const auto& m : peer_runs) add(m, "peer");
    std::vector<std::vector<std::string>> ratios{{"boxtree method"}};
    for (const auto& p : peer_runs) ratios.front().push_back("/ " + p.engine);
    for (const auto& b : boxtree_runs) {
      const std::string method = b.engine.substr(std::string("boxtree ").size());
      std::vector<std::string> line{method};
      for (const auto& p : peer_runs) {
        line.push_back(format("%.2f", b.seconds / p.seconds) + " / " +
                       format("%.2f", double(b.bytes) / double(p.bytes)));
        rows.push_back(
            boxtree::bench::compare("build_memory", case_name, kTimeMetric, method, b.seconds, p.engine, p.seconds));
        rows.push_back(boxtree::bench::compare("build_memory", case_name, kBytesMetric, method,
                                               double(b.bytes) / double(facets), p.engine,
                                               double(p.bytes) / double(facets)));
      }
      ratios.push_back(line);
    }
    const std::string title = case_name + ": make_terrain(" + std::to_string(cells) + ", " + std::to_string(cells) +
                              "), " + with_commas(facets) + " facets";
    std::printf("\n%s\n%s\nratios boxtree / peer: build time / bytes (lower: boxtree better)\n%s", title.c_str(),
                table(abs, false).c_str(), table(ratios, false).c_str());
    std::fflush(stdout);
    md << "### " << title << "\n\n"
       << table(abs, true) << "\nRatios boxtree / peer, build time / bytes (below 1: boxtree better):\n\n"
       << table(ratios, true) << "\n";
  }
  const double total = boxtree::bench::seconds_since(total_start);
  std::printf("\nbuild_bench: %.1f s, peak resident memory %.0f MB\n", total,
              double(boxtree::bench::peak_rss_bytes()) / 1e6);
  md << "Whole build benchmark: " << format("%.1f", total) << " s.\n";
  try {
    if (!plot_dir.empty()) {
      std::filesystem::create_directories(plot_dir);
      if (csv_path.empty()) csv_path = plot_dir + "/build_memory.csv";
      md << "\n![build time vs facets](build_time.png)\n![bytes per facet vs facets](build_bytes.png)\n";
    }
    if (!csv_path.empty()) boxtree::bench::write_text(csv_path, csv.str());
    if (!json_path.empty()) boxtree::bench::write_json(json_path, rows);
    if (!markdown_path.empty()) boxtree::bench::write_text(markdown_path, md.str());
    if (!plot_dir.empty()) {
      const std::string command =
          "/usr/bin/python3 '" BOXTREE_BENCH_SOURCE_DIR "/plot.py' '" + csv_path + "' '" + plot_dir + "'";
      if (std::system(command.c_str()) != 0)
        std::fprintf(stderr, "build_bench: plotting failed: %s\n", command.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "build_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
