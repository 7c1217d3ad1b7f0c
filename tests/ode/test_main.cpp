// SPDX-License-Identifier: MIT
// Test entry point. ODE's asserts are compiled into Debian's libode: its debug and error handlers
// are replaced by ones that throw, so API misuse fails the test that made it (with ODE's message)
// instead of aborting the whole suite. BOXTREE_ASSERT does the same. ODE is initialised once for
// the process and the boxtree class registered after it (the order ODE requires).
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <cstdarg>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "boxtree/error.h"
#include "boxtree/ode/boxtree_geom.h"

namespace {
struct OdeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string format(const char* kind, int number, const char* message, va_list args) {
  char text[1024];
  std::vsnprintf(text, sizeof text, message, args);
  return std::string("ODE ") + kind + " " + std::to_string(number) + ": " + text;
}

// ODE calls abort() if these return, so they must not: the exception unwinds through libode
// (C++ code built with unwind tables) back into the test.
[[noreturn]] void ode_debug(int number, const char* message, va_list args) {
  throw OdeFailure(format("INTERNAL ERROR", number, message, args));
}
[[noreturn]] void ode_error(int number, const char* message, va_list args) {
  throw OdeFailure(format("ERROR", number, message, args));
}

[[noreturn]] void boxtree_assert(const char* expression, const char* file, int line, const char* message) {
  throw std::logic_error(std::string("BOXTREE_ASSERT failed: ") + message + " (" + expression + ") at " + file + ":" +
                         std::to_string(line));
}
}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  boxtree::set_assert_handler(&boxtree_assert);
  dSetDebugHandler(&ode_debug);
  dSetErrorHandler(&ode_error);
  dInitODE2(0);
  dBoxtreeInit();
  const int result = RUN_ALL_TESTS();
  dBoxtreeClose();
  dCloseODE();
  return result;
}
