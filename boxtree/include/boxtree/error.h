// SPDX-License-Identifier: MIT
#pragma once
// Errors. Two kinds, one policy each (see STYLE.md, "Errors"):
//  * bad user input (files, meshes, options) -> boxtree::Error, thrown by loaders and builders,
//    with a message that names the file, line or facet;
//  * programmer errors (broken invariants, misuse of the API) -> BOXTREE_ASSERT, which calls a
//    replaceable handler (the default prints and aborts; the tests install one that throws so a
//    broken invariant becomes a test failure).
// Hot-path queries never throw and never print.
#include <stdexcept>
#include <string>

namespace boxtree {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using AssertHandler = void (*)(const char* expression, const char* file, int line, const char* message);

// Installs `handler` and returns the previous one. Not thread-safe: call it at start-up.
AssertHandler set_assert_handler(AssertHandler handler);

namespace detail {
[[noreturn]] void assert_failed(const char* expression, const char* file, int line, const char* message);
}  // namespace detail

}  // namespace boxtree

#define BOXTREE_ASSERT(cond, message)                                                  \
  do {                                                                                 \
    if (!(cond)) ::boxtree::detail::assert_failed(#cond, __FILE__, __LINE__, message); \
  } while (false)
