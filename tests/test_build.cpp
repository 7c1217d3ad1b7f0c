// SPDX-License-Identifier: MIT
// Builder: structural invariants on every kind of mesh, the O(log n) height, determinism, errors.
#include <gtest/gtest.h>

#include <cmath>

#include "boxtree/build.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "boxtree/volume/obb.h"
#include "boxtree/volume/pie_slice.h"
#include "support/meshes.h"

namespace boxtree {
namespace {

// Height bound the builder guarantees: each round pairs at least a quarter of the nodes.
int guaranteed_height_bound(std::size_t n) {
  return n <= 1 ? 0 : int(std::ceil(std::log(double(n)) / std::log(4.0 / 3.0)));
}

void expect_valid(const Tree<Aabb>& tree, const std::string& name) {
  EXPECT_EQ(validate_tree(tree), "") << name;
  const std::size_t n = tree.facet_count();
  EXPECT_EQ(tree.node_count(), 2 * n - 1) << name;
  EXPECT_LE(tree.height(), guaranteed_height_bound(n)) << name;
}

TEST(Build, InvariantsOnProceduralMeshes) {
  for (const auto& [name, mesh] : test::procedural_meshes()) {
    for (MergeCost cost : {MergeCost::surface_area, MergeCost::volume}) {
      BuildSettings settings;
      settings.cost = cost;
      BuildStats stats;
      const Tree<Aabb> tree = build_tree<Aabb>(mesh, settings, &stats);
      expect_valid(tree, name);
      // A round at most halves the nodes and adds at most one level; a single facet takes none.
      const std::size_t n = tree.facet_count();
      if (n == 1) {
        EXPECT_EQ(stats.rounds, 0) << name;
        EXPECT_EQ(stats.candidate_pairs, 0u) << name;
      } else {
        EXPECT_GE(stats.rounds, int(std::ceil(std::log2(double(n))))) << name;
        EXPECT_GE(stats.rounds, tree.height()) << name;
        EXPECT_LE(stats.rounds, guaranteed_height_bound(n)) << name;
        EXPECT_GE(stats.candidate_pairs, n / 2) << name;
      }
    }
  }
}

// On surfaces the adjacency pairs almost every node each round: the height stays within a small
// constant of log2 n (the requirement), well below the worst-case bound.
TEST(Build, HeightNearLog2OnSurfaces) {
  const std::pair<const char*, TriangleMesh> meshes[] = {
      {"terrain_64x64", make_terrain(64, 64, 5)},
      {"sphere_128x64", make_uv_sphere(128, 64)},
      {"bumpy_sphere_100x50", make_bumpy_sphere(100, 50, 0.2, 9)},
      {"soup_8192", make_triangle_soup(8192, 2, 1.0, 0.02)},
  };
  for (const auto& [name, mesh] : meshes) {
    const Tree<Aabb> tree = build_tree<Aabb>(mesh);
    const double log2n = std::log2(double(mesh.facet_count()));
    EXPECT_LE(tree.height(), int(std::ceil(log2n)) + 4) << name << ": height " << tree.height() << ", log2 n " << log2n;
    EXPECT_EQ(validate_tree(tree), "") << name;
  }
}

TEST(Build, InvariantsOnRealMeshes) {
  BOXTREE_REQUIRE_SHARED_MESHES();
  for (const std::string& name : test::shared_mesh_names()) {
    const TriangleMesh mesh = test::load_shared_mesh(name);
    const Tree<Aabb> tree = build_tree<Aabb>(mesh);
    expect_valid(tree, name);
    const double log2n = std::log2(double(mesh.facet_count()));
    EXPECT_LE(tree.height(), int(std::ceil(log2n)) + 6) << name << ": height " << tree.height();
  }
}

TEST(Build, Deterministic) {
  const TriangleMesh mesh = make_bumpy_sphere(60, 30, 0.25, 4);
  const Tree<Aabb> a = build_tree<Aabb>(mesh);
  const Tree<Aabb> b = build_tree<Aabb>(mesh);
  ASSERT_EQ(a.node_count(), b.node_count());
  EXPECT_EQ(a.height(), b.height());
  for (NodeIndex i = 0; i < a.node_count(); ++i) {
    ASSERT_EQ(a.is_leaf(i), b.is_leaf(i));
    if (a.is_leaf(i))
      ASSERT_EQ(a.facet(i), b.facet(i));
    else
      ASSERT_EQ(a.first_child(i), b.first_child(i));
    ASSERT_EQ(a.volume(i).min, b.volume(i).min);
    ASSERT_EQ(a.volume(i).max, b.volume(i).max);
  }
}

// Parent box is the smallest box enclosing the children: equal to the union, not just containing it.
TEST(Build, ParentIsSmallestEnclosingBox) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_terrain(16, 16, 1));
  for (NodeIndex i = 0; i < tree.node_count(); ++i) {
    if (tree.is_leaf(i)) {
      const TriangleMesh& m = tree.mesh();
      const FacetId f = tree.facet(i);
      const Aabb leaf = Aabb::from_triangle(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2));
      EXPECT_EQ(tree.volume(i).min, leaf.min);
      EXPECT_EQ(tree.volume(i).max, leaf.max);
      continue;
    }
    const NodeIndex c = tree.first_child(i);
    const Aabb merged = Aabb::enclosing(tree.volume(c), tree.volume(c + 1));
    EXPECT_EQ(tree.volume(i).min, merged.min);
    EXPECT_EQ(tree.volume(i).max, merged.max);
  }
}

// Merging neighbours keeps sibling leaves adjacent on a mesh: on a regular terrain most leaf
// pairs share an edge (the paper's pairing of neighbouring facets).
TEST(Build, LeafSiblingsAreNeighbours) {
  const Tree<Aabb> tree = build_tree<Aabb>(make_terrain(32, 32, 2));
  const TriangleMesh& m = tree.mesh();
  std::size_t leaf_pairs = 0, sharing = 0;
  for (NodeIndex i = 0; i < tree.node_count(); ++i) {
    if (tree.is_leaf(i)) continue;
    const NodeIndex c = tree.first_child(i);
    if (!tree.is_leaf(c) || !tree.is_leaf(c + 1)) continue;
    ++leaf_pairs;
    int shared = 0;
    for (VertexId v : m.triangles[tree.facet(c)])
      for (VertexId w : m.triangles[tree.facet(c + 1)]) shared += v == w;
    sharing += shared >= 1;
  }
  EXPECT_GT(leaf_pairs, m.facet_count() / 3);
  EXPECT_EQ(sharing, leaf_pairs);
}

// Same shape, node by node: links and leaves equal.
template <class A, class B>
void expect_same_topology(const Tree<A>& a, const Tree<B>& b, const std::string& name) {
  ASSERT_EQ(a.node_count(), b.node_count()) << name;
  EXPECT_EQ(a.height(), b.height()) << name;
  for (NodeIndex i = 0; i < a.node_count(); ++i) {
    ASSERT_EQ(a.is_leaf(i), b.is_leaf(i)) << name << " node " << i;
    if (a.is_leaf(i))
      ASSERT_EQ(a.facet(i), b.facet(i)) << name << " node " << i;
    else
      ASSERT_EQ(a.first_child(i), b.first_child(i)) << name << " node " << i;
  }
}

// PairRanking::bounding_box ranks the oriented kinds' candidates by their bounding boxes, i.e.
// exactly as the aabb build does: the same tree shape, each parent fitted once to its children.
// PairRanking::merged_volume (the paper's rule to the letter) gives valid trees of its own shape.
TEST(Build, PairRankings) {
  const std::pair<const char*, TriangleMesh> meshes[] = {
      {"terrain_24x24", make_terrain(24, 24, 3)},
      {"bumpy_sphere_30x15", make_bumpy_sphere(30, 15, 0.2, 7)},
      {"soup_500", make_triangle_soup(500, 4, 1.0, 0.05)},
  };
  for (const auto& [name, mesh] : meshes) {
    for (MergeCost cost : {MergeCost::surface_area, MergeCost::volume}) {
      BuildSettings settings;
      settings.cost = cost;
      const Tree<Aabb> boxes = build_tree<Aabb>(mesh, settings);
      settings.ranking = PairRanking::bounding_box;
      const Tree<ObbMin> obb = build_tree<ObbMin>(mesh, settings);
      const Tree<PieMin> pie = build_tree<PieMin>(mesh, settings);
      expect_same_topology(boxes, obb, name);
      expect_same_topology(boxes, pie, name);
      EXPECT_EQ(validate_tree(obb), "") << name;
      EXPECT_EQ(validate_tree(pie), "") << name;
      settings.ranking = PairRanking::merged_volume;
      const Tree<ObbMin> obb_exact = build_tree<ObbMin>(mesh, settings);
      const Tree<PieMin> pie_exact = build_tree<PieMin>(mesh, settings);
      EXPECT_EQ(validate_tree(obb_exact), "") << name;
      EXPECT_EQ(validate_tree(pie_exact), "") << name;
      EXPECT_LE(obb_exact.height(), guaranteed_height_bound(mesh.facet_count())) << name;
      EXPECT_LE(pie_exact.height(), guaranteed_height_bound(mesh.facet_count())) << name;
    }
  }
}

// The rounds rank pairs by boxes in a frame of the mesh's own (its bounding box's corner, a
// power-of-two scale), so moving a mesh far away or scaling it by a power of two, up to the
// largest coordinates allowed, gives the same tree shape; a vertex no facet uses does not count.
TEST(Build, ShapeIndependentOfPowerOfTwoScaleAndFarAwayVertices) {
  const TriangleMesh mesh = make_bumpy_sphere(40, 20, 0.2, 3);
  for (MergeCost cost : {MergeCost::surface_area, MergeCost::volume}) {
    BuildSettings settings;
    settings.cost = cost;
    const Tree<Aabb> reference = build_tree<Aabb>(mesh, settings);
    for (const double scale : {0x1p-60, 0x1p+40, 0x1p+150}) {
      TriangleMesh scaled = mesh;
      for (Vec3& v : scaled.vertices) v *= scale;
      const Tree<Aabb> tree = build_tree<Aabb>(scaled, settings);
      expect_same_topology(reference, tree, "scale " + std::to_string(scale));
      EXPECT_EQ(validate_tree(tree), "");
    }
    TriangleMesh unused_vertex = mesh;
    unused_vertex.vertices.push_back(Vec3::Constant(1e300));
    expect_same_topology(reference, build_tree<Aabb>(unused_vertex, settings), "unused vertex");
    TriangleMesh far = mesh;
    for (Vec3& v : far.vertices) v = v * 1e40 + Vec3(1e45, -3e44, 2e44);
    const Tree<Aabb> far_tree = build_tree<Aabb>(far, settings);
    expect_valid(far_tree, "far");
  }
}

TEST(Build, RejectsBadMeshes) {
  TriangleMesh empty;
  EXPECT_THROW(build_tree<Aabb>(empty), Error);
  TriangleMesh out_of_range;
  out_of_range.vertices = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  out_of_range.triangles = {{0, 1, 3}};
  EXPECT_THROW(build_tree<Aabb>(out_of_range), Error);
  TriangleMesh nan = out_of_range;
  nan.triangles = {{0, 1, 2}};
  nan.vertices[1].x() = std::nan("");
  EXPECT_THROW(build_tree<Aabb>(nan), Error);
  TriangleMesh inf = out_of_range;
  inf.triangles = {{0, 1, 2}};
  inf.vertices[2].z() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(build_tree<Aabb>(inf), Error);
  EXPECT_THROW(build_tree<Aabb>(std::shared_ptr<const TriangleMesh>()), Error);
}

// The caller's mesh is copied (by reference) or shared (by pointer), never modified: checked on
// the very objects the builder was given.
TEST(Build, LeavesCallerMeshUntouched) {
  const TriangleMesh original = make_triangle_soup(200, 5);
  TriangleMesh by_reference = original;
  const Tree<Aabb> copied = build_tree<Aabb>(by_reference);
  EXPECT_NE(&copied.mesh(), &by_reference);  // the tree holds its own copy
  EXPECT_EQ(by_reference.vertices, original.vertices);
  EXPECT_EQ(by_reference.triangles, original.triangles);
  EXPECT_EQ(copied.mesh().triangles, original.triangles);

  const auto shared = std::make_shared<const TriangleMesh>(original);
  const Tree<Aabb> tree = build_tree<Aabb>(shared);
  EXPECT_EQ(&tree.mesh(), shared.get());
  EXPECT_EQ(shared->vertices, original.vertices);
  EXPECT_EQ(shared->triangles, original.triangles);
}

}  // namespace
}  // namespace boxtree
