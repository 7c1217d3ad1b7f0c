// SPDX-License-Identifier: MIT
// Test entry point: a failed BOXTREE_ASSERT throws, so a broken invariant fails the test that
// triggered it instead of aborting the whole suite.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "boxtree/error.h"

namespace {
struct AssertionFailure : std::logic_error {
  using std::logic_error::logic_error;
};
void throwing_assert_handler(const char* expression, const char* file, int line, const char* message) {
  throw AssertionFailure(std::string("BOXTREE_ASSERT failed: ") + message + " (" + expression + ") at " + file + ":" +
                         std::to_string(line));
}
}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  boxtree::set_assert_handler(&throwing_assert_handler);
  return RUN_ALL_TESTS();
}
