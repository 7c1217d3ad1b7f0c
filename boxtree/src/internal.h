#pragma once
// Helpers shared by several source files of the library; not part of the public API.
#include "boxtree/mesh.h"

namespace boxtree::detail {

// Separating-axis test of the box {|x_i| <= ha_i} against the box with center t, axes r.col(j)
// and half extents hb, both in the first box's frame (Gottschalk, Lin, Manocha, "OBBTree",
// SIGGRAPH 1996, Sec. 4; Ericson, Real-Time Collision Detection, 4.4.1). 15 axes, enough for
// flat boxes too. Conservative by ~1e-12 of the sizes and distance (Gottschalk's epsilon on |R|
// plus 1e-12 * |t|_1): may report boxes that close as overlapping, never the reverse. NaN input
// gives false. Defined in geometry.cpp.
bool boxes_overlap(const Vec3& ha, const Vec3& t, const Mat3& r, const Vec3& hb);

// (b1, b2, n) orthonormal for a unit n (Duff, Burgess, Christensen, Hery, Kensler, Liani,
// Villemin, "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017): branch-free of any
// threshold. Defined in volume_obb.cpp.
void orthonormal_completion(const Vec3& n, Vec3& b1, Vec3& b2);

}  // namespace boxtree::detail
