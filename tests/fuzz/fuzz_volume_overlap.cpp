// SPDX-License-Identifier: MIT
// Fuzz target: the separating-axis overlap tests of the volume kinds against an exact reference.
// Two shapes are decoded from the input, each an axis-aligned box, an oriented box whose axes are
// a signed permutation, or a prism whose axis is a coordinate axis (a pie slice's volume), with
// every coordinate on the half-integer grid [-3, 3] (zero extents and degenerate bases included),
// and a rigid motion of the second (a signed permutation and a half-integer shift). On such input
// every operation is exact in floating point, so each overlap test (the generic polytope SAT,
// the kind-specific ones, and the two-frame ones) must give exactly the answer of an exact
// rational LP on the corners ("do the convex hulls meet?"; touching counts).
#include <array>
#include <cstdint>
#include <vector>

#include "boxtree/volume/obb.h"
#include "boxtree/volume/pie_slice.h"
#include "boxtree/volume/polytope.h"
#include "fuzz/fuzz_common.h"
#include "support/exact.h"

namespace {

using namespace boxtree;

class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t next() { return at_ < size_ ? data_[at_++] : 0; }
  Real half(int lo, int hi) { return Real(lo) + Real(next() % (2 * (hi - lo) + 1)) / 2; }  // lo, lo + 1/2, ..., hi
  Vec3 point() {
    const Real x = half(-3, 3), y = half(-3, 3), z = half(-3, 3);
    return {x, y, z};
  }
  // A rotation exact in floating point: a signed permutation with determinant +1.
  Mat3 signed_permutation() {
    static const int kPerms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    const std::uint8_t b = next();
    Mat3 m = Mat3::Zero();
    for (int i = 0; i < 3; ++i) m(i, kPerms[b % 6][i]) = (b >> (3 + i)) & 1 ? -1 : 1;
    if (m.determinant() < 0) m.col(0) = -m.col(0);
    return m;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

struct Shape {
  int kind = 0;  // 0 box, 1 oriented box, 2 prism
  Aabb aabb;
  Obb obb;
  Prism prism;
  ConvexPolytope polytope() const {
    return kind == 0 ? polytope_of(aabb) : kind == 1 ? polytope_of(obb) : polytope_of(prism);
  }
  std::vector<Vec3> corners() const {
    const ConvexPolytope p = polytope();
    return std::vector<Vec3>(p.vertices.begin(), p.vertices.begin() + p.vertex_count);
  }
};

Shape decode(Bytes& in) {
  Shape s;
  s.kind = in.next() % 3;
  if (s.kind == 0) {
    s.aabb.min = in.point();
    s.aabb.max = s.aabb.min + Vec3(in.half(0, 3), in.half(0, 3), in.half(0, 3));
  } else if (s.kind == 1) {
    s.obb.center = in.point();
    s.obb.axes = in.signed_permutation();
    s.obb.half_extents = Vec3(in.half(0, 2), in.half(0, 2), in.half(0, 2));
  } else {
    const std::uint8_t b = in.next();
    const int k = b % 3;
    const Real level = in.half(-3, 3);
    for (Vec3& corner : s.prism.base) {
      corner = in.point();
      corner[k] = level;
    }
    s.prism.axis = Vec3::Unit(k) * ((b >> 2) & 1 ? -1 : 1);
    s.prism.height = in.half(0, 3);
  }
  return s;
}

bool exact_overlap(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  std::vector<test::RPoint> pa, pb;
  for (const Vec3& p : a) pa.push_back(test::exact(p));
  for (const Vec3& p : b) pb.push_back(test::exact(p));
  return test::hulls_intersect(pa, pb);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in(data, size);
  const Shape a = decode(in);
  const Shape b = decode(in);
  const RigidTransform a_from_b{in.signed_permutation(), in.point()};

  // Same frame.
  const bool expected = exact_overlap(a.corners(), b.corners());
  FUZZ_CHECK(sat_overlap(a.polytope(), b.polytope()) == expected, "sat(a, b) != exact %d", int(expected));
  FUZZ_CHECK(sat_overlap(b.polytope(), a.polytope()) == expected, "sat(b, a) != exact %d", int(expected));
  if (a.kind == 0 && b.kind == 0) FUZZ_CHECK(overlaps(a.aabb, b.aabb) == expected, "aabb/aabb");
  if (a.kind == 0 && b.kind == 1) FUZZ_CHECK(overlaps(a.aabb, b.obb) == expected, "aabb/obb");
  if (a.kind == 1 && b.kind == 0) FUZZ_CHECK(overlaps(a.obb, b.aabb) == expected, "obb/aabb");
  if (a.kind == 1 && b.kind == 1) FUZZ_CHECK(overlaps(a.obb, b.obb) == expected, "obb/obb");
  if (a.kind == 2 && b.kind == 0) FUZZ_CHECK(overlaps(a.prism, b.aabb) == expected, "prism/aabb");
  if (a.kind == 2 && b.kind == 1) FUZZ_CHECK(overlaps(a.prism, b.obb) == expected, "prism/obb");

  // b given in its own frame: the two-frame tests against b's corners moved exactly.
  std::vector<Vec3> moved;
  for (const Vec3& p : b.corners()) moved.push_back(a_from_b.apply(p));
  const bool expected_moved = exact_overlap(a.corners(), moved);
  FUZZ_CHECK(sat_overlap(a.polytope(), b.polytope().transformed(a_from_b)) == expected_moved, "sat moved != exact %d",
             int(expected_moved));
  if (a.kind == b.kind) {
    bool got = false;
    if (a.kind == 0) got = overlaps(a.aabb, b.aabb, a_from_b);
    if (a.kind == 1) got = overlaps(a.obb, b.obb, a_from_b);
    if (a.kind == 2) got = overlaps(a.prism, b.prism, a_from_b);
    FUZZ_CHECK(got == expected_moved, "two-frame overlap of kind %d != exact %d", a.kind, int(expected_moved));
  }
  return 0;
}
