// SPDX-License-Identifier: MIT
#pragma once
// contact_cylinder_triangle (contact.h) for one cylinder against many triangles: what depends on
// the cylinder alone is worked out once. Not part of the public API.
#include "contact_internal.h"

namespace boxtree::detail {

// support_cylinder (contact.h) with the axis's unit direction and length worked out once: the
// same arithmetic in the same order, so the same points bit for bit.
struct CylinderSupport {
  Vec3 p0 = Vec3::Zero();
  Vec3 p1 = Vec3::Zero();
  Vec3 u = Vec3::Zero();  // (p1 - p0) / length when length > 0
  Real length = 0;        // |p1 - p0|
  Real radius = 0;

  CylinderSupport() = default;
  CylinderSupport(const Vec3& p0, const Vec3& p1, Real radius);
  Vec3 operator()(const Vec3& direction) const;
};

// contact_cylinder_triangle for one cylinder (axis p0-p1, radius) against a midphase's
// candidates: the checks of the cylinder's input, its axis frame, centre and coordinate size and
// its support functions are set up by the constructor; operator() is the per-triangle part. The
// free function builds one and calls it, so both give the same contacts bit for bit. Defined in
// contact_cylinder.cpp.
class CylinderTriangleContacts {
 public:
  CylinderTriangleContacts(const Vec3& p0, const Vec3& p1, Real radius);
  int operator()(const Vec3& a, const Vec3& b, const Vec3& c, const ContactOptions& options, ContactPoint* out) const;

 private:
  bool valid_ = false;    // finite ends and radius, radius >= 0
  CylinderSupport axis_;  // support_cylinder(p0, p1, radius, .)
  // The cylinder as the closed-form parts take it, rebuilt from p0, the unit axis and the length
  // (p1' = p0 + length u): support_cylinder(p0, p1', radius, .).
  CylinderSupport rebuilt_;
  Vec3 mid_ = Vec3::Zero();  // (p0 + p1) / 2
  Real coord_ = 0;           // max(max_abs(p0), max_abs(p1))
  // Unit vectors completing axis_.u to an orthonormal frame (when length > 0): the plane of the
  // cylinder's shadow along its axis, a disk of radius `radius` about mid_.
  Vec3 across0_ = Vec3::Zero();
  Vec3 across1_ = Vec3::Zero();
};

}  // namespace boxtree::detail
