// SPDX-License-Identifier: MIT
#pragma once
// Bullet <-> boxtree value conversions (btScalar may be float or double; boxtree is double).
#include <LinearMath/btTransform.h>

#include "boxtree/shapes.h"

namespace boxtree::bullet {

inline Vec3 to_vec(const btVector3& v) { return {Real(v.x()), Real(v.y()), Real(v.z())}; }
inline btVector3 to_bt(const Vec3& v) { return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())}; }
inline Mat3 to_mat(const btMatrix3x3& m) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = Real(m[i][j]);
  return r;
}
// Bullet's single-precision rotations are orthonormal only to ~1e-7; boxtree's tree-vs-tree
// query checks rotations, so re-orthonormalize.
inline RigidTransform to_rigid(const btTransform& t) {
  Mat3 r = to_mat(t.getBasis());
  const Eigen::Quaternion<Real> q(r);
  return {q.normalized().toRotationMatrix(), to_vec(t.getOrigin())};
}

}  // namespace boxtree::bullet
