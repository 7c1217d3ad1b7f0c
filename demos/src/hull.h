// SPDX-License-Identifier: MIT
#pragma once
// The convex hull of a few points (the scene's hull bodies), as a closed triangle mesh.
#include <vector>

#include "boxtree/mesh.h"

namespace demo {

// The hull's facets, counter-clockwise seen from outside; its vertices are the input points that
// are corners of the hull (points inside it or on a facet's plane are dropped). For the points of
// a scene body (up to a few hundred, in general position): an incremental hull, quadratic time.
// Throws boxtree::Error if the points span no volume.
boxtree::TriangleMesh convex_hull(const std::vector<boxtree::Vec3>& points);

}  // namespace demo
