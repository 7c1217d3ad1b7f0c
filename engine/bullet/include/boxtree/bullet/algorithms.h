// SPDX-License-Identifier: MIT
#pragma once
// Collision algorithms for BoxtreeMeshShape, registered with a btCollisionDispatcher. Both put
// the other body into the mesh's frame, call the core collider (boxtree/collider.h: the tree
// query with the body's tight volume, the per-facet narrowphase, one-sided facets, internal
// edges, the reduction to the manifold's 4 points) and hand its contacts to the manifold:
//  - convex body vs boxtree mesh: spheres, boxes, capsules and cylinders by the core's analytic
//    routines,
//    hulls with faces (hullFaces) by its separating axes, every other convex shape by Bullet's
//    own per-triangle GJK/EPA inside the collider's pipeline;
//  - boxtree mesh vs boxtree mesh (Bullet itself has nothing for concave vs concave): the
//    collider's mesh pair (meshes of different methods, scaled or mirrored meshes included).
//
// Call once per dispatcher, before any body is added to the world (Bullet caches an algorithm
// per overlapping pair).
#include <btBulletCollisionCommon.h>

#include "boxtree/bullet/config.h"
#include "boxtree/collider.h"

namespace boxtree::bullet {

struct AlgorithmSettings {
  // Convex vs mesh: the analytic routines for spheres, boxes, capsules and cylinders (else Bullet's GJK for
  // every candidate triangle, with the boxtree's tight-volume query still in front).
  bool analyticContacts = true;
  // Hulls whose faces Bullet has computed (btPolyhedralConvexShape::initializePolyhedralFeatures)
  // get boxtree's exact separating axes too (with analyticContacts): the least penetration of the
  // hull with its margin, and a patch of points in one step where a face rests on facets, instead
  // of one GJK/EPA point per triangle (a few mm shallower when deep). Off by default: its cost
  // against Bullet's GJK depends on the scene (bench/RESULTS.md).
  bool hullFaces = false;
  // Register the convex-vs-boxtree algorithm at all (false: Bullet's btConvexConcaveCollisionAlgorithm,
  // fed by processAllTriangles with the body's box).
  bool convexAlgorithm = true;
  // Register boxtree-vs-boxtree (mesh vs mesh).
  bool meshMeshAlgorithm = true;
  // How two meshes' intersecting facet pairs become contacts (boxtree/collider.h). Face normals
  // by default: chosen by measurement (bench/results/mesh_contacts.txt).
  MeshContactPolicy meshContacts = MeshContactPolicy::face_normals;
  // Mesh vs mesh with temporal coherence (boxtree/collider.h's MeshPairCache): each pair's
  // algorithm keeps the front of its last tree walk (at most 384 KiB, freed with the pair) and
  // starts the next step from it. The contacts are the same bit for bit. Off by default: on a
  // resting pile of meshes it cut the volume tests to 0.37x but took 1.8x the collision time
  // (boxtree/collide_front.h).
  bool meshCoherence = false;
  // Convex vs mesh with temporal coherence (boxtree/collider.h's ConvexPairCache, in each pair's
  // algorithm, freed with the pair): a pair whose input repeats bit for bit gets its last
  // contacts again without collision work. Bullet skips pairs of sleeping bodies and wakes what
  // touches an active kinematic object, so in a default world that is a kinematic body held still
  // against a static mesh (with a filter mask that lets them meet). The contacts are the same bit
  // for bit. Shapes that go through Bullet's GJK (support mappings) collide afresh.
  bool convexCoherence = true;
};

void registerBoxtreeAlgorithms(btCollisionDispatcher* dispatcher, const AlgorithmSettings& settings = {});

// The largest algorithm object these create, for btDefaultCollisionConstructionInfo::
// m_customCollisionAlgorithmMaxElementSize (registerBoxtreeAlgorithms checks it and throws
// boxtree::Error if the dispatcher's pool is too small).
int boxtreeAlgorithmMaxSize();

}  // namespace boxtree::bullet
