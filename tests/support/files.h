// SPDX-License-Identifier: MIT
#pragma once
// Mesh files written by the tests: scratch folders under the build tree, little-endian encoders
// for the binary formats, a binary STL writer, and the check that a load fails with a clear
// message. Shared by tests/test_mesh_io.cpp and tests/test_bad_input.cpp.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "boxtree/error.h"
#include "boxtree/io.h"

namespace boxtree::test {

// BOXTREE_TEST_TMP/<name>, created on first use.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(BOXTREE_TEST_TMP) / name;
  std::filesystem::create_directories(dir);
  return dir;
}

// Writes `bytes` to `path` (replacing it) and returns the path.
inline std::string write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  EXPECT_TRUE(out.good()) << "could not write " << path;
  return path.string();
}

// Little-endian encoders for the binary formats (independent of the host's byte order).
inline void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}
inline void put_u16(std::string& out, std::uint16_t v) {
  out += static_cast<char>(v & 0xff);
  out += static_cast<char>(v >> 8);
}
inline void put_f32(std::string& out, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, bits);
}

// A binary STL: 80-byte header, facet count, then per facet a zero normal, three corners and
// an attribute word.
inline std::string binary_stl(const std::vector<std::array<Vec3, 3>>& facets, const std::string& header_text) {
  std::string bytes = header_text;
  bytes.resize(80, ' ');
  put_u32(bytes, static_cast<std::uint32_t>(facets.size()));
  for (const std::array<Vec3, 3>& c : facets) {
    for (int i = 0; i < 3; ++i) put_f32(bytes, 0.0f);  // normal (ignored)
    for (const Vec3& p : c) {
      for (int i = 0; i < 3; ++i) put_f32(bytes, static_cast<float>(p[i]));
    }
    put_u16(bytes, 0);
  }
  return bytes;
}

// load_mesh must throw boxtree::Error whose one-line message starts with the path and contains
// every piece of `expected`. Returns the message ("" if none was thrown).
inline std::string expect_load_error(const std::string& path, const std::vector<std::string>& expected) {
  try {
    load_mesh(path);
    ADD_FAILURE() << "load_mesh(" << path << ") did not throw";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path, 0), 0u) << "message does not start with the path: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "message is not one line: " << message;
    for (const std::string& piece : expected) {
      EXPECT_NE(message.find(piece), std::string::npos) << "'" << piece << "' missing from: " << message;
    }
    return message;
  }
  return "";
}

}  // namespace boxtree::test
