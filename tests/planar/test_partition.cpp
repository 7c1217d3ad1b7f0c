// SPDX-License-Identifier: MIT
// Rectangular partitions: the generators make partitions, validation rejects overlaps and gaps.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/planar/partition.h"

namespace boxtree::planar {
namespace {

// Expects validate_partition to throw an Error whose message contains every one of `parts`.
void expect_invalid(const std::vector<Rect>& rects, std::initializer_list<const char*> parts) {
  try {
    validate_partition(rects);
    ADD_FAILURE() << "accepted an invalid partition";
  } catch (const Error& e) {
    for (const char* part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// Reference for small inputs: the cells tile their bounding box iff every cell of the grid of
// all their coordinates lies in exactly one of them.
bool tiles_brute_force(const std::vector<Rect>& rects) {
  std::vector<Real> xs, ys;
  for (const Rect& r : rects) {
    xs.insert(xs.end(), {r.min.x(), r.max.x()});
    ys.insert(ys.end(), {r.min.y(), r.max.y()});
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  for (std::size_t i = 0; i + 1 < xs.size(); ++i)
    for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
      const Vec2 p((xs[i] + xs[i + 1]) / 2, (ys[j] + ys[j + 1]) / 2);
      int count = 0;
      for (const Rect& r : rects) count += interior_contains(r, p) ? 1 : 0;
      if (count != 1) return false;
    }
  return true;
}

TEST(Partition, EveryGeneratorMakesAPartition) {
  for (const std::string& name : partition_generator_names()) {
    for (std::size_t count : {1, 2, 3, 7, 50, 400, 5000}) {
      SCOPED_TRACE(name + " " + std::to_string(count));
      const std::vector<Rect> cells = make_partition(name, count, 17 + count);
      EXPECT_NO_THROW(validate_partition(cells));
      if (name != "grid" && name != "brick") {
        EXPECT_EQ(cells.size(), count);
      }
      EXPECT_GE(cells.size(), count / 2);
      if (count <= 50) {
        EXPECT_TRUE(tiles_brute_force(cells));
      }
    }
  }
}

TEST(Partition, GeneratorsAreDeterministic) {
  for (const std::string& name : partition_generator_names())
    EXPECT_EQ(make_partition(name, 300, 5), make_partition(name, 300, 5)) << name;
}

TEST(Partition, PinwheelIsNotGuillotine) {
  // A pinwheel of five: no line through the square's interior avoids cutting a cell.
  const std::vector<Rect> cells = make_pinwheel_partition(5, 3);
  ASSERT_EQ(cells.size(), 5u);
  for (int axis = 0; axis < 2; ++axis)
    for (const Rect& c : cells)
      for (Real at : {c.min[axis], c.max[axis]}) {
        if (at <= 0 || at >= 1) continue;
        bool cuts = false;
        for (const Rect& d : cells) cuts |= d.min[axis] < at && at < d.max[axis];
        EXPECT_TRUE(cuts) << "a straight cut at " << at << " on axis " << axis;
      }
}

TEST(Partition, RejectsOverlapsNamingBothRectangles) {
  std::vector<Rect> cells = make_grid_partition(3, 3);
  cells[4].max.x() = cells[5].min.x() + 0.01;  // the centre now reaches into its right neighbour
  expect_invalid(cells, {"rectangles 4", "and 5", "overlap"});
  std::vector<Rect> duplicate = make_grid_partition(2, 1);
  duplicate.push_back(duplicate[0]);
  expect_invalid(duplicate, {"overlap"});
  // Overlap without a shared coordinate: a small square inside a big one.
  expect_invalid({Rect::from_bounds(0, 0, 1, 1), Rect::from_bounds(0.2, 0.2, 0.3, 0.3)},
                 {"rectangles 0", "and 1", "overlap"});
}

TEST(Partition, RejectsGaps) {
  std::vector<Rect> cells = make_grid_partition(3, 3);
  cells.erase(cells.begin() + 4);  // a hole in the middle
  expect_invalid(cells, {"gap"});
  std::vector<Rect> shrunk = make_grid_partition(3, 3);
  shrunk[0].max.x() -= 0.01;  // a thin slit between cells 0 and 1
  expect_invalid(shrunk, {"gap", "x = "});
  // A missing corner of the bounding rectangle.
  expect_invalid({Rect::from_bounds(0, 0, 2, 1), Rect::from_bounds(0, 1, 1, 2)}, {"gap"});
}

TEST(Partition, RejectsEmptyAndNonFiniteRectangles) {
  expect_invalid({}, {"no rectangles"});
  expect_invalid({Rect::from_bounds(0, 0, 1, 1), Rect::from_bounds(1, 0, 1, 1)}, {"rectangle 1", "empty"});
  expect_invalid({Rect::from_bounds(0, 0, std::numeric_limits<Real>::quiet_NaN(), 1)}, {"rectangle 0", "NaN"});
  expect_invalid({Rect::from_bounds(0, 0, std::numeric_limits<Real>::infinity(), 1)}, {"infinite"});
}

TEST(Partition, RandomPerturbationsAgreeWithBruteForce) {
  // Move one coordinate of a valid partition to another existing coordinate: validation must
  // agree with the brute-force tiling check either way.
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    std::vector<Rect> cells = make_partition(seed % 2 ? "pinwheel" : "guillotine", 12, seed);
    Random random(seed);
    Rect& victim = cells[random.next() % cells.size()];
    const Rect& donor = cells[random.next() % cells.size()];
    const int axis = int(random.next() % 2);
    if (random.next() % 2)
      victim.min[axis] = donor.max[axis];
    else
      victim.max[axis] = donor.min[axis];
    if (!(victim.min.x() < victim.max.x() && victim.min.y() < victim.max.y())) continue;
    bool accepted = true;
    try {
      validate_partition(cells);
    } catch (const Error&) {
      accepted = false;
    }
    // A valid partition of a smaller bounding box is still a partition.
    EXPECT_EQ(accepted, tiles_brute_force(cells)) << "seed " << seed;
  }
}

TEST(Partition, UnknownGenerator) { EXPECT_THROW(make_partition("spiral", 10, 1), Error); }

}  // namespace
}  // namespace boxtree::planar
