// SPDX-License-Identifier: MIT
// The planar boxtree (paper, Section 2): the pairing rounds of Theorem 2.2 with shortening,
// the tree layout, point location and the stabbing number.
#include "boxtree/planar/planar_tree.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <numeric>
#include <string>

#include "boxtree/error.h"
#include "boxtree/planar/partition.h"

namespace boxtree::planar {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Swaps x and y: horizontal segments of the cells are the vertical segments of the transposed
// cells, so one routine serves both colours.
Rect transposed(const Rect& r) { return {Vec2(r.min.y(), r.min.x()), Vec2(r.max.y(), r.max.x())}; }

// One cell edge lying on a vertical line x = `x`; the cell is on the `left` of the line or right.
struct Edge {
  Real x, y0, y1;
  std::uint32_t cell;
  bool left;
};

// A cell that a pair's box covers in part: its extent across the segment is cut at `at`.
struct Cover {
  std::uint32_t cell;
  bool cut_max;  // true: the cell is left of the segment, its max x becomes `at`; false: min x
  Real at;
};

// A segment's proposal: merge cells a and b; their bounding box (in the round's transposed
// frame) is the pair's new cell; `covers` are the other cells that box cuts into.
struct Offer {
  std::uint32_t a, b;
  Rect box;
  std::array<Cover, 8> covers;
  int cover_count = 0;
};

// The best pair across one vertical segment whose sides are `left` and `right` (cells sorted by
// y, each side tiling the segment). A pair (L, R) is valid when every other cell along the
// segment that its box meets lies within the box's y-range and reaches beyond the box in x:
// then the box is exactly L, R and full-height slices of those cells (the paper's "shortening
// in one direction"), and cutting those slices off leaves rectangles. Among valid pairs the box
// of least area wins (the paper: "whichever has the least horizontal extent"). If none is valid
// -- the paper's Figure 1 cases overlook ties in width, where the box would swallow a third
// cell, and case (2) with both narrowest cells on the same side of the two T-junctions, where it
// would cut a corner out of one -- two cells on one side with the same x-range are paired
// instead (their union is a rectangle: a degree-2 segment of the other colour).
bool best_offer(const std::vector<Rect>& cells, const std::vector<std::uint32_t>& left,
                const std::vector<std::uint32_t>& right, Offer& out) {
  bool found = false;
  Real best_area = 0;
  for (std::uint32_t l : left) {
    for (std::uint32_t r : right) {
      const Rect& L = cells[l];
      const Rect& R = cells[r];
      if (!(L.min.y() < R.max.y() && R.min.y() < L.max.y())) continue;  // not adjacent
      const Rect box = Rect::enclosing(L, R);
      Offer offer{l, r, box, {}, 0};
      bool valid = true;
      auto check_side = [&](const std::vector<std::uint32_t>& side, std::uint32_t member, bool is_left) {
        for (std::uint32_t c : side) {
          if (c == member || !valid) continue;
          const Rect& C = cells[c];
          if (!(C.min.y() < box.max.y() && box.min.y() < C.max.y())) continue;  // beside the box
          const bool inside_y = C.min.y() >= box.min.y() && C.max.y() <= box.max.y();
          const bool reaches = is_left ? C.min.x() < box.min.x() : C.max.x() > box.max.x();
          if (!inside_y || !reaches || offer.cover_count == int(offer.covers.size())) {
            valid = false;
            return;
          }
          offer.covers[offer.cover_count++] = {c, is_left, is_left ? box.min.x() : box.max.x()};
        }
      };
      check_side(left, l, true);
      check_side(right, r, false);
      if (!valid) continue;
      if (!found || box.area() < best_area) {
        found = true;
        best_area = box.area();
        out = offer;
      }
    }
  }
  if (found) return true;
  for (const auto* side : {&left, &right}) {
    for (std::size_t i = 0; i + 1 < side->size(); ++i) {
      const Rect& A = cells[(*side)[i]];
      const Rect& B = cells[(*side)[i + 1]];
      if (A.min.x() == B.min.x() && A.max.x() == B.max.x()) {
        out = Offer{(*side)[i], (*side)[i + 1], Rect::enclosing(A, B), {}, 0};
        return true;
      }
    }
  }
  return false;
}

struct ColourResult {
  std::vector<Offer> accepted;
  std::size_t low_degree_segments = 0;
  std::size_t offers = 0;
};

// Pairs across the vertical segments of `cells` (already transposed for the horizontal colour).
// split_at_crosses: at a cross junction the paper's perturbation lets one colour pass through;
// vertical segments pass through (one segment), horizontal ones are cut there (two segments),
// which keeps the graph that of a T-junction-only subdivision, where Lemma 2.1 holds.
ColourResult pair_across_vertical_segments(const std::vector<Rect>& cells, const Rect& domain, int max_degree,
                                           bool split_at_crosses) {
  ColourResult result;
  const std::size_t m = cells.size();
  std::vector<Edge> edges;
  edges.reserve(2 * m);
  for (std::uint32_t i = 0; i < m; ++i) {
    const Rect& c = cells[i];
    // Segments on the domain's boundary have one side only: they never pair.
    if (c.max.x() < domain.max.x()) edges.push_back({c.max.x(), c.min.y(), c.max.y(), i, true});
    if (c.min.x() > domain.min.x()) edges.push_back({c.min.x(), c.min.y(), c.max.y(), i, false});
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& a, const Edge& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y0 != b.y0) return a.y0 < b.y0;
    return a.left < b.left;
  });

  // Per cell: 0 free, 1 paired, 2 covered (cut on one or both sides).
  std::vector<std::uint8_t> role(m, 0);
  std::vector<Real> new_min(m), new_max(m);
  std::vector<std::uint32_t> left, right;
  auto consider_segment = [&]() {
    if (left.empty() || right.empty()) return;
    if (int(left.size() + right.size()) > max_degree) return;
    ++result.low_degree_segments;
    Offer offer;
    if (!best_offer(cells, left, right, offer)) return;
    ++result.offers;
    // Compatible with the pairs taken so far: members untouched, covered cells not paired and,
    // if already cut from the other side, keeping a non-empty middle.
    if (role[offer.a] != 0 || role[offer.b] != 0) return;
    for (int k = 0; k < offer.cover_count; ++k) {
      const Cover& cv = offer.covers[k];
      if (role[cv.cell] == 1) return;
      const Real lo = cv.cut_max ? (role[cv.cell] == 2 ? new_min[cv.cell] : cells[cv.cell].min.x()) : cv.at;
      const Real hi = cv.cut_max ? cv.at : (role[cv.cell] == 2 ? new_max[cv.cell] : cells[cv.cell].max.x());
      if (!(lo < hi)) return;
      if (role[cv.cell] == 2 &&
          (cv.cut_max ? new_max[cv.cell] != cells[cv.cell].max.x() : new_min[cv.cell] != cells[cv.cell].min.x()))
        return;  // already cut on this side
    }
    role[offer.a] = role[offer.b] = 1;
    for (int k = 0; k < offer.cover_count; ++k) {
      const Cover& cv = offer.covers[k];
      if (role[cv.cell] == 0) {
        role[cv.cell] = 2;
        new_min[cv.cell] = cells[cv.cell].min.x();
        new_max[cv.cell] = cells[cv.cell].max.x();
      }
      (cv.cut_max ? new_max[cv.cell] : new_min[cv.cell]) = cv.at;
    }
    result.accepted.push_back(offer);
  };

  // Walk each line x = c bottom to top; a segment is a maximal run of touching edges, cut at
  // cross junctions (a y where both sides change cell) when split_at_crosses. Segments are
  // visited left to right, so along a chain of offers sharing cells every other one is taken.
  for (std::size_t i = 0; i < edges.size();) {
    const Real x = edges[i].x;
    std::size_t j = i;
    while (j < edges.size() && edges[j].x == x) ++j;
    left.clear();
    right.clear();
    Real reach = edges[i].y0;
    for (std::size_t k = i; k < j; ++k) {
      const Edge& e = edges[k];
      if (e.y0 > reach) {  // a gap along the line: a new segment
        consider_segment();
        left.clear();
        right.clear();
      } else if (split_at_crosses && !left.empty() && !right.empty()) {
        // A cross: both sides start a new cell at this y (each side's cells end exactly here).
        const bool left_starts = e.left ? true : (k + 1 < j && edges[k + 1].left && edges[k + 1].y0 == e.y0);
        const bool right_starts = !e.left ? true : (k + 1 < j && !edges[k + 1].left && edges[k + 1].y0 == e.y0);
        if (left_starts && right_starts && cells[left.back()].max.y() == e.y0 && cells[right.back()].max.y() == e.y0) {
          consider_segment();
          left.clear();
          right.clear();
        }
      }
      (e.left ? left : right).push_back(e.cell);
      reach = std::max(reach, e.y1);
    }
    consider_segment();
    i = j;
  }
  return result;
}

}  // namespace

std::vector<PlanarMerge> planar_pairing(std::vector<Rect> cells, const PlanarBuildSettings& settings,
                                        PlanarBuildStats* stats) {
  PlanarBuildStats local;
  auto start = Clock::now();
  if (cells.empty()) throw Error("planar boxtree: no rectangles");
  if (settings.max_segment_degree < 2) throw Error("planar boxtree: max_segment_degree must be at least 2");
  if (settings.validate_input) validate_partition(cells);
  local.validate_seconds = seconds_since(start);
  start = Clock::now();

  const std::size_t n = cells.size();
  const Rect domain = bounding_rect(cells);
  std::vector<PlanarMerge> merges;
  merges.reserve(n - 1);
  std::vector<std::uint32_t> node(n);
  std::iota(node.begin(), node.end(), 0u);
  std::vector<Rect> boxes(cells);  // original (unshortened) box per node, for the fallback

  std::vector<Rect> flipped;
  while (cells.size() > 1) {
    const std::size_t m = cells.size();
    ColourResult vertical = pair_across_vertical_segments(cells, domain, settings.max_segment_degree, false);
    flipped.resize(m);
    for (std::size_t i = 0; i < m; ++i) flipped[i] = transposed(cells[i]);
    ColourResult horizontal =
        pair_across_vertical_segments(flipped, transposed(domain), settings.max_segment_degree, true);
    const bool use_vertical = vertical.accepted.size() >= horizontal.accepted.size();
    ColourResult& chosen = use_vertical ? vertical : horizontal;
    PlanarRoundStats round;
    round.cells = m;
    round.low_degree_segments = chosen.low_degree_segments;
    round.offers = chosen.offers;
    round.pairs = chosen.accepted.size();
    round.vertical = use_vertical;
    if (chosen.accepted.empty()) break;  // the fallback below finishes the tree

    // Apply: pairs become parents whose cell is the pair's box; covered cells are shortened.
    std::vector<std::uint8_t> gone(m, 0);
    for (const Offer& offer : chosen.accepted) {
      const std::uint32_t parent = std::uint32_t(n + merges.size());
      merges.push_back({node[offer.a], node[offer.b]});
      boxes.push_back(Rect::enclosing(boxes[node[offer.a]], boxes[node[offer.b]]));
      cells[offer.a] = use_vertical ? offer.box : transposed(offer.box);
      node[offer.a] = parent;
      gone[offer.b] = 1;
      for (int k = 0; k < offer.cover_count; ++k) {
        const Cover& cv = offer.covers[k];
        const int axis = use_vertical ? 0 : 1;
        (cv.cut_max ? cells[cv.cell].max[axis] : cells[cv.cell].min[axis]) = cv.at;
        ++round.shortened;
      }
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (gone[i]) continue;
      cells[kept] = cells[i];
      node[kept] = node[i];
      ++kept;
    }
    cells.resize(kept);
    node.resize(kept);
    local.rounds.push_back(round);
    if (settings.check_rounds) {
      try {
        validate_partition(cells);
      } catch (const Error& e) {
        BOXTREE_ASSERT(false, (std::string("shortened cells form a partition after each round: ") + e.what()).c_str());
      }
    }
  }

  // Fallback (not expected; counted): pair nodes in order of their boxes' centres until one remains.
  while (node.size() > 1) {
    ++local.fallback_rounds;
    const int axis = local.fallback_rounds % 2;
    std::sort(node.begin(), node.end(),
              [&](std::uint32_t a, std::uint32_t b) { return boxes[a].center()[axis] < boxes[b].center()[axis]; });
    std::vector<std::uint32_t> next;
    for (std::size_t i = 0; i < node.size(); i += 2) {
      if (i + 1 == node.size()) {
        next.push_back(node[i]);
        break;
      }
      next.push_back(std::uint32_t(n + merges.size()));
      merges.push_back({node[i], node[i + 1]});
      boxes.push_back(Rect::enclosing(boxes[node[i]], boxes[node[i + 1]]));
    }
    node.swap(next);
  }
  local.build_seconds = seconds_since(start);
  if (stats) *stats = local;
  return merges;
}

PlanarTree::PlanarTree(std::vector<Rect> cells, std::vector<Rect> boxes, std::vector<std::uint32_t> links, int height)
    : cells_(std::move(cells)), boxes_(std::move(boxes)), links_(std::move(links)), height_(height) {
  BOXTREE_ASSERT(boxes_.size() == links_.size(), "one box per node");
  if (height_ > kMaxHeight)
    throw Error("planar boxtree: height " + std::to_string(height_) + " exceeds the query stack");
}

PlanarTree build_planar_tree(std::vector<Rect> cells, const PlanarBuildSettings& settings, PlanarBuildStats* stats) {
  PlanarBuildStats local;
  const std::vector<PlanarMerge> merges = planar_pairing(cells, settings, &local);
  const auto start = Clock::now();
  const std::size_t n = cells.size();
  const std::size_t count = n + merges.size();
  BOXTREE_ASSERT(count == 2 * n - 1, "a binary tree over n leaves has 2n-1 nodes");
  // Build-order boxes and heights, then a depth-first layout with siblings adjacent.
  std::vector<Rect> boxes(cells);
  std::vector<int> heights(count, 0);
  boxes.reserve(count);
  for (std::size_t i = 0; i < merges.size(); ++i) {
    boxes.push_back(Rect::enclosing(boxes[merges[i].first], boxes[merges[i].second]));
    heights[n + i] = 1 + std::max(heights[merges[i].first], heights[merges[i].second]);
  }
  const std::uint32_t root = std::uint32_t(count - 1);
  std::vector<Rect> out_boxes(count);
  std::vector<std::uint32_t> out_links(count, 0);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{root, 0}};
  std::uint32_t next_slot = 1;
  while (!stack.empty()) {
    const auto [id, slot] = stack.back();
    stack.pop_back();
    out_boxes[slot] = boxes[id];
    if (id < n) {
      out_links[slot] = PlanarTree::kLeafFlag | id;
      continue;
    }
    out_links[slot] = next_slot;
    stack.push_back({merges[id - n].second, next_slot + 1});
    stack.push_back({merges[id - n].first, next_slot});
    next_slot += 2;
  }
  local.build_seconds += seconds_since(start);
  if (stats) *stats = local;
  return PlanarTree(std::move(cells), std::move(out_boxes), std::move(out_links), heights[root]);
}

bool cell_contains_half_open(const Rect& cell, const Rect& domain, const Vec2& p) {
  for (int axis = 0; axis < 2; ++axis) {
    if (p[axis] < cell.min[axis]) return false;
    if (p[axis] > cell.max[axis]) return false;
    if (p[axis] == cell.max[axis] && cell.max[axis] != domain.max[axis]) return false;
  }
  return true;
}

std::optional<RectId> locate_point(const PlanarTree& tree, const Vec2& p, PlanarQueryStats* stats) {
  if (tree.empty() || !contains(tree.domain(), p)) return std::nullopt;
  PlanarNode stack[PlanarTree::kMaxHeight + 2];
  int top = 0;
  stack[top++] = tree.root();
  std::uint64_t visited = 0;
  std::optional<RectId> found;
  while (top > 0) {
    const PlanarNode node = stack[--top];
    ++visited;
    if (tree.is_leaf(node)) {
      const RectId id = tree.cell_id(node);
      if (cell_contains_half_open(tree.cell(id), tree.domain(), p)) {
        found = id;
        break;
      }
      continue;
    }
    const PlanarNode child = tree.first_child(node);
    if (contains(tree.box(child + 1), p)) stack[top++] = child + 1;
    if (contains(tree.box(child), p)) stack[top++] = child;
  }
  if (stats) stats->nodes_visited += visited;
  return found;
}

std::optional<RectId> locate_point_brute_force(const std::vector<Rect>& cells, const Vec2& p) {
  const Rect domain = bounding_rect(cells);
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (cell_contains_half_open(cells[i], domain, p)) return RectId(i);
  return std::nullopt;
}

std::size_t point_depth(const PlanarTree& tree, const Vec2& p) {
  std::size_t depth = 0;
  for (std::size_t i = 0; i < tree.node_count(); ++i) depth += interior_contains(tree.box(PlanarNode(i)), p) ? 1 : 0;
  return depth;
}

namespace {

// Range add, global max over the elementary y-intervals (no push-down: each node stores the
// max of its subtree plus its own pending add).
class MaxAddTree {
 public:
  explicit MaxAddTree(std::size_t size)
      : size_(std::max<std::size_t>(size, 1)), max_(4 * size_, 0), add_(4 * size_, 0) {}
  void add(std::size_t lo, std::size_t hi, int delta) { add(1, 0, size_, lo, hi, delta); }  // [lo, hi)
  int max() const { return max_[1]; }

 private:
  void add(std::size_t node, std::size_t l, std::size_t r, std::size_t lo, std::size_t hi, int delta) {
    if (hi <= l || r <= lo) return;
    if (lo <= l && r <= hi) {
      add_[node] += delta;
      max_[node] += delta;
      return;
    }
    const std::size_t mid = (l + r) / 2;
    add(2 * node, l, mid, lo, hi, delta);
    add(2 * node + 1, mid, r, lo, hi, delta);
    max_[node] = add_[node] + std::max(max_[2 * node], max_[2 * node + 1]);
  }
  std::size_t size_;
  std::vector<int> max_, add_;
};

}  // namespace

std::size_t stabbing_number(const PlanarTree& tree) {
  // The deepest point of open boxes lies in an open cell of the grid of all box coordinates:
  // sweep x, and at each event abscissa apply removals (boxes ending there) before insertions,
  // then read the depth of the strip to the right.
  std::vector<Real> ys;
  ys.reserve(2 * tree.node_count());
  for (std::size_t i = 0; i < tree.node_count(); ++i) {
    ys.push_back(tree.box(PlanarNode(i)).min.y());
    ys.push_back(tree.box(PlanarNode(i)).max.y());
  }
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  auto y_index = [&](Real y) { return std::size_t(std::lower_bound(ys.begin(), ys.end(), y) - ys.begin()); };
  struct Event {
    Real x;
    int delta;
    std::uint32_t lo, hi;
  };
  std::vector<Event> events;
  events.reserve(2 * tree.node_count());
  for (std::size_t i = 0; i < tree.node_count(); ++i) {
    const Rect& b = tree.box(PlanarNode(i));
    if (!(b.min.x() < b.max.x() && b.min.y() < b.max.y())) continue;  // empty interior
    const auto lo = std::uint32_t(y_index(b.min.y())), hi = std::uint32_t(y_index(b.max.y()));
    events.push_back({b.min.x(), +1, lo, hi});
    events.push_back({b.max.x(), -1, lo, hi});
  }
  std::sort(events.begin(), events.end(),
            [](const Event& a, const Event& b) { return a.x != b.x ? a.x < b.x : a.delta < b.delta; });
  MaxAddTree depth(ys.size());
  int best = 0;
  for (std::size_t i = 0; i < events.size();) {
    const Real x = events[i].x;
    for (; i < events.size() && events[i].x == x; ++i) depth.add(events[i].lo, events[i].hi, events[i].delta);
    best = std::max(best, depth.max());
  }
  return std::size_t(best);
}

void validate_planar_tree(const PlanarTree& tree) {
  if (tree.empty()) throw Error("planar tree: empty");
  const std::size_t count = tree.node_count();
  if (count != 2 * tree.cell_count() - 1) throw Error("planar tree: node count is not 2n-1");
  std::vector<int> height(count, 0);
  std::vector<std::uint8_t> seen_cell(tree.cell_count(), 0), reached(count, 0);
  reached[0] = 1;
  for (std::size_t i = count; i-- > 0;) {
    const PlanarNode node = PlanarNode(i);
    if (tree.is_leaf(node)) {
      const RectId id = tree.cell_id(node);
      if (id >= tree.cell_count() || seen_cell[id])
        throw Error("planar tree: leaf " + std::to_string(i) + " has a bad or repeated cell");
      seen_cell[id] = 1;
      if (tree.box(node) != tree.cell(id))
        throw Error("planar tree: leaf " + std::to_string(i) + "'s box is not its cell");
      continue;
    }
    const PlanarNode c = tree.first_child(node);
    if (c <= node || c + 1 >= count) throw Error("planar tree: node " + std::to_string(i) + " has bad children");
    if (Rect::enclosing(tree.box(c), tree.box(c + 1)) != tree.box(node))
      throw Error("planar tree: node " + std::to_string(i) + "'s box is not the smallest enclosing its children");
    height[i] = 1 + std::max(height[c], height[c + 1]);
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!tree.is_leaf(PlanarNode(i))) {
      const PlanarNode c = tree.first_child(PlanarNode(i));
      if (reached[c] || reached[c + 1]) throw Error("planar tree: a node has two parents");
      reached[c] = reached[c + 1] = reached[i];
    }
  }
  if (std::find(reached.begin(), reached.end(), 0) != reached.end()) throw Error("planar tree: a node is unreachable");
  if (height[0] != tree.height()) throw Error("planar tree: stored height is wrong");
}

}  // namespace boxtree::planar
