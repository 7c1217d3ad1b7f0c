// SPDX-License-Identifier: MIT
// The convex-polytope description (contact_polytope.h) of boxes, triangles and convex polyhedra.
#include "contact_polytope.h"

#include <algorithm>

#include "boxtree/geometry.h"

namespace boxtree::detail {

Vec3 Polytope::closest_point(const Vec3& x) const {
  if (kind == Kind::kBox) {
    const Vec3 local = axes.transpose() * (x - center);
    return center + axes * local.cwiseMax(-half_extents).cwiseMin(half_extents);
  }
  if (kind == Kind::kTriangle) return closest_point_on_triangle(x, vertices[0], vertices[1], vertices[2]);
  Vec3 best = vertices[0];
  Real best_distance = kInf;
  for (int f = 0; f < face_count; ++f) {
    const Vec3& apex = vertices[loops[face_begin[f]]];
    for (int k = face_begin[f] + 1; k + 1 < face_begin[f + 1]; ++k) {
      const Vec3 y = closest_point_on_triangle(x, apex, vertices[loops[k]], vertices[loops[k + 1]]);
      const Real d = (y - x).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best = y;
      }
    }
  }
  return best;
}

namespace {

// An empty description (all counts zero) over the arrays of `arrays`.
Polytope over(PolytopeArrays& arrays, Polytope::Kind kind) {
  Polytope p;
  p.kind = kind;
  p.vertices = arrays.vertices;
  p.edge_from = arrays.edge_from;
  p.edge_to = arrays.edge_to;
  p.edge_direction = arrays.edge_direction;
  p.directions = arrays.directions;
  p.faces = arrays.faces;
  p.face_begin = arrays.face_begin;
  p.sides = arrays.sides;
  p.bounds = arrays.bounds;
  return p;
}

}  // namespace

Polytope polytope_of_box(const Obb& box, PolytopeArrays& arrays) {
  Polytope p = over(arrays, Polytope::Kind::kBox);
  p.bounds = arrays.faces;  // a box is the intersection of its faces' half-spaces
  const Vec3& c = box.center;
  const Vec3 h = box.half_extents.cwiseAbs();
  p.center = c;
  p.vertex_count = 8;
  for (int i = 0; i < 8; ++i) {
    Vec3 x = c;
    for (int k = 0; k < 3; ++k) x += ((i >> k) & 1 ? h[k] : -h[k]) * box.axes.col(k);
    arrays.vertices[i] = x;
  }
  p.direction_count = 3;
  for (int k = 0; k < 3; ++k) {
    arrays.directions[k] = box.axes.col(k);
    for (int i = 0; i < 8; ++i) {
      if ((i >> k) & 1) continue;
      arrays.edge_from[p.edge_count] = i;
      arrays.edge_to[p.edge_count] = i | (1 << k);
      arrays.edge_direction[p.edge_count] = k;
      ++p.edge_count;
    }
  }
  int side_count = 0;
  for (int k = 0; k < 3; ++k) {
    for (const Real sign : {Real(1), Real(-1)}) {
      const Vec3 n = sign * box.axes.col(k);
      arrays.face_begin[p.face_count] = side_count;
      arrays.faces[p.face_count++] = {n, n.dot(c) + h[k]};
      for (int j = 0; j < 3; ++j) {
        if (j == k) continue;
        const Vec3 m = box.axes.col(j);
        arrays.sides[side_count++] = {m, m.dot(c) + h[j]};
        arrays.sides[side_count++] = {-m, -m.dot(c) + h[j]};
      }
    }
  }
  arrays.face_begin[p.face_count] = side_count;
  p.bound_count = p.face_count;
  p.size = 2 * h.norm();
  p.coord = max_abs(c) + h.sum();
  p.axes = box.axes;
  p.half_extents = h;
  return p;
}

Polytope polytope_of_triangle(const TriangleFrame& tri, PolytopeArrays& arrays) {
  Polytope p = over(arrays, Polytope::Kind::kTriangle);
  p.vertex_count = 3;
  for (int i = 0; i < 3; ++i) arrays.vertices[i] = tri.v[i];
  p.center = (tri.v[0] + tri.v[1] + tri.v[2]) / 3;
  for (int i = 0; i < 3; ++i) {
    const Vec3 e = tri.v[(i + 1) % 3] - tri.v[i];
    const Real len = e.norm();
    if (!(len > kTiny * tri.size)) continue;
    arrays.directions[p.direction_count] = e / len;
    arrays.edge_from[p.edge_count] = i;
    arrays.edge_to[p.edge_count] = (i + 1) % 3;
    arrays.edge_direction[p.edge_count] = p.direction_count;
    ++p.edge_count;
    ++p.direction_count;
  }
  if (!tri.degenerate) {
    HalfSpace sides[3];
    for (int i = 0; i < 3; ++i) {
      const Vec3 m = inward_wall(tri, i).normalized();
      sides[i] = {-m, -m.dot(tri.v[i])};
    }
    for (const Real sign : {Real(1), Real(-1)}) {
      const Vec3 outward = sign * tri.normal;
      arrays.face_begin[p.face_count] = 3 * p.face_count;
      arrays.faces[p.face_count] = {outward, outward.dot(tri.v[0])};
      for (int i = 0; i < 3; ++i) arrays.sides[3 * p.face_count + i] = sides[i];
      arrays.bounds[p.bound_count++] = arrays.faces[p.face_count];
      ++p.face_count;
    }
    arrays.face_begin[p.face_count] = 3 * p.face_count;
    for (int i = 0; i < 3; ++i) arrays.bounds[p.bound_count++] = sides[i];
  }
  p.size = tri.size;
  p.coord = tri.coord;
  return p;
}

Polytope polytope_of_polyhedron(const ConvexPolyhedron& polyhedron) {
  Polytope p;
  p.kind = Polytope::Kind::kPolyhedron;
  p.vertex_count = int(polyhedron.vertices.size());
  p.vertices = polyhedron.vertices.data();
  p.edge_count = int(polyhedron.edge_from.size());
  p.edge_from = polyhedron.edge_from.data();
  p.edge_to = polyhedron.edge_to.data();
  p.edge_direction = polyhedron.edge_direction.data();
  p.direction_count = int(polyhedron.directions.size());
  p.directions = polyhedron.directions.data();
  p.face_count = polyhedron.face_count();
  p.faces = polyhedron.faces.data();
  p.face_begin = polyhedron.face_begin.data();
  p.sides = polyhedron.sides.data();
  p.bound_count = polyhedron.face_count();
  p.bounds = polyhedron.faces.data();
  p.center = polyhedron.center;
  p.size = polyhedron.size;
  p.coord = polyhedron.coord;
  p.patches_hold_depth = false;
  p.face_width = polyhedron.face_width.data();
  p.loops = polyhedron.loops.data();
  p.edge_cone = polyhedron.edge_cone.data();
  // Per triangle, the parallel classes cost 2 x 3 x classes projections of all corners,
  // the cones 3 x edges tests of 3 dot products (and their branches) plus a projection
  // per pair that passes. Measured on the drop scene's stretched icosahedra (15 classes,
  // 12 corners, 30 edges): classes 18.7, cones 20.5 us per terrain call; on random hulls
  // without parallel edges (12 to 32 corners) the cones are 1.9-2.5x faster per triangle.
  p.edges_by_cone = p.direction_count * (p.vertex_count + 3) > 8 * p.edge_count;
  const auto columns = [](const std::vector<Real>& values, std::size_t expected) {
    return values.size() == expected && expected > 0 ? values.data() : nullptr;
  };
  p.vertex_columns = columns(polyhedron.vertex_columns, 3 * polyhedron.vertices.size());
  p.face_columns = polyhedron.face_width.size() == polyhedron.faces.size()
                       ? columns(polyhedron.face_columns, 5 * polyhedron.faces.size())
                       : nullptr;
  p.edge_columns = polyhedron.edge_cone.size() == 3 * polyhedron.edge_from.size()
                       ? columns(polyhedron.edge_columns, 12 * polyhedron.edge_from.size())
                       : nullptr;
  return p;
}

}  // namespace boxtree::detail
