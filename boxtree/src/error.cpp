// SPDX-License-Identifier: MIT
#include "boxtree/error.h"

#include <cstdio>
#include <cstdlib>

namespace boxtree {
namespace {
void default_assert_handler(const char* expression, const char* file, int line, const char* message) {
  std::fprintf(stderr, "boxtree: assertion failed: %s (%s) at %s:%d\n", message, expression, file, line);
}
AssertHandler g_assert_handler = &default_assert_handler;
}  // namespace

AssertHandler set_assert_handler(AssertHandler handler) {
  AssertHandler previous = g_assert_handler;
  g_assert_handler = handler ? handler : &default_assert_handler;
  return previous;
}

namespace detail {
void assert_failed(const char* expression, const char* file, int line, const char* message) {
  g_assert_handler(expression, file, line, message);
  // A handler that returns (instead of throwing) must not let execution continue past a broken invariant.
  std::abort();
}
}  // namespace detail
}  // namespace boxtree
