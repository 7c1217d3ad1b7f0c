// SPDX-License-Identifier: MIT
// The terrain merge rule (paper, Section 3.1) on top of the planar pairing (Section 2).
#include "boxtree/planar/terrain.h"

#include <algorithm>
#include <numeric>

#include "boxtree/error.h"
#include "boxtree/planar/partition.h"
#include "boxtree/planar/planar_tree.h"

namespace boxtree::planar {

TerrainCells terrain_cells(const TriangleMesh& mesh) {
  const std::size_t n = mesh.facet_count();
  std::vector<Rect> projected(n);
  for (FacetId f = 0; f < n; ++f) {
    const Vec3 lo = mesh.corner(f, 0).cwiseMin(mesh.corner(f, 1)).cwiseMin(mesh.corner(f, 2));
    const Vec3 hi = mesh.corner(f, 0).cwiseMax(mesh.corner(f, 1)).cwiseMax(mesh.corner(f, 2));
    projected[f] = Rect::from_bounds(lo.x(), lo.y(), hi.x(), hi.y());
  }
  std::vector<FacetId> order(n);
  std::iota(order.begin(), order.end(), FacetId{0});
  auto key = [&](FacetId f) {
    const Rect& r = projected[f];
    return std::array<Real, 4>{r.min.x(), r.min.y(), r.max.x(), r.max.y()};
  };
  std::sort(order.begin(), order.end(),
            [&](FacetId a, FacetId b) { return key(a) != key(b) ? key(a) < key(b) : a < b; });
  TerrainCells out;
  out.cell_of_facet.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || projected[order[i]] != projected[order[i - 1]]) out.cells.push_back(projected[order[i]]);
    out.cell_of_facet[order[i]] = std::uint32_t(out.cells.size() - 1);
  }
  try {
    validate_partition(out.cells);
  } catch (const Error& e) {
    throw Error(std::string("terrain merge rule: the facets' projected bounding rectangles must tile the plane "
                            "(facets sharing a rectangle form one cell), but: ") +
                e.what());
  }
  return out;
}

MergeOrder terrain_merge_order(const TriangleMesh& mesh) {
  const std::size_t n = mesh.facet_count();
  const TerrainCells cells = terrain_cells(mesh);
  // Build order: leaves 0..n-1 are the facets; parents are appended.
  MergeOrder order;
  order.first.reserve(n - 1);
  order.second.reserve(n - 1);
  std::uint32_t next_parent = std::uint32_t(n);
  auto merge = [&](std::uint32_t a, std::uint32_t b) {
    order.first.push_back(a);
    order.second.push_back(b);
    return next_parent++;
  };

  // 1. The facets of one cell (two triangles of a grid square) are merged first, in pairs.
  std::vector<std::vector<std::uint32_t>> members(cells.cells.size());
  for (FacetId f = 0; f < n; ++f) members[cells.cell_of_facet[f]].push_back(f);
  std::vector<std::uint32_t> planar_node(2 * cells.cells.size() - 1);
  for (std::size_t c = 0; c < members.size(); ++c) {
    std::vector<std::uint32_t> level = members[c];
    while (level.size() > 1) {
      std::vector<std::uint32_t> next;
      for (std::size_t i = 0; i + 1 < level.size(); i += 2) next.push_back(merge(level[i], level[i + 1]));
      if (level.size() % 2) next.push_back(level.back());
      level.swap(next);
    }
    planar_node[c] = level.front();
  }
  // 2. The cells are paired by the planar rule; each merge lifts into the enclosing slab.
  PlanarBuildSettings planar_settings;
  planar_settings.validate_input = false;  // terrain_cells validated them
  PlanarBuildStats planar_stats;
  const std::vector<PlanarMerge> merges = planar_pairing(cells.cells, planar_settings, &planar_stats);
  const std::size_t cell_count = cells.cells.size();
  for (std::size_t i = 0; i < merges.size(); ++i)
    planar_node[cell_count + i] = merge(planar_node[merges[i].first], planar_node[merges[i].second]);

  order.rounds = int(planar_stats.rounds.size());
  for (const PlanarRoundStats& r : planar_stats.rounds) order.candidate_pairs += r.offers;
  return order;
}

}  // namespace boxtree::planar
