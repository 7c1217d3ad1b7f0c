// SPDX-License-Identifier: MIT
#include "boxtree/packed_tree.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

#include "boxtree/volume/obb.h"
#include "internal.h"
#include "query_internal.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace boxtree {

namespace {

constexpr Real kMaxQ = 65535;
constexpr int kWidth = PackedAabbTree::kWidth;
// Depth-first walks push at most kWidth - 1 entries per level.
constexpr int kStackSize = (kWidth - 1) * PackedAabbTree::kMaxHeight + kWidth;

}  // namespace

std::uint16_t PackedAabbTree::quantize_down(Real x, int axis) const {
  Real q = std::floor((x - origin_[axis]) * inv_step_[axis]);
  q = std::clamp(q, Real(0), kMaxQ);  // NaN-free: callers pass finite or clamped values
  // The multiply may round either way; step down until the grid value is really <= x.
  while (q > 0 && value(q, axis) > x) q -= 1;
  return std::uint16_t(q);
}

std::uint16_t PackedAabbTree::quantize_up(Real x, int axis) const {
  Real q = std::ceil((x - origin_[axis]) * inv_step_[axis]);
  q = std::clamp(q, Real(0), kMaxQ);
  while (q < kMaxQ && value(q, axis) < x) q += 1;
  return std::uint16_t(q);
}

PackedAabbTree::PackedAabbTree(const Tree<Aabb>& tree) {
  if (tree.empty()) return;
  mesh_ = tree.shared_mesh();
  height_ = 0;
  bounds_ = tree.volume(tree.root());

  // The grid spans the bounds plus kSpareSteps + 2 steps on each side, so that every box,
  // rounded outward by kSpareSteps, lies in [1, 65534]: an empty slot's box (min 65535, max 0)
  // then misses every query box clamped to that range. A flat axis (a planar terrain's
  // height) gets a tiny but non-zero step, relative to the mesh's size and position, so that
  // the grid stays invertible; its boxes are then exact to that step.
  const Vec3 extent = bounds_.extent();
  const Real magnitude = std::max(bounds_.min.cwiseAbs().maxCoeff(), bounds_.max.cwiseAbs().maxCoeff());
  const Real floor_extent = std::max({extent.maxCoeff() * Real(1e-9), magnitude * Real(1e-12), Real(1e-30)});
  constexpr int kMargin = kSpareSteps + 2;
  for (int i = 0; i < 3; ++i) {
    const Real span = std::max(extent[i], floor_extent);
    step_[i] = span / (kMaxQ - 2 * kMargin);
    inv_step_[i] = 1 / step_[i];
    origin_[i] = bounds_.min[i] - kMargin * step_[i];
  }

  if (tree.is_leaf(tree.root())) {
    root_link_ = kLeafFlag | tree.facet(tree.root());
    return;
  }
  root_link_ = 0;
  // Which source nodes become packed nodes, bottom-up: slots[v] are the children that v would
  // have as a packed node: its two children, with a child's own slots taken in (the child then
  // needs no packed node of its own) whenever they fit in four, the larger child first. Leaves
  // pair up into full nodes at the bottom, so there are about n / 3 packed nodes whatever the
  // parity of the levels (collapsing every two levels from the top leaves half the bottom nodes
  // with two children).
  // One byte per source node: bits 0 and 1, whether child 0 / 1 is taken in; bits 2-4, the
  // slot count. The child lists are expanded from these bits when the node is laid out (kept
  // whole, 20 bytes per node, they were 40 MB of temporary memory at 1M facets).
  std::vector<std::uint8_t> plan(tree.node_count(), 0);
  const auto slot_count = [&](NodeIndex c) { return tree.is_leaf(c) ? 1 : int(plan[c] >> 2); };
  std::size_t packed_count = 1;  // the root, and every inner child not taken into its parent
  // Children come after their parent in Tree's layout: a reverse sweep sees children first.
  for (NodeIndex v = NodeIndex(tree.node_count()); v-- > 0;) {
    if (tree.is_leaf(v)) continue;
    const NodeIndex c0 = tree.first_child(v), c1 = c0 + 1;
    bool take[2] = {false, false};
    if (!tree.is_leaf(c0) && !tree.is_leaf(c1) && slot_count(c0) + slot_count(c1) <= kWidth) {
      take[0] = take[1] = true;
    } else {
      // Take in one child's slots: the one with the larger box, if it fits.
      const bool larger_first = surface_area(tree.volume(c0)) >= surface_area(tree.volume(c1));
      for (int k : {larger_first ? 0 : 1, larger_first ? 1 : 0}) {
        const NodeIndex c = c0 + NodeIndex(k);
        if (!tree.is_leaf(c) && slot_count(c) + 1 <= kWidth) {
          take[k] = true;
          break;
        }
      }
    }
    int count = 0;
    for (int k = 0; k < 2; ++k) {
      const NodeIndex c = c0 + NodeIndex(k);
      if (take[k]) {
        count += slot_count(c);
      } else {
        ++count;
        packed_count += !tree.is_leaf(c);
      }
    }
    plan[v] = std::uint8_t(int(take[0]) | int(take[1]) << 1 | count << 2);
  }
  // The slots of inner node v, in order: each child, or the slots of a child taken in.
  const auto expand = [&](NodeIndex v, NodeIndex* out) {
    int count = 0;
    const auto visit = [&](const auto& self, NodeIndex node) -> void {
      const NodeIndex c0 = tree.first_child(node);
      for (int k = 0; k < 2; ++k) {
        const NodeIndex c = c0 + NodeIndex(k);
        if (plan[node] >> k & 1) {
          self(self, c);
        } else {
          out[count++] = c;
        }
      }
    };
    visit(visit, v);
    return count;
  };
  // Exactly: a guess and shrink_to_fit copied the whole array (1M facets: 22 MB).
  nodes_.reserve(packed_count);
  // Depth first, preorder: a node's first inner child is the next node (what the walks read
  // next). Each pending entry is a source node to pack, where its packed index must be written,
  // and its depth in the packed tree.
  struct Pending {
    NodeIndex source;
    std::uint32_t parent;  // packed index of the parent (unused for the root)
    int slot;              // which of the parent's links points here; -1 for the root
    int depth;
  };
  std::vector<Pending> pending{{tree.root(), 0, -1, 0}};
  while (!pending.empty()) {
    const Pending p = pending.back();
    pending.pop_back();
    const auto index = std::uint32_t(nodes_.size());
    if (p.slot >= 0) nodes_[p.parent].link[p.slot] = index;
    NodeIndex children[kWidth];
    const int count = expand(p.source, children);
    Node& node = nodes_.emplace_back();
    for (int slot = 0; slot < kWidth; ++slot) {
      if (slot >= count) {  // an empty box (min > max) and no link
        for (int i = 0; i < 3; ++i) node.min[i][slot] = 0xFFFF, node.max[i][slot] = 0;
        node.link[slot] = kEmpty;
        continue;
      }
      const Aabb& box = tree.volume(children[slot]);
      for (int i = 0; i < 3; ++i) {
        node.min[i][slot] = std::uint16_t(quantize_down(box.min[i], i) - kSpareSteps);
        node.max[i][slot] = std::uint16_t(quantize_up(box.max[i], i) + kSpareSteps);
      }
      node.link[slot] =
          tree.is_leaf(children[slot]) ? (kLeafFlag | tree.facet(children[slot])) : 0;  // inner: set when laid out
      if (tree.is_leaf(children[slot])) height_ = std::max(height_, p.depth + 1);
    }
    // Pushed last to first, so that the first inner child's subtree is laid out right after.
    for (int slot = count - 1; slot >= 0; --slot)
      if (!tree.is_leaf(children[slot])) pending.push_back({children[slot], index, slot, p.depth + 1});
  }
  assert(nodes_.size() == packed_count);
}

namespace {

using detail::StatsSink;

// A query box on the packed grid, rounded outward (so it contains the exact box).
struct GridBox {
  std::uint16_t min[3];
  std::uint16_t max[3];
#if defined(__SSE2__)
  // The same box as lanes for SSE2 (x in lanes 0-3, y in 4-7; z in 0-3), offset by -32768
  // (xor 0x8000) so that SSE2's signed 16-bit compares order the unsigned grid values.
  __m128i min_xy, max_xy, min_z, max_z;
  void prepare() {
    const auto lanes = [](std::uint16_t lo, std::uint16_t hi) {
      return _mm_setr_epi16(short(lo ^ 0x8000), short(lo ^ 0x8000), short(lo ^ 0x8000), short(lo ^ 0x8000),
                            short(hi ^ 0x8000), short(hi ^ 0x8000), short(hi ^ 0x8000), short(hi ^ 0x8000));
    };
    min_xy = lanes(min[0], min[1]);
    max_xy = lanes(max[0], max[1]);
    min_z = lanes(min[2], min[2]);
    max_z = lanes(max[2], max[2]);
  }
  // Bit c set: child c's box overlaps: four boxes in a handful of instructions.
  unsigned overlaps(const PackedAabbTree::Node& node) const {
    const __m128i bias = _mm_set1_epi16(short(0x8000));
    const auto load16 = [&](const std::uint16_t* p) {
      return _mm_xor_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)), bias);
    };
    const auto load8 = [&](const std::uint16_t* p) {
      return _mm_xor_si128(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), bias);
    };
    // Apart on an axis: the node's min above the query's max, or the query's min above the node's max.
    const __m128i apart_xy = _mm_or_si128(_mm_cmpgt_epi16(load16(&node.min[0][0]), max_xy),
                                          _mm_cmpgt_epi16(min_xy, load16(&node.max[0][0])));
    const __m128i apart_z =
        _mm_or_si128(_mm_cmpgt_epi16(load8(&node.min[2][0]), max_z), _mm_cmpgt_epi16(min_z, load8(&node.max[2][0])));
    const __m128i apart = _mm_or_si128(_mm_or_si128(apart_xy, _mm_unpackhi_epi64(apart_xy, apart_xy)), apart_z);
    return ~unsigned(_mm_movemask_epi8(_mm_packs_epi16(apart, apart))) & 0xFu;
  }
#else
  void prepare() {}
  unsigned overlaps(const PackedAabbTree::Node& node) const {
    unsigned mask = 0;
    for (int c = 0; c < kWidth; ++c) {
      const bool hit = (min[0] <= node.max[0][c]) & (node.min[0][c] <= max[0]) & (min[1] <= node.max[1][c]) &
                       (node.min[1][c] <= max[1]) & (min[2] <= node.max[2][c]) & (node.min[2][c] <= max[2]);
      mask |= unsigned(hit) << c;
    }
    return mask;
  }
#endif
};

// `box` on `tree`'s grid, rounded outward by one more step than needed (the multiply's error is
// far below a step, and this is per query, not per node), clamped to [1, 65534] where every
// packed box lies, so that empty slots never match. NaN sides give the whole range: never culls.
GridBox grid_box_of(const PackedAabbTree& tree, const Aabb& box) {
  GridBox grid;
  for (int i = 0; i < 3; ++i) {
    const Real lo = (std::max(box.min[i], tree.bounds().min[i]) - tree.origin()[i]) * tree.inv_step()[i];
    const Real hi = (std::min(box.max[i], tree.bounds().max[i]) - tree.origin()[i]) * tree.inv_step()[i];
    // Clamped first, the values are positive: truncation is floor (no libm call), and one more
    // step outward covers ceil. Written so that NaN takes the outer bound.
    grid.min[i] = std::uint16_t(lo - 1 >= 1 ? std::min(lo - 1, Real(0xFFFE)) : Real(1));
    grid.max[i] = std::uint16_t(hi + 2 <= 0xFFFE ? std::max(hi + 2, Real(1)) : Real(0xFFFE));
  }
  grid.prepare();
  return grid;
}

// The bounding boxes of the query shapes that volume/ does not define (Aabb and Obb are
// volume/aabb.h's and volume/obb.h's bounding_aabb).
Aabb bounding_aabb(const Sphere& sphere) {
  return {sphere.center.array() - sphere.radius, sphere.center.array() + sphere.radius};
}
Aabb bounding_aabb(const Capsule& capsule) {
  return {capsule.p0.cwiseMin(capsule.p1).array() - capsule.radius,
          capsule.p0.cwiseMax(capsule.p1).array() + capsule.radius};
}

#if defined(__SSE2__)
// One grid axis of a node's four children (`p`: node.min[i] or node.max[i]) as four floats,
// exact (the grid values are below 2^16).
__m128 grid_lanes(const std::uint16_t* p) {
  return _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128()));
}
#endif

// The three face axes of an oriented box as separating axes for four children at once, in
// single precision on the grid: with the box's bounding box on the grid (GridBox, the three
// world axes) these are the six face axes of the box-box test; the nine edge-edge axes are left
// to the callers that need an exact answer (they rarely separate what the faces do not).
// Along axis u, a child with grid corners lo, hi (world centre origin + step * (lo + hi) / 2,
// half extent step * (hi - lo) / 2) is apart from the box (centre C, radius r_u along u) when
//   |w . (lo + hi) - 2 u . (C - origin)| > |w| . (hi - lo) + 2 r_u,   w = u * step (per axis).
// lo + hi and hi - lo are exact in float; the products and sums round by a few float ulps of
// the terms' magnitudes, which `pad` (16 ulps of their sum) covers, so the test never culls a
// box that meets the oriented box. Non-finite input disables it (every child passes).
struct GridObbAxes {
  bool enabled = false;
  GridObbAxes() = default;  // disabled: every child passes
  float w[3][3] = {};       // [axis j][grid axis i]
  float two_k[3] = {};      // 2 u_j . (C - origin)
  float reach[3] = {};      // 2 r_j + pad

  // `radii`: the box's radius along each of its axes (its half extents if the axes are
  // orthonormal).
  GridObbAxes(const PackedAabbTree& tree, const Vec3& center, const Mat3& axes, const Vec3& radii) {
    const Vec3 offset = center - tree.origin();
    bool finite = true;
    for (int j = 0; j < 3; ++j) {
      const Vec3 u = axes.col(j);
      const Vec3 wj = u.cwiseProduct(tree.step());
      const Real k2 = 2 * u.dot(offset);
      const Real r2 = 2 * radii[j];
      const Real magnitude = wj.cwiseAbs().sum() * 2 * 65535 + std::abs(k2) + r2;
      const Real pad = 16 * Real(std::numeric_limits<float>::epsilon()) * magnitude;
      finite = finite && std::isfinite(magnitude) && magnitude < Real(1e30);
      for (int i = 0; i < 3; ++i) w[j][i] = float(wj[i]);
      two_k[j] = float(k2);
      reach[j] = float(r2 + pad);
    }
    enabled = finite;
  }

  // The children of `mask` (bit c: child c) that no face axis separates from the box.
  unsigned overlaps(const PackedAabbTree::Node& node, unsigned mask) const {
    if (!enabled || mask == 0) return mask;
#if defined(__SSE2__)
    __m128 sum[3], diff[3];
    for (int i = 0; i < 3; ++i) {
      const __m128 lo = grid_lanes(node.min[i]), hi = grid_lanes(node.max[i]);
      sum[i] = _mm_add_ps(lo, hi);
      diff[i] = _mm_sub_ps(hi, lo);
    }
    const __m128 sign = _mm_set1_ps(-0.0f);
    __m128 apart = _mm_setzero_ps();
    for (int j = 0; j < 3; ++j) {
      __m128 distance = _mm_set1_ps(-two_k[j]);
      __m128 radius = _mm_set1_ps(reach[j]);
      for (int i = 0; i < 3; ++i) {
        distance = _mm_add_ps(distance, _mm_mul_ps(_mm_set1_ps(w[j][i]), sum[i]));
        radius = _mm_add_ps(radius, _mm_mul_ps(_mm_set1_ps(std::abs(w[j][i])), diff[i]));
      }
      apart = _mm_or_ps(apart, _mm_cmpgt_ps(_mm_andnot_ps(sign, distance), radius));
    }
    return mask & ~unsigned(_mm_movemask_ps(apart));
#else
    for (int c = 0; c < kWidth; ++c) {
      if (!(mask >> c & 1u)) continue;
      for (int j = 0; j < 3; ++j) {
        float distance = -two_k[j], radius = reach[j];
        for (int i = 0; i < 3; ++i) {
          const float lo = float(node.min[i][c]), hi = float(node.max[i][c]);
          distance += w[j][i] * (lo + hi);
          radius += std::abs(w[j][i]) * (hi - lo);
        }
        if (std::abs(distance) > radius) {
          mask &= ~(1u << c);
          break;
        }
      }
    }
    return mask;
#endif
  }
};

// A sphere against four children at once, in single precision on the grid: child c is apart
// when the distance from the centre to its box exceeds the radius. The centre is first clamped to
// the grid ([0, 65535] steps on each axis, where every box lies): its distance beyond the grid on
// an axis (e.g. the height of a sphere over a flat terrain, whose grid is a sliver) adds to every
// child's distance, so its square is taken from the radius's once, in double. Per axis the gap in
// grid steps is then max(lo - c, c - hi, 0) for the clamped centre c; lo and hi are exact in
// float, c rounds by at most 2^-9 steps and each difference by 2^-8, so each gap is taken 2^-5
// steps smaller, a lower bound of the true gap; the squared world distance from those gaps
// rounds by a few float ulps, which `reach2` allows for (64 ulps of r^2, and 1e-9 of the part
// beyond the grid). So the test never culls a child whose true box the sphere touches. Disabled
// (every child passes) for centres or radii that double or float cannot hold.
struct GridSphere {
  bool enabled = false;
  float center[3] = {};  // on the grid, clamped to it
  float step[3] = {};    // world length of a grid step per axis
  float reach2 = 0;      // the squared radius less the squared distance beyond the grid, padded

  GridSphere(const PackedAabbTree& tree, const Sphere& sphere) {
    bool finite = std::isfinite(sphere.radius) && sphere.radius < Real(1e18);
    Real beyond2 = 0;
    for (int i = 0; i < 3; ++i) {
      const Real c = (sphere.center[i] - tree.origin()[i]) * tree.inv_step()[i];
      finite = finite && std::isfinite(c) && tree.step()[i] < Real(1e18);
      const Real clamped = std::clamp(c, Real(0), Real(65535));
      const Real beyond = (c - clamped) * tree.step()[i];
      beyond2 += beyond * beyond;
      center[i] = float(clamped);
      step[i] = float(tree.step()[i]);
    }
    const Real r2 = sphere.radius * sphere.radius;
    reach2 = float(r2 * (1 + 64 * Real(std::numeric_limits<float>::epsilon())) - beyond2 * (1 - Real(1e-9)));
    enabled = finite && std::isfinite(beyond2) && std::isfinite(reach2);
  }

  unsigned overlaps(const PackedAabbTree::Node& node, unsigned mask) const {
    if (!enabled || mask == 0) return mask;
    constexpr float kSlack = 1.0f / 32;
#if defined(__SSE2__)
    __m128 distance2 = _mm_setzero_ps();
    for (int i = 0; i < 3; ++i) {
      const __m128 c = _mm_set1_ps(center[i]);
      const __m128 below = _mm_sub_ps(grid_lanes(node.min[i]), c);  // > 0: the centre is below the box
      const __m128 above = _mm_sub_ps(c, grid_lanes(node.max[i]));  // > 0: the centre is above it
      const __m128 gap = _mm_max_ps(_mm_sub_ps(_mm_max_ps(below, above), _mm_set1_ps(kSlack)), _mm_setzero_ps());
      const __m128 world = _mm_mul_ps(gap, _mm_set1_ps(step[i]));
      distance2 = _mm_add_ps(distance2, _mm_mul_ps(world, world));
    }
    return mask & ~unsigned(_mm_movemask_ps(_mm_cmpgt_ps(distance2, _mm_set1_ps(reach2))));
#else
    for (int c = 0; c < kWidth; ++c) {
      if (!(mask >> c & 1u)) continue;
      float distance2 = 0;
      for (int i = 0; i < 3; ++i) {
        const float below = float(node.min[i][c]) - center[i], above = center[i] - float(node.max[i][c]);
        const float gap = std::max(std::max(below, above) - kSlack, 0.0f);
        distance2 += (gap * step[i]) * (gap * step[i]);
      }
      if (distance2 > reach2) mask &= ~(1u << c);
    }
    return mask;
#endif
  }
};

// Depth-first walk over the children whose box passes `child_mask(node)` (bit c: child c; never
// set for an empty slot);
// `leaf(facet)` returns false to stop. The caller has tested the root's volume (the exact bounds).
template <class ChildMask, class Leaf>
void walk(const PackedAabbTree& tree, ChildMask&& child_mask, Leaf&& leaf, QueryStats& stats) {
  const std::uint32_t root = tree.root_link();
  ++stats.nodes_visited;
  if (PackedAabbTree::is_leaf(root)) {
    leaf(PackedAabbTree::facet(root));
    return;
  }
  const PackedAabbTree::Node* nodes = tree.nodes().data();
  std::uint32_t stack[kStackSize];
  int top = 0;
  std::uint32_t current = root;
  for (;;) {
    const PackedAabbTree::Node& node = nodes[current];
    stats.volume_tests += kWidth;
    unsigned mask = child_mask(node);  // never has an empty slot's bit
    // Bits set in a 4-bit mask, from a table: without -mpopcnt (the x86-64 baseline),
    // __builtin_popcount is a call into libgcc, 6% of a box query on a small terrain.
    static_assert(kWidth == 4, "the table counts 4-bit masks");
    constexpr unsigned char kBitsSet[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    stats.nodes_visited += kBitsSet[mask];
    // Leaves are handled at once; of the inner children, descend into the first, keep the rest.
    bool descend = false;
    while (mask != 0) {
      const int slot = __builtin_ctz(mask);
      mask &= mask - 1;
      const std::uint32_t link = node.link[slot];
      if (PackedAabbTree::is_leaf(link)) {
        if (!leaf(PackedAabbTree::facet(link))) return;
      } else if (!descend) {
        current = link;
        descend = true;
      } else {
        // Read only after the current subtree: start loading it now (it is far in the array).
        __builtin_prefetch(&nodes[link]);
        stack[top++] = link;
      }
    }
    if (descend) continue;
    if (top == 0) return;
    current = stack[--top];
  }
}

// The children of `mask` whose (dequantized) box passes `test(box)`.
template <class Test>
unsigned refine_mask(const PackedAabbTree& tree, const PackedAabbTree::Node& node, unsigned mask, Test&& test) {
  for (unsigned rest = mask; rest != 0; rest &= rest - 1) {
    const int c = __builtin_ctz(rest);
    if (!test(tree.child_box(node, c))) mask &= ~(1u << c);
  }
  return mask;
}

// Bit c set: child c is a leaf (a facet).
unsigned leaf_slots(const PackedAabbTree::Node& node) {
  unsigned mask = 0;
  for (int c = 0; c < kWidth; ++c) mask |= unsigned(PackedAabbTree::is_leaf(node.link[c])) << c;
  return mask;
}

// The next float above f (+inf and NaN stay). std::nextafter is a call into libm, not inlined:
// 2% of a ray's time when every hit rescaled the ray's end with it.
inline float next_float_up(float f) {
  if (!(f < std::numeric_limits<float>::infinity())) return f;
  if (f == 0) return std::numeric_limits<float>::denorm_min();
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  bits = f > 0 ? bits + 1 : bits - 1;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}
inline float next_float_down(float f) { return -next_float_up(-f); }

// The ray in grid coordinates, restarted at its first point in the mesh's bounds (t = base) and
// scaled so that its largest direction component is 1 (parameter s = (t - base) / scale): there
// grid coordinates are at most ~65,536, so single precision places the ray to ~0.01 of a grid
// step, far inside the step that every packed box keeps to spare around the exact box. Float
// slab tests of four boxes at once are therefore conservative: a ray that meets an exact box
// meets its packed box in an interval about two steps long, and rounding moves the ends by a
// percent of that.
struct GridRay {
  Real base = 0;
  Real scale = 1;
  float origin[3] = {};
  float inv_direction[3] = {};

  GridRay() = default;
  GridRay(const PackedAabbTree& tree, const Ray& ray, Real t_first) : base(t_first) {
    const Vec3 start = ray.origin + t_first * ray.direction;
    Vec3 o = (start - tree.origin()).cwiseProduct(tree.inv_step());  // rounding: far below the grid steps
    Vec3 d = ray.direction.cwiseProduct(tree.inv_step());
    scale = 1 / std::max(d.cwiseAbs().maxCoeff(), std::numeric_limits<Real>::min());
    d *= scale;
    for (int i = 0; i < 3; ++i) {
      // A (nearly) parallel axis gets a tiny non-zero component: its slab then spans +-huge s.
      const Real di = std::abs(d[i]) < 1e-20 ? std::copysign(Real(1e-20), d[i]) : d[i];
      origin[i] = float(o[i]);
      inv_direction[i] = float(1 / di);
    }
  }
  // s of a ray parameter t, rounded outward (down for the start of a range, up for its end).
  float s_down(Real t) const { return next_float_down(float((t - base) / scale)); }
  float s_up(Real t) const { return next_float_up(float((t - base) / scale)); }
  Real t_of(float s) const { return base + Real(s) * scale; }

  // Bit c set: the ray meets child c's box for s in [s_lo, s_hi]; s_enter[c] is where it enters.
  unsigned hits(const PackedAabbTree::Node& node, float s_lo, float s_hi, float s_enter[kWidth]) const {
#if defined(__SSE2__)
    const __m128i zero = _mm_setzero_si128();
    __m128 near = _mm_set1_ps(s_lo);
    __m128 far = _mm_set1_ps(s_hi);
    for (int i = 0; i < 3; ++i) {
      const auto corner = [&](const std::uint16_t* p) {
        return _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), zero));
      };
      const __m128 o = _mm_set1_ps(origin[i]);
      const __m128 inv = _mm_set1_ps(inv_direction[i]);
      const __m128 t0 = _mm_mul_ps(_mm_sub_ps(corner(node.min[i]), o), inv);
      const __m128 t1 = _mm_mul_ps(_mm_sub_ps(corner(node.max[i]), o), inv);
      near = _mm_max_ps(near, _mm_min_ps(t0, t1));
      far = _mm_min_ps(far, _mm_max_ps(t0, t1));
    }
    _mm_storeu_ps(s_enter, near);
    return unsigned(_mm_movemask_ps(_mm_cmple_ps(near, far)));
#else
    unsigned mask = 0;
    for (int c = 0; c < kWidth; ++c) {
      float near = s_lo, far = s_hi;
      for (int i = 0; i < 3; ++i) {
        const float t0 = (float(node.min[i][c]) - origin[i]) * inv_direction[i];
        const float t1 = (float(node.max[i][c]) - origin[i]) * inv_direction[i];
        near = std::max(near, std::min(t0, t1));
        far = std::min(far, std::max(t0, t1));
      }
      s_enter[c] = near;
      if (near <= far) mask |= 1u << c;
    }
    return mask;
#endif
  }
};

// Front-to-back ray walk, one inner node per step(), so that several rays' walks can take turns
// (ray_closest_hits). `leaf(facet, t_max)` may lower t_max (which prunes everything entered
// farther) and returns false to stop the walk. kDeferLeaves (for walks that take turns): a leaf
// takes two steps of its own, the first starting the loads of its corners (their indices were
// requested when the leaf was found), the second testing it, so that those loads too overlap
// the other walks' work.
template <bool kDeferLeaves = false>
class OrderedRayWalk {
 public:
  // False when there is nothing to walk (an invalid ray, or one that misses the mesh's bounds);
  // a single-facet tree's leaf is visited here.
  template <class Leaf>
  bool start(const PackedAabbTree& tree, const Ray& ray, Leaf&& leaf, QueryStats& stats) {
    if (tree.empty() || !is_valid(ray)) return false;
    t_max_ = ray.t_max;
    Real t_enter = 0;
    ++stats.volume_tests;
    if (!intersect_ray(tree.bounds(), RayPrecomputed(ray), ray.t_min, t_max_, &t_enter)) return false;
    ++stats.nodes_visited;
    if (PackedAabbTree::is_leaf(tree.root_link())) {
      leaf(PackedAabbTree::facet(tree.root_link()), t_max_);
      return false;
    }
    grid_ = GridRay(tree, ray, t_enter);
    s_min_ = grid_.s_down(ray.t_min);
    t_of_s_max_ = t_max_;
    s_max_ = grid_.s_up(t_max_);
    nodes_ = tree.nodes().data();
    triangles_ = tree.mesh().triangles.data();
    vertices_ = tree.mesh().vertices.data();
    top_ = 0;
    corners_requested_ = false;
    current_ = tree.root_link();
    __builtin_prefetch(&nodes_[current_]);
    return true;
  }

  // Tests the current node's children and the leaves ahead of its nearest inner child (deferred:
  // the nearest child, leaf or not, is next), and moves to the next node (its load started);
  // false when the walk is over.
  template <class Leaf>
  bool step(Leaf&& leaf, QueryStats& stats) {
    if (kDeferLeaves && PackedAabbTree::is_leaf(current_)) {
      const FacetId f = PackedAabbTree::facet(current_);
      if (!corners_requested_) {
        for (const VertexId v : triangles_[f]) __builtin_prefetch(&vertices_[v]);
        corners_requested_ = true;
        return true;
      }
      corners_requested_ = false;
      if (!leaf(f, t_max_)) return false;
      update_s_max();
      return next_from_stack(leaf, stats);
    }
    const PackedAabbTree::Node& node = nodes_[current_];
    float s_enter[kWidth];
    unsigned mask = grid_.hits(node, s_min_, s_max_, s_enter);
    stats.volume_tests += kWidth;
    // The children met, sorted by entry (insertion sort of at most four).
    Entry hits[kWidth];
    int count = 0;
    while (mask != 0) {
      const int slot = __builtin_ctz(mask);
      mask &= mask - 1;
      const std::uint32_t link = node.link[slot];
      if (link == PackedAabbTree::kEmpty) continue;
      // Start loading what the child will need: its node, or a leaf's vertex indices (the
      // vertices themselves depend on them).
      if (!PackedAabbTree::is_leaf(link))
        __builtin_prefetch(&nodes_[link]);
      else
        __builtin_prefetch(&triangles_[PackedAabbTree::facet(link)]);
      const float s = s_enter[slot];  // at least s_min: hits() starts from it
      int k = count++;
      for (; k > 0 && hits[k - 1].s_enter > s; --k) hits[k] = hits[k - 1];
      hits[k] = {link, s};
    }
    // Nearest first: leaves ahead of the first inner child are tested at once, that child is
    // entered directly, and the rest wait on the stack (farthest deepest). A leaf or node that a
    // hit has moved beyond the ray's end is dropped.
    int k = 0;
    if (!kDeferLeaves) {
      for (; k < count && PackedAabbTree::is_leaf(hits[k].link); ++k) {
        if (hits[k].s_enter > s_max_) continue;
        ++stats.nodes_visited;
        if (!leaf(PackedAabbTree::facet(hits[k].link), t_max_)) return false;
        update_s_max();
      }
    }
    if (k < count && hits[k].s_enter > s_max_) count = k;  // the rest lie farther still
    for (int j = count - 1; j > k; --j) stack_[top_++] = hits[j];
    if (k < count) {
      ++stats.nodes_visited;
      current_ = hits[k].link;
      return true;
    }
    return next_from_stack(leaf, stats);
  }

 private:
  // Entries keep where the ray enters them in grid units (s, single precision: half the stack
  // of a double t, and no conversion per child).
  struct Entry {
    std::uint32_t link;
    float s_enter;
  };
  // Next from the stack, skipping what lies beyond the ray's end; leaves are tested here (or
  // entered, when deferred).
  template <class Leaf>
  bool next_from_stack(Leaf&& leaf, QueryStats& stats) {
    for (;;) {
      if (top_ == 0) return false;
      const Entry entry = stack_[--top_];
      if (entry.s_enter > s_max_) continue;
      ++stats.nodes_visited;
      if (kDeferLeaves || !PackedAabbTree::is_leaf(entry.link)) {
        current_ = entry.link;
        return true;
      }
      if (!leaf(PackedAabbTree::facet(entry.link), t_max_)) return false;
      update_s_max();
    }
  }

  // s_max follows t_max (rounded up, so the pruning against it is conservative); recomputed only
  // when a hit has shortened the ray.
  void update_s_max() {
    if (t_max_ != t_of_s_max_) s_max_ = grid_.s_up(t_of_s_max_ = t_max_);
  }

  GridRay grid_;
  Real t_max_ = 0;
  Real t_of_s_max_ = 0;
  float s_min_ = 0;
  float s_max_ = 0;
  const PackedAabbTree::Node* nodes_ = nullptr;
  const Triangle* triangles_ = nullptr;
  const Vec3* vertices_ = nullptr;
  std::uint32_t current_ = 0;  // an inner node, or with kDeferLeaves also a leaf
  bool corners_requested_ = false;
  int top_ = 0;
  Entry stack_[kStackSize];
};

template <class Leaf>
void ordered_ray_walk(const PackedAabbTree& tree, const Ray& ray, Leaf&& leaf, QueryStats& stats) {
  OrderedRayWalk<> walk;
  if (!walk.start(tree, ray, leaf, stats)) return;
  while (walk.step(leaf, stats)) {
  }
}

// The closest-hit leaf test: the watertight triangle test on the ray shortened to the best hit.
class ClosestHit {
 public:
  ClosestHit() = default;
  ClosestHit(const TriangleMesh& mesh, const Ray& ray, QueryStats& stats)
      : mesh_(&mesh), ray_(ray), shear_(ray_shear(ray.direction)), stats_(&stats) {}
  bool operator()(FacetId f, Real& t_max) {
    ++stats_->leaf_tests;
    TriangleHit hit;
    Ray clipped = ray_;
    clipped.t_max = t_max;
    if (intersect_ray_triangle(clipped, shear_, mesh_->corner(f, 0), mesh_->corner(f, 1), mesh_->corner(f, 2), hit)) {
      if (!best || hit.t < best->t || (hit.t == best->t && f < best->facet)) best = RayHit{f, hit.t, hit.u, hit.v};
      t_max = std::min(t_max, best->t);
    }
    return true;
  }
  std::optional<RayHit> best;

 private:
  const TriangleMesh* mesh_ = nullptr;
  Ray ray_;
  RayShear shear_;
  QueryStats* stats_ = nullptr;
};

}  // namespace

std::optional<RayHit> ray_closest_hit(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats) {
  StatsSink sink(stats);
  if (tree.empty()) return std::nullopt;
  ClosestHit leaf(tree.mesh(), ray, sink.local);
  ordered_ray_walk(tree, ray, leaf, sink.local);
  return leaf.best;
}

void ray_closest_hits(const PackedAabbTree& tree, const Ray* rays, std::size_t count, std::optional<RayHit>* hits,
                      QueryStats* stats) {
  // Each lane walks one ray; the lanes take turns one node (or one half of a leaf) at a time, so
  // that the load one lane has started (its next node, a leaf's corners) completes while the
  // others work. On the 524k-facet terrain this gives 1.5x the rays per second of one ray after
  // another, but where the hierarchy and the mesh fit in the caches the turns cost more than
  // they hide (10k facets: 0.73x): the rays then go one by one. Measured on a 1 MB L2: 32k facets
  // (1.5 MB) 0.9-0.95x, the 69k-facet bunny (3.2 MB) 1.06-1.14x; hence the 2 MB threshold. 4 to
  // 16 lanes give the same within 10%.
  StatsSink sink(stats);
  if (tree.empty()) {
    std::fill(hits, hits + count, std::nullopt);
    return;
  }
  const TriangleMesh& mesh = tree.mesh();
  constexpr std::size_t kInterleaveAboveBytes = std::size_t(2) << 20;
  if (tree.memory_bytes() + mesh.triangles.size() * sizeof(Triangle) + mesh.vertices.size() * sizeof(Vec3) <
      kInterleaveAboveBytes) {
    for (std::size_t i = 0; i < count; ++i) hits[i] = ray_closest_hit(tree, rays[i], &sink.local);
    return;
  }
  constexpr int kLanes = 8;
  struct Lane {
    OrderedRayWalk<true> walk;
    ClosestHit leaf;
    std::size_t ray = 0;
  };
  Lane lanes[kLanes];
  int active[kLanes];
  int active_count = 0;
  std::size_t next = 0;
  // Starts the next ray that needs a walk in `lane`; rays that end at their start are answered.
  const auto start_next = [&](Lane& lane) {
    while (next < count) {
      const std::size_t i = next++;
      lane.leaf = ClosestHit(mesh, rays[i], sink.local);
      lane.ray = i;
      if (lane.walk.start(tree, rays[i], lane.leaf, sink.local)) return true;
      hits[i] = lane.leaf.best;
    }
    return false;
  };
  for (int l = 0; l < kLanes; ++l) {
    if (start_next(lanes[l])) active[active_count++] = l;
  }
  while (active_count > 0) {
    for (int a = 0; a < active_count;) {
      Lane& lane = lanes[active[a]];
      if (lane.walk.step(lane.leaf, sink.local)) {
        ++a;
        continue;
      }
      hits[lane.ray] = lane.leaf.best;
      if (start_next(lane)) {
        ++a;
      } else {
        active[a] = active[--active_count];
      }
    }
  }
}

void ray_candidates(const PackedAabbTree& tree, const Ray& ray, FunctionRef<Real(FacetId, Real)> visit,
                    QueryStats* stats) {
  StatsSink sink(stats);
  ordered_ray_walk(
      tree, ray,
      [&](FacetId f, Real& t_max) {
        ++sink.local.leaf_tests;
        t_max = std::min(t_max, visit(f, t_max));
        return t_max >= ray.t_min;  // the visitor may stop the walk with a t below t_min
      },
      sink.local);
}

void ray_all_hits(const PackedAabbTree& tree, const Ray& ray, FunctionRef<bool(const RayHit&)> visit,
                  QueryStats* stats) {
  // Every hit: the ordered walk without ever shortening the ray.
  StatsSink sink(stats);
  const RayShear shear = ray_shear(ray.direction);
  ordered_ray_walk(
      tree, ray,
      [&](FacetId f, Real&) {
        ++sink.local.leaf_tests;
        const TriangleMesh& mesh = tree.mesh();
        TriangleHit hit;
        if (!intersect_ray_triangle(ray, shear, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2), hit))
          return true;
        return visit(RayHit{f, hit.t, hit.u, hit.v});
      },
      sink.local);
}

std::optional<RayHit> ray_any_hit(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::first_hit([&](auto visit) { ray_all_hits(tree, ray, visit, stats); });
}

std::vector<RayHit> ray_all_hits(const PackedAabbTree& tree, const Ray& ray, QueryStats* stats) {
  return detail::collect_sorted<RayHit>([&](auto visit) { ray_all_hits(tree, ray, visit, stats); }, detail::nearer_hit);
}

template <class Shape>
void query_overlap(const PackedAabbTree& tree, const Shape& shape, FunctionRef<bool(FacetId)> visit, QueryStats* stats,
                   FacetTest test) {
  StatsSink sink(stats);
  if (tree.empty() || !is_valid(shape)) return;  // an invalid shape matches nothing (shapes.h)
  ++sink.local.volume_tests;
  if (!overlaps(tree.bounds(), shape)) return;
  const TriangleMesh& mesh = tree.mesh();
  // An oriented box's frame is taken once per query, not once per leaf.
  const auto exact = [&] {
    if constexpr (std::is_same_v<Shape, Obb>) {
      return detail::ObbTriangleTest(shape);
    } else {
      return [&](const Vec3& a, const Vec3& b, const Vec3& c) { return triangle_overlaps(a, b, c, shape); };
    }
  }();
  const auto leaf = [&](FacetId f) {
    if (test == FacetTest::exact_triangle) {
      ++sink.local.leaf_tests;
      if (!exact(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2))) return true;
    }
    return visit(f);
  };
  // Every node test starts with the shape's bounding box on the grid: six integer compares per
  // child, four children at once. An Aabb query needs nothing more.
  const GridBox grid = grid_box_of(tree, bounding_aabb(shape));
  if constexpr (std::is_same_v<Shape, Aabb>) {
    walk(
        tree, [&](const PackedAabbTree::Node& node) { return grid.overlaps(node); }, leaf, sink.local);
  } else if constexpr (std::is_same_v<Shape, Obb> || std::is_same_v<Shape, Capsule>) {
    // Then the box's own face axes (a capsule's box: along its segment, the radius around it), in
    // float on the grid. An inner child that passes all six face axes is entered (the edge axes
    // would cull few more, at twice the cost); a leaf child gets the exact test only when the
    // caller asked for leaf volumes, since the triangle test decides otherwise. For capsules the
    // exact capsule-box distance on every child that passed the grid was half the time of an ODE
    // capsule on the drop scene's terrain (pair_replay --only capsule: ~14 -> ~9.5 us per call,
    // the same facets). (The radii allow for axes that are not quite orthonormal.)
    Vec3 center = Vec3::Zero(), half = Vec3::Zero();
    Mat3 axes = Mat3::Identity();
    if constexpr (std::is_same_v<Shape, Obb>) {
      center = shape.center;
      axes = shape.axes;
      half = shape.half_extents;
    } else {
      const Vec3 segment = shape.p1 - shape.p0;
      const Real length = segment.norm();
      if (length > 0 && std::isfinite(length)) {
        Vec3 b1, b2;
        detail::orthonormal_completion(segment / length, b1, b2);
        axes.col(0) = segment / length;
        axes.col(1) = b1;
        axes.col(2) = b2;
      }
      center = (shape.p0 + shape.p1) / 2;
      half = Vec3(length / 2 + shape.radius, shape.radius, shape.radius);
    }
    const GridObbAxes faces(tree, center, axes, (axes.transpose() * axes).cwiseAbs() * half);
    walk(
        tree,
        [&](const PackedAabbTree::Node& node) {
          const unsigned mask = faces.overlaps(node, grid.overlaps(node));
          if (test != FacetTest::leaf_volume) return mask;
          const unsigned leaves = mask & leaf_slots(node);
          return refine_mask(tree, node, leaves, [&](const Aabb& box) { return overlaps(box, shape); }) |
                 (mask & ~leaves);
        },
        leaf, sink.local);
  } else {
    // Spheres: the distance to four children at once, in float on the grid (GridSphere); a leaf
    // child gets the exact box test only when the caller asked for leaf volumes, since the
    // triangle test decides otherwise.
    const GridSphere sphere(tree, shape);
    walk(
        tree,
        [&](const PackedAabbTree::Node& node) {
          const unsigned mask = sphere.overlaps(node, grid.overlaps(node));
          if (test != FacetTest::leaf_volume) return mask;
          const unsigned leaves = mask & leaf_slots(node);
          return refine_mask(tree, node, leaves, [&](const Aabb& box) { return overlaps(box, shape); }) |
                 (mask & ~leaves);
        },
        leaf, sink.local);
  }
}

template <class Shape>
std::vector<FacetId> query_overlap(const PackedAabbTree& tree, const Shape& shape, QueryStats* stats, FacetTest test) {
  return detail::collect_sorted<FacetId>([&](auto visit) { query_overlap<Shape>(tree, shape, visit, stats, test); });
}

namespace {

// A node of the hierarchy as the tree-vs-tree walk sees it: the root, or child `slot` of an
// inner node (whose box and link live in that inner node).
struct NodeRef {
  static constexpr std::uint32_t kRoot = 0xFFFFFFFFu;
  std::uint32_t value = kRoot;  // kRoot or inner * kWidth + slot
};

std::uint32_t link_of(const PackedAabbTree& tree, NodeRef ref) {
  if (ref.value == NodeRef::kRoot) return tree.root_link();
  return tree.nodes()[ref.value / kWidth].link[ref.value % kWidth];
}

Aabb box_of(const PackedAabbTree& tree, NodeRef ref) {
  if (ref.value == NodeRef::kRoot) return tree.bounds();
  return tree.child_box(tree.nodes()[ref.value / kWidth], int(ref.value % kWidth));
}

}  // namespace

namespace {

// Facets of the larger tree gathered in one query before the walk gives up (see
// collide_through_facets): at most this many, and at most half the smaller tree's facets.
constexpr std::size_t kMaxGatheredFacets = 4096;

enum class Outcome { done, stopped, too_many };

// Tree-vs-tree for a small body against a large mesh (a body resting on a terrain), in two
// queries instead of one joint walk: (1) the facets of the large tree whose leaf boxes meet the
// small tree's root box (an exact triangle-box test here cost more than it saved), (2) for each
// of them, the small tree walked with that triangle's box in the small tree's own frame (an
// axis-aligned box on its grid: the cheapest test there is), and the exact triangle pair test on
// the leaves it reaches. The joint walk pays the rotation at every node pair: ~1,000 box tests
// for a 270-facet body resting on a 131k-facet terrain, 47 us per pair of trees; this pays it
// once per gathered facet (~43): 14.5 us, the same pairs (both end in the same exact test).
// Gives up (too_many, nothing reported) when the root box holds more facets than the limit, as
// for two meshes of a size: the joint walk is the better there.
Outcome collide_through_facets(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
                               FunctionRef<bool(const FacetPair&)> visit, QueryStats& local,
                               const CollideSettings& settings) {
  const bool a_is_large = a.facet_count() >= b.facet_count();
  const PackedAabbTree& large = a_is_large ? a : b;
  const PackedAabbTree& small = a_is_large ? b : a;
  const RigidTransform large_from_small = a_is_large ? a_from_b : a_from_b.inverse();
  const RigidTransform small_from_large = a_is_large ? a_from_b.inverse() : a_from_b;
  const std::size_t limit = std::min(kMaxGatheredFacets, small.facet_count() / 2);
  // Both steps cull in a frame the exact test (in a's frame) does not use: pad by a few hundred
  // ulps of the coordinates involved, as the box tests of volume/aabb.h do, so that touching
  // pairs are never culled by rounding.
  const auto extreme = [](const Aabb& box) { return box.min.cwiseAbs().cwiseMax(box.max.cwiseAbs()).maxCoeff(); };
  const Real pad = 256 * std::numeric_limits<Real>::epsilon() *
                   (extreme(large.bounds()) + extreme(small.bounds()) + a_from_b.translation.cwiseAbs().maxCoeff());
  const Aabb& root = small.bounds();
  const Obb root_box{large_from_small.apply(root.center()), large_from_small.rotation,
                     (root.extent() * Real(0.5)).array() + pad};
  // The per-thread buffer is borrowed (and returned on every exit), so that a visitor that
  // collides again on this thread gets a buffer of its own.
  thread_local std::vector<FacetId> spare;
  struct Borrowed {
    std::vector<FacetId> list;
    Borrowed() {
      list.swap(spare);
      list.clear();
    }
    ~Borrowed() { list.swap(spare); }
  } borrowed;
  std::vector<FacetId>& gathered = borrowed.list;
  query_overlap(
      large, root_box,
      [&](FacetId f) {
        gathered.push_back(f);
        return gathered.size() <= limit;
      },
      &local, FacetTest::leaf_volume);
  if (gathered.size() > limit) return Outcome::too_many;
  // Each pair is tested afresh (facets_intersect): the joint walk's FacetPairTest was measured
  // slower on this path.
  const TriangleMesh& mesh_a = a.mesh();
  const TriangleMesh& mesh_b = b.mesh();
  const TriangleMesh& large_mesh = large.mesh();
  bool stop = false;
  for (const FacetId f : gathered) {
    Aabb box = Aabb::empty();
    for (int k = 0; k < 3; ++k) box.expand(small_from_large.apply(large_mesh.corner(f, k)));
    box.min.array() -= pad;
    box.max.array() += pad;
    query_overlap(
        small, box,
        [&](FacetId g) {
          const FacetId fa = a_is_large ? f : g, fb = a_is_large ? g : f;
          ++local.leaf_tests;
          if (!detail::facets_intersect(mesh_a, fa, mesh_b, fb, a_from_b)) return true;
          stop = !visit(FacetPair{fa, fb}) || settings.stop_at_first;
          return !stop;
        },
        &local, FacetTest::leaf_volume);
    if (stop) return Outcome::stopped;
  }
  return Outcome::done;
}

}  // namespace

void collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats, const CollideSettings& settings) {
  if (!a_from_b.translation.allFinite() || !is_rotation(a_from_b.rotation, 1e-6))
    throw Error("collide: the transform's rotation is not orthonormal with determinant +1, or not finite");
  if (a.empty() || b.empty()) return;
  StatsSink sink(stats);
  QueryStats& local = sink.local;
  if (collide_through_facets(a, b, a_from_b, visit, local, settings) != Outcome::too_many) return;
  detail::FacetPairTest facets_intersect(a.mesh(), b.mesh(), a_from_b);
  const RigidTransform b_from_a = a_from_b.inverse();
  struct Pair {
    NodeRef a, b;
    Aabb box_a, box_b;
  };
  // Each step pops one pair and pushes at most kWidth, one level deeper in a or b: at most
  // (kWidth - 1) * (height(a) + height(b)) + 1 pairs are ever pending.
  Pair stack[(kWidth - 1) * 2 * PackedAabbTree::kMaxHeight + kWidth];
  int top = 0;
  // The other node's box as an oriented box in the split tree's frame (its bounding box on that
  // grid and its face axes), which culls most children in a few vector instructions; the exact
  // box-box test (all fifteen axes) decides for the rest.
  GridBox cull_grid{};
  GridObbAxes cull_faces;
  bool cached = false, cached_split_a = false;
  NodeRef cached_other;
  ++local.volume_tests;
  if (overlaps(a.bounds(), b.bounds(), a_from_b)) stack[top++] = {NodeRef{}, NodeRef{}, a.bounds(), b.bounds()};
  while (top > 0) {
    const Pair pair = stack[--top];
    ++local.nodes_visited;
    const std::uint32_t link_a = link_of(a, pair.a);
    const std::uint32_t link_b = link_of(b, pair.b);
    const bool leaf_a = PackedAabbTree::is_leaf(link_a);
    const bool leaf_b = PackedAabbTree::is_leaf(link_b);
    if (leaf_a && leaf_b) {
      const FacetId fa = PackedAabbTree::facet(link_a);
      const FacetId fb = PackedAabbTree::facet(link_b);
      ++local.leaf_tests;
      if (facets_intersect(fa, fb)) {
        if (!visit(FacetPair{fa, fb}) || settings.stop_at_first) return;
      }
      continue;
    }
    // Split the larger box (or the one that is not a leaf), as collide.cpp does.
    const bool split_a = !leaf_a && (leaf_b || surface_area(pair.box_a) >= surface_area(pair.box_b));
    const PackedAabbTree::Node& split = split_a ? a.nodes()[link_a] : b.nodes()[link_b];
    // The walk is depth first, so the same other node meets many split nodes in a row: its
    // culling form is kept until another one comes.
    const bool same_other = split_a ? (cached_split_a && pair.b.value == cached_other.value)
                                    : (!cached_split_a && pair.a.value == cached_other.value);
    if (!same_other || !cached) {
      const PackedAabbTree& tree = split_a ? a : b;
      const RigidTransform& to_split = split_a ? a_from_b : b_from_a;
      const Aabb& box = split_a ? pair.box_b : pair.box_a;
      const Obb other{to_split.apply(box.center()), to_split.rotation, box.extent() * Real(0.5)};
      cull_grid = grid_box_of(tree, bounding_aabb(other));
      cull_faces = GridObbAxes(tree, other.center, other.axes, other.half_extents);
      cached = true;
      cached_split_a = split_a;
      cached_other = split_a ? pair.b : pair.a;
    }
    const unsigned candidates = cull_faces.overlaps(split, cull_grid.overlaps(split));
    for (int slot = kWidth - 1; slot >= 0; --slot) {
      if (split.link[slot] == PackedAabbTree::kEmpty) continue;
      ++local.volume_tests;
      if (!(candidates >> slot & 1u)) continue;
      Pair child = pair;
      if (split_a) {
        child.a.value = link_a * kWidth + std::uint32_t(slot);
        child.box_a = box_of(a, child.a);
      } else {
        child.b.value = link_b * kWidth + std::uint32_t(slot);
        child.box_b = box_of(b, child.b);
      }
      // A child that passed the culling is entered without the exact box test's nine edge axes:
      // an inner one gets its children culled next, and a leaf pair goes to the triangle test,
      // which starts with the triangles' own boxes. The edge axes rejected 21 of 86,407 leaf
      // pairs on the 9,996-facet spheres at gap 0 and took a quarter of the time.
      stack[top++] = child;
    }
  }
}

std::vector<FacetPair> collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b,
                               QueryStats* stats, const CollideSettings& settings) {
  return detail::collect_sorted<FacetPair>([&](auto visit) { collide(a, b, a_from_b, visit, stats, settings); });
}

#define BOXTREE_INSTANTIATE_PACKED_OVERLAP(S)                                                                          \
  template void query_overlap<S>(const PackedAabbTree&, const S&, FunctionRef<bool(FacetId)>, QueryStats*, FacetTest); \
  template std::vector<FacetId> query_overlap<S>(const PackedAabbTree&, const S&, QueryStats*, FacetTest);
BOXTREE_INSTANTIATE_PACKED_OVERLAP(Aabb)
BOXTREE_INSTANTIATE_PACKED_OVERLAP(Obb)
BOXTREE_INSTANTIATE_PACKED_OVERLAP(Sphere)
BOXTREE_INSTANTIATE_PACKED_OVERLAP(Capsule)

}  // namespace boxtree
