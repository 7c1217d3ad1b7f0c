// SPDX-License-Identifier: MIT
#pragma once
// Axis-parallel rectangles in the plane: the boxes of the paper's Section 2.
// A rectangle is closed ([min, max] on each axis); a partition's cells are compared by their
// coordinates only (no arithmetic), so every test on them is exact.
#include <cstdint>

#include "boxtree/math.h"  // Real, Vec2

namespace boxtree::planar {

using RectId = std::uint32_t;

struct Rect {
  Vec2 min = Vec2::Zero();
  Vec2 max = Vec2::Zero();

  static Rect from_bounds(Real x0, Real y0, Real x1, Real y1) { return {Vec2(x0, y0), Vec2(x1, y1)}; }
  // Parent rule (paper, Section 2): the smallest rectangle enclosing both.
  static Rect enclosing(const Rect& a, const Rect& b) { return {a.min.cwiseMin(b.min), a.max.cwiseMax(b.max)}; }

  Real width() const { return max.x() - min.x(); }
  Real height() const { return max.y() - min.y(); }
  Real area() const { return width() * height(); }
  Vec2 center() const { return (min + max) * Real(0.5); }
  bool operator==(const Rect& o) const { return min == o.min && max == o.max; }
  bool operator!=(const Rect& o) const { return !(*this == o); }
};

// Closed containment.
inline bool contains(const Rect& r, const Vec2& p) {
  return p.x() >= r.min.x() && p.x() <= r.max.x() && p.y() >= r.min.y() && p.y() <= r.max.y();
}
inline bool contains(const Rect& outer, const Rect& inner) {
  return inner.min.x() >= outer.min.x() && inner.min.y() >= outer.min.y() && inner.max.x() <= outer.max.x() &&
         inner.max.y() <= outer.max.y();
}
// The interiors meet (touching along an edge or at a corner does not count).
inline bool interiors_overlap(const Rect& a, const Rect& b) {
  return a.min.x() < b.max.x() && b.min.x() < a.max.x() && a.min.y() < b.max.y() && b.min.y() < a.max.y();
}
// Open containment: p is in the interior.
inline bool interior_contains(const Rect& r, const Vec2& p) {
  return p.x() > r.min.x() && p.x() < r.max.x() && p.y() > r.min.y() && p.y() < r.max.y();
}

}  // namespace boxtree::planar
