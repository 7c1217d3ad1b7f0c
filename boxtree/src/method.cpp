// SPDX-License-Identifier: MIT
#include "boxtree/method.h"

#include <array>
#include <cstdlib>

#include "boxtree/error.h"

namespace boxtree {
namespace {
constexpr std::array<std::pair<const char*, VolumeKind>, 8> kNames = {{
    {"aabb", VolumeKind::aabb},
    {"obb-all", VolumeKind::obb_all},
    {"obb-max", VolumeKind::obb_max},
    {"obb-min", VolumeKind::obb_min},
    {"pie-max", VolumeKind::pie_max},
    {"pie-min", VolumeKind::pie_min},
    {"pie-max-general", VolumeKind::pie_max_general},
    {"pie-min-general", VolumeKind::pie_min_general},
}};

std::string valid_list() {
  std::string valid;
  for (const auto& [name, kind] : kNames) valid += std::string(valid.empty() ? "" : ", ") + name;
  return valid +
         ", the suffix -tight on oriented methods (e.g. obb-min-tight), and hybrids M+aabb@L (e.g. pie-min+aabb@4)";
}
}  // namespace

std::vector<std::string> method_names() {
  std::vector<std::string> names;
  for (const auto& [name, kind] : kNames) names.emplace_back(name);
  return names;
}

std::string method_name(const Method& method) {
  std::string base = "?";
  for (const auto& [name, kind] : kNames)
    if (kind == method.kind) base = name;
  if (method.tight) base += "-tight";
  return method.hybrid_level > 0 ? base + "+aabb@" + std::to_string(method.hybrid_level) : base;
}

Method parse_method(const std::string& name) {
  Method method;
  std::string base = name;
  const std::size_t plus = name.find("+aabb@");
  if (plus != std::string::npos) {
    base = name.substr(0, plus);
    const std::string level = name.substr(plus + 6);
    char* end = nullptr;
    const long value = level.empty() ? 0 : std::strtol(level.c_str(), &end, 10);
    if (level.empty() || *end != '\0' || value < 1 || value > 1000)
      throw Error("method '" + name + "': the hybrid level after '@' must be an integer from 1 to 1000");
    method.hybrid_level = int(value);
  }
  const std::string tight_suffix = "-tight";
  if (base.size() > tight_suffix.size() &&
      base.compare(base.size() - tight_suffix.size(), tight_suffix.size(), tight_suffix) == 0) {
    base.resize(base.size() - tight_suffix.size());
    method.tight = true;
  }
  for (const auto& [n, kind] : kNames)
    if (base == n) {
      method.kind = kind;
      if (kind == VolumeKind::aabb && method.hybrid_level > 0)
        throw Error("method '" + name +
                    "': aabb is axis-aligned already; hybrids combine an oriented method with aabb");
      if (kind == VolumeKind::aabb && method.tight)
        throw Error("method '" + name + "': aabb parents are exact already; -tight applies to oriented methods");
      return method;
    }
  throw Error("unknown method '" + name + "' (valid methods: " + valid_list() + ")");
}

BuildSettings settings_for(const Method& method, BuildSettings settings) {
  settings.hybrid_level = method.hybrid_level;
  if (method.tight) settings.parent_fit = ParentFit::fit_facets;
  return settings;
}

}  // namespace boxtree
