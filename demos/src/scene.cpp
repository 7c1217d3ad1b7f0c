// SPDX-License-Identifier: MIT
#include "scene.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "boxtree/build.h"
#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/io.h"
#include "boxtree/query.h"
#include "hull.h"

namespace demo {

namespace {

using boxtree::FacetId;
using boxtree::VertexId;

constexpr Real kPi = 3.14159265358979323846;

Real signed_volume(const TriangleMesh& mesh) {
  Real v = 0;
  for (std::size_t f = 0; f < mesh.facet_count(); ++f)
    v += mesh.corner(FacetId(f), 0).dot(mesh.corner(FacetId(f), 1).cross(mesh.corner(FacetId(f), 2)));
  return v / 6;
}

// Convex shapes around the origin: each face's normal must point away from the origin.
void orient_away_from_origin(TriangleMesh& mesh) {
  for (auto& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    if ((b - a).cross(c - a).dot(a + b + c) < 0) std::swap(t[1], t[2]);
  }
}

// A closed surface of revolution about z from a profile (radius, z) running from the north pole
// (radius 0) to the south pole (radius 0).
TriangleMesh lathe(const std::vector<std::pair<Real, Real>>& profile, int segments) {
  TriangleMesh mesh;
  const int rings = int(profile.size()) - 2;
  mesh.vertices.emplace_back(0, 0, profile.front().second);
  for (int r = 1; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const Real phi = 2 * kPi * s / segments;
      mesh.vertices.emplace_back(profile[r].first * std::cos(phi), profile[r].first * std::sin(phi), profile[r].second);
    }
  mesh.vertices.emplace_back(0, 0, profile.back().second);
  const VertexId south = VertexId(mesh.vertices.size() - 1);
  auto ring = [&](int r, int s) { return VertexId(1 + (r - 1) * segments + s % segments); };
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      mesh.triangles.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
      mesh.triangles.push_back({ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back({ring(rings, s), south, ring(rings, s + 1)});
  orient_away_from_origin(mesh);
  return mesh;
}

// Moves the mesh so that its bounding box is centred on the origin; returns the half extents.
Vec3 centre_bounds(TriangleMesh& mesh) {
  Vec3 lo = mesh.vertices.front(), hi = lo;
  for (const Vec3& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const Vec3 mid = (lo + hi) / 2;
  for (Vec3& v : mesh.vertices) v -= mid;
  return (hi - lo) / 2;
}

}  // namespace

const char* terrain_kind_name(TerrainKind kind) {
  switch (kind) {
    case TerrainKind::bowl:
      return "bowl";
    case TerrainKind::rough:
      return "rough";
    case TerrainKind::flat:
      return "flat";
  }
  return "?";
}

const char* body_mix_name(BodyMix mix) {
  switch (mix) {
    case BodyMix::mixed:
      return "mixed";
    case BodyMix::mixed_without_meshes:
      return "mixed-without-meshes";
    case BodyMix::sphere:
      return "sphere";
    case BodyMix::box:
      return "box";
    case BodyMix::capsule:
      return "capsule";
    case BodyMix::cylinder:
      return "cylinder";
    case BodyMix::hull8:
      return "hull8";
    case BodyMix::hull16:
      return "hull16";
    case BodyMix::hull32:
      return "hull32";
    case BodyMix::hull64:
      return "hull64";
    case BodyMix::mesh:
      return "mesh";
    case BodyMix::primitives_in_turn:
      return "primitives-in-turn";
  }
  return "?";
}

bool parse_body_mix(const std::string& name, BodyMix* mix) {
  for (int m = 0; m <= int(BodyMix::primitives_in_turn); ++m)
    if (name == body_mix_name(BodyMix(m))) {
      *mix = BodyMix(m);
      return true;
    }
  return false;
}

const char* shape_name(Shape shape) {
  switch (shape) {
    case Shape::sphere:
      return "sphere";
    case Shape::box:
      return "box";
    case Shape::capsule:
      return "capsule";
    case Shape::cylinder:
      return "cylinder";
    case Shape::convex:
      return "convex";
    case Shape::mesh:
      return "mesh";
  }
  return "?";
}

TriangleMesh make_box_mesh(const Vec3& h) {
  TriangleMesh mesh;
  for (int mask = 0; mask < 8; ++mask)
    mesh.vertices.emplace_back(mask & 1 ? h.x() : -h.x(), mask & 2 ? h.y() : -h.y(), mask & 4 ? h.z() : -h.z());
  // Two triangles per face; corner index bits are (x, y, z).
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& f : faces) {
    mesh.triangles.push_back({VertexId(f[0]), VertexId(f[1]), VertexId(f[2])});
    mesh.triangles.push_back({VertexId(f[0]), VertexId(f[2]), VertexId(f[3])});
  }
  orient_away_from_origin(mesh);
  return mesh;
}

TriangleMesh make_capsule_mesh(Real radius, Real half_length, int segments, int rings) {
  std::vector<std::pair<Real, Real>> profile;
  for (int r = 0; r <= rings; ++r) {  // northern hemisphere, ending on the equator
    const Real theta = kPi / 2 * r / rings;
    profile.emplace_back(radius * std::sin(theta), half_length + radius * std::cos(theta));
  }
  for (int r = 0; r <= rings; ++r) {  // southern hemisphere, starting on the equator
    const Real theta = kPi / 2 + kPi / 2 * r / rings;
    profile.emplace_back(radius * std::sin(theta), -half_length + radius * std::cos(theta));
  }
  profile.back().first = 0;
  return lathe(profile, segments);
}

TriangleMesh make_cylinder_mesh(Real radius, Real half_length, int segments) {
  return lathe({{0, half_length}, {radius, half_length}, {radius, -half_length}, {0, -half_length}}, segments);
}

TriangleMesh make_icosahedron(Real radius) {
  const Real phi = (1 + std::sqrt(Real(5))) / 2;
  TriangleMesh mesh;
  for (Real a : {-1.0, 1.0})
    for (Real b : {-phi, phi}) {
      mesh.vertices.emplace_back(0, a, b);
      mesh.vertices.emplace_back(a, b, 0);
      mesh.vertices.emplace_back(b, 0, a);
    }
  // The faces are the triples of mutually adjacent vertices (edge length 2).
  const int n = int(mesh.vertices.size());
  auto adjacent = [&](int i, int j) { return std::abs((mesh.vertices[i] - mesh.vertices[j]).norm() - 2) < 1e-9; };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k)
        if (adjacent(i, j) && adjacent(j, k) && adjacent(i, k))
          mesh.triangles.push_back({VertexId(i), VertexId(j), VertexId(k)});
  const Real scale = radius / std::sqrt(1 + phi * phi);
  for (Vec3& v : mesh.vertices) v *= scale;
  orient_away_from_origin(mesh);
  return mesh;
}

std::shared_ptr<const TriangleMesh> make_demo_terrain(const TerrainOptions& options, std::uint64_t seed,
                                                      std::string* name) {
  TriangleMesh mesh;
  if (!options.mesh_path.empty()) {
    mesh = boxtree::load_mesh(options.mesh_path);
    if (options.up_axis == 'y')  // a quarter turn about x: y-up becomes z-up (keeps the winding)
      for (Vec3& v : mesh.vertices) v = Vec3(v.x(), -v.z(), v.y());
    Vec3 lo = mesh.vertices.front(), hi = lo;
    for (const Vec3& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
    const Real width = std::max(hi.x() - lo.x(), hi.y() - lo.y());
    if (!(width > 0)) throw boxtree::Error(options.mesh_path + ": the mesh has no extent across x and y");
    const Real scale = options.width / width;
    const Vec3 shift((lo.x() + hi.x()) / 2, (lo.y() + hi.y()) / 2, lo.z());
    for (Vec3& v : mesh.vertices) v = (v - shift) * scale;
    if (name) *name = options.mesh_path;
  } else {
    if (options.cells < 2 || options.cells > 4096) throw boxtree::Error("--terrain-size must be in [2, 4096]");
    if (!(options.width > 0) || !(options.noise_height >= 0))
      throw boxtree::Error("the terrain's width must be positive and its noise height not negative");
    const bool flat = options.kind == TerrainKind::flat;
    mesh = boxtree::make_terrain(options.cells, options.cells, seed, options.width, flat ? 0 : options.noise_height);
    const Real half = options.width / 2;
    for (Vec3& v : mesh.vertices) {
      v.x() -= half;
      v.y() -= half;
      if (options.kind != TerrainKind::bowl) continue;
      // The bowl: flat in the middle, a rim rising towards the square's edges (a rounded square,
      // so that the corners rise as well).
      const Real u = v.x() / half, w = v.y() / half;
      const Real r = std::min(Real(1), std::pow(u * u * u * u + w * w * w * w, Real(0.25)));
      const Real rim = std::max(Real(0), r - Real(0.55)) / Real(0.45);
      v.z() += 7 * rim * rim;
    }
    const std::string size = std::to_string(options.cells) + "x" + std::to_string(options.cells);
    if (name)
      *name = options.kind == TerrainKind::bowl    ? "fractal terrain " + size
              : options.kind == TerrainKind::rough ? "fractal terrain " + size + " without the bowl"
                                                   : "flat grid " + size;
  }
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

struct TerrainProbe::Impl {
  boxtree::Tree<boxtree::Aabb> tree;
  Real top = 0;
};

TerrainProbe::TerrainProbe(std::shared_ptr<const TriangleMesh> terrain) : impl_(std::make_unique<Impl>()) {
  impl_->tree = boxtree::build_tree<boxtree::Aabb>(std::move(terrain));
  impl_->top = impl_->tree.volume(impl_->tree.root()).max.z() + 1;
}
TerrainProbe::~TerrainProbe() = default;

bool TerrainProbe::height_at(Real x, Real y, Real* z) const {
  const auto hit = boxtree::ray_closest_hit(impl_->tree, boxtree::Ray{{x, y, impl_->top}, {0, 0, -1}});
  if (!hit) return false;
  *z = impl_->top - hit->t;
  return true;
}

namespace {

// The body's shape for a draw `pick` in [0, 1) (the mixes' shares, scene.h), for the scene's
// `index`th body.
Shape shape_of(BodyMix mix, Real pick, int index) {
  if (mix == BodyMix::mixed_without_meshes) pick *= 0.88;  // the mixed shares below the meshes'
  switch (mix) {
    case BodyMix::mixed:
    case BodyMix::mixed_without_meshes:
      return pick < 0.2    ? Shape::sphere
             : pick < 0.4  ? Shape::box
             : pick < 0.55 ? Shape::capsule
             : pick < 0.7  ? Shape::cylinder
             : pick < 0.88 ? Shape::convex
                           : Shape::mesh;
    case BodyMix::sphere:
      return Shape::sphere;
    case BodyMix::box:
      return Shape::box;
    case BodyMix::capsule:
      return Shape::capsule;
    case BodyMix::cylinder:
      return Shape::cylinder;
    case BodyMix::hull8:
    case BodyMix::hull16:
    case BodyMix::hull32:
    case BodyMix::hull64:
      return Shape::convex;
    case BodyMix::mesh:
      return Shape::mesh;
    case BodyMix::primitives_in_turn: {
      const Shape in_turn[] = {Shape::sphere, Shape::box, Shape::capsule, Shape::cylinder};
      return in_turn[index % 4];
    }
  }
  return Shape::sphere;
}

// The hull bodies' points: 0 for the mixes' stretched icosahedra.
int hull_points_of(BodyMix mix) {
  switch (mix) {
    case BodyMix::hull8:
      return 8;
    case BodyMix::hull16:
      return 16;
    case BodyMix::hull32:
      return 32;
    case BodyMix::hull64:
      return 64;
    default:
      return 0;
  }
}

// `count` points on the unit sphere, spread evenly (a Fibonacci lattice: z in even steps, longitude
// by the golden angle), jittered and turned at random. Evenly spread, their hull holds the origin
// well inside (ODE's convexes need it; independent random points can all fall on one side).
// Random draws never share one call here: the order of a call's arguments is unspecified (gcc
// evaluates them last first, clang first first). They are drawn one per statement in the order
// gcc gave the former one-call forms, last argument first, so that the scenes are the ones gcc
// built before (Scene.DefaultScenesUnchanged pins them), now on every compiler.

// Three draws uniform in [lo, hi), z first, then y, then x (see above).
Vec3 uniform_z_first(boxtree::Random& random, Real lo, Real hi) {
  const Real z = random.uniform(lo, hi);
  const Real y = random.uniform(lo, hi);
  const Real x = random.uniform(lo, hi);
  return {x, y, z};
}

std::vector<Vec3> points_around_sphere(int count, boxtree::Random& random) {
  const Vec3 turn_axis = random.unit_vector();  // the axis first: see above
  const Quat turn(Eigen::AngleAxis<Real>(random.uniform(0, 2 * kPi), turn_axis));
  const Real golden_angle = kPi * (3 - std::sqrt(Real(5)));
  std::vector<Vec3> points;
  for (int k = 0; k < count; ++k) {
    const Real z = 1 - (2 * k + 1) / Real(count), r = std::sqrt(1 - z * z), phi = golden_angle * k;
    const Vec3 even(r * std::cos(phi), r * std::sin(phi), z);
    points.push_back(turn * (even + random.uniform_vec3(-0.15, 0.15)).normalized());
  }
  return points;
}

}  // namespace

Scene make_scene(const TerrainOptions& options, int count, std::uint64_t seed) {
  SceneOptions scene_options;
  scene_options.terrain = options;
  scene_options.bodies = count;
  return make_scene(scene_options, seed);
}

bool over_terrain(const Scene& scene, const Vec3& point) {
  return point.x() >= scene.bounds_min.x() && point.x() <= scene.bounds_max.x() && point.y() >= scene.bounds_min.y() &&
         point.y() <= scene.bounds_max.y();
}

Scene make_scene(const SceneOptions& options, std::uint64_t seed) {
  const int count = options.bodies;
  Scene scene;
  scene.terrain = make_demo_terrain(options.terrain, seed, &scene.terrain_name);
  scene.bounds_min = scene.bounds_max = scene.terrain->vertices.front();
  for (const Vec3& v : scene.terrain->vertices)
    scene.bounds_min = scene.bounds_min.cwiseMin(v), scene.bounds_max = scene.bounds_max.cwiseMax(v);

  // A separate stream from the terrain's, so that the bodies do not change with the terrain size.
  boxtree::Random random(seed * 0x9E3779B97F4A7C15ULL + 12345);
  scene.probe = std::make_shared<const TerrainProbe>(scene.terrain);
  const TerrainProbe& probe = *scene.probe;
  // Drop columns on a grid over the middle of the terrain, layer above layer.
  const DropLayout& layout = options.layout;
  const Real spacing = layout.spacing, layer_height = layout.layer_height;
  if (!(spacing > 0) || !(layout.max_width >= 0))
    throw boxtree::Error("the drop columns' spacing must be positive and their width not negative");
  // A square of columns as wide as the count needs, at most the middle of the terrain.
  const Real max_half =
      std::min(layout.max_width / 2, 0.3 * (scene.bounds_max - scene.bounds_min).head<2>().minCoeff());
  const int per_side =
      std::clamp(int(std::ceil(std::sqrt(Real(std::max(count, 1))))), 1, int(2 * max_half / spacing) + 1);
  const Real drop_half = spacing * (per_side - 1) / 2;
  const int per_layer = per_side * per_side;
  // Terrain height over each column (the highest point near it), computed once.
  std::vector<Real> column_top(per_layer, scene.bounds_min.z());
  const Vec3 mid = (scene.bounds_min + scene.bounds_max) / 2;
  for (int c = 0; c < per_layer; ++c) {
    const Real cx = mid.x() - drop_half + spacing * (c % per_side), cy = mid.y() - drop_half + spacing * (c / per_side);
    for (Real dx : {-layout.ground_reach, Real(0), layout.ground_reach})
      for (Real dy : {-layout.ground_reach, Real(0), layout.ground_reach}) {
        Real z;
        if (probe.height_at(cx + dx, cy + dy, &z)) column_top[c] = std::max(column_top[c], z);
      }
  }
  scene.bodies.reserve(std::size_t(std::max(count, 0)));
  for (int i = 0; i < count; ++i) {
    BodySpec b;
    b.shape = shape_of(options.mix, random.uniform(), i);
    const Real size = random.uniform(0.25, 0.55);
    const bool one_size = options.mix == BodyMix::primitives_in_turn;  // its sizes: scene.h
    TriangleMesh mesh;
    Real volume = 0;
    switch (b.shape) {
      case Shape::sphere:
        b.radius = one_size ? 0.5 : size;
        volume = 4.0 / 3.0 * kPi * b.radius * b.radius * b.radius;
        b.colour = {0.85, 0.25, 0.2};
        break;
      case Shape::box:
        b.half_extents = one_size ? Vec3(0.5, 0.4, 0.3) : Vec3(uniform_z_first(random, 0.5, 1) * size);
        volume = 8 * b.half_extents.prod();
        b.colour = {0.95, 0.7, 0.2};
        break;
      case Shape::capsule:
        b.radius = one_size ? 0.3 : 0.5 * size;
        b.half_length = one_size ? 0.5 : random.uniform(0.4, 1) * size;
        volume = kPi * b.radius * b.radius * (2 * b.half_length + 4.0 / 3.0 * b.radius);
        b.colour = {0.3, 0.55, 0.95};
        break;
      case Shape::cylinder:
        b.radius = one_size ? 0.4 : random.uniform(0.5, 0.9) * size;
        b.half_length = one_size ? 0.3 : random.uniform(0.3, 0.8) * size;
        volume = 2 * kPi * b.radius * b.radius * b.half_length;
        b.colour = {0.6, 0.35, 0.85};
        break;
      case Shape::convex: {
        // A stretched icosahedron, or the hull of points on a sphere (all are corners): any
        // linear map keeps a convex polyhedron convex.
        if (const int points = hull_points_of(options.mix)) {
          mesh = convex_hull(points_around_sphere(points, random));
        } else {
          mesh = make_icosahedron(1);
        }
        const Vec3 stretch = uniform_z_first(random, 0.6, 1.2);
        for (Vec3& v : mesh.vertices) v = v.cwiseProduct(stretch) * size;
        b.colour = {0.2, 0.75, 0.7};
        break;
      }
      case Shape::mesh:
        // Small closed non-convex meshes, for mesh-vs-mesh contacts.
        if (random.uniform() < 0.5) {
          mesh = boxtree::make_bumpy_sphere(14, 9, 0.2, random.next());
          for (Vec3& v : mesh.vertices) v *= size;
        } else {
          mesh = boxtree::make_torus(0.7 * size, 0.3 * size, 18, 8);
        }
        b.colour = {0.9, 0.45, 0.7};
        break;
    }
    if (b.shape == Shape::convex || b.shape == Shape::mesh) {
      b.half_extents = centre_bounds(mesh);
      volume = signed_volume(mesh);
      b.mesh = std::make_shared<const TriangleMesh>(std::move(mesh));
    }
    // A little variation in shade so that neighbours of one kind are told apart.
    b.colour = (b.colour * random.uniform(0.8, 1.1)).cwiseMin(1.0);
    b.mass = options.body_density * volume;
    const int layer = i / per_layer, column = i % per_layer;
    const Real x = mid.x() - drop_half + spacing * (column % per_side) + random.uniform(-layout.jitter, layout.jitter);
    const Real y = mid.y() - drop_half + spacing * (column / per_side) + random.uniform(-layout.jitter, layout.jitter);
    b.position = Vec3(x, y, column_top[column] + layout.clearance + layer_height * layer);
    const Vec3 axis = random.unit_vector();
    const Real angle = random.uniform(0, 2 * kPi);
    if (layout.random_orientation) {
      b.orientation = Quat(Eigen::AngleAxis<Real>(angle, axis));
    } else if (one_size && b.shape == Shape::capsule) {
      b.orientation = Quat(Eigen::AngleAxis<Real>(kPi / 2, Vec3::UnitY()));  // lying along x
    }
    scene.bodies.push_back(std::move(b));
  }
  return scene;
}

std::vector<Vec3> bottom_points(const BodySpec& body, const Pose& pose) {
  const auto world = [&](const Vec3& local) { return Vec3(pose.position + pose.orientation * local); };
  const Vec3 down(0, 0, -1);
  std::vector<Vec3> points;
  switch (body.shape) {
    case Shape::sphere:
      points.push_back(pose.position + down * body.radius);
      break;
    case Shape::box: {
      const Vec3& h = body.half_extents;
      for (int k = 0; k < 8; ++k)
        points.push_back(world(Vec3(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z())));
      break;
    }
    case Shape::capsule:
      for (const Real end : {-body.half_length, body.half_length})
        points.push_back(world(Vec3(0, 0, end)) + down * body.radius);
      break;
    case Shape::cylinder:
      for (int k = 0; k < 32; ++k) {
        const Real angle = (k % 16) * kPi / 8;
        points.push_back(world(Vec3(body.radius * std::cos(angle), body.radius * std::sin(angle),
                                    k < 16 ? body.half_length : -body.half_length)));
      }
      break;
    case Shape::convex:
    case Shape::mesh:
      for (const Vec3& v : body.mesh->vertices) points.push_back(world(v));
      break;
  }
  return points;
}

std::optional<Real> depth_below_terrain(const TerrainProbe& probe, const BodySpec& body, const Pose& pose) {
  if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite()) return std::nullopt;
  std::optional<Real> depth;
  for (const Vec3& p : bottom_points(body, pose)) {
    Real ground = 0;
    if (probe.height_at(p.x(), p.y(), &ground)) depth = std::max(depth.value_or(-1e30), ground - p.z());
  }
  return depth;
}

TriangleMesh render_mesh_of(const BodySpec& body) {
  switch (body.shape) {
    case Shape::sphere:
      return boxtree::make_uv_sphere(20, 12, body.radius);
    case Shape::box:
      return make_box_mesh(body.half_extents);
    case Shape::capsule:
      return make_capsule_mesh(body.radius, body.half_length, 18, 5);
    case Shape::cylinder:
      return make_cylinder_mesh(body.radius, body.half_length, 20);
    case Shape::convex:
    case Shape::mesh:
      return *body.mesh;
  }
  return {};
}

}  // namespace demo
