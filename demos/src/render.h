// SPDX-License-Identifier: MIT
#pragma once
// Off-screen rendering with OSMesa (Mesa's llvmpipe; no display needed) in a compatibility
// context with legacy fixed-function GL: enough for shaded meshes, lines and PNG frames.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene.h"

namespace demo {

// A mesh ready to draw: one position, normal and colour per triangle corner. Normals are
// averaged over the facets around a vertex that bend by less than about 40 degrees, so round
// shapes look smooth and edges stay sharp.
struct DrawMesh {
  std::vector<float> positions, normals, colours;  // 3 floats per corner
  std::size_t corner_count() const { return positions.size() / 3; }
};
DrawMesh make_draw_mesh(const TriangleMesh& mesh, const Vec3& colour);
// Colour by height: green lowlands, brown slopes, pale tops.
DrawMesh make_terrain_draw_mesh(const TriangleMesh& mesh);

struct Camera {
  Vec3 eye = Vec3(0, -10, 10);
  Vec3 target = Vec3::Zero();
  Real fov_y_degrees = 40;
  Real near_plane = 0.1, far_plane = 1000;
};
// A camera that looks at the box [lo, hi] from the given azimuth (degrees around z from -y)
// and elevation (degrees above the horizon), far enough back that the box's bounding sphere,
// scaled by `fill`, is in view (a box fills its bounding sphere only partly: fill < 1 crops the
// sphere's empty rim).
Camera frame_box(const Vec3& lo, const Vec3& hi, Real aspect, Real azimuth_degrees = 30, Real elevation_degrees = 40,
                 Real fill = 0.85);

class Renderer {
 public:
  // Throws std::runtime_error if no OSMesa context can be made.
  Renderer(int width, int height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }

  // Clears to a vertical gradient and sets camera and light.
  void begin_frame(const Camera& camera);
  void draw(const DrawMesh& mesh, const Pose& pose = Pose());
  // Translucent polygons (convex, given by their corners) and lines, for the overlay.
  void draw_translucent_polygons(const std::vector<std::vector<Vec3>>& polygons, const std::vector<Vec3>& colours,
                                 float alpha);
  void draw_lines(const std::vector<Vec3>& segment_ends, const std::vector<Vec3>& colours, float width);
  // Finishes the frame and writes it as an RGB PNG (throws std::runtime_error on failure).
  void write_png(const std::string& path);

 private:
  int width_, height_;
  std::vector<std::uint8_t> buffer_;  // RGBA, bottom row first (OSMesa's default)
  void* context_ = nullptr;           // OSMesaContext
};

}  // namespace demo
