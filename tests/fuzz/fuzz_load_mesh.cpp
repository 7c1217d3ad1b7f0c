// SPDX-License-Identifier: MIT
// Fuzz target: load_mesh on arbitrary bytes. The first byte picks the format (.obj, .stl, .ply,
// .off); the rest is the file. Either the load throws boxtree::Error with one line that starts
// with the path, or it returns a mesh that validate_mesh accepts and whose tree validates.
// Nothing else may happen: no crash, hang, sanitizer report or other exception.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>

#include "boxtree/build.h"
#include "boxtree/error.h"
#include "boxtree/io.h"
#include "boxtree/stats.h"
#include "boxtree/volume/aabb.h"
#include "fuzz/fuzz_common.h"

// Assimp allocates some state on the first use of each reader and keeps it (about 2.5 kB,
// once); loading one small valid file per format before fuzzing keeps libFuzzer's per-input leak
// check about our code and Assimp's per-load behaviour.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const std::string base =
      (std::filesystem::temp_directory_path() / ("boxtree_fuzz_init_" + std::to_string(getpid()))).string();
  const char* const facet =
      "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
  const std::pair<const char*, std::string> files[] = {
      {".stl", std::string("solid a\n") + facet + "endsolid a\n"},
      {".ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {".off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
  };
  for (const auto& [extension, text] : files) {
    const std::string path = base + extension;
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) continue;
    std::fwrite(text.data(), 1, text.size(), file);
    std::fclose(file);
    try {
      boxtree::load_mesh(path);
    } catch (const boxtree::Error&) {
    }
    std::remove(path.c_str());
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".obj", ".stl", ".ply", ".off"};
  static const std::string base =
      (std::filesystem::temp_directory_path() / ("boxtree_fuzz_" + std::to_string(getpid()))).string();
  const std::string path = base + kExtensions[data[0] % 4];
  {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    FUZZ_CHECK(file != nullptr, "cannot write %s", path.c_str());
    if (size > 1) std::fwrite(data + 1, 1, size - 1, file);
    std::fclose(file);
  }
  boxtree::TriangleMesh mesh;
  try {
    mesh = boxtree::load_mesh(path);
  } catch (const boxtree::Error& e) {
    const std::string message = e.what();
    FUZZ_CHECK(message.rfind(path, 0) == 0, "message does not name the file: %s", message.c_str());
    FUZZ_CHECK(message.find('\n') == std::string::npos, "message is not one line: %s", message.c_str());
    FUZZ_CHECK(message.size() > path.size() + 2, "message says nothing: %s", message.c_str());
    std::remove(path.c_str());
    return 0;
  }
  std::remove(path.c_str());
  boxtree::validate_mesh(mesh, path, /*for_tree=*/false);  // throws if the loader let anything invalid through
  FUZZ_CHECK(mesh.facet_count() > 0, "a mesh with no facets loaded");
  if (mesh.facet_count() > 20000) return 0;
  try {
    const boxtree::Tree<boxtree::Aabb> tree = boxtree::build_tree<boxtree::Aabb>(mesh);
    const std::string problem = boxtree::validate_tree(tree);
    FUZZ_CHECK(problem.empty(), "invalid tree: %s", problem.c_str());
  } catch (const boxtree::Error& e) {
    // The only mesh a loader accepts and the builder refuses: coordinates beyond +-1e50.
    FUZZ_CHECK(std::string(e.what()).find("beyond +-1e50") != std::string::npos, "build refused: %s", e.what());
  }
  return 0;
}
