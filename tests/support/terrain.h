// SPDX-License-Identifier: MIT
#pragma once
// Probing a terrain from above, for the engine drop tests (tests/bullet, tests/ode): the ground
// height under a point and how far a body's bottom points are below it. The engines' suites
// differ only in how they list a body's bottom points (world.h, ode_scene.h).
#include <algorithm>
#include <optional>
#include <vector>

#include "boxtree/any_tree.h"

namespace boxtree::test {

// Terrain height under (x, y): the closest hit of a vertical ray from z = 1000 on a tree of the
// terrain; nullopt off the terrain.
inline std::optional<Real> terrain_height_at(const AnyTree& terrain, Real x, Real y) {
  const auto hit = terrain.ray_closest_hit(Ray{Vec3(x, y, 1000), Vec3(0, 0, -1)});
  if (!hit) return std::nullopt;
  return 1000 - hit->t;
}

// The same, -1e9 off the terrain.
inline Real terrain_height(const AnyTree& terrain, Real x, Real y) {
  return terrain_height_at(terrain, x, y).value_or(Real(-1e9));
}

// How deep a body is in the ground: the largest (terrain height under a bottom point - the
// point's height) over its bottom points with terrain under them; negative when it is clear of
// the ground, nullopt when no point is over the terrain.
inline std::optional<Real> depth_below(const AnyTree& terrain, const std::vector<Vec3>& bottom_points) {
  std::optional<Real> depth;
  for (const Vec3& p : bottom_points) {
    if (const auto ground = terrain_height_at(terrain, p.x(), p.y()))
      depth = std::max(depth.value_or(-1e30), *ground - p.z());
  }
  return depth;
}

}  // namespace boxtree::test
