// SPDX-License-Identifier: MIT
#pragma once
// The scalar vocabulary every other header speaks: the real type, Eigen's fixed-size vectors and
// matrices over it, and rigid transforms. Includes nothing of boxtree.
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products and rotations, used throughout

namespace boxtree {

using Real = double;
using Vec2 = Eigen::Matrix<Real, 2, 1>;
using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;

// x_a = rotation * x_b + translation. Used as `a_from_b` in tree-vs-tree queries.
struct RigidTransform {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();

  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
  RigidTransform inverse() const { return {rotation.transpose(), -(rotation.transpose() * translation)}; }
  static RigidTransform identity() { return {}; }
};

}  // namespace boxtree
