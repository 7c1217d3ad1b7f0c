// SPDX-License-Identifier: MIT
#pragma once
// The terrain merge rule (paper, Section 3.1): for a terrain whose facets' vertical projections
// fall into rectangular cells that tile the plane (a grid terrain such as make_terrain: the two
// triangles of a grid cell share one projected bounding rectangle), the planar pairing of
// Section 2 is applied to the cells and each node is lifted into the smallest horizontal slab
// enclosing its children. For axis-aligned boxes that lift is exactly the smallest box enclosing
// both children; other volume kinds are fitted to the same topology with their own parent rule.
//
// Selected through BuildSettings::strategy = BuildStrategy::terrain (build.h); callable directly.
#include <memory>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/planar/rect.h"
#include "boxtree/tree.h"

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

// Validates the mesh (validate_mesh) and its cells, then builds the tree by the terrain rule.
// Deterministic. stats->rounds counts the planar pairing rounds.
template <class Volume>
Tree<Volume> build_terrain_tree(std::shared_ptr<const TriangleMesh> mesh, BuildStats* stats = nullptr);

}  // namespace boxtree::planar
