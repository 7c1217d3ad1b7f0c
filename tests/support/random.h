// SPDX-License-Identifier: MIT
#pragma once
// Random inputs for the randomized cross-checks (a fixed seed per test: failures reproduce).
//
// The tests and the benchmarks have one generator: generate.h's `boxtree::Random` (splitmix64,
// the one of the procedural meshes and the demos' scenes), which maps its 64-bit words to doubles
// with its own arithmetic. The conveniences below do the same, never through <random>'s
// distributions or std::shuffle, whose algorithms each standard library chooses: a seed gives the
// same inputs with libstdc++, libc++ and MSVC.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>

#include <Eigen/Geometry>

#include "boxtree/generate.h"
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
// draws are one per statement (or in a braced list, which is evaluated left to right). Where they
// once shared a call, they are drawn in the order gcc evaluated that call, last argument first
// (z before y before x): any fixed order would do, that one is kept.

// A Vec3 of three draws, z first, then y, then x (see above).
template <class Draw>
Vec3 vec3_z_first(Draw&& draw) {
  const Real z = draw();
  const Real y = draw();
  const Real x = draw();
  return {x, y, z};
}

// boxtree::Random (next, uniform, uniform_vec3, unit_vector) and the tests' conveniences.
struct Random : boxtree::Random {
  using boxtree::Random::Random;
  // Uniform in [lo, hi], lo <= hi (the modulo's bias is below 2^-32 for the ranges tests use).
  int integer(int lo, int hi) {
    const std::uint64_t range = std::uint64_t(std::int64_t(hi) - lo) + 1;
    return static_cast<int>(lo + static_cast<std::int64_t>(next() % range));
  }
  bool chance(Real p) { return uniform() < p; }
  // Standard normal (Box-Muller: the radius drawn first, then the angle).
  Real normal() {
    const Real u = 1 - uniform();  // in (0, 1]
    const Real angle = 6.283185307179586 * uniform();
    return std::sqrt(-2 * std::log(u)) * std::cos(angle);
  }
  Real grid(int lo, int hi, int denominator = 1) {
    return Real(integer(lo * denominator, hi * denominator)) / denominator;
  }
  Vec3 grid_point(int lo, int hi, int denominator = 1) {
    const Real x = grid(lo, hi, denominator);
    const Real y = grid(lo, hi, denominator);
    const Real z = grid(lo, hi, denominator);
    return {x, y, z};
  }
  Vec3 point(Real lo, Real hi) { return uniform_vec3(lo, hi); }
  // Uniform in the box [lo, hi], x first.
  Vec3 point(const Vec3& lo, const Vec3& hi) {
    const Real x = uniform(lo.x(), hi.x());
    const Real y = uniform(lo.y(), hi.y());
    const Real z = uniform(lo.z(), hi.z());
    return {x, y, z};
  }
  Mat3 rotation() {
    // z, y, x, then w (see above).
    const Real z = uniform(-1, 1);
    const Real y = uniform(-1, 1);
    const Real x = uniform(-1, 1);
    const Real w = uniform(-1, 1);
    Eigen::Quaterniond q(w, x, y, z);
    if (q.norm() < 0.1) q = Eigen::Quaterniond(1, 0.2, 0.3, 0.4);
    return q.normalized().toRotationMatrix();
  }
  RigidTransform motion(Real reach) { return {rotation(), point(-reach, reach)}; }
  // Fisher-Yates, from the back.
  template <class It>
  void shuffle(It first, It last) {
    const auto n = std::distance(first, last);
    for (auto i = n - 1; i > 0; --i) std::iter_swap(first + i, first + integer(0, static_cast<int>(i)));
  }
};

}  // namespace boxtree::test
