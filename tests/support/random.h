// SPDX-License-Identifier: MIT
#pragma once
// Random inputs for the randomized cross-checks (a fixed seed per test: failures reproduce).
//
// The one generator of the tests and benchmarks is generate.h's splitmix64 `boxtree::Random`
// (the one the procedural meshes use). Everything below maps its 64-bit words to numbers with
// our own arithmetic, never with <random>'s distributions or std::shuffle, whose algorithms the
// standard leaves to each library: a seed gives the same inputs with libstdc++, libc++ and MSVC,
// so a failure seen on one platform reproduces on every other.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <utility>

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

// boxtree::Random (next, uniform, uniform_vec3, unit_vector) plus the tests' conveniences.
struct Random : boxtree::Random {
  using boxtree::Random::Random;
  // Uniform in [lo, hi] (lo <= hi; the modulo bias is below 2^-32 for the ranges tests use).
  int integer(int lo, int hi) {
    const std::uint64_t range = std::uint64_t(std::int64_t(hi) - lo) + 1;
    return static_cast<int>(lo + static_cast<std::int64_t>(next() % range));
  }
  bool chance(Real p) { return uniform() < p; }
  // Standard normal (Box-Muller).
  Real normal() {
    const Real u = 1 - uniform();  // in (0, 1]
    return std::sqrt(-2 * std::log(u)) * std::cos(6.283185307179586 * uniform());
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
  // Uniform in the box [lo, hi] (x, then y, then z: the draws are ordered).
  Vec3 point(const Vec3& lo, const Vec3& hi) {
    const Real x = uniform(lo.x(), hi.x());
    const Real y = uniform(lo.y(), hi.y());
    const Real z = uniform(lo.z(), hi.z());
    return {x, y, z};
  }
  Mat3 rotation() {
    const Real w = uniform(-1, 1), x = uniform(-1, 1), y = uniform(-1, 1), z = uniform(-1, 1);
    Eigen::Quaterniond q(w, x, y, z);
    if (q.norm() < 0.1) q = Eigen::Quaterniond(1, 0.2, 0.3, 0.4);
    return q.normalized().toRotationMatrix();
  }
  RigidTransform motion(Real reach) {
    const Mat3 r = rotation();
    return {r, point(-reach, reach)};
  }
  // Fisher-Yates.
  template <class It>
  void shuffle(It first, It last) {
    const auto n = std::distance(first, last);
    for (auto i = n - 1; i > 0; --i) std::iter_swap(first + i, first + integer(0, static_cast<int>(i)));
  }
};

}  // namespace boxtree::test
