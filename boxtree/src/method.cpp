#include "boxtree/method.h"

#include "boxtree/error.h"

namespace boxtree {

std::vector<std::string> method_names() { return {"aabb"}; }

std::string method_name(Method method) {
  switch (method) {
    case Method::aabb:
      return "aabb";
  }
  return "?";
}

Method parse_method(const std::string& name) {
  if (name == "aabb") return Method::aabb;
  std::string valid;
  for (const std::string& n : method_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw Error("unknown method '" + name + "' (valid methods: " + valid + ")");
}

}  // namespace boxtree
