// SPDX-License-Identifier: MIT
// `boxtree`: inspect meshes and run queries from the command line. Subcommands, options and
// JSON keys are a contract that scripts rely on (see README.md); add keys, never rename them.
// Errors: one line on stderr starting with "boxtree: error:", exit code 1 (2 for usage errors).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/generate.h"
#include "boxtree/io.h"
#include "boxtree/method.h"
#include "boxtree/query.h"
#include "boxtree/stats.h"
#include "boxtree/version.h"

namespace {

using namespace boxtree;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

MergeCost parse_cost(const std::string& name) {
  if (name == "area") return MergeCost::surface_area;
  if (name == "volume") return MergeCost::volume;
  throw Error("unknown cost '" + name + "' (valid costs: area, volume)");
}

// Numbers separated by whitespace or commas; every token must be a finite number.
std::vector<double> parse_numbers(const std::string& text, const std::string& what) {
  std::string spaced = text;
  for (char& c : spaced)
    if (c == ',') c = ' ';
  std::istringstream in(spaced);
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size()) throw Error(what + ": '" + token + "' is not a number");
    if (!std::isfinite(value)) throw Error(what + ": '" + token + "' is not finite");
    values.push_back(value);
  }
  return values;
}

struct Options {
  std::string method = "aabb";
  std::string cost = "area";
  bool json = false;
};

BuildSettings settings_of(const Options& o) {
  BuildSettings s;
  s.cost = parse_cost(o.cost);
  return s;
}

void print_json(const json& j) { std::cout << j.dump() << "\n"; }

int run_info(const Options& o, const std::string& path) {
  const Method method = parse_method(o.method);
  const BuildSettings settings = settings_for(method, settings_of(o));
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(path));
  const MeshStats mesh_stats = compute_mesh_stats(*mesh);
  return with_method(method, [&](auto tag) {
    using Volume = typename decltype(tag)::type;
    BuildStats build;
    const Tree<Volume> tree = build_tree<Volume>(mesh, settings, &build);
    const TreeStats s = compute_tree_stats(tree);
    if (o.json) {
      json levels = json::array();
      for (const LevelStats& l : s.levels)
        levels.push_back(
            {{"level", l.level}, {"nodes", l.nodes}, {"avg_area", l.avg_area}, {"avg_volume", l.avg_volume}});
      print_json({{"mesh", path},
                  {"method", o.method},
                  {"facets", s.facets},
                  {"vertices", mesh_stats.vertices},
                  {"degenerate_facets", mesh_stats.degenerate_facets},
                  {"height", s.height},
                  {"nodes", s.nodes},
                  {"memory_bytes", s.memory_bytes},
                  {"mesh_bytes", s.mesh_bytes},
                  {"build_seconds", build.seconds},
                  {"build_rounds", build.rounds},
                  {"levels", levels},
                  {"plane_cost", s.plane_cost},
                  {"plane_cost_mean_width", s.plane_cost_mean_width}});
    } else {
      std::printf("mesh         %s\n", path.c_str());
      std::printf("method       %s\n", o.method.c_str());
      std::printf("facets       %zu (%zu degenerate), %zu vertices\n", s.facets, mesh_stats.degenerate_facets,
                  mesh_stats.vertices);
      std::printf("tree         %zu nodes, height %d, %zu bytes (%.1f B/facet), built in %.3f s (%d rounds)\n", s.nodes,
                  s.height, s.memory_bytes, double(s.memory_bytes) / double(s.facets), build.seconds, build.rounds);
      std::printf("plane cost   %.3f = sum S_v / S_root (paper; = expected volumes cut per random line)\n",
                  s.plane_cost);
      std::printf("             %.3f = sum W_v / W_root (expected volumes cut per random plane, W = mean width)\n",
                  s.plane_cost_mean_width);
      std::printf("level  nodes      avg_area        avg_volume\n");
      for (const LevelStats& l : s.levels)
        std::printf("%5d  %-9zu  %-14.6g  %-14.6g\n", l.level, l.nodes, l.avg_area, l.avg_volume);
    }
    return 0;
  });
}

int run_collide(const Options& o, const std::string& path_a, const std::string& path_b,
                const std::string& transform_text, bool first_only) {
  const Method method = parse_method(o.method);
  const BuildSettings settings = settings_for(method, settings_of(o));
  RigidTransform a_from_b;
  Eigen::Matrix<double, 3, 4> affine = Eigen::Matrix<double, 3, 4>::Zero();
  affine.leftCols<3>() = Mat3::Identity();
  if (!transform_text.empty()) {
    const std::vector<double> v = parse_numbers(transform_text, "--transform");
    if (v.size() != 12)
      throw Error("--transform: expected 12 numbers (3x4 row-major: r00 r01 r02 tx r10 ... tz), got " +
                  std::to_string(v.size()));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) affine(r, c) = v[std::size_t(r * 4 + c)];
  }
  auto mesh_a = std::make_shared<const TriangleMesh>(load_mesh(path_a));
  TriangleMesh loaded_b = load_mesh(path_b);
  const bool rigid = is_rotation(affine.leftCols<3>(), 1e-6);
  if (rigid) {
    a_from_b.rotation = affine.leftCols<3>();
    a_from_b.translation = affine.col(3);
  } else {
    // Not a rigid motion (scaling, shear, mirroring): apply it to B's vertices, as the contract
    // says, and collide in A's frame.
    for (Vec3& p : loaded_b.vertices) p = affine.leftCols<3>() * p + affine.col(3);
  }
  auto mesh_b = std::make_shared<const TriangleMesh>(std::move(loaded_b));
  return with_method(method, [&](auto tag) {
    using Volume = typename decltype(tag)::type;
    const auto build_start = Clock::now();
    const Tree<Volume> tree_a = build_tree<Volume>(mesh_a, settings);
    const Tree<Volume> tree_b = build_tree<Volume>(mesh_b, settings);
    const double build_seconds = seconds_since(build_start);
    QueryStats stats;
    CollideSettings collide_settings;
    collide_settings.stop_at_first = first_only;
    const auto start = Clock::now();
    std::size_t pairs = 0;
    collide<Volume>(
        tree_a, tree_b, a_from_b,
        [&](const FacetPair&) {
          ++pairs;
          return true;
        },
        &stats, collide_settings);
    const double seconds = seconds_since(start);
    if (o.json) {
      print_json({{"method", o.method},
                  {"pairs", pairs},
                  {"bv_tests", stats.volume_tests},
                  {"leaf_tests", stats.leaf_tests},
                  {"nodes_visited", stats.nodes_visited},
                  {"seconds", seconds},
                  {"build_seconds", build_seconds},
                  {"facets_a", mesh_a->facet_count()},
                  {"facets_b", mesh_b->facet_count()},
                  {"rigid_transform", rigid}});
    } else {
      std::printf("%zu intersecting facet pairs%s; %llu volume tests, %llu triangle tests, %.6f s (build %.3f s)\n",
                  pairs, first_only ? " (stopped at first)" : "", (unsigned long long)stats.volume_tests,
                  (unsigned long long)stats.leaf_tests, seconds, build_seconds);
    }
    return 0;
  });
}

std::vector<Ray> read_rays(const std::string& path) {
  std::ifstream file;
  std::istream* in = &std::cin;
  if (path != "-") {
    file.open(path);
    if (!file) throw Error(path + ": cannot open ray file");
    in = &file;
  }
  std::vector<Ray> rays;
  std::string line;
  for (std::size_t number = 1; std::getline(*in, line); ++number) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;  // blank or comment: not a ray line
    const std::string where = path + ":" + std::to_string(number);
    const std::vector<double> v = parse_numbers(line, where);
    if (v.size() != 6) throw Error(where + ": expected 6 numbers 'ox oy oz dx dy dz', got " + std::to_string(v.size()));
    Ray ray;
    ray.origin = Vec3(v[0], v[1], v[2]);
    ray.direction = Vec3(v[3], v[4], v[5]);
    if (ray.direction.isZero(0)) throw Error(where + ": ray direction is zero");
    rays.push_back(ray);
  }
  if (path != "-" && file.bad()) throw Error(path + ": read error");
  return rays;
}

int run_ray(const Options& o, const std::string& path, const std::string& rays_path) {
  const Method method = parse_method(o.method);
  const BuildSettings settings = settings_for(method, settings_of(o));
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(path));
  const std::vector<Ray> rays = read_rays(rays_path);
  return with_method(method, [&](auto tag) {
    using Volume = typename decltype(tag)::type;
    const Tree<Volume> tree = build_tree<Volume>(mesh, settings);
    std::string out;
    for (const Ray& ray : rays) {
      QueryStats stats;
      const std::optional<RayHit> hit = ray_closest_hit(tree, ray, &stats);
      if (o.json) {
        json j = {{"hit", hit.has_value()},
                  {"facet", hit ? json(hit->facet) : json(nullptr)},
                  {"t", hit ? json(hit->t) : json(nullptr)},
                  {"nodes_visited", stats.nodes_visited}};
        if (hit) {
          j["u"] = hit->u;
          j["v"] = hit->v;
        }
        out += j.dump();
        out += '\n';
      } else if (hit) {
        char buffer[160];
        std::snprintf(buffer, sizeof buffer, "hit facet %u t %.17g (%llu nodes)\n", hit->facet, hit->t,
                      (unsigned long long)stats.nodes_visited);
        out += buffer;
      } else {
        out += "miss (" + std::to_string(stats.nodes_visited) + " nodes)\n";
      }
    }
    std::fwrite(out.data(), 1, out.size(), stdout);
    return 0;
  });
}

int run_generate(const std::string& kind, const std::string& out_path, int size, std::uint64_t seed) {
  TriangleMesh mesh;
  if (kind == "terrain") {
    mesh = make_terrain(size, size, seed);
  } else if (kind == "sphere") {
    mesh = make_uv_sphere(2 * size, size);
  } else if (kind == "bumpy-sphere") {
    mesh = make_bumpy_sphere(2 * size, size, 0.2, seed);
  } else if (kind == "soup") {
    mesh = make_triangle_soup(std::size_t(size), seed);
  } else {
    throw Error("unknown mesh kind '" + kind + "' (valid kinds: terrain, sphere, bumpy-sphere, soup)");
  }
  save_obj(mesh, out_path);
  std::printf("wrote %s: %zu facets, %zu vertices\n", out_path.c_str(), mesh.facet_count(), mesh.vertices.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"boxtree: bottom-up bounding-volume hierarchies (BOXTREE, Barequet et al.) for triangle meshes"};
  app.set_version_flag("--version", std::string("boxtree ") + BOXTREE_VERSION_STRING);
  app.require_subcommand(1);
  Options options;
  std::string method_help = "Hierarchy method:";
  for (const std::string& n : method_names()) method_help += " " + n;
  method_help += ", or a hybrid M+aabb@L (method M below level L, boxes from level L up)";
  auto add_common = [&](CLI::App* sub) {
    sub->add_option("--method", options.method, method_help)->capture_default_str();
    sub->add_option("--cost", options.cost, "Merge cost of a candidate pair: area or volume")->capture_default_str();
    sub->add_flag("--json", options.json, "Machine-readable JSON output");
  };

  std::string mesh_path, mesh_b_path, transform_text, rays_path;
  bool first_only = false;
  CLI::App* info =
      app.add_subcommand("info", "Build a tree and print its statistics (height, memory, per-level area/volume)");
  info->add_option("MESH", mesh_path, "Mesh file (.obj .stl .ply .off)")->required();
  add_common(info);

  CLI::App* collide_cmd = app.add_subcommand("collide", "Count intersecting facet pairs of two meshes");
  collide_cmd->add_option("A", mesh_path, "First mesh")->required();
  collide_cmd->add_option("B", mesh_b_path, "Second mesh")->required();
  collide_cmd->add_option(
      "--transform", transform_text,
      "3x4 row-major transform applied to B's vertices: \"r00 r01 r02 tx r10 r11 r12 ty r20 r21 r22 tz\"");
  collide_cmd->add_flag("--first", first_only, "Stop at the first intersecting pair");
  add_common(collide_cmd);

  CLI::App* ray =
      app.add_subcommand("ray", "Closest hit (t >= 0) of each ray 'ox oy oz dx dy dz' in a file, one line each");
  ray->add_option("MESH", mesh_path, "Mesh file")->required();
  ray->add_option("--rays", rays_path, "Ray file, one ray per line ('-' for standard input)")->required();
  add_common(ray);

  std::string kind, out_path;
  int size = 64;
  std::uint64_t seed = 1;
  CLI::App* generate = app.add_subcommand("generate", "Write a procedural mesh as OBJ");
  generate->add_option("KIND", kind, "terrain (size^2 cells), sphere, bumpy-sphere (size rings), soup (size triangles)")
      ->required();
  generate->add_option("--out", out_path, "Output OBJ file")->required();
  generate->add_option("--size", size, "Size parameter (see KIND)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1 << 24));
  generate->add_option("--seed", seed, "Random seed")->capture_default_str();

  if (argc > 1 && argv[1][0] != '-') {
    const std::string name = argv[1];
    bool known = false;
    std::string valid;
    for (const CLI::App* sub : app.get_subcommands({})) {
      known = known || sub->get_name() == name;
      valid += (valid.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr << "boxtree: error: unknown subcommand '" << name << "' (valid subcommands: " << valid << ")\n";
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return 0;
  } catch (const CLI::CallForAllHelp&) {
    std::cout << app.help("", CLI::AppFormatMode::All);
    return 0;
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what() << "\n";
    return 0;
  } catch (const CLI::ParseError& e) {
    std::cerr << "boxtree: error: " << e.what() << " (see boxtree --help)\n";
    return 2;
  }

  try {
    if (info->parsed()) return run_info(options, mesh_path);
    if (collide_cmd->parsed()) return run_collide(options, mesh_path, mesh_b_path, transform_text, first_only);
    if (ray->parsed()) return run_ray(options, mesh_path, rays_path);
    if (generate->parsed()) return run_generate(kind, out_path, size, seed);
  } catch (const std::exception& e) {
    std::cerr << "boxtree: error: " << e.what() << "\n";
    return 1;
  }
  return 1;
}
