#pragma once
// Hierarchy methods by name: the one run-time switch at the edge (CLI, adapters). Inside the
// library the volume kind is a template parameter; with_method turns a name into that type once.
#include <string>
#include <utility>
#include <vector>

#include "boxtree/volume/volume.h"

namespace boxtree {

enum class Method {
  aabb,  // axis-aligned boxes (paper 3.1)
};

template <class Volume>
struct VolumeTag {
  using type = Volume;
};

// The names `--method` accepts, in a stable order.
std::vector<std::string> method_names();
// Throws boxtree::Error naming the unknown method and listing the valid ones.
Method parse_method(const std::string& name);
std::string method_name(Method method);

// Calls f(VolumeTag<V>{}) with the volume type of `method`.
template <class F>
decltype(auto) with_method(Method method, F&& f) {
  switch (method) {
    case Method::aabb:
      break;
  }
  return std::forward<F>(f)(VolumeTag<Aabb>{});
}

}  // namespace boxtree
