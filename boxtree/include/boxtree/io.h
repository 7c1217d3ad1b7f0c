// SPDX-License-Identifier: MIT
#pragma once
// Mesh files. Formats by extension (case-insensitive): .obj (tinyobjloader), .stl (ASCII and
// binary), .ply (ASCII and binary) and .off (Assimp). Facet order is the file's; polygons with
// more than three corners are fan-triangulated in order (0,1,2), (0,2,3), ...
// Vertices are kept as in the file (no welding, no reordering).
// Precision: OBJ numbers are read exactly (std::from_chars, round-trip with save_obj). Debian's
// Assimp stores coordinates as float, so STL/PLY/OFF vertices are float-rounded (binary STL and
// binary PLY float data are exact; ASCII PLY/OFF/STL text may be off by an ulp of a float).
// Assimp 5.2 is unsafe on some malformed files (endless loops, huge allocations), so PLY, OFF
// and binary STL files are checked structurally before Assimp reads them.
#include <string>

#include "boxtree/mesh.h"

namespace boxtree {

// Loads and validates a mesh. Throws boxtree::Error with a message that starts with the file
// name and names the line or facet at fault: missing/unreadable file, unknown extension,
// malformed content, no facets, index out of range, NaN/Inf coordinates.
TriangleMesh load_mesh(const std::string& path);

// Writes a plain OBJ ("v x y z" with round-trip precision, "f i j k" 1-based). Throws on I/O errors.
void save_obj(const TriangleMesh& mesh, const std::string& path);

}  // namespace boxtree
