// SPDX-License-Identifier: MIT
#pragma once
// Query cross-checks against brute force, templated on the volume kind so that every method
// (tests/test_methods.cpp) runs the same checks as the axis-aligned boxes (tests/test_query.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/query.h"
#include "boxtree/volume/hybrid.h"
#include "support/brute_force.h"
#include "support/meshes.h"
#include "support/random.h"

namespace boxtree::test {

// Build settings for a volume kind in tests: hybrids switch to boxes at level 3, low enough
// that every test tree has both kinds of volume.
template <class V>
BuildSettings test_settings() {
  BuildSettings settings;
  if constexpr (is_hybrid_v<V>) settings.hybrid_level = 3;
  return settings;
}

template <class V>
Tree<V> build_for_test(const TriangleMesh& mesh) {
  return build_tree<V>(mesh, test_settings<V>());
}

inline Aabb mesh_bounds(const TriangleMesh& m) {
  Aabb box;
  for (const Triangle& t : m.triangles)
    for (VertexId v : t) box.expand(m.vertices[v]);
  return box;
}

inline Vec3 random_point_near(Random& r, const Aabb& box, double margin = 0.2) {
  // Flat axes get a margin of 1e-3 of the largest extent (of 1e-3 for a point-like mesh).
  const Real largest = box.extent().maxCoeff();
  const Vec3 e = box.extent().cwiseMax(Vec3::Constant(largest > 0 ? 1e-3 * largest : 1e-3));
  Vec3 p;
  for (int i = 0; i < 3; ++i) p[i] = r.uniform(box.min[i] - margin * e[i], box.max[i] + margin * e[i]);
  return p;
}

inline Mat3 random_rotation(Random& r) {
  // z, y, x, then w: gcc's order for the former Quaterniond(w, x, y, z) of four draws (see tests/support/random.h).
  const Real z = r.uniform(-1, 1);
  const Real y = r.uniform(-1, 1);
  const Real x = r.uniform(-1, 1);
  const Real w = r.uniform(-1, 1);
  Eigen::Quaterniond q(w, x, y, z);
  q.normalize();
  return q.toRotationMatrix();
}

// `t_tolerance` > 0 (relative) is for ill-conditioned facets (slivers of aspect ratio ~1e12),
// whose hit distances are accurate to about eps x aspect ratio only: there the closest hit must be
// one of brute force's hits within that tolerance of its nearest, not necessarily the same facet.
// TreeT: Tree<V> or PackedAabbTree (anything with the query functions of query.h).
template <class TreeT>
void check_rays(const TreeT& tree, int count, std::uint64_t seed, const std::string& name, Real t_tolerance = 0) {
  const TriangleMesh& mesh = tree.mesh();
  const Aabb box = mesh_bounds(mesh);
  Random r(seed);
  int hits = 0;
  for (int i = 0; i < count; ++i) {
    Ray ray;
    ray.origin = random_point_near(r, box, 0.5);
    // Aim at a random facet's interior half the time so that many rays hit.
    if (i % 2 == 0) {
      const FacetId f = FacetId(r.next() % mesh.facet_count());
      const double u = r.uniform(), v = r.uniform() * (1 - u);
      const Vec3 target = (1 - u - v) * mesh.corner(f, 0) + u * mesh.corner(f, 1) + v * mesh.corner(f, 2);
      ray.direction = (target - ray.origin) * r.uniform(0.1, 3);
    } else {
      const Real length = r.uniform(0.1, 10);  // first: see tests/support/random.h
      ray.direction = r.unit_vector() * length;
    }
    if (ray.direction.isZero(0)) continue;
    if (i % 5 == 0) ray.t_max = r.uniform(0.2, 2);  // segments
    const auto expected = brute_ray_all_hits(mesh, ray);
    QueryStats stats;
    const auto closest = ray_closest_hit(tree, ray, &stats);
    ASSERT_EQ(closest.has_value(), !expected.empty()) << name << " ray " << i;
    if (closest && t_tolerance > 0) {
      ++hits;
      EXPECT_NEAR(closest->t, expected.front().t, t_tolerance * std::abs(expected.front().t)) << name << " ray " << i;
      EXPECT_TRUE(std::any_of(expected.begin(), expected.end(),
                              [&](const RayHit& h) { return h.facet == closest->facet && h.t == closest->t; }))
          << name << " ray " << i;
    } else if (closest) {
      ++hits;
      EXPECT_EQ(closest->facet, expected.front().facet) << name << " ray " << i;
      EXPECT_EQ(closest->t, expected.front().t) << name << " ray " << i;
      EXPECT_EQ(closest->u, expected.front().u);
      EXPECT_EQ(closest->v, expected.front().v);
      EXPECT_GE(stats.leaf_tests, 1u);
    }
    const auto all = ray_all_hits(tree, ray);
    ASSERT_EQ(all.size(), expected.size()) << name << " ray " << i;
    for (std::size_t k = 0; k < all.size(); ++k) EXPECT_EQ(all[k].facet, expected[k].facet);
    const auto any = ray_any_hit(tree, ray);
    ASSERT_EQ(any.has_value(), !expected.empty());
    if (any) {
      EXPECT_TRUE(std::any_of(expected.begin(), expected.end(),
                              [&](const RayHit& h) { return h.facet == any->facet && h.t == any->t; }));
    }
  }
  if (compute_mesh_stats(mesh).degenerate_facets < mesh.facet_count()) {
    EXPECT_GT(hits, count / 4) << name << ": the test must exercise hits";
  } else {
    EXPECT_EQ(hits, 0) << name << ": degenerate facets are never hit";
  }
}

template <class V, class Shape>
void expect_overlap_matches(const Tree<V>& tree, const Shape& shape, const std::string& what) {
  QueryStats stats;
  const std::vector<FacetId> got = query_overlap(tree, shape, &stats);
  EXPECT_EQ(violations(got, brute_overlap(tree.mesh(), shape)), "") << what;
  EXPECT_LE(stats.volume_tests, 2 * tree.node_count());
  // Leaf-volume mode: the facets whose leaf boxes overlap the shape.
  std::vector<FacetId> expected_leaf;
  const TriangleMesh& m = tree.mesh();
  for (FacetId f = 0; f < m.facet_count(); ++f)
    if (overlaps(V::from_triangle(m.corner(f, 0), m.corner(f, 1), m.corner(f, 2)), shape)) expected_leaf.push_back(f);
  EXPECT_EQ(query_overlap(tree, shape, nullptr, FacetTest::leaf_volume), expected_leaf) << what << " (leaf volumes)";
}

// One query shape of each kind around a random point near `box`, sized 0.1% to 20% of its
// diagonal; every 7th oriented box is flat.
struct QueryShapes {
  Aabb aabb;
  Obb obb;
  Sphere sphere;
  Capsule capsule;
};
inline QueryShapes random_query_shapes(Random& r, const Aabb& box, int i) {
  const Vec3 c = random_point_near(r, box);
  const double s = box.extent().norm() * r.uniform(0.001, 0.2);
  QueryShapes q;
  q.aabb = Aabb::from_points(c, c + r.uniform_vec3(-s, s));
  q.obb = Obb{c, random_rotation(r), r.uniform_vec3(0, s)};
  if (i % 7 == 0) q.obb.half_extents[i % 3] = 0;
  q.sphere = Sphere{c, s};
  q.capsule = Capsule{c, c + r.unit_vector() * s * 2, s * 0.3};
  return q;
}

template <class V>
void check_overlaps(const Tree<V>& tree, int count, const std::string& name) {
  const Aabb box = mesh_bounds(tree.mesh());
  Random r(23);
  std::size_t reported = 0;
  for (int i = 0; i < count; ++i) {
    const QueryShapes q = random_query_shapes(r, box, i);
    expect_overlap_matches(tree, q.aabb, name + " aabb");
    expect_overlap_matches(tree, q.obb, name + " obb");
    expect_overlap_matches(tree, q.sphere, name + " sphere");
    expect_overlap_matches(tree, q.capsule, name + " capsule");
    reported += query_overlap(tree, q.sphere).size();
  }
  EXPECT_GT(reported, 0u) << name << ": the test must exercise overlaps";
}

// Planes (some axis-aligned: they hit flat boxes exactly) and stabbing counts at mesh corners
// and random points, against brute force.
template <class V>
void check_planes_and_stabbing(const Tree<V>& tree, int count, const std::string& name) {
  const TriangleMesh& mesh = tree.mesh();
  const Aabb box = mesh_bounds(mesh);
  Random r(31);
  for (int i = 0; i < count; ++i) {
    Plane plane{i % 8 == 0 ? Vec3(Vec3::Unit(i % 3)) : r.unit_vector(), 0};
    plane.offset = plane.normal.dot(random_point_near(r, box, 0.05));
    EXPECT_EQ(violations(query_plane(tree, plane), brute_plane(mesh, plane)), "") << name << " plane " << i;
    Vec3 p = i % 2 ? mesh.corner(FacetId(r.next() % mesh.facet_count()), 0) : random_point_near(r, box);
    // Brute force over all nodes: those containing p whose ancestors all contain it (parents
    // come before their children in the layout). Trees that keep children inside their parents
    // (validate_tree checks it) make this every node containing p.
    std::vector<char> reached(tree.node_count(), 0);
    std::size_t expected = 0;
    for (NodeIndex node = 0; node < tree.node_count(); ++node) {
      if (node != tree.root() && !reached[node]) continue;
      if (!contains(tree.volume(node), p)) continue;
      ++expected;
      if (!tree.is_leaf(node)) reached[tree.first_child(node)] = reached[tree.first_child(node) + 1] = 1;
    }
    EXPECT_EQ(stabbing_count(tree, p), expected) << name;
  }
}

// Tree vs tree at the identity and `poses - 1` random motions (translations up to `reach`),
// against all-pairs brute force. Returns the number of pairs found.
template <class TreeT>
std::size_t check_collide(const TreeT& a, const TreeT& b, int poses, Real reach, const std::string& name) {
  Random r(5);
  std::size_t total = 0;
  for (int pose = 0; pose < poses; ++pose) {
    RigidTransform t;
    if (pose > 0) {
      t.rotation = random_rotation(r);
      t.translation = r.uniform_vec3(-reach, reach);
    }
    const std::vector<FacetPair> got = collide(a, b, t);
    EXPECT_EQ(violations(got, brute_collide(a.mesh(), b.mesh(), t)), "") << name << " pose " << pose;
    total += got.size();
  }
  return total;
}

// Watertightness: a ray aimed exactly at a shared vertex or at a point on a shared edge of a
// closed mesh, along a line through an interior point, must hit. (Such a line cannot merely
// graze the surface: it passes through the interior. Rays from outside aimed at a silhouette
// edge may legitimately miss, so they are not used.) Checked for rays starting at the interior
// point and for rays starting outside, beyond the target.
template <class TreeT>
void check_watertight_tree(const TreeT& tree, const Vec3& inside, const std::string& name, int count) {
  const TriangleMesh& mesh = tree.mesh();
  Random r(17);
  int misses = 0, brute_misses = 0;
  for (int i = 0; i < count; ++i) {
    const Triangle& t = mesh.triangles[r.next() % mesh.facet_count()];
    const int k = int(r.next() % 3);
    const Vec3& p = mesh.vertices[t[k]];
    const Vec3& q = mesh.vertices[t[(k + 1) % 3]];
    const Vec3 target = i % 2 ? p : Vec3(p + (q - p) * r.uniform());  // a vertex, or a point on an edge
    Ray from_inside;
    from_inside.origin = inside;
    from_inside.direction = target - inside;
    Ray from_outside;
    from_outside.origin = target + (target - inside) * r.uniform(0.01, 3);
    from_outside.direction = inside - from_outside.origin;
    for (const Ray& ray : {from_inside, from_outside}) {
      misses += !ray_closest_hit(tree, ray).has_value();
      brute_misses += !brute_ray_closest_hit(mesh, ray).has_value();
    }
  }
  EXPECT_EQ(brute_misses, 0) << name << ": the ray-triangle test leaks";
  EXPECT_EQ(misses, 0) << name << ": the tree culls hits";
}

template <class V>
void check_watertight(const TriangleMesh& mesh, const Vec3& inside, const std::string& name, int count,
                      const BuildSettings& settings = test_settings<V>()) {
  check_watertight_tree(build_tree<V>(mesh, settings), inside, name, count);
}

// A point inside a closed mesh: just behind a facet, on the side where a generic ray crosses
// the surface an odd number of times (agreed on by several directions).
inline Vec3 inside_point(const TriangleMesh& mesh) {
  Random r(8);
  for (FacetId f = 0; f < mesh.facet_count(); f += 7) {
    const Vec3 a = mesh.corner(f, 0), b = mesh.corner(f, 1), c = mesh.corner(f, 2);
    const Vec3 n = (b - a).cross(c - a);
    if (n.norm() == 0) continue;
    const double step = 1e-3 * std::sqrt(n.norm());
    for (double sign : {-1.0, 1.0}) {
      const Vec3 p = (a + b + c) / 3 + sign * step * n.normalized();
      int odd = 0;
      for (int k = 0; k < 5; ++k) odd += brute_ray_all_hits(mesh, Ray{p, r.unit_vector()}).size() % 2;
      if (odd == 5) return p;
    }
  }
  ADD_FAILURE() << "no inside point found";
  return Vec3::Zero();
}

}  // namespace boxtree::test
