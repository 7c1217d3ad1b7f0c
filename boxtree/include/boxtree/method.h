// SPDX-License-Identifier: MIT
#pragma once
// Hierarchy methods by name: the one run-time switch at the edge (CLI, adapters). Inside the
// library the volume kind is a template parameter; with_method turns a name into that type once.
//
// Names (the CLI's --method): aabb, obb-all, obb-max, obb-min, pie-max, pie-min (the paper's six;
// pie slices use its minimum-area isosceles triangle), pie-max-general, pie-min-general (pie
// slices from the general minimum-area triangle), and hybrids "M+aabb@L": method M below level
// L, axis-aligned boxes from level L up (levels count from the leaves, L >= 1). The suffix
// "-tight" on an oriented method (e.g. "obb-min-tight", "pie-min-tight+aabb@6") fits parents
// to the facets below them instead of to their children's volumes (ParentFit::fit_facets).
#include <string>
#include <utility>
#include <vector>

#include "boxtree/build.h"
#include "boxtree/volume/hybrid.h"

namespace boxtree {

enum class VolumeKind { aabb, obb_all, obb_max, obb_min, pie_max, pie_min, pie_max_general, pie_min_general };

struct Method {
  VolumeKind kind = VolumeKind::aabb;
  int hybrid_level = 0;  // 0: not a hybrid; L >= 1: boxes from level L up
  bool tight = false;    // parents fitted to the facets below them (ParentFit::fit_facets)
};

template <class Volume>
struct VolumeTag {
  using type = Volume;
};

// The base names `--method` accepts, in a stable order (hybrids are formed from them).
std::vector<std::string> method_names();
// Throws boxtree::Error naming the unknown method and listing the valid ones.
Method parse_method(const std::string& name);
std::string method_name(const Method& method);
// Settings with the method's hybrid level applied.
BuildSettings settings_for(const Method& method, BuildSettings settings = {});

// Calls f(VolumeTag<V>{}) with the volume type of `method`.
template <class F>
decltype(auto) with_method(const Method& method, F&& f) {
  auto pick = [&](auto tag) -> decltype(auto) {
    using V = typename decltype(tag)::type;
    if constexpr (std::is_same_v<V, Aabb>) {
      return f(VolumeTag<Aabb>{});
    } else {
      if (method.hybrid_level > 0) return f(VolumeTag<Hybrid<V>>{});
      return f(VolumeTag<V>{});
    }
  };
  switch (method.kind) {
    case VolumeKind::obb_all:
      return pick(VolumeTag<ObbAll>{});
    case VolumeKind::obb_max:
      return pick(VolumeTag<ObbMax>{});
    case VolumeKind::obb_min:
      return pick(VolumeTag<ObbMin>{});
    case VolumeKind::pie_max:
      return pick(VolumeTag<PieMax>{});
    case VolumeKind::pie_min:
      return pick(VolumeTag<PieMin>{});
    case VolumeKind::pie_max_general:
      return pick(VolumeTag<PieMaxGeneral>{});
    case VolumeKind::pie_min_general:
      return pick(VolumeTag<PieMinGeneral>{});
    case VolumeKind::aabb:
      break;
  }
  return pick(VolumeTag<Aabb>{});
}

}  // namespace boxtree
