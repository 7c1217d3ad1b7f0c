// SPDX-License-Identifier: MIT
#pragma once
// The terrain merge rule (paper, Section 3.1): for a terrain whose facets' vertical projections
// fall into rectangular cells that tile the plane (a grid terrain such as make_terrain: the two
// triangles of a grid cell share one projected bounding rectangle), the planar pairing of
// Section 2 is applied to the cells and each node is lifted into the smallest horizontal slab
// enclosing its children. For axis-aligned boxes that lift is exactly the smallest box enclosing
// both children; other volume kinds are fitted to the same topology with their own parent rule.
//
// Selected through BuildSettings::merge_rule = planar::terrain_merge_order (build.h).
#include <vector>

#include "boxtree/build.h"
#include "boxtree/planar/rect.h"

namespace boxtree::planar {

// The cells of a terrain: distinct projected bounding rectangles of the facets, and each
// facet's cell. Throws boxtree::Error (naming the overlapping facets' cells or the gap) if the
// distinct rectangles do not tile their bounding rectangle, i.e. the mesh is not a terrain of
// that kind.
struct TerrainCells {
  std::vector<Rect> cells;
  std::vector<std::uint32_t> cell_of_facet;
};
TerrainCells terrain_cells(const TriangleMesh& mesh);

// The terrain rule's merge order (a MergeRule, build.h) for a valid mesh: the facets of each cell
// merged in pairs, then the cells by the planar pairing (planar_tree.h). Throws as terrain_cells.
// Deterministic. rounds counts the planar pairing rounds, candidate_pairs their offers.
MergeOrder terrain_merge_order(const TriangleMesh& mesh);

}  // namespace boxtree::planar
