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

struct TerrainOptions {
  int cells = 128;        // per side; 2 * cells^2 facets
  std::string mesh_path;  // instead of the generated terrain
  char up_axis = 'z';     // of the mesh file: 'y' turns y-up into z-up
};

class TerrainProbe;

struct Scene {
  std::shared_ptr<const TriangleMesh> terrain;  // z up, gravity along -z
  std::string terrain_name;
  std::vector<BodySpec> bodies;
  Vec3 bounds_min = Vec3::Zero(), bounds_max = Vec3::Zero();  // of the terrain
  std::shared_ptr<const TerrainProbe> probe;                  // heights of the terrain
};

// The generated terrain: fractal value noise (boxtree::make_terrain) inside a bowl whose rim
// keeps the bodies from rolling off, 40 m across, centred on the origin; or a mesh file scaled
// to the same width. Throws boxtree::Error for unreadable meshes.
std::shared_ptr<const TriangleMesh> make_demo_terrain(const TerrainOptions& options, std::uint64_t seed,
                                                      std::string* name = nullptr);

// `count` bodies above the terrain, in layers, with random shapes, sizes, orientations and
// colours; a deterministic function of the seed.
Scene make_scene(const TerrainOptions& options, int count, std::uint64_t seed);

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
