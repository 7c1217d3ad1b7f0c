// SPDX-License-Identifier: MIT
// Validation and generators of rectangular partitions (paper, Section 2).
#include "boxtree/planar/partition.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

#include "boxtree/error.h"
#include "boxtree/generate.h"  // boxtree::Random

namespace boxtree::planar {
namespace {

std::string describe(const Rect& r) {
  std::ostringstream out;
  out.precision(17);
  out << "[" << r.min.x() << ", " << r.max.x() << "] x [" << r.min.y() << ", " << r.max.y() << "]";
  return out.str();
}

// Pairwise interior overlaps by a sweep over x: the active cells (those whose x-range contains
// the sweep line) have disjoint y-ranges as long as no overlap was found, so a new cell can only
// overlap its predecessor in y order.
void check_no_overlaps(const std::vector<Rect>& rects) {
  const std::size_t n = rects.size();
  std::vector<std::uint32_t> by_min(n), by_max(n);
  std::iota(by_min.begin(), by_min.end(), 0u);
  std::iota(by_max.begin(), by_max.end(), 0u);
  std::sort(by_min.begin(), by_min.end(), [&](auto a, auto b) { return rects[a].min.x() < rects[b].min.x(); });
  std::sort(by_max.begin(), by_max.end(), [&](auto a, auto b) { return rects[a].max.x() < rects[b].max.x(); });
  std::map<Real, std::uint32_t> active;  // y-min -> cell
  std::size_t removed = 0;
  for (std::size_t i = 0; i < n;) {
    const Real x = rects[by_min[i]].min.x();
    // Cells ending at or before x no longer meet the open strip to the right of x.
    for (; removed < n && rects[by_max[removed]].max.x() <= x; ++removed) {
      const Rect& r = rects[by_max[removed]];
      auto it = active.find(r.min.y());
      if (it != active.end() && it->second == by_max[removed]) active.erase(it);
    }
    for (; i < n && rects[by_min[i]].min.x() == x; ++i) {
      const std::uint32_t id = by_min[i];
      const Rect& r = rects[id];
      auto next = active.lower_bound(r.max.y());
      if (next != active.begin()) {
        const std::uint32_t other = std::prev(next)->second;
        if (rects[other].max.y() > r.min.y()) {
          throw Error("planar partition: rectangles " + std::to_string(std::min(id, other)) + " " +
                      describe(rects[std::min(id, other)]) + " and " + std::to_string(std::max(id, other)) + " " +
                      describe(rects[std::max(id, other)]) + " overlap");
        }
      }
      active.emplace(r.min.y(), id);
    }
  }
}

// No gaps, given no overlaps: the indicator sum f of the cells equals the domain's indicator iff
// their x-derivatives agree, i.e. on every vertical line the left edges (+1) and right edges (-1)
// of the cells cancel, except on the domain's own left (+1) and right (-1) sides. A mismatch on
// a line x = c over (y0, y1) means that region borders an uncovered one.
void check_no_gaps(const std::vector<Rect>& rects, const Rect& domain) {
  struct Event {
    Real x, y;
    int delta;
  };
  std::vector<Event> events;
  events.reserve(4 * rects.size() + 4);
  for (const Rect& r : rects) {
    events.push_back({r.min.x(), r.min.y(), +1});
    events.push_back({r.min.x(), r.max.y(), -1});
    events.push_back({r.max.x(), r.min.y(), -1});
    events.push_back({r.max.x(), r.max.y(), +1});
  }
  // Subtract the domain's own edges so that the expected sum is zero everywhere.
  events.push_back({domain.min.x(), domain.min.y(), -1});
  events.push_back({domain.min.x(), domain.max.y(), +1});
  events.push_back({domain.max.x(), domain.min.y(), +1});
  events.push_back({domain.max.x(), domain.max.y(), -1});
  std::sort(events.begin(), events.end(),
            [](const Event& a, const Event& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  for (std::size_t i = 0; i < events.size();) {
    const Real x = events[i].x;
    int sum = 0;
    while (i < events.size() && events[i].x == x) {
      const Real y = events[i].y;
      while (i < events.size() && events[i].x == x && events[i].y == y) sum += events[i++].delta;
      if (sum != 0) {
        const Real y_next = (i < events.size() && events[i].x == x) ? events[i].y : y;
        std::ostringstream out;
        out.precision(17);
        out << "planar partition: the rectangles leave a gap " << (sum > 0 ? "left" : "right")
            << " of the segment x = " << x << ", y in [" << y << ", " << y_next
            << "] (the cells do not tile their bounding rectangle " << describe(domain) << ")";
        throw Error(out.str());
      }
    }
  }
}

}  // namespace

Rect bounding_rect(const std::vector<Rect>& rects) {
  Rect out = rects.empty() ? Rect{} : rects.front();
  for (const Rect& r : rects) out = Rect::enclosing(out, r);
  return out;
}

void validate_partition(const std::vector<Rect>& rects) {
  if (rects.empty()) throw Error("planar partition: no rectangles");
  if (rects.size() >= 0x80000000u) throw Error("planar partition: too many rectangles");
  for (std::size_t i = 0; i < rects.size(); ++i) {
    const Rect& r = rects[i];
    if (!r.min.allFinite() || !r.max.allFinite())
      throw Error("planar partition: rectangle " + std::to_string(i) + " has a NaN or infinite coordinate");
    if (!(r.min.x() < r.max.x()) || !(r.min.y() < r.max.y()))
      throw Error("planar partition: rectangle " + std::to_string(i) + " " + describe(r) + " is empty (min >= max)");
  }
  check_no_overlaps(rects);
  check_no_gaps(rects, bounding_rect(rects));
}

std::vector<Rect> make_grid_partition(int cols, int rows) {
  if (cols < 1 || rows < 1) throw Error("make_grid_partition: cols and rows must be positive");
  std::vector<Rect> out;
  out.reserve(std::size_t(cols) * std::size_t(rows));
  // Coordinates i / cols are computed once per line so that neighbours share them exactly.
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i)
      out.push_back(Rect::from_bounds(Real(i) / cols, Real(j) / rows, Real(i + 1) / cols, Real(j + 1) / rows));
  return out;
}

namespace {

// Splits cell `index` across axis at fraction t; the second part is appended.
void split(std::vector<Rect>& cells, std::size_t index, int axis, Real t) {
  Rect& r = cells[index];
  const Real cut = r.min[axis] + t * (r.max[axis] - r.min[axis]);
  if (!(cut > r.min[axis] && cut < r.max[axis])) return;  // too thin to split in double precision
  Rect second = r;
  r.max[axis] = cut;
  second.min[axis] = cut;
  cells.push_back(second);
}

}  // namespace

std::vector<Rect> make_guillotine_partition(std::size_t count, std::uint64_t seed) {
  if (count < 1) throw Error("make_guillotine_partition: count must be positive");
  Random random(seed);
  std::vector<Rect> cells{Rect::from_bounds(0, 0, 1, 1)};
  cells.reserve(count);
  while (cells.size() < count) {
    const std::size_t index = std::size_t(random.next() % cells.size());
    // Cut across the longer side more often, so that cells stay roughly square on average.
    const Rect& r = cells[index];
    const int longer = r.width() >= r.height() ? 0 : 1;
    const int axis = random.uniform() < 0.75 ? longer : 1 - longer;
    split(cells, index, axis, random.uniform(0.2, 0.8));
  }
  return cells;
}

std::vector<Rect> make_pinwheel_partition(std::size_t count, std::uint64_t seed) {
  if (count < 1) throw Error("make_pinwheel_partition: count must be positive");
  Random random(seed);
  std::vector<Rect> cells{Rect::from_bounds(0, 0, 1, 1)};
  cells.reserve(count + 4);
  //   +------+-------------+        a < b in x, c < d in y; the four arms turn around the
  //   |      |     top     |        centre [a,b] x [c,d] like a windmill, so no line crosses
  //   | left +---+---------+ d      the square without cutting a cell.
  //   |      |ctr|         |
  //   +------+---+  right  | c
  //   |  bottom  |         |
  //   +----------+---------+
  //          a   b
  while (cells.size() + 4 <= count) {
    const std::size_t index = std::size_t(random.next() % cells.size());
    const Rect r = cells[index];
    const Real a = r.min.x() + random.uniform(0.2, 0.45) * r.width();
    const Real b = r.min.x() + random.uniform(0.55, 0.8) * r.width();
    const Real c = r.min.y() + random.uniform(0.2, 0.45) * r.height();
    const Real d = r.min.y() + random.uniform(0.55, 0.8) * r.height();
    if (!(r.min.x() < a && a < b && b < r.max.x() && r.min.y() < c && c < d && d < r.max.y())) continue;
    cells[index] = Rect::from_bounds(a, c, b, d);                    // centre
    cells.push_back(Rect::from_bounds(r.min.x(), r.min.y(), b, c));  // bottom
    cells.push_back(Rect::from_bounds(b, r.min.y(), r.max.x(), d));  // right
    cells.push_back(Rect::from_bounds(a, d, r.max.x(), r.max.y()));  // top
    cells.push_back(Rect::from_bounds(r.min.x(), c, a, r.max.y()));  // left
  }
  while (cells.size() < count) {
    const std::size_t index = std::size_t(random.next() % cells.size());
    // The fraction first, then the axis: the order gcc gave the former single call (a call's
    // arguments are evaluated in an unspecified order), which keeps the partitions it generated
    // before, now on every compiler.
    const Real fraction = random.uniform(0.3, 0.7);
    split(cells, index, int(random.next() & 1), fraction);
  }
  return cells;
}

std::vector<Rect> make_skewed_partition(std::size_t count, std::uint64_t seed) {
  if (count < 1) throw Error("make_skewed_partition: count must be positive");
  Random random(seed);
  std::vector<Rect> cells{Rect::from_bounds(0, 0, 1, 1)};
  cells.reserve(count);
  while (cells.size() < count) {
    const std::size_t index = std::size_t(random.next() % cells.size());
    const int axis = random.uniform() < 0.8 ? 0 : 1;
    Real t = std::pow(Real(10), random.uniform(-3, std::log10(0.5)));
    if (random.next() & 1) t = 1 - t;
    split(cells, index, axis, t);
  }
  return cells;
}

std::vector<Rect> make_brick_partition(std::size_t count, std::uint64_t seed) {
  if (count < 1) throw Error("make_brick_partition: count must be positive");
  Random random(seed);
  // About sqrt(count) rows of about sqrt(count) bricks; every row is cut at its own offsets so
  // that no vertical edge lines up with one in the next row.
  const std::size_t rows = std::max<std::size_t>(1, std::size_t(std::sqrt(Real(count))));
  std::vector<Rect> cells;
  cells.reserve(count);
  for (std::size_t j = 0; j < rows; ++j) {
    const std::size_t in_row = count / rows + (j < count % rows ? 1 : 0);
    const Real y0 = Real(j) / Real(rows), y1 = Real(j + 1) / Real(rows);
    std::vector<Real> cuts{0, 1};
    for (std::size_t k = 1; k < in_row; ++k) cuts.push_back((Real(k) - random.uniform(0.05, 0.95)) / Real(in_row - 1));
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k)
      if (cuts[k] < cuts[k + 1]) cells.push_back(Rect::from_bounds(cuts[k], y0, cuts[k + 1], y1));
  }
  return cells;
}

std::vector<std::string> partition_generator_names() { return {"grid", "guillotine", "pinwheel", "skewed", "brick"}; }

std::vector<Rect> make_partition(const std::string& generator, std::size_t count, std::uint64_t seed) {
  if (generator == "grid") {
    const int cols = std::max(1, int(std::lround(std::sqrt(Real(count)))));
    const int rows = std::max(1, int((count + std::size_t(cols) - 1) / std::size_t(cols)));
    return make_grid_partition(cols, rows);
  }
  if (generator == "guillotine") return make_guillotine_partition(count, seed);
  if (generator == "pinwheel") return make_pinwheel_partition(count, seed);
  if (generator == "skewed") return make_skewed_partition(count, seed);
  if (generator == "brick") return make_brick_partition(count, seed);
  std::string names;
  for (const std::string& name : partition_generator_names()) names += (names.empty() ? "" : ", ") + name;
  throw Error("unknown partition generator '" + generator + "' (valid: " + names + ")");
}

}  // namespace boxtree::planar
