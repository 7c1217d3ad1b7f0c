// SPDX-License-Identifier: MIT
#include "overlay.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "boxtree/build.h"
#include "boxtree/method.h"

namespace demo {

namespace {

using Polygon = std::vector<Vec3>;

// The faces of each volume kind, from the corners its header exposes.
void box_faces(const std::array<Vec3, 8>& c, std::vector<Polygon>& out) {
  // Corner index bits are (x, y, z) signs, as in corners(Obb).
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& f : faces) out.push_back({c[f[0]], c[f[1]], c[f[2]], c[f[3]]});
}

void faces_of(const boxtree::Aabb& box, std::vector<Polygon>& out) {
  std::array<Vec3, 8> c;
  for (int mask = 0; mask < 8; ++mask)
    c[mask] = Vec3(mask & 1 ? box.max.x() : box.min.x(), mask & 2 ? box.max.y() : box.min.y(),
                   mask & 4 ? box.max.z() : box.min.z());
  box_faces(c, out);
}

template <boxtree::PrincipalAxis K>
void faces_of(const boxtree::OrientedBox<K>& v, std::vector<Polygon>& out) {
  box_faces(boxtree::corners(v.box), out);
}

template <boxtree::PrincipalAxis K, boxtree::TriangleRule R>
void faces_of(const boxtree::PieSlice<K, R>& v, std::vector<Polygon>& out) {
  // corners(Prism): the base triangle 0, 1, 2, then the same corners swept along the axis.
  const auto c = boxtree::corners(v.prism);
  out.push_back({c[0], c[1], c[2]});
  out.push_back({c[3], c[4], c[5]});
  for (int i = 0; i < 3; ++i) out.push_back({c[i], c[(i + 1) % 3], c[(i + 1) % 3 + 3], c[i + 3]});
}

template <class L>
void faces_of(const boxtree::Hybrid<L>& v, std::vector<Polygon>& out) {
  if (v.is_box)
    faces_of(v.box, out);
  else
    faces_of(v.lower, out);
}

// A distinct, stable colour per volume (golden-ratio hue steps).
Vec3 colour_of(std::size_t i) {
  const Real h = std::fmod(0.13 + 0.618033988749895 * Real(i), 1.0) * 6;
  const Real x = 1 - std::abs(std::fmod(h, 2.0) - 1);
  Vec3 c;
  switch (int(h)) {
    case 0:
      c = {1, x, 0};
      break;
    case 1:
      c = {x, 1, 0};
      break;
    case 2:
      c = {0, 1, x};
      break;
    case 3:
      c = {0, x, 1};
      break;
    case 4:
      c = {x, 0, 1};
      break;
    default:
      c = {1, 0, x};
      break;
  }
  return 0.25 + 0.7 * c.array();
}

template <class V>
OverlayResult draw_cut(Renderer& renderer, const boxtree::Tree<V>& tree, int level, const DrawMesh& mesh_draw,
                       const std::string& path) {
  // Subtree heights: children follow their parent in a depth-first order, so a reverse pass
  // sees both children before the parent.
  std::vector<boxtree::NodeIndex> order{tree.root()};
  for (std::size_t i = 0; i < order.size(); ++i)
    if (!tree.is_leaf(order[i])) {
      order.push_back(tree.first_child(order[i]));
      order.push_back(tree.first_child(order[i]) + 1);
    }
  std::vector<int> height(tree.node_count(), 0);
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (!tree.is_leaf(*it))
      height[*it] = 1 + std::max(height[tree.first_child(*it)], height[tree.first_child(*it) + 1]);

  std::vector<Polygon> polygons;
  std::vector<Vec3> polygon_colours, edges, edge_colours;
  OverlayResult result;
  result.height = tree.height();
  std::vector<boxtree::NodeIndex> stack{tree.root()};
  while (!stack.empty()) {
    const boxtree::NodeIndex node = stack.back();
    stack.pop_back();
    if (height[node] > level) {
      stack.push_back(tree.first_child(node));
      stack.push_back(tree.first_child(node) + 1);
      continue;
    }
    const Vec3 colour = colour_of(result.volumes++);
    const std::size_t first = polygons.size();
    faces_of(tree.volume(node), polygons);
    for (std::size_t p = first; p < polygons.size(); ++p) {
      polygon_colours.push_back(colour);
      for (std::size_t k = 0; k < polygons[p].size(); ++k) {
        edges.push_back(polygons[p][k]);
        edges.push_back(polygons[p][(k + 1) % polygons[p].size()]);
        edge_colours.push_back(0.7 * colour);
      }
    }
  }
  // Frame the volumes (they reach beyond the mesh), seen from the front left and above.
  Vec3 lo = edges.front(), hi = lo;
  for (const Vec3& p : edges) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  renderer.begin_frame(frame_box(lo, hi, Real(renderer.width()) / renderer.height(), 30, 30, 0.68));
  renderer.draw(mesh_draw);
  // A faint fill tells the volumes apart where their edges cross; the edges carry the shape.
  renderer.draw_translucent_polygons(polygons, polygon_colours, 0.07f);
  renderer.draw_lines(edges, edge_colours, 2.0f);
  renderer.write_png(path);
  return result;
}

}  // namespace

OverlayResult render_overlay(Renderer& renderer, std::shared_ptr<const TriangleMesh> mesh,
                             const std::string& method_name, int level, const std::string& path) {
  const boxtree::Method method = boxtree::parse_method(method_name);
  const DrawMesh mesh_draw = make_draw_mesh(*mesh, Vec3(0.95, 0.72, 0.45));
  return boxtree::with_method(method, [&](auto tag) {
    using V = typename decltype(tag)::type;
    const auto tree = boxtree::build_tree<V>(mesh, boxtree::settings_for(method));
    return draw_cut(renderer, tree, level, mesh_draw, path);
  });
}

}  // namespace demo
