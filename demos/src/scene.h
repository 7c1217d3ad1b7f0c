// SPDX-License-Identifier: MIT
#pragma once
// The demo's scene, independent of the physics engine: a static terrain mesh and a list of
// bodies (shape, size, start pose, colour). Bullet and ODE build their worlds from it, the
// renderer draws it, and the same seed always gives the same scene.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "boxtree/mesh.h"

namespace demo {

using boxtree::Real;
using boxtree::TriangleMesh;
using boxtree::Vec3;
using Quat = Eigen::Quaternion<Real>;

enum class Shape { sphere, box, capsule, cylinder, convex, mesh };
const char* shape_name(Shape shape);

struct BodySpec {
  Shape shape = Shape::sphere;
  // sphere: radius; box: half extents; capsule and cylinder: radius, half length of the
  // straight part along local z (as ODE and Bullet's *ShapeZ have it); convex and mesh: the
  // half extents of the mesh's bounding box (the mass model of ODE).
  Real radius = 0;
  Vec3 half_extents = Vec3::Zero();
  Real half_length = 0;
  // convex: the hull's vertices and facets (a convex polyhedron with triangle faces, outward
  // counter-clockwise); mesh: a closed triangle mesh. Centred on the body origin.
  std::shared_ptr<const TriangleMesh> mesh;
  Real mass = 1;
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  Vec3 colour = Vec3::Ones();  // linear RGB in [0, 1]
};

struct Pose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
};

// The generated terrain's shape (all are TerrainOptions::width across, centred on the origin):
//   bowl   fractal value noise (TerrainOptions::noise_height high) inside a bowl whose 7 m rim
//          keeps the bodies from rolling off;
//   rough  the same noise without the bowl: bodies that roll off its edge leave the scene;
//   flat   a flat grid at z = 0, triangulated like the others.
enum class TerrainKind { bowl, rough, flat };
const char* terrain_kind_name(TerrainKind kind);

struct TerrainOptions {
  int cells = 128;  // per side; 2 * cells^2 facets
  TerrainKind kind = TerrainKind::bowl;
  // Across x and y (m); a mesh file is scaled to it. The bodies' sizes (0.25 to 0.55 m) suit 40 m.
  Real width = 40;
  Real noise_height = 4;  // of the generated bowl and rough terrains (m), at most
  std::string mesh_path;  // instead of the generated terrain
  char up_axis = 'z';     // of the mesh file: 'y' turns y-up into z-up
};

// Which bodies a scene drops:
//   mixed                 20% spheres, 20% boxes, 15% capsules, 15% cylinders, 18% convex hulls (stretched
//                         icosahedra, 12 points), 12% small closed meshes (bumpy spheres and tori);
//   mixed_without_meshes  the same shares without the meshes;
//   sphere ... mesh       one kind alone (hull8 ... hull64: hulls of 8 to 64 points on a stretched sphere);
//   primitives_in_turn    sphere, box, capsule, cylinder in turn, one size each (the same bodies on
//                         every seed, for comparing engines body by body): a sphere of radius 0.5 m,
//                         a 1 x 0.8 x 0.6 m box, a capsule of radius 0.3 m with a 1 m straight part,
//                         a cylinder of radius 0.4 m, 0.6 m long.
enum class BodyMix {
  mixed,
  mixed_without_meshes,
  sphere,
  box,
  capsule,
  cylinder,
  hull8,
  hull16,
  hull32,
  hull64,
  mesh,
  primitives_in_turn
};
const char* body_mix_name(BodyMix mix);
// The mix named by body_mix_name; false for an unknown name.
bool parse_body_mix(const std::string& name, BodyMix* mix);

// Where the bodies start: columns on a square grid over the middle of the terrain, as many per
// side as the count needs within `max_width` and the middle 60% of the terrain, filled layer by
// layer. The defaults give the demo's pile.
struct DropLayout {
  Real spacing = 1.5;       // between neighbouring columns (m)
  Real max_width = 22;      // of the square of columns (m)
  Real clearance = 1.2;     // of a first-layer body's centre above the highest ground near its column (m)
  Real ground_reach = 0.8;  // "near": the ground is probed at the column and this far along x and y (m)
  Real layer_height = 1.8;  // between layers (m)
  Real jitter = 0.25;       // each body's random offset from its column along x and y, at most (m)
  // Off: every body starts unrotated, except the capsules of BodyMix::primitives_in_turn, which
  // lie along x (the straight part level).
  bool random_orientation = true;
};

struct SceneOptions {
  TerrainOptions terrain;
  int bodies = 300;
  BodyMix mix = BodyMix::mixed;
  DropLayout layout;
  Real body_density = 500;  // kg/m^3: a body's mass is its volume times this
};

class TerrainProbe;

struct Scene {
  std::shared_ptr<const TriangleMesh> terrain;  // z up, gravity along -z
  std::string terrain_name;
  std::vector<BodySpec> bodies;
  Vec3 bounds_min = Vec3::Zero(), bounds_max = Vec3::Zero();  // of the terrain
  std::shared_ptr<const TerrainProbe> probe;                  // heights of the terrain
};

// The generated terrain (TerrainKind, from boxtree::make_terrain), or a mesh file scaled to the
// same width. Throws boxtree::Error for unreadable meshes.
std::shared_ptr<const TriangleMesh> make_demo_terrain(const TerrainOptions& options, std::uint64_t seed,
                                                      std::string* name = nullptr);

// `options.bodies` bodies of the mix above the middle of the terrain, placed by `options.layout`,
// with random shapes, sizes, orientations and colours; a deterministic function of the options
// and the seed (which also seeds the generated terrain). The defaults (bowl, mixed) give the
// demo's scene.
Scene make_scene(const SceneOptions& options, std::uint64_t seed);
// make_scene with `count` mixed bodies.
Scene make_scene(const TerrainOptions& options, int count, std::uint64_t seed);

// Whether (x, y) of `point` is over the terrain's bounding box: bodies that left it (off the edge
// of a rough or flat terrain) are no longer in the scene.
bool over_terrain(const Scene& scene, const Vec3& point);

// Height of the terrain's top surface under (x, y): a ray from above. False if there is none.
class TerrainProbe {
 public:
  explicit TerrainProbe(std::shared_ptr<const TriangleMesh> terrain);
  ~TerrainProbe();
  bool height_at(Real x, Real y, Real* z) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The points of a body at `pose` that rest on the ground, in the world: the lowest point of a
// sphere and of each capsule cap, the corners of a box, 16 points around each rim of a cylinder,
// the vertices of a convex or mesh body. Their lowest is the body's lowest point; on a slope the
// others reach the ground first. (Bullet's hulls carry a 4 cm margin outside their vertices.)
std::vector<Vec3> bottom_points(const BodySpec& body, const Pose& pose);

// How far a body is in the terrain: the largest (terrain height under a bottom point - the point's
// height) over its bottom_points with terrain under them; negative when the body is clear of the
// ground, nullopt when no point is over the terrain (or the pose is not finite).
std::optional<Real> depth_below_terrain(const TerrainProbe& probe, const BodySpec& body, const Pose& pose);

// The body's surface for drawing, in the body frame.
TriangleMesh render_mesh_of(const BodySpec& body);

// Closed meshes used by the scene (also for the hierarchy overlay).
TriangleMesh make_box_mesh(const Vec3& half_extents);
TriangleMesh make_capsule_mesh(Real radius, Real half_length, int segments, int rings);
TriangleMesh make_cylinder_mesh(Real radius, Real half_length, int segments);
TriangleMesh make_icosahedron(Real radius);

}  // namespace demo
