// SPDX-License-Identifier: MIT
#pragma once
// Random inputs for the randomized cross-checks (a fixed seed per test: failures reproduce).
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <random>

#include <Eigen/Geometry>

#include "boxtree/shapes.h"

namespace boxtree::test {

// A test's case count times BOXTREE_TEST_SCALE (default 1; at least 1 case), for longer local runs.
inline int scaled(int n) {
  static const double scale = [] {
    const char* text = std::getenv("BOXTREE_TEST_SCALE");
    return text ? std::max(0.01, std::atof(text)) : 1.0;
  }();
  return std::max(1, static_cast<int>(n * scale));
}

// Several draws must never share one expression: C++ leaves the order in which a call's (or a
// constructor's) arguments are evaluated unspecified, and gcc evaluates them last first where
// clang goes first first, so the two compilers' CI passes would test different inputs. The tests'
// draws are one per statement (or in a braced list, which is evaluated left to right); where they
// once shared a call, they are drawn in the order gcc evaluated that call, last argument first,
// so that the inputs, and every threshold measured on them with gcc, are unchanged.

// A Vec3 of three draws, z first, then y, then x: the order gcc gave the former
// Vec3(draw(), draw(), draw()) (kept so that the inputs measured with gcc stay the same).
template <class Draw>
Vec3 vec3_z_first(Draw&& draw) {
  const Real z = draw();
  const Real y = draw();
  const Real x = draw();
  return {x, y, z};
}

struct Random {
  std::mt19937_64 engine;
  explicit Random(std::uint64_t seed) : engine(seed) {}
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine); }
  Real uniform(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(engine); }
  bool chance(Real p) { return uniform(0, 1) < p; }
  Real grid(int lo, int hi, int denominator = 1) {
    return Real(integer(lo * denominator, hi * denominator)) / denominator;
  }
  Vec3 grid_point(int lo, int hi, int denominator = 1) {
    const Real x = grid(lo, hi, denominator);
    const Real y = grid(lo, hi, denominator);
    const Real z = grid(lo, hi, denominator);
    return {x, y, z};
  }
  Vec3 point(Real lo, Real hi) {
    const Real x = uniform(lo, hi);
    const Real y = uniform(lo, hi);
    const Real z = uniform(lo, hi);
    return {x, y, z};
  }
  Vec3 unit_vector() {
    for (;;) {
      const Vec3 v = point(-1, 1);
      const Real n = v.norm();
      if (n > 0.1 && n <= 1) return v / n;
    }
  }
  Mat3 rotation() {
    // z, y, x, then w: gcc's order for the former Quaterniond(w, x, y, z) of four draws (see above).
    const Real z = uniform(-1, 1);
    const Real y = uniform(-1, 1);
    const Real x = uniform(-1, 1);
    const Real w = uniform(-1, 1);
    Eigen::Quaterniond q(w, x, y, z);
    if (q.norm() < 0.1) q = Eigen::Quaterniond(1, 0.2, 0.3, 0.4);
    return q.normalized().toRotationMatrix();
  }
  RigidTransform motion(Real reach) { return {rotation(), point(-reach, reach)}; }
};

}  // namespace boxtree::test
