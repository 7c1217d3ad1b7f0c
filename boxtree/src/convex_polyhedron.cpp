// SPDX-License-Identifier: MIT
// make_convex_polyhedron: checks a face description of a convex hull and derives what the
// separating-axis narrowphase needs (face planes, side planes, edges, edge directions).
#include "boxtree/convex_polyhedron.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "boxtree/error.h"
#include "boxtree/volume/aabb.h"

namespace boxtree {
namespace {

[[noreturn]] void fail(const std::string& what) { throw Error("make_convex_polyhedron: " + what); }

// Two unit edge directions are one class when parallel to this (sine of the angle): rounding
// leaves ~1e-16 between the parallel edges of a hull given exactly, and axes this close are the
// same axis to the separating-axis test anyway.
constexpr Real kParallel = 1e-9;

}  // namespace

ConvexPolyhedron make_convex_polyhedron(const std::vector<Vec3>& points, const std::vector<std::vector<int>>& faces) {
  if (points.size() < 4) fail("need at least 4 points, got " + std::to_string(points.size()));
  if (faces.size() < 4) fail("need at least 4 faces, got " + std::to_string(faces.size()));
  Aabb bounds = Aabb::empty();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) fail("point " + std::to_string(i) + " is not finite");
    bounds.expand(points[i]);
  }
  const Real size = bounds.extent().norm();
  if (!(size > 0)) fail("all points coincide");
  const Real tolerance = 1e-6 * size;

  ConvexPolyhedron p;
  std::vector<int> renumbered(points.size(), -1);
  std::map<std::pair<int, int>, int> directed;  // corner pair -> the face that uses it that way
  p.face_begin.push_back(0);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const std::vector<int>& loop = faces[f];
    const std::string name = "face " + std::to_string(f);
    if (loop.size() < 3) fail(name + " has fewer than 3 corners");
    if (loop.size() > std::size_t(kMaxPolyhedronFaceCorners))
      fail(name + " has more than " + std::to_string(kMaxPolyhedronFaceCorners) + " corners");
    for (std::size_t i = 0; i < loop.size(); ++i) {
      if (loop[i] < 0 || std::size_t(loop[i]) >= points.size())
        fail(name + ": corner index " + std::to_string(loop[i]) + " out of range");
      for (std::size_t j = 0; j < i; ++j)
        if (loop[j] == loop[i]) fail(name + " repeats corner " + std::to_string(loop[i]));
    }
    // Newell's normal: robust for any simple planar polygon, whatever corner is first.
    Vec3 normal = Vec3::Zero();
    Vec3 mean = Vec3::Zero();
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3& a = points[std::size_t(loop[i])];
      const Vec3& b = points[std::size_t(loop[(i + 1) % loop.size()])];
      normal += a.cross(b);
      mean += a;
    }
    mean /= Real(loop.size());
    const Real length = normal.norm();
    if (!(length > tolerance * tolerance)) fail(name + " has no area");
    normal /= length;
    Real offset = normal.dot(mean);
    for (int index : loop) {
      if (std::abs(normal.dot(points[std::size_t(index)]) - offset) > tolerance) fail(name + " is not planar");
    }
    Real above = 0;
    Real below = 0;
    for (const Vec3& x : points) {
      above = std::max(above, normal.dot(x) - offset);
      below = std::max(below, offset - normal.dot(x));
    }
    std::vector<int> ordered(loop);
    if (!(above > tolerance) && !(below > tolerance)) fail("all points are on " + name + ": the polyhedron is flat");
    if (above > tolerance) {
      if (below > tolerance) fail("points on both sides of " + name + ": not convex");
      // Wound clockwise seen from outside: turn it around.
      normal = -normal;
      offset = -offset;
      std::reverse(ordered.begin(), ordered.end());
    }
    p.faces.push_back({normal, offset});
    for (std::size_t i = 0; i < ordered.size(); ++i) {
      const int from = ordered[i];
      const int to = ordered[(i + 1) % ordered.size()];
      const Vec3 edge = points[std::size_t(to)] - points[std::size_t(from)];
      Vec3 out = edge.cross(normal);
      const Real out_length = out.norm();
      if (!(out_length > 0)) fail(name + " has a zero-length edge");
      out /= out_length;
      const Real side_offset = out.dot(points[std::size_t(from)]);
      for (int other : ordered) {
        if (out.dot(points[std::size_t(other)]) - side_offset > tolerance) fail(name + " is not convex");
      }
      if (!directed.emplace(std::pair<int, int>{from, to}, int(f)).second)
        fail("edge " + std::to_string(from) + "-" + std::to_string(to) +
             " is not shared by exactly two faces: the faces do not close");
      for (int corner : {from, to}) {
        if (renumbered[std::size_t(corner)] < 0) {
          renumbered[std::size_t(corner)] = int(p.vertices.size());
          p.vertices.push_back(points[std::size_t(corner)]);
        }
      }
      p.loops.push_back(renumbered[std::size_t(from)]);
      p.sides.push_back({out, side_offset});
    }
    p.face_begin.push_back(int(p.loops.size()));
  }
  // A closed surface: every edge once each way (two faces, opposite windings).
  for (const auto& [edge, face] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (reverse == directed.end())
      fail("edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) +
           " is not shared by exactly two faces: the faces do not close");
    if (edge.first > edge.second) continue;  // each undirected edge once
    const int from = renumbered[std::size_t(edge.first)];
    const int to = renumbered[std::size_t(edge.second)];
    const Vec3 d = (p.vertices[std::size_t(to)] - p.vertices[std::size_t(from)]).normalized();
    int direction = -1;
    for (std::size_t k = 0; k < p.directions.size() && direction < 0; ++k) {
      if (d.cross(p.directions[k]).norm() <= kParallel) direction = int(k);
    }
    if (direction < 0) {
      direction = int(p.directions.size());
      p.directions.push_back(d);
    }
    p.edge_from.push_back(from);
    p.edge_to.push_back(to);
    p.edge_direction.push_back(direction);
    const Vec3& a1 = p.faces[std::size_t(face)].normal;
    const Vec3& a2 = p.faces[std::size_t(reverse->second)].normal;
    const Vec3 arc = a1.cross(a2);
    const Vec3 along = p.vertices[std::size_t(to)] - p.vertices[std::size_t(from)];
    p.edge_cone.push_back((a1 + a2).cross(along));
    p.edge_cone.push_back(arc.cross(a1).cross(along));
    p.edge_cone.push_back(a2.cross(arc).cross(along));
  }
  // Each face's plane through its outermost corner (the mean of its loop is within the
  // planarity tolerance of it) and the polyhedron's width along its normal.
  p.face_width.resize(p.faces.size());
  for (std::size_t f = 0; f < p.faces.size(); ++f) {
    Real lo = std::numeric_limits<Real>::infinity(), hi = -lo;
    for (const Vec3& v : p.vertices) {
      lo = std::min(lo, p.faces[f].normal.dot(v));
      hi = std::max(hi, p.faces[f].normal.dot(v));
    }
    p.faces[f].offset = hi;
    p.face_width[f] = hi - lo;
  }
  Aabb corners = Aabb::empty();
  for (const Vec3& v : p.vertices) {
    p.center += v;
    corners.expand(v);
  }
  p.center /= Real(p.vertices.size());
  p.size = corners.extent().norm();
  p.coord = std::max(corners.min.cwiseAbs().maxCoeff(), corners.max.cwiseAbs().maxCoeff());
  update_columns(p);
  return p;
}

void transform_polyhedron(const ConvexPolyhedron& in, const RigidTransform& transform, ConvexPolyhedron& out) {
  const Mat3& r = transform.rotation;
  const Vec3& t = transform.translation;
  if (r.determinant() < 0) {
    // A reflection turns every face's loop clockwise seen from outside, which the sides and edge
    // cones below are built on: the mirrored polyhedron is made anew from its moved corners
    // (make_convex_polyhedron takes either winding).
    std::vector<Vec3> points(in.vertices.size());
    for (std::size_t i = 0; i < in.vertices.size(); ++i) points[i] = r * in.vertices[i] + t;
    std::vector<std::vector<int>> faces(in.faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f)
      faces[f].assign(in.loops.begin() + in.face_begin[f], in.loops.begin() + in.face_begin[f + 1]);
    out = make_convex_polyhedron(points, faces);
    return;
  }
  out.vertices.resize(in.vertices.size());
  for (std::size_t i = 0; i < in.vertices.size(); ++i) out.vertices[i] = r * in.vertices[i] + t;
  // A plane n . x = d moves to (r n) . x = d + (r n) . t.
  const auto move = [&](const std::vector<Plane>& from, std::vector<Plane>& to) {
    to.resize(from.size());
    for (std::size_t i = 0; i < from.size(); ++i) {
      const Vec3 n = r * from[i].normal;
      to[i] = {n, from[i].offset + n.dot(t)};
    }
  };
  move(in.faces, out.faces);
  move(in.sides, out.sides);
  out.face_width = in.face_width;  // widths do not change under a rigid motion
  out.face_begin = in.face_begin;
  out.loops = in.loops;
  out.edge_from = in.edge_from;
  out.edge_to = in.edge_to;
  out.edge_direction = in.edge_direction;
  out.edge_cone.resize(in.edge_cone.size());
  for (std::size_t k = 0; k < in.edge_cone.size(); ++k) out.edge_cone[k] = r * in.edge_cone[k];
  out.directions.resize(in.directions.size());
  for (std::size_t k = 0; k < in.directions.size(); ++k) out.directions[k] = r * in.directions[k];
  out.center = r * in.center + t;
  out.size = in.size;
  Real coord = 0;
  for (const Vec3& v : out.vertices) coord = std::max(coord, v.cwiseAbs().maxCoeff());
  out.coord = coord;
  update_columns(out);
}

void update_columns(ConvexPolyhedron& p) {
  const std::size_t vertices = p.vertices.size();
  p.vertex_columns.resize(3 * vertices);
  for (std::size_t i = 0; i < vertices; ++i) {
    for (int c = 0; c < 3; ++c) p.vertex_columns[c * vertices + i] = p.vertices[i][c];
  }
  const std::size_t faces = p.faces.size();
  p.face_columns.resize(5 * faces);
  for (std::size_t f = 0; f < faces; ++f) {
    const Vec3 inward = -p.faces[f].normal;
    for (int c = 0; c < 3; ++c) p.face_columns[c * faces + f] = inward[c];
    const Real lo = -p.faces[f].offset;
    p.face_columns[3 * faces + f] = lo;
    p.face_columns[4 * faces + f] = lo + (f < p.face_width.size() ? p.face_width[f] : Real(0));
  }
  const std::size_t edges = p.edge_from.size();
  p.edge_columns.resize(12 * edges);
  for (std::size_t e = 0; e < edges; ++e) {
    const Vec3 d = p.vertices[p.edge_to[e]] - p.vertices[p.edge_from[e]];
    for (int c = 0; c < 3; ++c) p.edge_columns[c * edges + e] = d[c];
    for (int k = 0; k < 3 && 3 * e + k < p.edge_cone.size(); ++k) {
      for (int c = 0; c < 3; ++c) p.edge_columns[(3 + 3 * k + c) * edges + e] = p.edge_cone[3 * e + k][c];
    }
  }
}

}  // namespace boxtree
