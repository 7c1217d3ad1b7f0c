// SPDX-License-Identifier: MIT
// Mesh files (contract in boxtree/io.h).
//
// OBJ goes through tinyobjloader's callback API, STL/PLY/OFF through Assimp. Both libraries are
// lenient in ways that would silently change a mesh, so each is wrapped:
//  * tinyobjloader: LoadObj() (shape API) drops faces with bad indices after only a warning, and
//    its number parser maps "nan", "inf" and garbage to 0 and is not correctly rounded (about
//    60% of "%.17g" values come back one ulp off). We therefore use LoadObjWithCallback, which
//    hands over every `v` and `f` record in file order with raw indices, and re-read the numbers
//    of that record's line with std::from_chars (exact, locale-free), which also gives us the
//    line number of every record for error messages.
//  * Assimp: silent by default (NullLogger), but some loaders report data loss only through the
//    logger (the OFF loader clamps out-of-range indices and drops faces with more than 9 corners;
//    the PLY parser skips unparsable values). While Assimp runs we install a logger that records
//    warnings and errors, and fail the load on any. No post-processing step is used: they may
//    reorder or re-triangulate faces (aiProcess_Triangulate does not promise fans in order).
//    Assimp 5.2 is not safe on every bad input, so each format is checked before it reads it:
//    STL's binary size (it only says "failed to determine STL storage representation"), PLY's
//    structure (its reader hangs or reads out of bounds on truncated files) and OFF's counts and
//    line lengths (it allocates what the header says, and overflows a line buffer).
//    Assimp keeps coordinates in float (ai_real), so STL/PLY/OFF vertices are float values.
#include "boxtree/io.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#define TINYOBJLOADER_IMPLEMENTATION
#include <assimp/MemoryIOWrapper.h>
#include <assimp/scene.h>
#include <tiny_obj_loader.h>

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/Logger.hpp>

#include "boxtree/error.h"

namespace boxtree {
namespace {

constexpr const char* kSupported = ".obj, .stl, .ply, .off";
// See validate_mesh: facet ids must fit a signed 32-bit counter.
constexpr std::size_t kMaxFacets = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw Error(path + ": " + what); }

// Text from a file, made safe for a one-line message: at most `max_length` characters shown,
// control and non-ASCII bytes escaped.
std::string shown(std::string_view text, std::size_t max_length = 40) {
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < max_length; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  if (text.size() > max_length) out += "...";
  return out + "'";
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c); });
  return ext;
}

std::string read_whole_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) fail(path, "cannot open: no such file");
  if (status.type() == std::filesystem::file_type::directory) fail(path, "cannot open: it is a directory");

  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::string data;
  char buffer[1 << 16];
  for (;;) {
    const std::size_t n = std::fread(buffer, 1, sizeof buffer, file);
    data.append(buffer, n);
    if (n < sizeof buffer) break;
  }
  const bool read_error = std::ferror(file) != 0;
  const int saved_errno = errno;
  std::fclose(file);
  if (read_error) fail(path, std::string("unreadable: read error: ") + std::strerror(saved_errno));
  if (data.empty()) fail(path, "empty file (0 bytes)");
  return data;
}

// Appends polygon `corners` as the fan (0,1,2), (0,2,3), ...
void append_fan(const std::string& path, const VertexId* corners, std::size_t count, TriangleMesh& mesh) {
  for (std::size_t k = 1; k + 1 < count; ++k) {
    if (mesh.triangles.size() >= kMaxFacets) fail(path, "too many facets (at most 2^31-1 are supported)");
    mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
  }
}

// ---- OBJ ---------------------------------------------------------------------------------------

// A read-only stream over the file's bytes whose read position tells which line tinyobjloader has
// just consumed.
class MemoryBuffer : public std::streambuf {
 public:
  MemoryBuffer(const char* begin, const char* end) {
    char* b = const_cast<char*>(begin);  // never written: std::streambuf only reads through it
    setg(b, b, const_cast<char*>(end));
  }
  std::size_t consumed() const { return static_cast<std::size_t>(gptr() - eback()); }
};

bool is_obj_space(char c) { return c == ' ' || c == '\t'; }

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_obj_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_obj_space(line[i])) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

enum class NumberStatus { ok, malformed };

// Exact (correctly rounded) decimal to double; accepts a leading '+', "nan" and "inf" (the
// caller rejects non-finite values where they matter). Overflow gives +-inf, underflow +-0, as
// strtod would.
NumberStatus parse_real(std::string_view text, double* out) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') {
    ++first;
    if (first != last && (*first == '+' || *first == '-')) return NumberStatus::malformed;
  }
  const auto result = std::from_chars(first, last, *out);
  if (result.ptr != last || first == last) return NumberStatus::malformed;
  if (result.ec == std::errc()) return NumberStatus::ok;
  if (result.ec != std::errc::result_out_of_range) return NumberStatus::malformed;

  // from_chars only says "out of range": overflow or underflow follows from the decimal order of
  // the first significant digit plus the exponent.
  const bool negative = *first == '-';
  const char* p = negative ? first + 1 : first;
  long long integer_digits = 0, fraction_digits = 0;
  long long first_integer = -1, first_fraction = -1;  // index of the first nonzero digit
  bool in_fraction = false;
  for (; p != last && *p != 'e' && *p != 'E'; ++p) {
    if (*p == '.') {
      in_fraction = true;
    } else if (in_fraction) {
      if (first_integer < 0 && first_fraction < 0 && *p != '0') first_fraction = fraction_digits;
      ++fraction_digits;
    } else {
      if (first_integer < 0 && *p != '0') first_integer = integer_digits;
      ++integer_digits;
    }
  }
  const long long order = first_integer >= 0    ? integer_digits - 1 - first_integer
                          : first_fraction >= 0 ? -(first_fraction + 1)
                                                : -1;  // all zeros (never out of range)
  long long exponent = 0;
  if (p != last) {
    ++p;
    const bool exponent_negative = p != last && *p == '-';
    if (p != last && (*p == '-' || *p == '+')) ++p;
    for (; p != last; ++p) exponent = std::min<long long>(exponent * 10 + (*p - '0'), 1000000000LL);
    if (exponent_negative) exponent = -exponent;
  }
  const double magnitude = order + exponent < 0 ? 0.0 : std::numeric_limits<double>::infinity();
  *out = negative ? -magnitude : magnitude;
  return NumberStatus::ok;
}

// Everything tinyobjloader reports, in file order, turned into a TriangleMesh.
struct ObjReader {
  const std::string* path = nullptr;
  const char* data = nullptr;  // the bytes the stream reads
  const MemoryBuffer* buffer = nullptr;

  // Line bookkeeping: terminators counted in [0, counted_to).
  std::size_t counted_to = 0;
  std::size_t terminators = 0;

  TriangleMesh mesh;
  std::vector<std::size_t> vertex_lines;  // the line of each `v` record
  std::vector<std::size_t> facet_lines;   // the line of the `f` record each facet comes from
  std::vector<VertexId> corners;          // scratch

  // The record tinyobjloader has just parsed: the text of its line (without terminator) and its
  // 1-based number. tinyobjloader ends a line at "\n", "\r\n" or a lone "\r" (safeGetline) and
  // has consumed the terminator when it calls back.
  std::string_view current_line(std::size_t* line_number) {
    const std::size_t end_with_terminator = buffer->consumed();
    for (std::size_t i = counted_to; i < end_with_terminator; ++i) {
      if (data[i] == '\n') {
        ++terminators;
      } else if (data[i] == '\r') {
        ++terminators;
        if (i + 1 < end_with_terminator && data[i + 1] == '\n') ++i;
      }
    }
    counted_to = end_with_terminator;
    std::size_t end = end_with_terminator;
    if (end > 0 && data[end - 1] == '\n') --end;
    if (end > 0 && data[end - 1] == '\r') --end;
    const bool terminated = end != end_with_terminator;
    *line_number = terminators + (terminated ? 0 : 1);
    std::size_t start = end;
    while (start > 0 && data[start - 1] != '\n' && data[start - 1] != '\r') --start;
    return std::string_view(data + start, end - start);
  }

  std::string at_line(std::size_t line) const { return "line " + std::to_string(line) + ": "; }

  void on_vertex() {
    std::size_t line = 0;
    const std::string_view text = current_line(&line);
    const std::vector<std::string_view> fields = split_fields(text);  // fields[0] == "v"
    if (fields.size() < 4) {
      fail(*path, at_line(line) + "malformed vertex record " + shown(text) + ": needs 3 coordinates");
    }
    if (mesh.vertices.size() >= std::numeric_limits<VertexId>::max()) {
      fail(*path, at_line(line) + "too many vertices (at most 2^32-1 are supported)");
    }
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      if (parse_real(fields[1 + k], &p[k]) != NumberStatus::ok) {
        fail(*path, at_line(line) + "malformed number " + shown(fields[1 + k]) + " in vertex record");
      }
    }
    mesh.vertices.push_back(p);
    vertex_lines.push_back(line);
  }

  void on_face(int tinyobj_corner_count) {
    std::size_t line = 0;
    const std::string_view text = current_line(&line);
    const std::vector<std::string_view> fields = split_fields(text);  // fields[0] == "f"
    const std::size_t corner_count = fields.size() - 1;
    const std::string where = at_line(line) + "facet " + std::to_string(mesh.triangles.size()) + ": ";
    if (static_cast<std::size_t>(tinyobj_corner_count) != corner_count) {
      fail(*path, at_line(line) + "malformed face record " + shown(text));
    }
    if (corner_count < 3) {
      fail(*path,
           at_line(line) + "face record with " + std::to_string(corner_count) + " corners (a facet needs at least 3)");
    }
    corners.clear();
    const std::size_t defined = mesh.vertices.size();  // relative indices count back from here
    for (std::size_t k = 1; k <= corner_count; ++k) {
      // A corner is v, v/t, v//n or v/t/n; only v matters here.
      const std::string_view token = fields[k].substr(0, fields[k].find('/'));
      long long index = 0;
      const char* first = token.data();
      const char* last = token.data() + token.size();
      if (first != last && *first == '+') ++first;
      const auto result = std::from_chars(first, last, index);
      if (result.ptr != last || first == last) {
        fail(*path, where + "malformed vertex index " + shown(fields[k]));
      }
      if (result.ec == std::errc::result_out_of_range) {
        fail(*path, where + "vertex index " + shown(token) + " out of range");
      }
      if (index == 0) {
        fail(*path, where + "vertex index 0 is invalid (OBJ indices start at 1; negative ones count back)");
      }
      long long resolved = 0;
      if (index > 0) {
        // Checked against the final vertex count after the whole file is read: OBJ readers
        // (tinyobjloader's LoadObj included) accept references to vertices defined later.
        resolved = index - 1;
        if (resolved >= static_cast<long long>(std::numeric_limits<VertexId>::max())) {
          fail(*path, where + "vertex index " + std::to_string(index) + " out of range");
        }
      } else {
        resolved = static_cast<long long>(defined) + index;
        if (resolved < 0) {
          fail(*path, where + "vertex index " + std::to_string(index) + " out of range (only " +
                          std::to_string(defined) + " vertices are defined before this line)");
        }
      }
      corners.push_back(static_cast<VertexId>(resolved));
    }
    append_fan(*path, corners.data(), corners.size(), mesh);
    facet_lines.resize(mesh.triangles.size(), line);
  }
};

TriangleMesh load_obj(const std::string& path, const std::string& data) {
  // Binary data would be split into arbitrary "lines"; tinyobjloader skips what it does not
  // recognise, so garbage could load as a smaller mesh. No text OBJ contains a NUL byte.
  const std::size_t nul = data.find('\0');
  if (nul != std::string::npos) {
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(data.begin(), data.begin() + nul, '\n'));
    fail(path, "binary data, not a text OBJ file (NUL byte at offset " + std::to_string(nul) + ", line " +
                   std::to_string(line) + ")");
  }
  // A UTF-8 byte-order mark would hide the first record from tinyobjloader.
  const std::size_t skip = data.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;

  ObjReader reader;
  reader.path = &path;
  reader.data = data.data() + skip;
  MemoryBuffer buffer(data.data() + skip, data.data() + data.size());
  reader.buffer = &buffer;
  std::istream stream(&buffer);

  tinyobj::callback_t callbacks;
  callbacks.vertex_cb = [](void* user, tinyobj::real_t, tinyobj::real_t, tinyobj::real_t, tinyobj::real_t) {
    static_cast<ObjReader*>(user)->on_vertex();
  };
  callbacks.index_cb = [](void* user, tinyobj::index_t*, int count) { static_cast<ObjReader*>(user)->on_face(count); };
  std::string warnings, errors;
  // No material reader: `mtllib` must not make us open other files.
  const bool ok = tinyobj::LoadObjWithCallback(stream, callbacks, &reader, nullptr, &warnings, &errors);
  if (!ok || !errors.empty()) {
    std::string message = errors.empty() ? std::string("tinyobjloader failed") : errors;
    std::replace(message.begin(), message.end(), '\n', ' ');
    fail(path, "malformed OBJ: " + message);
  }

  TriangleMesh& mesh = reader.mesh;
  if (mesh.triangles.empty()) {
    fail(path, "no facets (" + std::to_string(mesh.vertices.size()) + " vertices, no `f` records)");
  }
  // Positive indices past the end, and non-finite coordinates, named with their lines.
  const std::size_t vertex_count = mesh.vertices.size();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (VertexId v : mesh.triangles[f]) {
      if (v >= vertex_count) {
        fail(path, "line " + std::to_string(reader.facet_lines[f]) + ": facet " + std::to_string(f) +
                       ": vertex index " + std::to_string(std::uint64_t(v) + 1) + " out of range (the file has " +
                       std::to_string(vertex_count) + " vertices)");
      }
    }
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (VertexId v : mesh.triangles[f]) {
      const Vec3& p = mesh.vertices[v];
      if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
        std::ostringstream message;
        message << "line " << reader.vertex_lines[v] << ": vertex " << v << " has a non-finite coordinate (" << p.x()
                << ", " << p.y() << ", " << p.z() << "), used by facet " << f << " (line " << reader.facet_lines[f]
                << ")";
        fail(path, message.str());
      }
    }
  }
  return std::move(reader.mesh);
}

// ---- Assimp (STL, PLY, OFF) --------------------------------------------------------------------

// Records Assimp's warnings and errors instead of printing them.
class CapturingLogger final : public Assimp::Logger {
 public:
  explicit CapturingLogger(std::vector<std::string>* problems) : problems_(problems) {}
  bool attachStream(Assimp::LogStream*, unsigned int) override { return false; }
  bool detachStream(Assimp::LogStream*, unsigned int) override { return false; }

 private:
  void OnDebug(const char*) override {}
  void OnVerboseDebug(const char*) override {}
  void OnInfo(const char*) override {}
  void OnWarn(const char* message) override { problems_->emplace_back(message); }
  void OnError(const char* message) override { problems_->emplace_back(message); }
  std::vector<std::string>* problems_;
};

// Assimp's logger is process-wide, so imports that swap it in are serialised.
std::mutex& assimp_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::string one_line(std::string text) {
  // Messages about the in-memory file name Assimp was given would confuse the user.
  for (std::size_t at; (at = text.find(AI_MEMORYIO_MAGIC_FILENAME)) != std::string::npos;) {
    text.replace(at, std::strlen(AI_MEMORYIO_MAGIC_FILENAME), "<file>");
  }
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

// Assimp only takes a binary STL whose size is exactly 84 + 50 * (facet count in the header);
// anything else it calls "failed to determine STL storage representation". Say what is wrong.
void check_stl_storage(const std::string& path, const std::string& data) {
  const std::size_t first = data.find_first_not_of(" \t\r\n");
  const bool text =
      first != std::string::npos && data.compare(first, 5, "solid") == 0 && data.find('\0') == std::string::npos;
  if (data.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, 4);  // little-endian, as the format says (and x86/ARM are)
    const std::uint64_t expected = 84 + 50 * std::uint64_t(count);
    if (expected == data.size()) return;  // binary; Assimp checks this before "solid"
    if (text) return;                     // ASCII
    fail(path, std::string(expected > data.size() ? "truncated" : "corrupt") + " binary STL: header declares " +
                   std::to_string(count) + " facets (" + std::to_string(expected) + " bytes) but the file has " +
                   std::to_string(data.size()) + " bytes");
  }
  if (!text) {
    fail(path, "not an STL file: too short for a binary STL (" + std::to_string(data.size()) +
                   " bytes, the header alone is 84) and no ASCII 'solid' keyword");
  }
}

// ---- PLY structure check ------------------------------------------------------------------------
//
// Assimp 5.2's PLY reader trusts the file: a header without end_header or a truncated ASCII body
// makes it loop forever, a corrupt binary body can make it read out of bounds, and a comment
// line between an element's properties makes it drop the properties after it, silently. So
// before Assimp reads a PLY file, its structure is walked here: header lines, then every element
// instance (one line of the right number of values in ASCII; the right number of bytes, list
// lengths included, in binary). Values themselves are left to Assimp.

struct PlyProperty {
  int count_size = 0;  // bytes of a list's length field; 0 for a scalar property
  bool count_signed = false;
  int value_size = 0;  // bytes of one value
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Sizes of the PLY types, under the names Assimp knows.
bool ply_type(std::string_view name, int* size, bool* is_signed, bool* is_integer) {
  struct Type {
    const char* name;
    int size;
    bool is_signed, is_integer;
  };
  static const Type types[] = {{"char", 1, true, true},     {"int8", 1, true, true},     {"uchar", 1, false, true},
                               {"uint8", 1, false, true},   {"short", 2, true, true},    {"int16", 2, true, true},
                               {"ushort", 2, false, true},  {"uint16", 2, false, true},  {"int", 4, true, true},
                               {"int32", 4, true, true},    {"uint", 4, false, true},    {"uint32", 4, false, true},
                               {"float", 4, true, false},   {"float32", 4, true, false}, {"double", 8, true, false},
                               {"float64", 8, true, false}, {"double64", 8, true, false}};
  for (const Type& t : types) {
    if (name == t.name) {
      *size = t.size;
      *is_signed = t.is_signed;
      *is_integer = t.is_integer;
      return true;
    }
  }
  return false;
}

// Checks a PLY file's structure (see above). Returns true when the file is ASCII and its last line
// has no line end: Assimp's line reader needs one appended.
bool check_ply_structure(const std::string& path, const std::string& data) {
  const auto malformed = [&](std::size_t line, const std::string& what) {
    fail(path, "malformed PLY file: line " + std::to_string(line) + ": " + what);
  };

  // Header: '\n'-terminated lines ("\r\n" allowed), ending with "end_header".
  std::vector<PlyElement> elements;
  bool binary = false, big_endian = false, properties_closed = true, crlf_header = false;
  std::size_t at = 0, line = 0;
  for (bool done = false; !done;) {
    ++line;
    const std::size_t end = data.find('\n', at);
    if (end == std::string::npos) {
      fail(path, "malformed PLY file: the header has no end_header line (truncated or not a PLY file)");
    }
    std::string_view text(data.data() + at, end - at);
    crlf_header = !text.empty() && text.back() == '\r';
    if (crlf_header) text.remove_suffix(1);
    at = end + 1;
    if (text.find_first_of(std::string_view("\r\0", 2)) != std::string_view::npos) {
      malformed(line, "stray CR or NUL byte in the header");
    }
    const std::vector<std::string_view> fields = split_fields(text);
    const std::string_view keyword = fields.empty() ? std::string_view() : fields[0];
    if (line == 1) {
      if (fields.size() != 1 || (keyword != "ply" && keyword != "PLY"))
        malformed(line, "the file must start with 'ply'");
      continue;
    }
    if (line == 2) {
      // Assimp looks for the format on the second line only.
      if (fields.size() != 3 || keyword != "format")
        malformed(line, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
      if (fields[1] == "binary_little_endian") {
        binary = true;
      } else if (fields[1] == "binary_big_endian") {
        binary = big_endian = true;
      } else if (fields[1] != "ascii") {
        malformed(line, "unknown format " + shown(fields[1]));
      }
      continue;
    }
    if (keyword == "element") {
      if (fields.size() != 3) malformed(line, "expected 'element <name> <count>'");
      PlyElement element;
      element.name = std::string(fields[1]);
      const auto result = std::from_chars(fields[2].data(), fields[2].data() + fields[2].size(), element.count);
      // Assimp keeps counts in 32 bits.
      if (result.ec != std::errc() || result.ptr != fields[2].data() + fields[2].size() ||
          element.count > std::numeric_limits<std::uint32_t>::max()) {
        malformed(line, "bad element count " + shown(fields[2]));
      }
      elements.push_back(std::move(element));
      properties_closed = false;
    } else if (keyword == "property") {
      if (elements.empty()) malformed(line, "property before any element");
      // Assimp stops reading an element's properties at the first other line and silently drops
      // the rest, so such headers are refused rather than misread.
      if (properties_closed)
        malformed(line, "property after a comment or blank line inside an element (not supported)");
      PlyProperty property;
      bool value_signed = false, value_integer = false, count_integer = false;
      const bool is_list = fields.size() >= 2 && fields[1] == "list";
      if (is_list) {
        if (fields.size() != 5) malformed(line, "expected 'property list <count type> <value type> <name>'");
        if (!ply_type(fields[2], &property.count_size, &property.count_signed, &count_integer) || !count_integer) {
          malformed(line, "bad list count type " + shown(fields[2]));
        }
        if (!ply_type(fields[3], &property.value_size, &value_signed, &value_integer)) {
          malformed(line, "unknown type " + shown(fields[3]));
        }
      } else {
        if (fields.size() != 3) malformed(line, "expected 'property <type> <name>'");
        if (!ply_type(fields[1], &property.value_size, &value_signed, &value_integer)) {
          malformed(line, "unknown type " + shown(fields[1]));
        }
      }
      elements.back().properties.push_back(property);
    } else if (keyword == "end_header") {
      if (fields.size() != 1) malformed(line, "extra text after end_header");
      done = true;
    } else if (keyword == "comment" || keyword == "obj_info" || fields.empty()) {
      properties_closed = true;
    } else {
      malformed(line, "unknown header line " + shown(text));
    }
  }

  if (binary) {
    // Assimp drops a first data byte of 0x0a after a "\n" header, taking it for half of "\r\n".
    if (!crlf_header && at < data.size() && data[at] == '\n') {
      fail(path, "binary PLY data starting with byte 0x0a cannot be read correctly by Assimp 5.2");
    }
    const auto read_count = [&](std::size_t offset, const PlyProperty& p) -> std::int64_t {
      std::uint64_t value = 0;
      for (int i = 0; i < p.count_size; ++i) {
        const std::uint64_t byte = static_cast<unsigned char>(data[offset + i]);
        value |= byte << (8 * (big_endian ? p.count_size - 1 - i : i));
      }
      if (p.count_signed && (value >> (8 * p.count_size - 1)) != 0) return -1;
      return static_cast<std::int64_t>(value);
    };
    std::uint64_t offset = at;
    const std::uint64_t size = data.size();
    for (const PlyElement& element : elements) {
      bool has_list = false;
      std::uint64_t fixed = 0;
      for (const PlyProperty& p : element.properties) {
        has_list = has_list || p.count_size > 0;
        fixed += p.value_size;
      }
      if (!has_list) {
        if (element.count * fixed > size - offset) {
          fail(path, "truncated PLY file: element '" + element.name + "' needs " +
                         std::to_string(element.count * fixed) + " bytes at offset " + std::to_string(offset) +
                         " but the file has " + std::to_string(size) + " bytes");
        }
        offset += element.count * fixed;
        continue;
      }
      for (std::uint64_t i = 0; i < element.count; ++i) {
        for (const PlyProperty& p : element.properties) {
          std::uint64_t need = p.value_size;
          if (p.count_size > 0) {
            if (static_cast<std::uint64_t>(p.count_size) > size - offset)
              need = p.count_size;  // reported below
            else {
              const std::int64_t n = read_count(offset, p);
              if (n < 0) {
                fail(path, "malformed PLY file: element '" + element.name + "' " + std::to_string(i) +
                               ": negative list length at offset " + std::to_string(offset));
              }
              need = p.count_size + static_cast<std::uint64_t>(n) * p.value_size;
            }
          }
          if (need > size - offset) {
            fail(path, "truncated PLY file: element '" + element.name + "' " + std::to_string(i) + " of " +
                           std::to_string(element.count) + " ends past the end of the file (" + std::to_string(size) +
                           " bytes)");
          }
          offset += need;
        }
      }
    }
    return false;
  }

  // ASCII: one instance per '\n'-terminated line, no blank lines in between (Assimp's line
  // reader skips one blank line but not two), no lone CR or NUL (Assimp takes both for line ends).
  if (data.find('\0', at) != std::string::npos) fail(path, "malformed PLY file: NUL byte in ASCII data");
  for (const PlyElement& element : elements) {
    for (std::uint64_t i = 0; i < element.count; ++i) {
      ++line;
      if (at >= data.size()) {
        fail(path, "truncated PLY file: element '" + element.name + "' has " + std::to_string(element.count) +
                       " entries but the data ends after " + std::to_string(i));
      }
      std::size_t end = data.find('\n', at);
      if (end == std::string::npos) end = data.size();
      std::string_view text(data.data() + at, end - at);
      at = end + 1;
      if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
      if (text.find('\r') != std::string_view::npos)
        malformed(line, "stray CR byte (CR-only line ends are not supported)");
      const std::vector<std::string_view> fields = split_fields(text);
      if (fields.empty()) malformed(line, "blank line inside the data");
      std::size_t next = 0;
      for (const PlyProperty& p : element.properties) {
        std::uint64_t values = 1;
        if (p.count_size > 0) {
          if (next >= fields.size()) break;
          const std::string_view count = fields[next++];
          const auto result = std::from_chars(count.data(), count.data() + count.size(), values);
          if (result.ec != std::errc() || result.ptr != count.data() + count.size()) {
            malformed(line,
                      "bad list length " + shown(count) + " in element '" + element.name + "' " + std::to_string(i));
          }
        }
        if (values > fields.size() - next) {
          next = fields.size() + 1;  // too few values
          break;
        }
        next += static_cast<std::size_t>(values);
      }
      if (next != fields.size()) {
        malformed(line, std::string(next > fields.size() ? "too few" : "too many") + " values for element '" +
                            element.name + "' " + std::to_string(i));
      }
    }
  }
  return data.back() != '\n';
}

// Assimp 5.2's OFF reader allocates what the header's counts ask for before reading any data
// (a corrupt count means gigabytes), and copies each line into a 4096-byte buffer writing one byte
// past it for longer lines. Both are refused here: counts must fit the file's lines.
void check_off_structure(const std::string& path, const std::string& data) {
  std::size_t lines = 0;
  for (std::size_t at = 0, line = 1; at < data.size(); ++line) {
    std::size_t end = data.find_first_of("\r\n", at);
    if (end == std::string::npos) end = data.size();
    if (end - at >= 4096) {
      fail(path, "malformed OFF file: line " + std::to_string(line) + " is longer than 4095 characters");
    }
    at = end + (data.compare(end, 2, "\r\n") == 0 ? 2 : 1);
    lines = line;
  }
  // The header as Assimp reads it: [ST][C][N][4][n]OFF (optional), a dimension after "nOFF",
  // then the vertex, face and edge counts; '#' starts a comment.
  std::vector<std::string_view> tokens;
  for (std::size_t at = 0; at < data.size() && tokens.size() < 5;) {
    const char c = data[at];
    if (c == '#') {
      at = data.find_first_of("\r\n", at);
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      ++at;
    } else {
      std::size_t end = data.find_first_of(" \t\r\n#", at);
      if (end == std::string::npos) end = data.size();
      tokens.emplace_back(data.data() + at, end - at);
      at = end;
    }
  }
  std::size_t next = 0;
  if (!tokens.empty() && tokens[0].size() >= 3 && tokens[0].substr(tokens[0].size() - 3) == "OFF") {
    next = tokens[0].find('n') != std::string_view::npos ? 2 : 1;
  }
  std::uint64_t counts[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    const std::string_view token = next + i < tokens.size() ? tokens[next + i] : std::string_view();
    const auto result = std::from_chars(token.data(), token.data() + token.size(), counts[i]);
    if (token.empty() || result.ec != std::errc() || result.ptr != token.data() + token.size()) {
      fail(path, "malformed OFF file: bad header: expected vertex and face counts, found " + shown(token));
    }
  }
  if (counts[0] > lines || counts[1] > lines - counts[0]) {
    fail(path, "truncated OFF file: the header declares " + std::to_string(counts[0]) + " vertices and " +
                   std::to_string(counts[1]) + " faces but the file has " + std::to_string(lines) + " lines");
  }
  // Face lines: Assimp 5.2 reads as many indices as a face's first number says, past the end of
  // the line and of the buffer if the line is short (a crash found by tests/fuzz), and drops faces
  // of fewer than 3 or more than 9 corners. Each face line must therefore hold 3 to 9 indices, all
  // present. The data lines are the non-blank, non-comment lines after the counts.
  const std::string_view face_count_token = tokens[next + 1];
  std::size_t at = static_cast<std::size_t>(face_count_token.data() + face_count_token.size() - data.data());
  at = data.find_first_of("\r\n", at);
  std::uint64_t data_line = 0;
  while (at != std::string::npos && at < data.size() && data_line < counts[0] + counts[1]) {
    at = data.find_first_not_of("\r\n", at);
    if (at == std::string::npos) break;
    std::size_t end = data.find_first_of("\r\n", at);
    if (end == std::string::npos) end = data.size();
    const std::string_view text(data.data() + at, end - at);
    at = end;
    const std::vector<std::string_view> fields = split_fields(text);
    if (fields.empty() || fields[0][0] == '#') continue;
    if (data_line++ < counts[0]) continue;  // a vertex
    std::uint64_t corners = 0;
    const auto result = std::from_chars(fields[0].data(), fields[0].data() + fields[0].size(), corners);
    if (result.ec != std::errc() || corners < 3 || corners > 9 || fields.size() < corners + 1) {
      fail(path, "malformed OFF file: face " + std::to_string(data_line - counts[0] - 1) + " " + shown(text) +
                     ": needs 3 to 9 corners, all given");
    }
  }
}

TriangleMesh load_with_assimp(const std::string& path, const std::string& data, const std::string& ext) {
  const std::string format = ext.substr(1);  // "stl", "ply" or "off"
  std::string upper = format;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return char(c - 'a' + 'A'); });
  if (format == "stl") check_stl_storage(path, data);
  if (format == "off") check_off_structure(path, data);
  std::string terminated;  // a copy, only when Assimp needs a final line end
  if (format == "ply" && check_ply_structure(path, data)) terminated = data + '\n';
  const std::string& bytes = terminated.empty() ? data : terminated;

  std::vector<std::string> problems;
  std::lock_guard<std::mutex> lock(assimp_mutex());
  // Only replace the silent default logger: set() deletes the logger it replaces, so an
  // application's own logger is left alone (it then sees Assimp's messages; we do not).
  const bool capture = Assimp::DefaultLogger::isNullLogger();
  if (capture) Assimp::DefaultLogger::set(new CapturingLogger(&problems));
  struct RestoreLogger {
    bool active;
    ~RestoreLogger() {
      if (active) Assimp::DefaultLogger::set(nullptr);  // deletes ours, back to the NullLogger
    }
  } restore{capture};

  Assimp::Importer importer;
  // From memory: we have the bytes already, and the extension (not Assimp's guess) picks the reader.
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), 0, format.c_str());
  if (!scene) fail(path, "malformed " + upper + " file: " + one_line(importer.GetErrorString()));
  if (!problems.empty()) {
    std::string message = "malformed " + upper + " file: " + one_line(problems.front());
    if (problems.size() > 1) message += " (and " + std::to_string(problems.size() - 1) + " more problems)";
    fail(path, message);
  }

  TriangleMesh mesh;
  std::vector<VertexId> corners;
  std::size_t polygon = 0;  // counted over all meshes, in the file's order
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    if (!part || part->mNumFaces == 0) continue;
    const std::size_t base = mesh.vertices.size();
    if (base + part->mNumVertices > std::numeric_limits<VertexId>::max()) {
      fail(path, "too many vertices (at most 2^32-1 are supported)");
    }
    if (part->mNumVertices > 0 && !part->mVertices) fail(path, "malformed " + upper + " file: vertices missing");
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      mesh.vertices.emplace_back(Real(p.x), Real(p.y), Real(p.z));
    }
    for (unsigned f = 0; f < part->mNumFaces; ++f, ++polygon) {
      const aiFace& face = part->mFaces[f];
      const std::string where =
          "polygon " + std::to_string(polygon) + " (facet " + std::to_string(mesh.triangles.size()) + "): ";
      if (face.mNumIndices < 3) {
        fail(path, where + std::to_string(face.mNumIndices) + " corners (a facet needs at least 3)");
      }
      corners.clear();
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        const unsigned index = face.mIndices[k];
        if (index >= part->mNumVertices) {
          fail(path, where + "vertex index " + std::to_string(index) + " out of range (" +
                         std::to_string(part->mNumVertices) + " vertices)");
        }
        corners.push_back(static_cast<VertexId>(base + index));
      }
      append_fan(path, corners.data(), corners.size(), mesh);
    }
  }
  if (mesh.triangles.empty()) fail(path, "no facets (" + std::to_string(mesh.vertices.size()) + " vertices)");
  return mesh;
}

}  // namespace

TriangleMesh load_mesh(const std::string& path) {
  const std::string ext = lower_extension(path);
  const bool assimp_format = ext == ".stl" || ext == ".ply" || ext == ".off";
  if (ext != ".obj" && !assimp_format) {
    fail(path, "unknown mesh file extension " + (ext.empty() ? std::string("(none)") : shown(ext)) +
                   " (supported: " + kSupported + ")");
  }
  const std::string data = read_whole_file(path);
  TriangleMesh mesh = ext == ".obj" ? load_obj(path, data) : load_with_assimp(path, data, ext);
  validate_mesh(mesh, path, /*for_tree=*/false);  // any finite coordinate loads; build_tree limits them
  return mesh;
}

void save_obj(const TriangleMesh& mesh, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  int write_errno = 0;
  const auto check = [&](int written) {
    if (written < 0 && write_errno == 0) write_errno = errno ? errno : EIO;
  };
  // %.17g round-trips every double exactly (and load_mesh parses it exactly).
  for (const Vec3& p : mesh.vertices) {
    if (write_errno) break;
    check(std::fprintf(file, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z()));
  }
  for (const Triangle& t : mesh.triangles) {
    if (write_errno) break;
    check(std::fprintf(file, "f %llu %llu %llu\n", static_cast<unsigned long long>(t[0]) + 1,
                       static_cast<unsigned long long>(t[1]) + 1, static_cast<unsigned long long>(t[2]) + 1));
  }
  // Buffered data reaches the disk (or fails, e.g. when it is full) only at fclose.
  if (std::fclose(file) != 0 && write_errno == 0) write_errno = errno ? errno : EIO;
  if (write_errno) fail(path, std::string("write failed: ") + std::strerror(write_errno));
}

}  // namespace boxtree
