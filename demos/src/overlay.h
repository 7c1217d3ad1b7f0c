// SPDX-License-Identifier: MIT
#pragma once
// The hierarchy overlay (after the paper's Plates 1 and 2): a mesh with the boxtree's volumes at
// one level drawn over it, translucent faces with outlined edges.
#include <string>

#include "render.h"

namespace demo {

struct OverlayResult {
  std::size_t volumes = 0;  // volumes drawn
  int height = 0;           // of the whole tree
};

// Builds the tree of `mesh` with `method` (boxtree/method.h names) and draws the cut of the tree
// at `level` (level = height of a node's subtree, leaves 0): every node of level <= `level` whose
// parent is above it, so the volumes drawn cover the whole mesh. A level above the root's draws
// the root. Writes the image to `path`. Throws boxtree::Error for an unknown method.
OverlayResult render_overlay(Renderer& renderer, std::shared_ptr<const TriangleMesh> mesh, const std::string& method,
                             int level, const std::string& path);

}  // namespace demo
