// SPDX-License-Identifier: MIT
#include <boxtree/build.h>
#include <boxtree/generate.h>
#include <boxtree/query.h>
#include <boxtree/version.h>

#include <cstdio>
#include <cstring>

int main() {
  const boxtree::Tree<boxtree::Aabb> tree = boxtree::build_tree<boxtree::Aabb>(boxtree::make_uv_sphere(16, 8));
  boxtree::Ray ray;
  ray.origin = boxtree::Vec3(0, 0, 5);
  ray.direction = boxtree::Vec3(0, 0, -1);
  const auto hit = boxtree::ray_closest_hit(tree, ray);
  std::printf("consumer: boxtree %s (library %s), %zu facets, hit t = %g\n", BOXTREE_VERSION_STRING,
              boxtree::library_version(), tree.facet_count(), hit ? hit->t : -1.0);
  // Headers and library from the same install.
  if (std::strcmp(boxtree::library_version(), BOXTREE_VERSION_STRING) != 0) return 1;
  return hit && hit->t > 3.9 && hit->t < 4.0 + 1e-12 ? 0 : 1;
}
