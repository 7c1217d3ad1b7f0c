// SPDX-License-Identifier: MIT
// Mesh loading, saving and validation (boxtree/io.h, boxtree/mesh.h).
// Every format is checked on small files written here, facet by facet, so that facet order and
// fan triangulation are pinned; errors are checked for the file name and the specific problem.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/io.h"
#include "boxtree/mesh.h"
#include "support/files.h"
#include "support/meshes.h"

namespace fs = std::filesystem;
using boxtree::TriangleMesh;
using boxtree::Vec3;

namespace {

using Corners = std::array<Vec3, 3>;
using boxtree::test::binary_stl;
using boxtree::test::expect_load_error;
using boxtree::test::put_f32;
using boxtree::test::put_u32;

fs::path scratch_dir() { return boxtree::test::scratch_dir("mesh_io"); }

std::string write_file(const std::string& name, const std::string& bytes) {
  return boxtree::test::write_bytes(scratch_dir() / name, bytes);
}

std::vector<Corners> facet_corners(const TriangleMesh& mesh) {
  std::vector<Corners> out;
  for (boxtree::FacetId f = 0; f < mesh.facet_count(); ++f)
    out.push_back({mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)});
  return out;
}

// Exact comparison, facet by facet and corner by corner (order matters).
void expect_facets(const TriangleMesh& mesh, const std::vector<Corners>& expected) {
  const std::vector<Corners> actual = facet_corners(mesh);
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t f = 0; f < expected.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(actual[f][k], expected[f][k])
          << "facet " << f << " corner " << k << ": got (" << actual[f][k].transpose() << "), expected ("
          << expected[f][k].transpose() << ")";
    }
  }
}

void expect_validate_error(const TriangleMesh& mesh, const std::vector<std::string>& expected) {
  try {
    boxtree::validate_mesh(mesh, "hand-built");
    ADD_FAILURE() << "validate_mesh did not throw";
  } catch (const boxtree::Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("hand-built: ", 0), 0u) << message;
    for (const std::string& piece : expected) {
      EXPECT_NE(message.find(piece), std::string::npos) << "'" << piece << "' missing from: " << message;
    }
  }
}

Vec3 v3(double x, double y, double z) { return Vec3(x, y, z); }

// ---- round trips, one per format ------------------------------------------------------------------

TEST(MeshIoObj, FanOrderGroupsMaterialsAndRelativeIndices) {
  // The quad's 1-3 diagonal is the shorter one, so a "shortest diagonal" split (tinyobjloader's
  // own triangulation) would give different triangles than the fan (0,1,2),(0,2,3).
  const std::string path = write_file("order.obj",
                                      "# groups and materials interleaved; the file order must survive\n"
                                      "mtllib missing.mtl\n"
                                      "v 0 0 0\n"         // 1
                                      "v 1 0 0\n"         // 2
                                      "v 3 3 0\n"         // 3
                                      "v 0 1 0\n"         // 4
                                      "v 0.5 1.5 0.25\n"  // 5
                                      "v 2 0 -1\n"        // 6
                                      "v 2 1 0.125\n"     // 7
                                      "vt 0 0\n"
                                      "vn 0 0 1\n"
                                      "g first\n"
                                      "usemtl red\n"
                                      "f 1 2 3 4\n"
                                      "g second\n"
                                      "usemtl blue\n"
                                      "f 6/1/1 7/1/1 5//1 4/1 2\n"
                                      "usemtl red\n"
                                      "f -1 -2 -3\n"
                                      "g first\n"
                                      "f 3 2 1\n");
  const TriangleMesh mesh = boxtree::load_mesh(path);
  const Vec3 p1 = v3(0, 0, 0), p2 = v3(1, 0, 0), p3 = v3(3, 3, 0), p4 = v3(0, 1, 0), p5 = v3(0.5, 1.5, 0.25),
             p6 = v3(2, 0, -1), p7 = v3(2, 1, 0.125);
  expect_facets(mesh, {{p1, p2, p3},
                       {p1, p3, p4},  // quad
                       {p6, p7, p5},
                       {p6, p5, p4},
                       {p6, p4, p2},    // pentagon
                       {p7, p6, p5},    // -1 -2 -3
                       {p3, p2, p1}});  // back in group "first"
  EXPECT_EQ(mesh.vertices.size(), 7u);
}

TEST(MeshIoObj, CrlfBareCountLineAndUppercaseExtension) {
  // Like FCL's env.obj: CRLF line ends and a first line "vertices faces" that is no OBJ record.
  const std::string path =
      write_file("CRLF.OBJ", "4 2\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nv 1 1 1\r\nf 1 2 3\r\nf 2 4 3");
  const TriangleMesh mesh = boxtree::load_mesh(path);
  expect_facets(mesh, {{v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)}, {v3(1, 0, 0), v3(1, 1, 1), v3(0, 1, 0)}});
}

TEST(MeshIoStl, AsciiKeepsFacetOrder) {
  const std::string path = write_file("ascii.stl",
                                      "solid test\n"
                                      "facet normal 0 0 1\n outer loop\n"
                                      "  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n"
                                      " endloop\nendfacet\n"
                                      "facet normal 0 0 -1\n outer loop\n"
                                      "  vertex 0.5 0.25 -2\n  vertex 1.5e2 0 0\n  vertex -3 1 2.25\n"
                                      " endloop\nendfacet\n"
                                      "endsolid test\n");
  const TriangleMesh mesh = boxtree::load_mesh(path);
  expect_facets(mesh, {{v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)}, {v3(0.5, 0.25, -2), v3(150, 0, 0), v3(-3, 1, 2.25)}});
}

TEST(MeshIoStl, BinaryKeepsFacetOrder) {
  const std::vector<Corners> facets = {{v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)},
                                       {v3(0.5, 0.25, 0.125), v3(2, 0, 0), v3(0, 3, -4)},
                                       {v3(-1, -2, -3), v3(1e-3f, 7, 8), v3(9, 10, 11)}};
  // Many exporters start the binary header with "solid" too; the size decides.
  const std::string path = write_file("binary.stl", binary_stl(facets, "solid but binary"));
  const TriangleMesh mesh = boxtree::load_mesh(path);
  expect_facets(mesh, facets);
}

TEST(MeshIoPly, AsciiFansPolygonsInOrder) {
  const std::string path = write_file("ascii.ply",
                                      "ply\nformat ascii 1.0\ncomment polygons of 3, 5 and 4 corners\n"
                                      "element vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                                      "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n-2 0.25 3\n"
                                      "3 0 1 4\n"
                                      "5 5 0 1 2 3\n"
                                      "4 3 2 1 0\n");
  const TriangleMesh mesh = boxtree::load_mesh(path);
  const Vec3 p0 = v3(0, 0, 0), p1 = v3(1, 0, 0), p2 = v3(1, 1, 0), p3 = v3(0, 1, 0), p4 = v3(0.5, 0.5, 1),
             p5 = v3(-2, 0.25, 3);
  expect_facets(mesh, {{p0, p1, p4}, {p5, p0, p1}, {p5, p1, p2}, {p5, p2, p3}, {p3, p2, p1}, {p3, p1, p0}});
}

TEST(MeshIoPly, BinaryLittleEndianFansPolygonsInOrder) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  const std::vector<Vec3> points = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0.5), v3(0, 1, 0), v3(0.25, -0.5, 8)};
  for (const Vec3& p : points) {
    for (int i = 0; i < 3; ++i) put_f32(bytes, static_cast<float>(p[i]));
  }
  bytes += static_cast<char>(4);
  for (std::uint32_t i : {4u, 3u, 2u, 1u}) put_u32(bytes, i);
  bytes += static_cast<char>(3);
  for (std::uint32_t i : {0u, 2u, 4u}) put_u32(bytes, i);
  const TriangleMesh mesh = boxtree::load_mesh(write_file("binary.ply", bytes));
  const auto& p = points;
  expect_facets(mesh, {{p[4], p[3], p[2]}, {p[4], p[2], p[1]}, {p[0], p[2], p[4]}});
}

TEST(MeshIoPly, BigEndianAndCrlfHeaders) {
  std::string bytes =
      "ply\r\nformat binary_big_endian 1.0\r\nelement vertex 4\r\nproperty float x\r\nproperty float y\r\n"
      "property float z\r\nelement face 1\r\nproperty list uchar uint vertex_indices\r\nend_header\r\n";
  const auto put_be32 = [&](std::uint32_t v) {
    for (int i = 3; i >= 0; --i) bytes += static_cast<char>((v >> (8 * i)) & 0xff);
  };
  const std::vector<Vec3> points = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0.5), v3(0, 1, -0.25)};
  for (const Vec3& p : points) {
    for (int i = 0; i < 3; ++i) {
      const float f = static_cast<float>(p[i]);
      std::uint32_t bits;
      std::memcpy(&bits, &f, 4);
      put_be32(bits);
    }
  }
  bytes += static_cast<char>(4);
  for (std::uint32_t i : {0u, 1u, 2u, 3u}) put_be32(i);
  expect_facets(boxtree::load_mesh(write_file("big_endian.ply", bytes)),
                {{points[0], points[1], points[2]}, {points[0], points[2], points[3]}});

  const TriangleMesh ascii = boxtree::load_mesh(
      write_file("crlf.ply",
                 "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
                 "property float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
                 "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 2 1 0"));  // and no final line end
  expect_facets(ascii, {{v3(0, 1, 0), v3(1, 0, 0), v3(0, 0, 0)}});
}

TEST(MeshIoOff, QuadIsFannedInOrder) {
  const std::string path = write_file("quad.off",
                                      "OFF\n5 3 0\n0 0 0\n2 0 0\n2 2 0\n0 2 0\n1 1 1.5\n"
                                      "3 0 1 4\n4 0 1 2 3\n3 3 2 4\n");
  const TriangleMesh mesh = boxtree::load_mesh(path);
  const Vec3 p0 = v3(0, 0, 0), p1 = v3(2, 0, 0), p2 = v3(2, 2, 0), p3 = v3(0, 2, 0), p4 = v3(1, 1, 1.5);
  expect_facets(mesh, {{p0, p1, p4}, {p0, p1, p2}, {p0, p2, p3}, {p3, p2, p4}});
}

TEST(MeshIoObj, SaveThenLoadIsBitExact) {
  boxtree::Random rng(12345);
  TriangleMesh mesh;
  // Random bit patterns cover every exponent (subnormals included), plus hand-picked edge values.
  const double specials[] = {0.0,
                             -0.0,
                             0.1,
                             1.0 / 3.0,
                             std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::min(),
                             std::numeric_limits<double>::max(),
                             -std::numeric_limits<double>::max(),
                             123456789.123456789,
                             -2.5e-300};
  for (double s : specials) mesh.vertices.push_back(v3(s, -s, s * 0.5));
  while (mesh.vertices.size() < 500) {
    Vec3 p;
    for (int i = 0; i < 3; ++i) {
      do {
        const std::uint64_t bits = rng.next();
        std::memcpy(&p[i], &bits, 8);
      } while (!std::isfinite(p[i]));
    }
    mesh.vertices.push_back(p);
  }
  for (std::uint32_t i = 0; i + 2 < mesh.vertices.size(); ++i) mesh.triangles.push_back({i, i + 2, i + 1});
  const std::string path = (scratch_dir() / "round_trip.obj").string();
  boxtree::save_obj(mesh, path);
  const TriangleMesh loaded = boxtree::load_mesh(path);
  ASSERT_EQ(loaded.vertices.size(), mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    EXPECT_EQ(std::memcmp(loaded.vertices[v].data(), mesh.vertices[v].data(), 3 * sizeof(double)), 0)
        << "vertex " << v << ": " << loaded.vertices[v].transpose() << " vs " << mesh.vertices[v].transpose();
  }
  EXPECT_EQ(loaded.triangles, mesh.triangles);
}

TEST(MeshIoObj, SaveToUnwritablePathThrows) {
  TriangleMesh mesh;
  mesh.vertices = {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)};
  mesh.triangles = {{0, 1, 2}};
  const std::string path = (scratch_dir() / "no_such_dir" / "out.obj").string();
  try {
    boxtree::save_obj(mesh, path);
    ADD_FAILURE() << "save_obj did not throw";
  } catch (const boxtree::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path, 0), 0u) << e.what();
  }
}

// ---- errors -----------------------------------------------------------------------------------------

TEST(MeshIoError, MissingFile) {
  const std::string path = (scratch_dir() / "does_not_exist.obj").string();
  fs::remove(path);
  expect_load_error(path, {"cannot open", "no such file"});
}

TEST(MeshIoError, EmptyFile) {
  expect_load_error(write_file("empty.obj", ""), {"empty file"});
  expect_load_error(write_file("empty.stl", ""), {"empty file"});
}

std::string garbage(std::size_t size, std::uint64_t seed) {
  boxtree::Random rng(seed);
  std::string bytes(size, '\0');
  for (char& c : bytes) c = static_cast<char>(rng.next() & 0xff);
  return bytes;
}

TEST(MeshIoError, BinaryGarbageStl) {
  std::string bytes = garbage(1000, 1);
  bytes[80] = bytes[81] = bytes[82] = bytes[83] = '\x7f';  // the facet count: far more than 1000 bytes hold
  expect_load_error(write_file("garbage.stl", bytes), {"binary STL", "header declares"});
  expect_load_error(write_file("short_garbage.stl", garbage(40, 2)), {"not an STL file", "too short"});
}

TEST(MeshIoError, BinaryGarbageObj) {
  expect_load_error(write_file("garbage.obj", garbage(1000, 3)), {"binary data", "NUL byte"});
}

TEST(MeshIoError, TruncatedBinaryStl) {
  const std::vector<Corners> facets(4, Corners{v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)});
  std::string bytes = binary_stl(facets, "truncated");
  bytes.resize(bytes.size() - 30);
  expect_load_error(write_file("truncated.stl", bytes), {"truncated binary STL", "4 facets", "284 bytes", "254 bytes"});
}

TEST(MeshIoError, ObjIndexZero) {
  expect_load_error(write_file("index_zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 0 1 2\n"),
                    {"line 5", "facet 1", "index 0"});
}

TEST(MeshIoError, ObjIndexBeyondCountNamesTheFaceLine) {
  // The bad face is on line 3, not the last line (tinyobjloader's own warning names the last).
  expect_load_error(write_file("index_high.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\nv 0 1 0\nf 1 2 3\n\n# end\n"),
                    {"line 3", "facet 0", "vertex index 9", "out of range", "3 vertices"});
}

TEST(MeshIoError, ObjNegativeIndexBeyondRange) {
  expect_load_error(write_file("index_negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -3\nf -1 -4 -2\n"),
                    {"line 5", "facet 1", "vertex index -4", "out of range"});
}

TEST(MeshIoError, ObjMalformedNumberAndFace) {
  expect_load_error(write_file("bad_number.obj", "v 0 0 0\nv 1 0x10 0\nv 0 1 0\nf 1 2 3\n"), {"line 2", "'0x10'"});
  expect_load_error(write_file("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 two 3\n"), {"line 4", "'two'"});
  expect_load_error(write_file("two_corners.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n"),
                    {"line 5", "2 corners"});
}

TEST(MeshIoError, NanCoordinate) {
  expect_load_error(write_file("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
                    {"line 2", "vertex 1", "non-finite", "facet 0"});
  std::string stl =
      binary_stl({{v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)}, {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)}}, "nan");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::string bits;
  put_f32(bits, nan);
  stl.replace(84 + 50 + 12 + 12 + 4, 4, bits);  // second facet, second corner, y
  expect_load_error(write_file("nan.stl", stl), {"facet 1", "vertex 4", "non-finite"});
}

TEST(MeshIoError, InfCoordinate) {
  expect_load_error(write_file("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"),
                    {"line 3", "vertex 2", "non-finite"});
  // Overflowing the double range is infinite too.
  expect_load_error(write_file("overflow.obj", "v 0 0 0\nv 1 0 1e999\nv 0 1 0\nf 1 2 3\n"),
                    {"line 2", "vertex 1", "non-finite"});
}

TEST(MeshIoError, NonFiniteUnusedVertexIsAccepted) {
  const TriangleMesh mesh =
      boxtree::load_mesh(write_file("unused_nan.obj", "v nan 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 2 3 4\n"));
  EXPECT_EQ(mesh.facet_count(), 1u);
  EXPECT_EQ(boxtree::compute_mesh_stats(mesh).unused_vertices, 1u);
}

TEST(MeshIoError, VerticesButNoFaces) {
  expect_load_error(write_file("no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), {"no facets", "3 vertices"});
  expect_load_error(write_file("no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), {"no valid faces"});
}

TEST(MeshIoError, UnknownExtension) {
  expect_load_error(write_file("mesh.xyz", "v 0 0 0\n"),
                    {"unknown mesh file extension", "'.xyz'", ".obj, .stl, .ply, .off"});
  expect_load_error(write_file("no_extension", "v 0 0 0\n"), {"unknown mesh file extension", "(none)"});
}

TEST(MeshIoError, AssimpIndexProblemsAreErrors) {
  // Assimp's OFF reader clamps an out-of-range index to the last vertex and only logs it.
  expect_load_error(write_file("index_high.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 9 2\n"),
                    {"malformed OFF", "out of range"});
  expect_load_error(write_file("index_high.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                               "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n"),
                    {"polygon 1", "facet 1", "vertex index 3", "out of range"});
}

const char* const kPlyHeader =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

// Inputs on which Assimp 5.2's PLY reader hangs, reads out of bounds or silently drops data.
TEST(MeshIoError, PlyStructureIsCheckedBeforeAssimp) {
  // No end_header (Assimp loops forever).
  expect_load_error(write_file("no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"),
                    {"malformed PLY", "end_header"});
  // Truncated ASCII data (Assimp loops forever).
  expect_load_error(write_file("truncated_ascii.ply", std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1"),
                    {"line 12", "too few values", "'vertex' 2"});
  expect_load_error(write_file("missing_face.ply", std::string(kPlyHeader) + "0 0 0\n1 0 0\n0 1 0\n"),
                    {"truncated PLY", "'face'"});
  // A comment between properties (Assimp drops the properties after it).
  expect_load_error(write_file("comment_in_element.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\ncomment here\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                    {"line 6", "property after a comment"});
  // Truncated binary data, and a list length running past the end.
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 9; ++i) put_f32(bytes, static_cast<float>(i + 1));
  std::string faces = bytes;
  faces += static_cast<char>(3);
  for (std::uint32_t i : {0u, 1u, 2u}) put_u32(faces, i);
  EXPECT_EQ(boxtree::load_mesh(write_file("binary_ok.ply", faces)).facet_count(), 1u);
  expect_load_error(write_file("truncated_binary.ply", faces.substr(0, faces.size() - 3)),
                    {"truncated PLY", "'face' 0 of 1"});
  faces[bytes.size()] = static_cast<char>(200);  // list length 200
  expect_load_error(write_file("long_list.ply", faces), {"truncated PLY", "'face' 0 of 1"});
  expect_load_error(write_file("truncated_vertices.ply", bytes.substr(0, bytes.size() - 5)),
                    {"truncated PLY", "'vertex'"});
}

// Inputs on which Assimp 5.2's OFF reader allocates gigabytes or overflows its line buffer.
TEST(MeshIoError, OffStructureIsCheckedBeforeAssimp) {
  expect_load_error(write_file("huge_count.off", "OFF\n3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                    {"truncated OFF", "2000000000 faces", "6 lines"});
  expect_load_error(write_file("bad_count.off", "OFF\n3 99999999999999999999999 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                    {"malformed OFF", "bad header"});
  expect_load_error(
      write_file("long_line.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 " + std::string(5000, '0') + "\n"),
      {"line 6", "longer than 4095"});
}

TEST(MeshIoError, AssimpStaysSilent) {
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_THROW(boxtree::load_mesh(write_file("silent.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")),
               boxtree::Error);
  EXPECT_THROW(boxtree::load_mesh(write_file("silent.ply", "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n")),
               boxtree::Error);
  EXPECT_NO_THROW(boxtree::load_mesh(write_file("silent_ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")));
  const std::string out = testing::internal::GetCapturedStdout();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
}

// ---- validation and statistics ---------------------------------------------------------------------

TEST(MeshValidate, DegenerateFacetsAreAcceptedAndCounted) {
  const TriangleMesh mesh = boxtree::load_mesh(write_file("degenerate.obj",
                                                          "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 4 0 0\nv 9 9 9\nv -1 -1 5\n"
                                                          "f 1 2 3\n"     // area 2
                                                          "f 1 2 2\n"     // repeated index
                                                          "f 1 2 4\n"     // collinear corners
                                                          "f 2 2 2\n"));  // a point
  const boxtree::MeshStats stats = boxtree::compute_mesh_stats(mesh);
  EXPECT_EQ(stats.facets, 4u);
  EXPECT_EQ(stats.vertices, 6u);
  EXPECT_EQ(stats.degenerate_facets, 3u);
  EXPECT_EQ(stats.unused_vertices, 2u);
  EXPECT_EQ(stats.bounds_min, v3(0, 0, 0));  // the unused (9,9,9) and (-1,-1,5) do not count
  EXPECT_EQ(stats.bounds_max, v3(4, 2, 0));
  EXPECT_DOUBLE_EQ(stats.total_area, 2.0);
  EXPECT_DOUBLE_EQ(boxtree::facet_area(mesh, 0), 2.0);
  EXPECT_EQ(boxtree::facet_area(mesh, 2), 0.0);
}

TEST(MeshValidate, FacetAreaIsTheArea) {
  TriangleMesh mesh;
  mesh.vertices = {v3(1, 1, 1), v3(4, 1, 1), v3(1, 1, 5)};  // legs 3 and 4
  mesh.triangles = {{0, 1, 2}};
  EXPECT_DOUBLE_EQ(boxtree::facet_area(mesh, 0), 6.0);
  EXPECT_DOUBLE_EQ(boxtree::compute_mesh_stats(mesh).total_area, 6.0);
}

TEST(MeshValidate, HandBuiltMeshes) {
  TriangleMesh mesh;
  expect_validate_error(mesh, {"no facets"});

  mesh.vertices = {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  expect_validate_error(mesh, {"facet 1", "vertex index 3", "out of range", "3 vertices"});

  mesh.vertices.push_back(v3(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  expect_validate_error(mesh, {"facet 1", "vertex 3", "non-finite"});

  mesh.vertices[3] = v3(0, std::numeric_limits<double>::infinity(), 0);
  expect_validate_error(mesh, {"facet 1", "vertex 3", "non-finite"});

  mesh.triangles.pop_back();  // the infinite vertex is now unused: legal
  EXPECT_NO_THROW(boxtree::validate_mesh(mesh, "hand-built"));
}

// ---- the shared real meshes -------------------------------------------------------------------------

struct SharedMeshFacts {
  std::size_t triangles, vertices, degenerate;
};

// The statistics table of /work/shared/meshes/README.md (the source of truth).
const std::map<std::string, SharedMeshFacts>& shared_mesh_table() {
  static const std::map<std::string, SharedMeshFacts> table = {
      {"stanford_bunny.obj", {69451, 35947, 0}},
      {"stanford_bunny_res2.obj", {16301, 8171, 0}},
      {"stanford_bunny_res3.obj", {3851, 1889, 0}},
      {"stanford_bunny_res4.obj", {948, 453, 0}},
      {"bunny_libigl_closed.obj", {6966, 3485, 0}},
      {"ode_bunny.obj", {902, 453, 0}},
      {"stanford_armadillo_86k.obj", {86482, 43243, 0}},
      {"stanford_dragon_res3.obj", {47794, 22998, 0}},
      {"utah_teapot.obj", {6320, 3644, 0}},
      {"suzanne.obj", {968, 507, 0}},
      {"spot.obj", {5856, 2930, 0}},
      {"env.obj", {2180, 6540, 0}},
      {"rob.obj", {216, 648, 0}},
      {"bullet_diff_ring.obj", {57640, 28816, 0}},
      {"bullet_kiva_pod_lowres.obj", {10184, 5204, 0}},
      {"bullet_leoTest1.obj", {41262, 21979, 22}},
  };
  return table;
}

TEST(MeshIoShared, EveryMeshLoadsWithTheReadmeCounts) {
  const fs::path dir = boxtree::test::shared_mesh_dir();
  BOXTREE_REQUIRE_SHARED_PATH(dir.string());
  std::size_t seen = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string name = entry.path().filename().string();
    SCOPED_TRACE(name);
    const auto it = shared_mesh_table().find(name);
    if (it == shared_mesh_table().end()) {
      ADD_FAILURE() << name << " is not in the README table; add its counts here";
      continue;
    }
    ++seen;
    const TriangleMesh mesh = boxtree::load_mesh(entry.path().string());
    const boxtree::MeshStats stats = boxtree::compute_mesh_stats(mesh);
    EXPECT_EQ(mesh.facet_count(), it->second.triangles);
    EXPECT_EQ(mesh.vertices.size(), it->second.vertices);
    EXPECT_EQ(stats.degenerate_facets, it->second.degenerate);
  }
  EXPECT_EQ(seen, shared_mesh_table().size()) << "meshes of the README table are missing from " << dir;
}

TEST(MeshIoShared, LeoTest1HasTwentyTwoDegenerateFacets) {
  const fs::path path = fs::path(boxtree::test::shared_mesh_dir()) / "bullet_leoTest1.obj";
  BOXTREE_REQUIRE_SHARED_PATH(path.string());
  EXPECT_EQ(boxtree::compute_mesh_stats(boxtree::load_mesh(path.string())).degenerate_facets, 22u);
}

}  // namespace
