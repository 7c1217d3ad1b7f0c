// SPDX-License-Identifier: MIT
#pragma once
// Collision algorithms for BoxtreeMeshShape, registered with a btCollisionDispatcher:
//  - convex body vs boxtree mesh: queries the tree with the body's tight volume (sphere, oriented
//    box, capsule; the body's box in the mesh frame for other convex shapes), computes sphere /
//    capsule / box contacts per facet with the core's analytic routines (boxtree/contact.h) and
//    falls back to Bullet's per-triangle GJK for other convex shapes;
//  - boxtree mesh vs boxtree mesh (Bullet itself has nothing for concave vs concave): the
//    tree-vs-tree query plus triangle-triangle contacts.
//
// Call once per dispatcher, before any body is added to the world (Bullet caches an algorithm
// per overlapping pair).
#include <btBulletCollisionCommon.h>

#include "boxtree/bullet/config.h"

namespace boxtree::bullet {

struct AlgorithmSettings {
  // Convex vs mesh: the analytic routines for spheres, boxes and capsules (else Bullet's GJK for
  // every candidate triangle, with the boxtree's tight-volume query still in front).
  bool analyticContacts = true;
  // Hulls whose faces Bullet has computed (btPolyhedralConvexShape::initializePolyhedralFeatures)
  // get boxtree's exact separating axes too (with analyticContacts): the least penetration of the
  // hull with its margin, and a patch of points in one step where a face rests on facets, instead
  // of one GJK/EPA point per triangle (a few mm shallower when deep). Off by default: on the drop
  // scene (500 bodies, a sixth of them 12-corner hulls) it costs 5-6% more collision time than
  // Bullet's GJK (alternating runs: 17.6-18.2 vs 18.5-19.3 ms per step; 12% before the
  // separating axes' scratch stopped being initialised per call).
  bool hullFaces = false;
  // Register the convex-vs-boxtree algorithm at all (false: Bullet's btConvexConcaveCollisionAlgorithm,
  // fed by processAllTriangles with the body's box).
  bool convexAlgorithm = true;
  // Register boxtree-vs-boxtree (mesh vs mesh).
  bool meshMeshAlgorithm = true;
};

void registerBoxtreeAlgorithms(btCollisionDispatcher* dispatcher, const AlgorithmSettings& settings = {});

// The largest algorithm object these create, for btDefaultCollisionConstructionInfo::
// m_customCollisionAlgorithmMaxElementSize (registerBoxtreeAlgorithms checks it and throws
// boxtree::Error if the dispatcher's pool is too small).
int boxtreeAlgorithmMaxSize();

}  // namespace boxtree::bullet
