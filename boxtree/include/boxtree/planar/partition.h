// SPDX-License-Identifier: MIT
#pragma once
// Rectangular partitions: validation and generators (paper, Section 2: "n axis-parallel
// rectangles that partition the unit square"). All generators are deterministic functions of
// their arguments and produce cells that tile their domain exactly (cuts reuse coordinates, so
// adjacent cells share bit-identical edges).
#include <cstdint>
#include <string>
#include <vector>

#include "boxtree/planar/rect.h"

namespace boxtree::planar {

// Throws boxtree::Error unless the rectangles tile their bounding rectangle: no rectangle empty
// or with a NaN/Inf coordinate, no two interiors overlapping (the message names both), no
// uncovered region (the message names a point on its boundary). O(n log n), exact: only
// coordinate comparisons.
void validate_partition(const std::vector<Rect>& rects);

// The bounding rectangle of all (the partition's domain).
Rect bounding_rect(const std::vector<Rect>& rects);

// cols x rows equal cells of [0,1]^2 (every inner vertex is a "cross" junction).
std::vector<Rect> make_grid_partition(int cols, int rows);

// Guillotine: start from [0,1]^2 and split a random cell across a random axis at a random
// fraction in [0.2, 0.8] until there are `count` cells.
std::vector<Rect> make_guillotine_partition(std::size_t count, std::uint64_t seed);

// Non-guillotine: recursively replace a random cell by a pinwheel (windmill) of five cells,
// four arms around a centre, which no straight cut separates; a final count not of the form
// 1 + 4k is reached with guillotine cuts.
std::vector<Rect> make_pinwheel_partition(std::size_t count, std::uint64_t seed);

// Skewed: guillotine cuts at fractions spread log-uniformly over [1e-3, 1/2] from either end,
// mostly across one axis, giving slivers with aspect ratios up to ~1e6 next to fat cells.
std::vector<Rect> make_skewed_partition(std::size_t count, std::uint64_t seed);

// Adversarial for the segment graph: rows of bricks, each row offset at random, so that every
// horizontal maximal segment spans the whole width and has high degree; only vertical segments
// can pair.
std::vector<Rect> make_brick_partition(std::size_t count, std::uint64_t seed);

// The generators by name (for tests and benches): grid, guillotine, pinwheel, skewed, brick.
// `grid` makes a near-square grid of about `count` cells. Throws boxtree::Error on an unknown name.
std::vector<std::string> partition_generator_names();
std::vector<Rect> make_partition(const std::string& generator, std::size_t count, std::uint64_t seed);

}  // namespace boxtree::planar
