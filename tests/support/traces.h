// SPDX-License-Identifier: MIT
#pragma once
// Bit-for-bit comparison of two simulation traces (every body's state after each step, one
// equal block per step), for the engine adapters' coherence tests (tests/bullet, tests/ode).
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <vector>

namespace boxtree::test {

// Fails (fatally: call it under ASSERT_NO_FATAL_FAILURE) unless `with` and `without`, `steps`
// blocks each, are the same bytes, naming the first step where they part.
template <class Scalar>
void expect_same_bits_every_step(const std::vector<Scalar>& with, const std::vector<Scalar>& without, int steps) {
  ASSERT_EQ(with.size(), without.size());
  const std::size_t per_step = with.size() / std::size_t(steps);
  for (int i = 0; i < steps; ++i) {
    const std::size_t at = std::size_t(i) * per_step;
    ASSERT_EQ(std::memcmp(with.data() + at, without.data() + at, per_step * sizeof(Scalar)), 0)
        << "the worlds part at step " << i;
  }
}

}  // namespace boxtree::test
