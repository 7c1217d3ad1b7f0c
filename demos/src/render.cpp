// SPDX-License-Identifier: MIT
#include "render.h"

#include <GL/osmesa.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace demo {

namespace {

using boxtree::FacetId;
using Mat4 = Eigen::Matrix<double, 4, 4>;

Vec3 facet_normal_scaled(const TriangleMesh& mesh, FacetId f) {  // length = twice the area
  return (mesh.corner(f, 1) - mesh.corner(f, 0)).cross(mesh.corner(f, 2) - mesh.corner(f, 0));
}

template <class ColourOf>
DrawMesh build_draw_mesh(const TriangleMesh& mesh, ColourOf colour_of) {
  const std::size_t n = mesh.facet_count();
  std::vector<Vec3> facet_normals(n);
  for (std::size_t f = 0; f < n; ++f) facet_normals[f] = facet_normal_scaled(mesh, FacetId(f));
  // Facets around each vertex (compressed rows).
  std::vector<std::uint32_t> start(mesh.vertices.size() + 1, 0), around(3 * n);
  for (const auto& t : mesh.triangles)
    for (auto v : t) ++start[v + 1];
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t f = 0; f < n; ++f)
    for (auto v : mesh.triangles[f]) around[fill[v]++] = std::uint32_t(f);

  const Real crease_cos = std::cos(40.0 * 3.14159265358979 / 180);
  DrawMesh out;
  out.positions.reserve(9 * n);
  out.normals.reserve(9 * n);
  out.colours.reserve(9 * n);
  for (std::size_t f = 0; f < n; ++f) {
    const Vec3 own = facet_normals[f].normalized();
    for (int k = 0; k < 3; ++k) {
      const auto v = mesh.triangles[f][k];
      Vec3 normal = Vec3::Zero();
      for (auto i = start[v]; i < start[v + 1]; ++i) {
        const Vec3& other = facet_normals[around[i]];
        const Real length = other.norm();
        if (length > 0 && own.dot(other) >= crease_cos * length) normal += other;
      }
      if (!(normal.squaredNorm() > 0)) normal = own;
      normal.normalize();
      const Vec3& p = mesh.vertices[v];
      const Vec3 c = colour_of(p);
      for (int i = 0; i < 3; ++i) {
        out.positions.push_back(float(p[i]));
        out.normals.push_back(float(std::isfinite(normal[i]) ? normal[i] : 0));
        out.colours.push_back(float(c[i]));
      }
    }
  }
  return out;
}

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = (target - eye).normalized();
  const Vec3 s = f.cross(up).normalized();
  const Vec3 u = s.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4 perspective(Real fov_y_degrees, Real aspect, Real near_plane, Real far_plane) {
  const Real f = 1 / std::tan(fov_y_degrees * 3.14159265358979 / 360);
  Mat4 m = Mat4::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (far_plane + near_plane) / (near_plane - far_plane);
  m(2, 3) = 2 * far_plane * near_plane / (near_plane - far_plane);
  m(3, 2) = -1;
  return m;
}

}  // namespace

DrawMesh make_draw_mesh(const TriangleMesh& mesh, const Vec3& colour) {
  return build_draw_mesh(mesh, [&](const Vec3&) { return colour; });
}

DrawMesh make_terrain_draw_mesh(const TriangleMesh& mesh) {
  Real lo = mesh.vertices.front().z(), hi = lo;
  for (const Vec3& v : mesh.vertices) lo = std::min(lo, v.z()), hi = std::max(hi, v.z());
  const Real range = hi > lo ? hi - lo : 1;
  const std::array<std::pair<Real, Vec3>, 4> stops = {{{0.0, Vec3(0.28, 0.50, 0.22)},
                                                       {0.35, Vec3(0.48, 0.60, 0.28)},
                                                       {0.7, Vec3(0.55, 0.44, 0.32)},
                                                       {1.0, Vec3(0.93, 0.93, 0.90)}}};
  return build_draw_mesh(mesh, [&](const Vec3& p) {
    const Real t = (p.z() - lo) / range;
    for (std::size_t i = 1; i < stops.size(); ++i)
      if (t <= stops[i].first) {
        const Real s = (t - stops[i - 1].first) / (stops[i].first - stops[i - 1].first);
        return Vec3(stops[i - 1].second + s * (stops[i].second - stops[i - 1].second));
      }
    return stops.back().second;
  });
}

Camera frame_box(const Vec3& lo, const Vec3& hi, Real aspect, Real azimuth_degrees, Real elevation_degrees, Real fill) {
  constexpr Real deg = 3.14159265358979 / 180;
  Camera camera;
  const Vec3 centre = (lo + hi) / 2;
  const Real radius = std::max((hi - lo).norm() / 2, Real(1e-3));
  const Real az = azimuth_degrees * deg, el = elevation_degrees * deg;
  const Vec3 direction(std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), std::sin(el));
  // The (scaled) bounding sphere fits the narrower of the two fields of view.
  const Real half_fov =
      std::min(camera.fov_y_degrees / 2 * deg, std::atan(aspect * std::tan(camera.fov_y_degrees / 2 * deg)));
  const Real distance = fill * radius / std::sin(half_fov);
  camera.target = centre;
  camera.eye = centre + distance * direction;
  camera.near_plane = std::max(distance - 2 * radius, distance * 0.01);
  camera.far_plane = distance + 2 * radius;
  return camera;
}

Renderer::Renderer(int width, int height)
    : width_(width), height_(height), buffer_(std::size_t(width) * std::size_t(height) * 4) {
  if (width < 16 || height < 16 || width > 16384 || height > 16384)
    throw std::runtime_error("image size must be between 16 and 16384 pixels per side");
  // A legacy (compatibility-profile) context with a 24-bit depth buffer.
  OSMesaContext context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!context) throw std::runtime_error("OSMesa: cannot create a context");
  context_ = context;
  if (!OSMesaMakeCurrent(context, buffer_.data(), GL_UNSIGNED_BYTE, width, height)) {
    OSMesaDestroyContext(context);
    throw std::runtime_error("OSMesa: cannot make the context current");
  }
  glViewport(0, 0, width, height);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_NORMALIZE);
  glShadeModel(GL_SMOOTH);
  glEnable(GL_LIGHT0);
  const GLfloat ambient[] = {0.32f, 0.32f, 0.34f, 1}, diffuse[] = {0.78f, 0.76f, 0.72f, 1};
  glLightfv(GL_LIGHT0, GL_AMBIENT, ambient);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
  // Open meshes from files show their back faces: light them too.
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glEnable(GL_COLOR_MATERIAL);
  glEnable(GL_LINE_SMOOTH);
  glHint(GL_LINE_SMOOTH_HINT, GL_NICEST);
}

Renderer::~Renderer() { OSMesaDestroyContext(static_cast<OSMesaContext>(context_)); }

void Renderer::begin_frame(const Camera& camera) {
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // Sky: a gradient quad behind everything.
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_LIGHTING);
  glBegin(GL_QUADS);
  glColor3f(0.93f, 0.94f, 0.96f);
  glVertex2f(-1, -1);
  glVertex2f(1, -1);
  glColor3f(0.62f, 0.74f, 0.88f);
  glVertex2f(1, 1);
  glVertex2f(-1, 1);
  glEnd();
  glEnable(GL_DEPTH_TEST);

  glMatrixMode(GL_PROJECTION);
  const Mat4 projection =
      perspective(camera.fov_y_degrees, Real(width_) / height_, camera.near_plane, camera.far_plane);
  glLoadMatrixd(projection.data());
  glMatrixMode(GL_MODELVIEW);
  const Mat4 view = look_at(camera.eye, camera.target, Vec3::UnitZ());
  glLoadMatrixd(view.data());
  // A directional light fixed in the world (w = 0), from above and behind the camera's left.
  const GLfloat light_direction[] = {-0.35f, -0.55f, 0.76f, 0};
  glLightfv(GL_LIGHT0, GL_POSITION, light_direction);
}

void Renderer::draw(const DrawMesh& mesh, const Pose& pose) {
  if (mesh.corner_count() == 0) return;
  Mat4 model = Mat4::Identity();
  model.block<3, 3>(0, 0) = pose.orientation.toRotationMatrix();
  model.block<3, 1>(0, 3) = pose.position;
  glPushMatrix();
  glMultMatrixd(model.data());
  glEnable(GL_LIGHTING);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glEnableClientState(GL_COLOR_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, mesh.positions.data());
  glNormalPointer(GL_FLOAT, 0, mesh.normals.data());
  glColorPointer(3, GL_FLOAT, 0, mesh.colours.data());
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(mesh.corner_count()));
  glDisableClientState(GL_COLOR_ARRAY);
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
  glPopMatrix();
}

void Renderer::draw_translucent_polygons(const std::vector<std::vector<Vec3>>& polygons,
                                         const std::vector<Vec3>& colours, float alpha) {
  glDisable(GL_LIGHTING);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glDepthMask(GL_FALSE);  // see-through: nothing behind is hidden by them
  for (std::size_t i = 0; i < polygons.size(); ++i) {
    const Vec3& c = colours[i];
    glColor4f(float(c.x()), float(c.y()), float(c.z()), alpha);
    glBegin(GL_POLYGON);
    for (const Vec3& p : polygons[i]) glVertex3d(p.x(), p.y(), p.z());
    glEnd();
  }
  glDepthMask(GL_TRUE);
  glDisable(GL_BLEND);
}

void Renderer::draw_lines(const std::vector<Vec3>& ends, const std::vector<Vec3>& colours, float width) {
  glDisable(GL_LIGHTING);
  glLineWidth(width);
  glBegin(GL_LINES);
  for (std::size_t i = 0; i + 1 < ends.size(); i += 2) {
    const Vec3& c = colours[i / 2];
    glColor3d(c.x(), c.y(), c.z());
    glVertex3d(ends[i].x(), ends[i].y(), ends[i].z());
    glVertex3d(ends[i + 1].x(), ends[i + 1].y(), ends[i + 1].z());
  }
  glEnd();
}

void Renderer::write_png(const std::string& path) {
  glFinish();  // llvmpipe renders in threads: wait before reading the buffer
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = png_uint_32(width_);
  image.height = png_uint_32(height_);
  // RGB: the frames are opaque, and a quarter smaller without alpha.
  std::vector<std::uint8_t> rgb(std::size_t(width_) * std::size_t(height_) * 3);
  for (std::size_t i = 0, n = std::size_t(width_) * std::size_t(height_); i < n; ++i)
    for (int k = 0; k < 3; ++k) rgb[3 * i + k] = buffer_[4 * i + k];
  image.format = PNG_FORMAT_RGB;
  // A negative stride: the buffer is bottom row first, PNG rows run top to bottom.
  if (!png_image_write_to_file(&image, path.c_str(), 0, rgb.data(), -png_int_32(3 * width_), nullptr))
    throw std::runtime_error("cannot write " + path + ": " + image.message);
}

}  // namespace demo
