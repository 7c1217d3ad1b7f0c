// SPDX-License-Identifier: MIT
#include "boxtree/collide_front.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "query_internal.h"

namespace boxtree {
namespace {

using Record = CollideFront::Record;
constexpr int kWidth = PackedAabbTree::kWidth;
constexpr std::uint32_t kRoot = 0xFFFFFFFFu;  // the root's reference; else inner node * kWidth + slot
// A cut record's expiry for a leaf pair whose facets may touch (tested on every call); as the
// least expiry of an inner record's subtree, it says that the subtree holds such a pair.
constexpr Real kAlways = -std::numeric_limits<Real>::infinity();
bool is_inner(const Record& r) { return r.split != Record::kCut; }

std::uint32_t link_of(const PackedAabbTree& tree, std::uint32_t ref) {
  if (ref == kRoot) return tree.root_link();
  return tree.nodes()[ref / kWidth].link[ref % kWidth];
}

Aabb box_of(const PackedAabbTree& tree, std::uint32_t ref) {
  if (ref == kRoot) return tree.bounds();
  return tree.child_box(tree.nodes()[ref / kWidth], int(ref % kWidth));
}

// The radius, about the centre of b's quantization grid, of a ball holding every box of b (the
// grid spans them all, the root's exact bounds included).
Real grid_radius(const PackedAabbTree& tree, Vec3* center) {
  const Vec3 lo = tree.origin().cwiseMin(tree.bounds().min);
  const Vec3 hi = (tree.origin() + tree.step() * Real(65535)).cwiseMax(tree.bounds().max);
  *center = (lo + hi) * Real(0.5);
  return (hi - lo).norm() * Real(0.5);
}

// How a subtree of the front came out of a call.
struct Outcome {
  bool apart = false;           // every pair of it is apart (its parent may be pulled up)
  bool tested = false;          // some pair of it had its volumes tested in this call
  Real least_expiry = kAlways;  // the least expiry of its cut records (kAlways: one touches)
};

struct FrontWalk {
  const PackedAabbTree& a;
  const PackedAabbTree& b;
  const RigidTransform& a_from_b;
  FunctionRef<bool(const FacetPair&)> visit;
  QueryStats& stats;
  FrontStats& front_stats;
  const std::vector<Record>& in;
  std::vector<Record>& out;
  std::size_t max_records;
  Real travel;  // CollideFront::travel_ after this call's motion
  Real pad;     // rounding allowance of the distance bound
  Mat3 abs_rotation;
  std::size_t next = 0;  // the next record of `in`
  bool overflow = false, stopped = false;

  // Room for `count` more records in `out`; false (and the overflow noted) past max_records.
  bool make_room(std::size_t count) {
    if (overflow) return false;
    if (out.size() + count > max_records) {
      overflow = true;
      return false;
    }
    // Grown by hand so that a buffer never holds more than max_records records.
    if (out.size() + count > out.capacity())
      out.reserve(std::min(max_records, std::max({std::size_t(64), 2 * out.size(), out.size() + count})));
    return true;
  }

  // A cut record: apart until the motion reaches `expiry` (kAlways: tested on every call).
  Outcome emit_cut(std::uint32_t x, std::uint32_t y, Real expiry, bool apart, bool tested) {
    if (make_room(1)) out.push_back({x, y, expiry, 1, Record::kCut});
    return {apart, tested, expiry};
  }
  // An inner record; its subtree's span and least expiry are filled in by close_inner.
  std::size_t open_inner(std::uint32_t x, std::uint32_t y, std::uint8_t split) {
    const std::size_t at = out.size();
    if (make_room(1)) out.push_back({x, y, kAlways, 1, split});
    return at;
  }
  void close_inner(std::size_t at, Real least_expiry) {
    if (overflow || at >= out.size()) return;
    out[at].span = std::uint32_t(out.size() - at);
    out[at].expiry = least_expiry;
  }

  // A lower bound of the distance between the box of a's node x and the box of b's node y (in
  // a's frame), less the pad: positive only if they are apart. The six face axes of the two boxes
  // (the separation along a unit axis bounds the distance from below).
  Real distance_bound(std::uint32_t x, std::uint32_t y) {
    ++stats.volume_tests;
    const Aabb box_a = box_of(a, x);
    const Aabb box_b = box_of(b, y);
    const Vec3 half_a = (box_a.max - box_a.min) * Real(0.5);
    const Vec3 half_b = (box_b.max - box_b.min) * Real(0.5);
    const Vec3 d = a_from_b.apply((box_b.min + box_b.max) * Real(0.5)) - (box_a.min + box_a.max) * Real(0.5);
    const Vec3 along_a = d.cwiseAbs() - half_a - abs_rotation * half_b;
    const Vec3 along_b = (a_from_b.rotation.transpose() * d).cwiseAbs() - half_b - abs_rotation.transpose() * half_a;
    return std::max(along_a.maxCoeff(), along_b.maxCoeff()) - pad;
  }

  // Whether the pair's children in the test tree are the children of its node of a (else of its
  // node of b): the larger box is split, as in the fresh descent (the boxes are fixed in their
  // trees, so this never changes).
  bool splits_a(std::uint32_t x, std::uint32_t y, std::uint32_t link_x, std::uint32_t link_y) const {
    const bool leaf_x = PackedAabbTree::is_leaf(link_x);
    const bool leaf_y = PackedAabbTree::is_leaf(link_y);
    return !leaf_x && (leaf_y || surface_area(box_of(a, x)) >= surface_area(box_of(b, y)));
  }
  // The children (node references in the split tree) of the split node `link`; returns how many.
  static int children(const PackedAabbTree& tree, std::uint32_t link, std::uint32_t* child) {
    const PackedAabbTree::Node& node = tree.nodes()[link];
    int count = 0;
    for (int slot = 0; slot < kWidth; ++slot)
      if (node.link[slot] != PackedAabbTree::kEmpty) child[count++] = link * kWidth + std::uint32_t(slot);
    return count;
  }

  // A lower bound of the distance between facet fa and facet fb (moved into a's frame), less the
  // pad: their separation along either facet's normal (-infinity for degenerate facets).
  Real facet_distance_bound(FacetId fa, FacetId fb) const {
    const TriangleMesh& ma = a.mesh();
    const TriangleMesh& mb = b.mesh();
    const Vec3 pa[3] = {ma.corner(fa, 0), ma.corner(fa, 1), ma.corner(fa, 2)};
    const Vec3 pb[3] = {a_from_b.apply(mb.corner(fb, 0)), a_from_b.apply(mb.corner(fb, 1)),
                        a_from_b.apply(mb.corner(fb, 2))};
    Real best = -std::numeric_limits<Real>::infinity();
    const auto along_normal = [&](const Vec3* own, const Vec3* other) {
      const Vec3 normal = (own[1] - own[0]).cross(own[2] - own[0]);
      const Real length = normal.norm();
      if (!(length > 0)) return;
      const Vec3 n = normal / length;
      const Real plane = n.dot(own[0]);
      Real lo = std::numeric_limits<Real>::infinity(), hi = -lo;
      for (int k = 0; k < 3; ++k) {
        const Real h = n.dot(other[k]) - plane;
        lo = std::min(lo, h);
        hi = std::max(hi, h);
      }
      best = std::max(best, std::max(lo, -hi));
    };
    along_normal(pa, pb);
    along_normal(pb, pa);
    return best - pad;
  }

  // A pair met in this call: its volumes tested, and descended from if they may overlap.
  Outcome test(std::uint32_t x, std::uint32_t y) {
    const Real distance = distance_bound(x, y);
    if (distance > 0) return emit_cut(x, y, travel + distance, true, true);
    const std::uint32_t link_x = link_of(a, x);
    const std::uint32_t link_y = link_of(b, y);
    if (PackedAabbTree::is_leaf(link_x) && PackedAabbTree::is_leaf(link_y)) {
      const FacetId fa = PackedAabbTree::facet(link_x);
      const FacetId fb = PackedAabbTree::facet(link_y);
      ++stats.leaf_tests;
      if (detail::facets_intersect(a.mesh(), fa, b.mesh(), fb, a_from_b)) {
        if (!visit(FacetPair{fa, fb})) stopped = true;
        return emit_cut(x, y, kAlways, false, true);
      }
      // Apart facets in overlapping boxes (most leaf pairs of a resting contact): kept apart by
      // their own distance, so that they are not tested again while the motion stays below it.
      const Real facets_apart = facet_distance_bound(fa, fb);
      if (facets_apart > 0) return emit_cut(x, y, travel + facets_apart, true, true);
      return emit_cut(x, y, kAlways, false, true);
    }
    ++front_stats.descended;
    ++stats.nodes_visited;
    const bool split_a = splits_a(x, y, link_x, link_y);
    const std::size_t at = open_inner(x, y, split_a ? Record::kSplitA : Record::kSplitB);
    std::uint32_t child[kWidth];
    const int count = children(split_a ? a : b, split_a ? link_x : link_y, child);
    Real least = std::numeric_limits<Real>::infinity();
    for (int i = 0; i < count && !stopped; ++i)
      least = std::min(least, (split_a ? test(child[i], y) : test(x, child[i])).least_expiry);
    close_inner(at, least);
    return {false, true, least};
  }

  // The next record of the last front and its subtree.
  // A subtree whose cut records all stay apart (the motion is below their least expiry, so none
  // touches) is copied as it is, without a visit per record: what visiting it would write.
  Outcome resume() {
    const Record r = in[next];
    ++stats.nodes_visited;
    if (r.expiry != kAlways && travel < r.expiry) {
      const std::size_t span = r.span;
      if (make_room(span))
        out.insert(out.end(), in.begin() + std::ptrdiff_t(next), in.begin() + std::ptrdiff_t(next + span));
      if (!is_inner(r)) {
        ++front_stats.kept_apart;
      } else {
        ++front_stats.kept_whole;
        for (std::size_t i = next; i < next + span; ++i) front_stats.kept_apart += !is_inner(in[i]);
      }
      next += span;
      // As a visit would: a cut record is apart; an inner record that is not pulled up is not.
      return {!is_inner(r), false, r.expiry};
    }
    ++next;
    if (!is_inner(r)) {
      ++front_stats.retested;
      return test(r.a, r.b);
    }
    const std::size_t at = open_inner(r.a, r.b, r.split);
    const bool split_a = r.split == Record::kSplitA;
    std::uint32_t child[kWidth];
    const int count = split_a ? children(a, link_of(a, r.a), child) : children(b, link_of(b, r.b), child);
    bool apart = true, tested = false;
    Real least = std::numeric_limits<Real>::infinity();
    for (int i = 0; i < count; ++i) {
      if (stopped) return {false, true};
      const Outcome o = resume();
      apart = apart && o.apart;
      tested = tested || o.tested;
      least = std::min(least, o.least_expiry);
    }
    if (apart && tested) {
      const Real distance = distance_bound(r.a, r.b);
      if (distance > 0) {
        ++front_stats.pulled_up;
        if (!overflow) out.resize(at);
        return emit_cut(r.a, r.b, travel + distance, true, true);
      }
    }
    close_inner(at, least);
    return {false, tested, least};
  }
};

// A bound on how far any point of b's boxes moved in a's frame from `before` to `after`:
// |(R1 - R0) c + t1 - t0| + |R1 - R0|_F r for the ball (c, r) holding them, with room for rounding.
Real motion_bound(const RigidTransform& before, const RigidTransform& after, const Vec3& center, Real radius) {
  const Mat3 turn = after.rotation - before.rotation;
  const Real moved = (turn * center + (after.translation - before.translation)).norm() + turn.norm() * radius;
  const Real scale = center.norm() + radius + before.translation.norm() + after.translation.norm();
  return moved * (1 + 1e-12) + 64 * std::numeric_limits<Real>::epsilon() * scale;
}

}  // namespace

void CollideFront::clear() {
  records_.clear();
  spare_.clear();
  tree_a_ = tree_b_ = nullptr;
  travel_ = 0;
}

std::size_t CollideFront::cut_size() const {
  std::size_t n = 0;
  for (const Record& r : records_) n += !is_inner(r);
  return n;
}

void collide(const PackedAabbTree& a, const PackedAabbTree& b, const RigidTransform& a_from_b, CollideFront& front,
             FunctionRef<bool(const FacetPair&)> visit, QueryStats* stats) {
  if (!a_from_b.translation.allFinite() || !is_rotation(a_from_b.rotation, 1e-6))
    throw Error("collide: the transform's rotation is not orthonormal with determinant +1, or not finite");
  front.last_ = {};
  if (a.empty() || b.empty()) {
    front.clear();
    return;
  }
  if (front.fresh_calls_ > 0) {
    --front.fresh_calls_;
    front.last_.fresh = true;
    collide(a, b, a_from_b, visit, stats);
    return;
  }
  Vec3 center_b;
  const Real radius_b = grid_radius(b, &center_b);
  const bool same_trees = front.tree_a_ == &a && front.tree_b_ == &b && front.nodes_a_ == a.nodes().size() &&
                          front.nodes_b_ == b.nodes().size();
  if (!same_trees) {
    front.clear();
    front.tree_a_ = &a;
    front.tree_b_ = &b;
    front.nodes_a_ = a.nodes().size();
    front.nodes_b_ = b.nodes().size();
  } else if (!front.records_.empty()) {
    front.travel_ += motion_bound(front.last_pose_, a_from_b, center_b, radius_b);
  }
  front.last_pose_ = a_from_b;

  detail::StatsSink sink(stats);
  const auto extreme = [](const Aabb& box) { return box.min.cwiseAbs().cwiseMax(box.max.cwiseAbs()).maxCoeff(); };
  const Real pad =
      256 * std::numeric_limits<Real>::epsilon() *
      (extreme(a.bounds()) + center_b.cwiseAbs().maxCoeff() + radius_b + a_from_b.translation.cwiseAbs().maxCoeff());
  front.spare_.clear();
  FrontWalk walk{a,
                 b,
                 a_from_b,
                 visit,
                 sink.local,
                 front.last_,
                 front.records_,
                 front.spare_,
                 front.max_records_,
                 front.travel_,
                 pad,
                 a_from_b.rotation.cwiseAbs()};
  front.last_.records_in = front.records_.size();
  if (front.records_.empty()) {
    ++sink.local.nodes_visited;
    walk.test(kRoot, kRoot);
  } else {
    walk.resume();
  }
  front.records_.swap(front.spare_);
  if (walk.stopped || walk.overflow) {
    front.last_.overflowed = walk.overflow;
    front.clear();
    if (walk.overflow) {
      front.fresh_calls_ = CollideFront::kFreshCallsAfterOverflow;
      std::vector<Record>().swap(front.records_);  // the memory goes too
      std::vector<Record>().swap(front.spare_);
    }
  }
  front.last_.records_out = front.records_.size();
}

}  // namespace boxtree
