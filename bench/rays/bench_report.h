// SPDX-License-Identifier: MIT
#pragma once
// Result rows and the machine description shared by ray_bench and build_bench (issue 7,
// sections 3-4). One row compares one boxtree figure with one peer's figure measured in the
// same process on the same data; `ratio` is boxtree / peer (absent where a ratio means nothing,
// e.g. disagreement counts).
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "boxtree/method.h"

namespace boxtree::bench {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The benches' names for the exact trees beside the packed forms AnyTree holds: a method's name
// + "-exact" (aabb-exact, pie-min-exact, pie-min-general-tight-exact). `method` is the name
// without the suffix.
struct ExactSuffix {
  std::string method;
  bool exact = false;
};
inline ExactSuffix split_exact_suffix(const std::string& name) {
  const std::string suffix = "-exact";
  if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
    return {name.substr(0, name.size() - suffix.size()), true};
  return {name, false};
}

// Whether AnyTree::build holds a packed form for `method` (plain aabb and plain pie slices, tight
// or not; not their hybrids): the methods an `-exact` name applies to.
inline bool has_packed_form(const Method& method) {
  const bool pie = method.kind == VolumeKind::pie_max || method.kind == VolumeKind::pie_min ||
                   method.kind == VolumeKind::pie_max_general || method.kind == VolumeKind::pie_min_general;
  return method.kind == VolumeKind::aabb || (pie && method.hybrid_level == 0);
}

struct Row {
  std::string section;         // "rays", "build_memory"
  std::string case_name;       // e.g. "terrain-524k/outside"
  std::string metric;          // says whether lower or higher is better
  std::string boxtree_method;  // e.g. "aabb", "obb-all"
  double boxtree = 0;
  std::string peer;  // e.g. "embree rtcIntersect1"
  double peer_value = 0;
  std::optional<double> ratio;  // boxtree / peer_value
};

// A row with ratio = boxtree / peer_value (no ratio if peer_value is 0).
Row compare(std::string section, std::string case_name, std::string metric, std::string method, double boxtree,
            std::string peer, double peer_value);

// Writes the rows as a JSON array of objects with the keys section, case, metric,
// boxtree_method, boxtree, peer, peer_value, ratio (null when absent). Throws on I/O errors.
void write_json(const std::string& path, const std::vector<Row>& rows);

// Markdown lines describing where the numbers come from: CPU model (/proc/cpuinfo), cores,
// memory, load average at start, compiler and flags, peer library versions (`peers`).
std::string machine_markdown(const std::string& peers);

// Writes text to a file (throws on I/O errors).
void write_text(const std::string& path, const std::string& text);

// 1234567 -> "1,234,567".
std::string with_commas(std::uint64_t x);
// One number through a printf format (e.g. "%.3f").
std::string format(const char* fmt, double x);
// A plain-text (aligned columns) or markdown table; the first row is the header.
std::string table(const std::vector<std::vector<std::string>>& cells, bool markdown);

// Peak resident set of this process so far (VmHWM), bytes; 0 if unknown.
std::uint64_t peak_rss_bytes();

}  // namespace boxtree::bench
