// SPDX-License-Identifier: MIT
// Bottom-up boxtree construction (paper, Sections 2-3).
//
// Round structure (m active nodes; each round orders them along the Morton curve of their box
// centres):
//   1. candidates = contracted mesh adjacency (facets sharing a vertex, welded by position)
//                 + "near" pairs: the `near_window` neighbours on each side along the Morton curve;
//   2. each candidate's key: the surface area (or volume) of the merged volume (for axis-aligned
//      boxes, and the oriented kinds with PairRanking::bounding_box, of the merged bounding box);
//   3. greedy maximal matching, cheapest first (ties broken by the nodes' smallest facet ids:
//      deterministic), found without sorting (Preis' locally dominant pairs, see greedy_matching);
//   4. matched pairs become parents, unmatched nodes are carried; adjacency is contracted.
// Everything per round is linear in the candidates (short per-node lists, radix-sorted Morton
// codes, buffers reused between rounds), as in PLOC (Meister & Bittner, "Parallel Locally-Ordered
// Clustering for Bounding Volume Hierarchy Construction", TVCG 2018), which also merges each node
// with its cheapest neighbour along a Morton order; here the neighbours include the mesh adjacency
// and the matching is the paper's greedy one.
// Memory traffic, not arithmetic, is what a large build spends its time on, so: one pass per
// round builds the next round's candidate lists (contraction, Morton neighbours and each list's
// cheapest partner at once); the lists hold 4-byte partner codes and no keys where a key is cheap
// to compute again (boxes: a merged box's area costs less than storing and reading it); the
// rounds' boxes are single precision (BoxF); a round's nodes keep the order of the previous
// round's (parents where their first child was), so the lists of one round are read in order
// while the next round's are written; arrays are reserved once at their largest size and the
// lists are never zero-filled before being written (a large build's first touch of its pages,
// the kernel zeroing them, costs as much as one of its passes).
// Why the Morton pairs: the Morton order is a path through all active nodes, and a maximal
// matching on a graph containing a path over all m nodes leaves an independent set of that path
// unmatched, i.e. at most ceil(m/2) nodes, so each round pairs >= m/4 nodes and the height is at
// most log_{4/3} n. On meshes, adjacency pairs almost everything and the height is ~log2 n.
#include "boxtree/build.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>
#include <optional>
#include <type_traits>

#include "boxtree/detail/volume_kinds.h"
#include "internal.h"

namespace boxtree {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

// A hint to load the cache line at `address` ahead of its use.
inline void prefetch([[maybe_unused]] const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address);
#endif
}

// Sorts [begin, end) increasing (distinct values). The lists are short (a dozen entries on
// meshes), where insertion sort beats std::sort.
void sort_short(std::uint32_t* begin, std::uint32_t* end) {
  if (end - begin < 2) return;  // also a null `begin`: no arithmetic on it
  if (end - begin > 48) {
    std::sort(begin, end);
    return;
  }
  for (std::uint32_t* i = begin + 1; i < end; ++i) {
    const std::uint32_t x = *i;
    std::uint32_t* j = i;
    for (; j > begin && *(j - 1) > x; --j) *j = *(j - 1);
    *j = x;
  }
}

// Welded vertex ids: bit-identical positions (and 0 / -0) share an id, numbered in order of
// first use; an open-addressing hash over the coordinates' bits.
std::vector<VertexId> weld_vertices(const TriangleMesh& mesh) {
  const std::size_t count = mesh.vertices.size();
  std::size_t capacity = 16;
  while (capacity < 2 * count) capacity *= 2;
  std::vector<std::uint32_t> table(capacity, kNone);  // welded id + 1's representative vertex
  std::vector<VertexId> welded(count);
  std::vector<VertexId> representative;
  representative.reserve(count);
  const auto bits = [](Real x) {
    std::uint64_t b;
    const Real y = x + Real(0);  // -0 -> +0
    std::memcpy(&b, &y, sizeof b);
    return b;
  };
  for (std::size_t v = 0; v < count; ++v) {
    const Vec3& p = mesh.vertices[v];
    std::uint64_t h = bits(p.x()) * 0x9e3779b97f4a7c15ULL;
    h = (h ^ (h >> 29) ^ bits(p.y())) * 0xbf58476d1ce4e5b9ULL;
    h = (h ^ (h >> 31) ^ bits(p.z())) * 0x94d049bb133111ebULL;
    h ^= h >> 32;
    std::size_t slot = std::size_t(h) & (capacity - 1);
    while (true) {
      const std::uint32_t id = table[slot];
      if (id == kNone) {
        table[slot] = std::uint32_t(representative.size());
        welded[v] = VertexId(representative.size());
        representative.push_back(VertexId(v));
        break;
      }
      if (mesh.vertices[representative[id]] == p) {
        welded[v] = id;
        break;
      }
      slot = (slot + 1) & (capacity - 1);
    }
  }
  return welded;
}

// Facets that share a vertex position (welding bit-identical coordinates, so triangle soups such
// as PQP's env.obj still get their adjacency): the facets around each welded vertex (its fan),
// from which the first round's candidates are gathered (gather_facet_neighbors).
struct FacetFans {
  std::vector<std::uint32_t> corners;   // 3 per facet: welded vertex ids, kNone for a repeated one
  std::vector<std::uint32_t> offsets;   // the fan of welded vertex v: incident[offsets[v] .. offsets[v + 1])
  std::vector<std::uint32_t> incident;  // positions of the fan's facets, in increasing facet id order
  std::size_t bound = 0;                // an upper bound of the gathered neighbours, summed over facets
};

FacetFans facet_fans(const TriangleMesh& mesh, int max_fan, const std::vector<std::uint32_t>& position) {
  const std::size_t n = mesh.triangles.size();
  FacetFans fans;
  {
    const std::vector<VertexId> welded = weld_vertices(mesh);
    fans.corners.resize(3 * n);
    for (FacetId f = 0; f < n; ++f) {
      // A facet repeating a vertex lists it once.
      const VertexId a = welded[mesh.triangles[f][0]], b = welded[mesh.triangles[f][1]],
                     c = welded[mesh.triangles[f][2]];
      std::uint32_t* const out = &fans.corners[3 * std::size_t(f)];
      out[0] = a;
      out[1] = b == a ? kNone : b;
      out[2] = c == a || c == b ? kNone : c;
    }
  }
  std::size_t welded_count = 0;
  for (std::uint32_t w : fans.corners)
    if (w != kNone) welded_count = std::max(welded_count, std::size_t(w) + 1);
  fans.offsets.assign(welded_count + 1, 0);
  for (std::uint32_t w : fans.corners)
    if (w != kNone) ++fans.offsets[w + 1];
  std::partial_sum(fans.offsets.begin(), fans.offsets.end(), fans.offsets.begin());
  fans.incident.resize(fans.offsets.back());
  {
    std::vector<std::uint32_t> cursor(fans.offsets.begin(), fans.offsets.end() - 1);
    for (FacetId f = 0; f < n; ++f)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = fans.corners[3 * std::size_t(f) + k];
        if (w == kNone) continue;
        fans.incident[cursor[w]++] = position[f];
      }
  }
  for (std::uint32_t w : fans.corners)
    if (w != kNone)
      fans.bound += std::min<std::size_t>(fans.offsets[w + 1] - fans.offsets[w], 2 + std::size_t(max_fan));
  return fans;
}

// Appends to `out` the positions of the facets in the fans of facet f's vertices (or, for a
// vertex shared by more than `max_fan` facets, its chain neighbours there: the facets before and
// after it in facet order, bounding the work at high-valence vertices), each once, without
// position p (f's): stamp[q] == p marks those already listed; facet_at: the facet at each position.
// Returns the new end.
std::uint32_t* gather_facet_neighbors(const FacetFans& fans, FacetId f, std::uint32_t p, int max_fan,
                                      const std::uint32_t* facet_at, std::uint32_t* stamp, std::uint32_t* out) {
  stamp[p] = p;
  const auto add = [&](std::uint32_t q) {
    if (stamp[q] == p) return;
    stamp[q] = p;
    *out++ = q;
  };
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t w = fans.corners[3 * std::size_t(f) + k];
    if (w == kNone) continue;
    const std::uint32_t vb = fans.offsets[w], ve = fans.offsets[w + 1];
    if (ve - vb <= std::uint32_t(max_fan)) {
      for (std::uint32_t i = vb; i < ve; ++i) add(fans.incident[i]);
    } else {
      const std::uint32_t i = std::uint32_t(std::partition_point(fans.incident.begin() + vb, fans.incident.begin() + ve,
                                                                 [&](std::uint32_t q) { return facet_at[q] < f; }) -
                                            fans.incident.begin());
      if (i > vb) add(fans.incident[i - 1]);
      if (i + 1 < ve) add(fans.incident[i + 1]);
    }
  }
  return out;
}

// A 10-bit coordinate spread to every third bit: the bits of 30-bit Morton codes.
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0x3ff;
  x = (x | x << 16) & 0x030000ffu;
  x = (x | x << 8) & 0x0300f00fu;
  x = (x | x << 4) & 0x030c30c3u;
  x = (x | x << 2) & 0x09249249u;
  return x;
}

// Stable LSD radix sort of (code, index) by code, 10 bits per pass: the Morton order with ties
// left in their previous order.
void radix_sort(std::vector<std::pair<std::uint32_t, std::uint32_t>>& keys,
                std::vector<std::pair<std::uint32_t, std::uint32_t>>& scratch) {
  scratch.resize(keys.size());
  for (int shift = 0; shift < 30; shift += 10) {
    std::array<std::uint32_t, 1025> count{};
    for (const auto& k : keys) ++count[((k.first >> shift) & 0x3ff) + 1];
    for (int b = 0; b < 1024; ++b) count[b + 1] += count[b];
    for (const auto& k : keys) scratch[count[(k.first >> shift) & 0x3ff]++] = k;
    keys.swap(scratch);
  }
}

// The rank of a candidate pair: its cost, then (volume cost only) its surface area, as flat
// volumes tie at volume 0. Pairs of equal keys are ordered by their nodes' tie order. Both floats
// are packed into one integer that orders as the pair (cost, tie) does, compared in one step.
struct Key {
  std::uint64_t bits;

  Key() = default;
  Key(float cost, float tie) : bits(std::uint64_t(ordered_bits(cost)) << 32 | ordered_bits(tie)) {}
  bool operator<(const Key& o) const { return bits < o.bits; }
  bool operator==(const Key& o) const { return bits == o.bits; }

 private:
  // Unsigned integers in the order of the floats (not NaN; -0 as +0).
  static std::uint32_t ordered_bits(float x) {
    x += 0.0f;
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    return b & 0x80000000u ? ~b : b | 0x80000000u;
  }
};

// A round's candidates: for node position u, slots [offsets[u], offsets[u + 1]) hold its
// candidate partners q, as codes: 2 q, or 2 q + 1 for a Morton neighbour that is not a mesh
// neighbour (such pairs are not carried to the next round). Keys are stored (the same key in both
// nodes' lists) only where they are costly to compute (oriented volumes fitted per candidate);
// there each list keeps its partners above u sorted increasing, otherwise lists are unordered
// and a key is computed again where it is needed, which costs less than storing it.
struct CandidateLists {
  std::vector<std::uint32_t> offsets;
  std::unique_ptr<std::uint32_t[]> codes;  // not initialized: every slot is written before it is read
  std::unique_ptr<Key[]> keys;             // only with stored keys
  std::size_t capacity = 0;
  // While lists with stored keys are built: the slot of the next partner above u still to be read.
  std::vector<std::uint32_t> cursor;
  // The cheapest partner of each node (kNone for an empty list), updated by the matching.
  std::vector<std::uint32_t> best;

  // Empty lists for m nodes with room for `slots` candidates in all.
  void reset(std::uint32_t m, std::size_t slots, bool store_keys) {
    offsets.resize(std::size_t(m) + 1);
    offsets[0] = 0;
    best.resize(m);
    if (store_keys) cursor.resize(m);
    if (slots > capacity) {
      codes.reset();
      keys.reset();
      codes.reset(new std::uint32_t[slots]);
      if (store_keys) keys.reset(new Key[slots]);
      capacity = slots;
    }
  }
};

// The axis-aligned box the rounds keep per node, to rank pairs by their merged box and to sort
// nodes along the Morton curve (the tree's volumes are computed exactly afterwards): in single
// precision, half the bytes of an Aabb, so that more of a node's neighbours share its cache
// lines. Coordinates are relative to the mesh's bounding box and scaled by a power of two to
// about [0, 1] (in float range for any valid mesh); where they are exact in float (CAD models'
// round numbers), the ranks and the order are those of the double-precision boxes, so ties stay
// ties. Sizes are computed in double, as for an Aabb.
struct BoxF {
  float min[3];
  float max[3];

  static BoxF enclosing(const BoxF& a, const BoxF& b) {
    BoxF r;
    for (int i = 0; i < 3; ++i) {
      r.min[i] = std::min(a.min[i], b.min[i]);
      r.max[i] = std::max(a.max[i], b.max[i]);
    }
    return r;
  }
  Real extent(int i) const { return Real(max[i]) - Real(min[i]); }
  // As surface_area(Aabb) and volume(Aabb), operation for operation.
  Real area() const { return 2 * (extent(0) * extent(1) + extent(1) * extent(2) + extent(2) * extent(0)); }
  Real volume() const { return extent(0) * extent(1) * extent(2); }
  Real center(int i) const { return (Real(min[i]) + Real(max[i])) * Real(0.5); }
};

// The greedy matching (take candidates cheapest first, skip those touching a matched node)
// without sorting any candidates: with a strict total order on candidates (key, then the pair of
// the nodes' tie orders), greedy equals repeatedly matching "locally dominant" pairs, each the cheapest
// remaining candidate of both its nodes (Preis, STACS 1999). A node's best remaining partner is
// found by a scan of its list and kept until that partner is matched; a node whose best partner
// prefers someone else defers to that partner first, so chains follow strictly decreasing keys
// and end in a mutual pair. The same result as the global sort, in O(E) scans on meshes.
// `key(slot, u, v)` is the key of candidate slot `slot` of u, partner v; `c.best` holds each
// node's cheapest partner on entry.
template <class KeyOf>
void greedy_matching(CandidateLists& c, const KeyOf& key, const std::vector<std::uint32_t>& order, std::size_t m,
                     std::vector<std::uint32_t>& partner, std::vector<std::uint32_t>& stack) {
  partner.assign(m, kNone);
  const std::uint32_t* const codes = c.codes.get();
  std::vector<std::uint32_t>& best_partner = c.best;
  // The best remaining partner of u, or kNone. Pairs of equal keys are ordered by their nodes'
  // `order` (smaller, then larger), i.e. for a fixed u by the partner's order.
  auto best = [&](std::uint32_t u) {
    std::uint32_t s_partner = best_partner[u];
    if (s_partner == kNone || partner[s_partner] == kNone) return s_partner;
    std::uint32_t s = kNone;
    s_partner = kNone;
    Key s_key{};
    for (std::uint32_t i = c.offsets[u], end = c.offsets[u + 1]; i < end; ++i) {
      const std::uint32_t v = codes[i] >> 1;
      if (partner[v] != kNone) continue;
      const Key k = key(i, u, v);
      if (s == kNone || k < s_key || (k == s_key && order[v] < order[s_partner])) {
        s = i;
        s_partner = v;
        s_key = k;
      }
    }
    best_partner[u] = s_partner;
    return s_partner;
  };
  stack.clear();
  for (std::uint32_t start = 0; start < m; ++start) {
    if (partner[start] != kNone) continue;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::uint32_t u = stack.back();
      if (partner[u] != kNone) {
        stack.pop_back();
        continue;
      }
      const std::uint32_t v = best(u);
      if (v == kNone) {
        stack.pop_back();
        continue;
      }
      if (best(v) == u) {
        stack.pop_back();
        partner[u] = v;
        partner[v] = u;
      } else {
        stack.push_back(v);  // v prefers a cheaper pair: settle v first, then come back to u
      }
    }
  }
}

// The hybrid of a tree (volume/hybrid.h): the same topology, with the volumes of nodes at
// `level` and above replaced by the smallest boxes enclosing their children's volumes, or, with
// `facet_boxes`, the leaf volumes below them. Children always have larger indices than their parent
// (depth-first layout), so one backward pass sees every child before its parent.
template <class Lower>
Tree<Hybrid<Lower>> make_hybrid(const Tree<Lower>& tree, int level, bool facet_boxes) {
  const std::size_t count = tree.node_count();
  std::vector<int> height(count, 0);
  std::vector<Aabb> facets_box(facet_boxes ? count : 0);
  std::vector<Hybrid<Lower>> volumes(count);
  std::vector<std::uint32_t> links(count);
  for (std::size_t i = count; i-- > 0;) {
    const NodeIndex node = NodeIndex(i);
    if (tree.is_leaf(node)) {
      links[i] = Tree<Hybrid<Lower>>::kLeafFlag | tree.facet(node);
      if (facet_boxes) facets_box[i] = bounding_aabb(tree.volume(node));
    } else {
      const NodeIndex c = tree.first_child(node);
      BOXTREE_ASSERT(c > node, "children follow their parent in the layout");
      links[i] = c;
      height[i] = 1 + std::max(height[c], height[c + 1]);
      if (facet_boxes) facets_box[i] = Aabb::enclosing(facets_box[c], facets_box[c + 1]);
    }
    if (height[i] >= level && !tree.is_leaf(node)) {
      const NodeIndex c = tree.first_child(node);
      volumes[i] = Hybrid<Lower>::upper(facet_boxes ? facets_box[i]
                                                    : Aabb::enclosing(volumes[c].bounds(), volumes[c + 1].bounds()));
    } else {
      volumes[i] = Hybrid<Lower>{tree.volume(node), Aabb(), false};
    }
  }
  return Tree<Hybrid<Lower>>(tree.shared_mesh(), std::move(volumes), std::move(links), tree.height());
}

// The corners of a leaf volume: ParentFit::fit_facets fits parents to these rather than to the
// facets, so that leaf volumes (which may be larger than their facets: a leaf box is the facet's
// enclosing rectangle) stay inside their ancestors and a descent finds every leaf volume that
// meets a query (FacetTest::leaf_volume).
template <PrincipalAxis K>
std::array<Vec3, 8> leaf_corners(const OrientedBox<K>& leaf) {
  return corners(leaf.box);
}
template <PrincipalAxis K, TriangleRule R>
std::array<Vec3, 6> leaf_corners(const PieSlice<K, R>& leaf) {
  return corners(leaf.prism);
}

// ParentFit::fit_facets: each parent's volume refitted to the corners of the leaf volumes below
// it, where that is smaller (by the build's cost) than the volume around its children.
template <class Volume>
void fit_parents_to_facets(std::vector<Volume>& volumes, const std::vector<std::uint32_t>& links, MergeCost cost) {
  const std::uint32_t leaf_flag = Tree<Volume>::kLeafFlag;
  const std::size_t count = volumes.size();
  // Leaves in depth-first order: the leaves below a node are the run [begin, end) of `leaves`.
  std::vector<std::uint32_t> leaves;
  leaves.reserve((count + 1) / 2);
  std::vector<std::uint32_t> begin(count), end(count);
  std::vector<std::pair<std::uint32_t, bool>> stack = {{0u, false}};
  while (!stack.empty()) {
    const auto [node, done] = stack.back();
    stack.pop_back();
    if (done) {
      end[node] = std::uint32_t(leaves.size());
      continue;
    }
    begin[node] = std::uint32_t(leaves.size());
    if (links[node] & leaf_flag) {
      leaves.push_back(node);
      end[node] = std::uint32_t(leaves.size());
      continue;
    }
    stack.push_back({node, true});
    stack.push_back({links[node] + 1, false});
    stack.push_back({links[node], false});
  }
  const auto cost_of = [&](const Volume& v) { return cost == MergeCost::volume ? volume(v) : surface_area(v); };
  std::vector<Vec3> points;
  for (std::uint32_t node = 0; node < count; ++node) {
    if (links[node] & leaf_flag) continue;
    points.clear();
    for (std::uint32_t k = begin[node]; k < end[node]; ++k) {
      const auto c = leaf_corners(volumes[leaves[k]]);
      points.insert(points.end(), c.begin(), c.end());
    }
    const std::optional<Volume> fitted = Volume::fitted(points.data(), points.size());
    if (fitted && cost_of(*fitted) < cost_of(volumes[node])) volumes[node] = *fitted;
  }
}

// BuildSettings::merge_rule: the tree of the rule's merge order over a mesh build_tree has
// checked, each parent the enclosing volume of its children, laid out depth-first.
template <class Volume>
Tree<Volume> build_by_rule(std::shared_ptr<const TriangleMesh> mesh_ptr, MergeRule rule,
                           std::chrono::steady_clock::time_point start, BuildStats* stats) {
  const TriangleMesh& mesh = *mesh_ptr;
  const std::size_t n = mesh.facet_count();
  const MergeOrder order = rule(mesh);
  BOXTREE_ASSERT(order.first.size() == n - 1 && order.second.size() == n - 1, "a merge order has n - 1 parents");

  // Build order: leaves 0..n-1 are the facets, parent k is node n + k.
  const std::size_t node_count = 2 * n - 1;
  std::vector<Volume> volumes;
  volumes.reserve(node_count);
  for (FacetId f = 0; f < n; ++f)
    volumes.push_back(Volume::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)));
  std::vector<std::uint32_t> first(n, 0), second(n, 0);  // by build index (a leaf's are unused)
  first.insert(first.end(), order.first.begin(), order.first.end());
  second.insert(second.end(), order.second.begin(), order.second.end());
  std::vector<int> heights(node_count, 0);
  std::vector<bool> merged(node_count, false);
  for (std::size_t node = n; node < node_count; ++node) {
    const std::uint32_t a = first[node], b = second[node];
    BOXTREE_ASSERT(a < node && b < node && a != b && !merged[a] && !merged[b],
                   "a merge order merges every node once, after it is built");
    merged[a] = merged[b] = true;
    volumes.push_back(Volume::enclosing(volumes[a], volumes[b]));
    heights[node] = 1 + std::max(heights[a], heights[b]);
  }

  std::vector<Volume> out_volumes;
  std::vector<std::uint32_t> out_links;
  const std::uint32_t root = std::uint32_t(node_count - 1);
  detail::depth_first_layout(volumes, first, second, root, n, Tree<Volume>::kLeafFlag, out_volumes, out_links);
  if (stats) {
    stats->rounds = order.rounds;
    stats->candidate_pairs = order.candidate_pairs;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return Tree<Volume>(std::move(mesh_ptr), std::move(out_volumes), std::move(out_links), heights[root]);
}

// build_tree's checks of the mesh: throws Error unless there is one, valid (validate_mesh) and
// within Tree<Volume>'s facet limit.
template <class Volume>
void check_mesh(const TriangleMesh* mesh) {
  if (!mesh) throw Error("build_tree: no mesh given");
  validate_mesh(*mesh);
  if (mesh->facet_count() > Tree<Volume>::kMaxFacets) throw Error("build_tree: too many facets");
}

// build_tree's checks of the greedy rounds' settings: throws Error unless the Morton window and
// the neighbour bound are usable.
void check_greedy_settings(const BuildSettings& settings) {
  if (settings.near_window < 1) throw Error("build_tree: near_window must be at least 1");
  if (settings.max_neighbors < 2) throw Error("build_tree: max_neighbors must be at least 2");
}

// The tree's arrays in their final layout (what Tree's constructor takes).
template <class Volume>
struct TreeLayout {
  std::vector<Volume> volumes;
  std::vector<std::uint32_t> links;
  int height = 0;
};

// One greedy bottom-up build (the rounds described at the top of the file) over a checked mesh
// with n >= 1 facets. Use: pair_up() once (the rounds, down to one root), then layout(). The
// steps, in order: the constructor (scales of keys and boxes, the leaves' volumes when
// PairRanking::merged_volume ranks by them), order_facets (the first round's positions),
// list_mesh_neighbors (the first round's candidate lists), then per round match (the greedy
// matching), merge_pairs (parents and carried nodes), order_groups (their Morton order) and
// contract_lists (the next round's lists).
//
// Nodes in build order: leaves 0..n-1 (node i is facet i), parents appended, children in
// `children`. The rounds work on axis-aligned bounding boxes only (for boxes, the volumes
// themselves): volumes of another kind are fitted during the rounds only for
// PairRanking::merged_volume, which ranks candidates by them; otherwise once per parent, in the
// final layout.
template <class Volume>
class GreedyBuild {
 public:
  GreedyBuild(const TriangleMesh& mesh, const BuildSettings& settings)
      : mesh_(mesh),
        settings_(settings),
        n_(mesh.facet_count()),
        fit_during_rounds_(!kIsAabb && settings.ranking == PairRanking::merged_volume),
        store_keys_(fit_during_rounds_),
        volume_cost_(settings.cost == MergeCost::volume),
        window_(std::uint32_t(settings.near_window)),
        next_node_(std::uint32_t(n_)) {
    children_.reserve(2 * (n_ - 1));
    if (fit_during_rounds_) {
      volumes_.reserve(2 * n_ - 1);
      for (FacetId f = 0; f < n_; ++f)
        volumes_.push_back(Volume::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)));
    }
    Aabb bounds;  // of the facets (a vertex that no facet uses is not checked by validate_mesh)
    for (FacetId f = 0; f < n_; ++f)
      for (int k = 0; k < 3; ++k) bounds.expand(mesh.corner(f, k));

    // Keys are floats, costs divided by the mesh's size (its largest extent squared for areas,
    // cubed for volumes) to stay in float range; rounding to float keeps the order of costs up to
    // ties, which the nodes' tie orders break.
    const Real max_extent = bounds.extent().maxCoeff();
    const Real inv_extent = max_extent > 0 && std::isfinite(1 / max_extent) ? 1 / max_extent : 1;
    area_scale_ = inv_extent * inv_extent;
    volume_scale_ = area_scale_ * inv_extent;
    // The frame of the rounds' boxes (BoxF): x -> (x - origin) * unit, unit a power of two; the
    // keys' scales divided by unit^2 and unit^3 (exactly) to give the same keys.
    origin_ = bounds.min;
    unit_ = max_extent > 0 ? std::ldexp(Real(1), -std::ilogb(max_extent)) : Real(1);
    box_area_scale_ = area_scale_ / (unit_ * unit_);
    box_volume_scale_ = volume_scale_ / (unit_ * unit_ * unit_);
  }

  // Pairs the nodes round by round until one is left; returns it (the root's build index).
  std::uint32_t pair_up() {
    list_mesh_neighbors(order_facets());
    while (active_.size() > 1) {
      const std::uint32_t m = std::uint32_t(active_.size());
      ++stats_.rounds;
      stats_.candidate_pairs += current_.offsets[m] / 2;
      match(m);
      const std::uint32_t next_m = merge_pairs(m);
      BOXTREE_ASSERT(next_m < m, "a round always pairs at least one node");
      if (next_m == 1) {
        active_.swap(next_active_);
        break;
      }
      order_groups(next_m);
      contract_lists(m, next_m);
    }
    return active_[0];
  }

  // The final layout: depth-first from the root, the two children of a node in adjacent slots
  // after their parent; a parent's volume is computed (or copied) once its children's are, in the
  // same traversal. The height is the deepest leaf's depth.
  TreeLayout<Volume> layout(std::uint32_t root) const {
    const std::size_t node_count = 2 * n_ - 1;
    BOXTREE_ASSERT(children_.size() == 2 * (n_ - 1), "a binary tree over n leaves has n-1 parents");
    const std::uint32_t leaf_flag = Tree<Volume>::kLeafFlag;
    TreeLayout<Volume> out;
    out.links.resize(node_count);
    out.volumes.resize(node_count);
    struct Visit {
      std::uint32_t node, slot, depth;
      bool children_done;
    };
    std::vector<Visit> visits{{root, 0, 0, false}};
    std::uint32_t next_slot = 1;
    while (!visits.empty()) {
      Visit& v = visits.back();
      const std::uint32_t slot = v.slot;
      if (v.node < n_) {
        const FacetId f = v.node;
        out.links[slot] = leaf_flag | f;
        out.volumes[slot] = fit_during_rounds_
                                ? volumes_[f]
                                : Volume::from_triangle(mesh_.corner(f, 0), mesh_.corner(f, 1), mesh_.corner(f, 2));
        out.height = std::max(out.height, int(v.depth));
        visits.pop_back();
      } else if (v.children_done) {
        const std::uint32_t c = out.links[slot];
        out.volumes[slot] =
            fit_during_rounds_ ? volumes_[v.node] : Volume::enclosing(out.volumes[c], out.volumes[c + 1]);
        visits.pop_back();
      } else {
        v.children_done = true;
        const std::uint32_t c = next_slot, depth = v.depth + 1;
        const std::size_t k = 2 * (std::size_t(v.node) - n_);
        out.links[slot] = c;
        next_slot += 2;
        const std::uint32_t first_child = children_[k], second_child = children_[k + 1];
        visits.push_back({second_child, c + 1, depth, false});  // invalidates v
        visits.push_back({first_child, c, depth, false});
      }
    }
    return out;
  }

  const BuildStats& stats() const { return stats_; }

 private:
  static constexpr bool kIsAabb = std::is_same_v<Volume, Aabb>;

  Key make_key(Real area, Real vol) const {
    if (volume_cost_) return {float(vol * volume_scale_), float(area * area_scale_)};
    return {float(area * area_scale_), 0.0f};
  }

  BoxF round_box(const Vec3& a, const Vec3& b, const Vec3& c) const {
    const Aabb box = Aabb::from_triangle(a, b, c);
    BoxF r;
    for (int i = 0; i < 3; ++i) {
      r.min[i] = float((box.min[i] - origin_[i]) * unit_);
      r.max[i] = float((box.max[i] - origin_[i]) * unit_);
    }
    return r;
  }

  // The rank of merging the nodes at positions p and q: of their boxes (symmetric in p and q),
  Key box_pair_key(std::uint32_t p, std::uint32_t q) const {
    const BoxF merged = BoxF::enclosing(active_box_[p], active_box_[q]);
    if (volume_cost_) return {float(merged.volume() * box_volume_scale_), float(merged.area() * box_area_scale_)};
    return {float(merged.area() * box_area_scale_), 0.0f};
  }

  // and of any kind, p's Morton rank below q's (fitting is not symmetric).
  Key pair_key(std::uint32_t p, std::uint32_t q) const {
    if constexpr (!kIsAabb) {
      if (fit_during_rounds_) {
        const Volume merged = Volume::enclosing(volumes_[active_[p]], volumes_[active_[q]]);
        return make_key(surface_area(merged), volume_cost_ ? volume(merged) : 0);
      }
    }
    return box_pair_key(p, q);
  }

  // The key of candidate `slot` (a slot of u's list, partner v) once the lists are built.
  Key candidate_key(const CandidateLists& lists, std::uint32_t slot, std::uint32_t u, std::uint32_t v) const {
    return store_keys_ ? lists.keys[slot] : box_pair_key(u, v);
  }

  // morton_[i] = (code, index into boxes) in Morton order of the boxes' centres, ties in the order
  // of tie(index) (increasing).
  template <class Tie>
  void morton_order(const BoxF* boxes, std::uint32_t count, const Tie& tie) {
    Real lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::uint32_t i = 0; i < count; ++i)
      for (int k = 0; k < 3; ++k) {
        const Real c = boxes[i].center(k);
        lo[k] = std::min(lo[k], c);
        hi[k] = std::max(hi[k], c);
      }
    Real scale[3];
    for (int k = 0; k < 3; ++k) scale[k] = hi[k] - lo[k] > 0 ? Real(0x3ff) / (hi[k] - lo[k]) : 0;
    morton_.reserve(count);
    morton_.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      std::uint32_t code = 0;
      for (int k = 0; k < 3; ++k) {
        const Real q = std::clamp((boxes[i].center(k) - lo[k]) * scale[k], Real(0), Real(0x3ff));
        code |= spread_bits(std::uint32_t(q)) << k;
      }
      morton_[i] = {code, i};
    }
    radix_sort(morton_, morton_scratch_);
    for (std::uint32_t i = 0; i + 1 < count;) {  // runs of equal codes (short), sorted by `tie`
      std::uint32_t j = i + 1;
      while (j < count && morton_[j].first == morton_[i].first) ++j;
      if (j - i > 1)
        std::sort(morton_.begin() + i, morton_.begin() + j,
                  [&](const auto& a, const auto& b) { return tie(a.second) < tie(b.second); });
      i = j;
    }
  }

  // The first round's active nodes: the facets in the Morton order of their boxes (ties by facet
  // id), each its own tie order. Returns each facet's position.
  std::vector<std::uint32_t> order_facets() {
    std::vector<std::uint32_t> position(n_);  // of facet f
    // Room for the first round (the largest); the arrays are reused by the later rounds.
    for (auto* v : {&active_, &next_active_, &active_rank_, &next_rank_, &active_order_, &next_order_}) v->reserve(n_);
    next_box_.resize(n_);
    for (FacetId f = 0; f < n_; ++f)
      next_box_[f] = round_box(mesh_.corner(f, 0), mesh_.corner(f, 1), mesh_.corner(f, 2));
    morton_order(next_box_.data(), std::uint32_t(n_), [](std::uint32_t f) { return f; });
    active_.resize(n_);
    active_box_.resize(n_);
    active_rank_.resize(n_);
    active_order_.resize(n_);
    for (std::uint32_t p = 0; p < n_; ++p) {
      active_[p] = morton_[p].second;
      active_order_[p] = active_[p];
      active_box_[p] = next_box_[active_[p]];
      active_rank_[p] = p;
      position[morton_[p].second] = p;
    }
    return position;
  }

  // Builds list i of `lists` (whose lists below i are built) from the codes 2 q of the mesh
  // neighbours q gathered in list i's slots [offsets[i], offsets[i] + count) (distinct, without i,
  // stamp[q] == i): adds the Morton neighbours not already there and keeps the list's cheapest
  // partner (the matching's first choice). With stored keys, computes the keys of the partners above
  // i and reads those below i from their lists (where partners above are read in increasing
  // order: each list keeps its upper part sorted and a cursor in it).
  // `by_rank`: the positions in Morton order (null: the identity), `rank`: i's rank there.
  void build_list(CandidateLists& lists, std::uint32_t i, std::uint32_t m, std::uint32_t count,
                  const std::pair<std::uint32_t, std::uint32_t>* by_rank, std::uint32_t rank) {
    const std::uint32_t first_slot = lists.offsets[i];
    std::uint32_t* const begin = lists.codes.get() + first_slot;
    std::uint32_t* end = begin + count;
    for (std::uint32_t k = rank >= window_ ? rank - window_ : 0, k_end = std::min(m, rank + window_ + 1); k < k_end;
         ++k) {
      const std::uint32_t w = by_rank ? by_rank[k].second : k;
      if (k != rank && stamp_[w] != i) *end++ = 2 * w + 1;
    }
    lists.offsets[i + 1] = first_slot + std::uint32_t(end - begin);
    std::uint32_t best = kNone;
    Key best_key{};
    const auto consider = [&](const std::uint32_t* c, const Key& key) {
      const std::uint32_t q = *c >> 1;
      if (best == kNone || key < best_key || (key == best_key && active_order_[q] < active_order_[best])) {
        best = q;
        best_key = key;
      }
    };
    if (!store_keys_) {
      for (const std::uint32_t* c = begin; c < end; ++c) {
        const std::uint32_t q = *c >> 1;
        consider(c, box_pair_key(i, q));
      }
    } else {
      std::uint32_t* const middle = std::partition(begin, end, [i](std::uint32_t code) { return code < 2 * i; });
      sort_short(middle, end);
      Key* const keys = lists.keys.get() + first_slot;
      for (const std::uint32_t* c = begin; c < middle; ++c) {
        const std::uint32_t r = lists.cursor[*c >> 1]++;
        BOXTREE_ASSERT(lists.codes[r] >> 1 == i, "candidate lists are symmetric");
        keys[c - begin] = lists.keys[r];
        consider(c, keys[c - begin]);
      }
      lists.cursor[i] = first_slot + std::uint32_t(middle - begin);
      for (const std::uint32_t* c = middle; c < end; ++c) {
        const std::uint32_t q = *c >> 1;
        keys[c - begin] = active_rank_[q] < active_rank_[i] ? pair_key(q, i) : pair_key(i, q);
        consider(c, keys[c - begin]);
      }
    }
    lists.best[i] = best;
  }

  // The first round's candidate lists: each facet's mesh neighbours (facet_fans) and Morton
  // neighbours. `position`: each facet's position (order_facets); its storage is reused.
  void list_mesh_neighbors(std::vector<std::uint32_t> position) {
    const FacetFans fans = facet_fans(mesh_, settings_.max_neighbors, position);
    if (n_ <= 1) return;
    current_.reset(std::uint32_t(n_), fans.bound + 2 * std::size_t(window_) * n_, store_keys_);
    stamp_.swap(position);  // no longer needed: its pages serve again
    stamp_.assign(n_, kNone);
    for (std::uint32_t p = 0; p < n_; ++p) {
      // Prefetch the fans a few positions ahead (facets in Morton order are scattered in the
      // mesh's order): the corners, then their fans' offsets, then the fans.
      if (p + 16 < n_) prefetch(&fans.corners[3 * std::size_t(active_[p + 16])]);
      if (p + 8 < n_) {
        const std::uint32_t* c = &fans.corners[3 * std::size_t(active_[p + 8])];
        for (int k = 0; k < 3; ++k)
          if (c[k] != kNone) prefetch(&fans.offsets[c[k]]);
      }
      if (p + 4 < n_) {
        const std::uint32_t* c = &fans.corners[3 * std::size_t(active_[p + 4])];
        for (int k = 0; k < 3; ++k)
          if (c[k] != kNone) prefetch(&fans.incident[fans.offsets[c[k]]]);
        prefetch(&active_box_[p + 4]);
      }
      std::uint32_t* const begin = current_.codes.get() + current_.offsets[p];
      const std::uint32_t* end =
          gather_facet_neighbors(fans, active_[p], p, settings_.max_neighbors, active_.data(), stamp_.data(), begin);
      const std::uint32_t count = std::uint32_t(end - begin);
      for (std::uint32_t k = 0; k < count; ++k) begin[k] *= 2;
      build_list(current_, p, std::uint32_t(n_), count, nullptr, p);
    }
  }

  // Greedy maximal matching of the m active nodes, cheapest first: partner_.
  void match(std::uint32_t m) {
    greedy_matching(
        current_,
        [&](std::uint32_t slot, std::uint32_t u, std::uint32_t v) { return candidate_key(current_, slot, u, v); },
        active_order_, m, partner_, stack_);
  }

  // Parents for pairs (children in Morton order), carried nodes as they are: group g, the next
  // round's position, in the order of the groups' first positions (group_, group_first_, and the
  // next_ arrays but for the ranks). Returns the number of groups.
  std::uint32_t merge_pairs(std::uint32_t m) {
    group_.assign(m, kNone);
    group_first_.clear();
    next_active_.clear();
    next_box_.clear();
    next_order_.clear();
    for (std::uint32_t p = 0; p < m; ++p) {
      if (group_[p] != kNone) continue;
      const std::uint32_t q = partner_[p];
      const std::uint32_t g = std::uint32_t(next_active_.size());
      group_[p] = g;
      group_first_.push_back(p);
      if (q == kNone) {
        next_active_.push_back(active_[p]);
        next_box_.push_back(active_box_[p]);
        next_order_.push_back(active_order_[p]);
        continue;
      }
      group_[q] = g;
      const bool p_first = active_rank_[p] < active_rank_[q];
      const std::uint32_t a = active_[p_first ? p : q], b = active_[p_first ? q : p];
      if (fit_during_rounds_) volumes_.push_back(Volume::enclosing(volumes_[a], volumes_[b]));
      children_.push_back(a);
      children_.push_back(b);
      next_active_.push_back(next_node_++);
      next_box_.push_back(BoxF::enclosing(active_box_[p], active_box_[q]));
      next_order_.push_back(std::min(active_order_[p], active_order_[q]));
    }
    return std::uint32_t(next_active_.size());
  }

  // Morton order of the next_m groups (next_rank_), ties as if the groups were numbered in Morton
  // order of their first members (as they would be with positions in Morton order).
  void order_groups(std::uint32_t next_m) {
    morton_order(next_box_.data(), next_m, [&](std::uint32_t g) {
      const std::uint32_t p = group_first_[g], q = partner_[p];
      return q == kNone ? active_rank_[p] : std::min(active_rank_[p], active_rank_[q]);
    });
    next_rank_.resize(next_m);
    for (std::uint32_t i = 0; i < next_m; ++i) next_rank_[morton_[i].second] = i;
  }

  // The next round: the groups become the active nodes, and their lists are built from the m
  // current lists. A group's mesh neighbours are its members' mesh neighbours' groups; Morton
  // neighbours and keys need the next round's boxes, ranks and orders.
  void contract_lists(std::uint32_t m, std::uint32_t next_m) {
    active_.swap(next_active_);
    active_box_.swap(next_box_);
    active_rank_.swap(next_rank_);
    active_order_.swap(next_order_);
    stamp_.assign(next_m, kNone);
    next_.reset(next_m, current_.offsets[m] + 2 * std::size_t(window_) * next_m, store_keys_);
    for (std::uint32_t i = 0; i < next_m; ++i) {
      std::uint32_t* const begin = next_.codes.get() + next_.offsets[i];
      std::uint32_t* end = begin;
      stamp_[i] = i;  // drops i itself
      for (const std::uint32_t p : {group_first_[i], partner_[group_first_[i]]}) {
        if (p == kNone) break;
        for (std::uint32_t j = current_.offsets[p], j_end = current_.offsets[p + 1]; j < j_end; ++j) {
          // Without branches (taken at random): skip Morton neighbours only and groups listed.
          const std::uint32_t code = current_.codes[j];
          const std::uint32_t r = group_[code >> 1];
          const bool add = !(code & 1) & (stamp_[r] != i);
          stamp_[r] = add ? i : stamp_[r];
          *end = 2 * r;
          end += add;
        }
      }
      build_list(next_, i, next_m, std::uint32_t(end - begin), morton_.data(), active_rank_[i]);
    }
    std::swap(current_, next_);
  }

  const TriangleMesh& mesh_;
  const BuildSettings& settings_;
  const std::size_t n_;
  const bool fit_during_rounds_;
  const bool store_keys_;
  const bool volume_cost_;
  const std::uint32_t window_;
  std::vector<Volume> volumes_;  // by build index, when fit_during_rounds_
  // The children of parent b (build index n + k): children_[2 k], children_[2 k + 1].
  std::vector<std::uint32_t> children_;
  std::uint32_t next_node_;  // the next parent's build index
  Real area_scale_ = 1;
  Real volume_scale_ = 1;
  Vec3 origin_ = Vec3::Zero();
  Real unit_ = 1;
  Real box_area_scale_ = 1;
  Real box_volume_scale_ = 1;
  // The active nodes by position: in the first round the Morton order of the facets, then each
  // round's parents and carried nodes in the order of their first member's position (so that
  // nodes stay near their neighbours in memory and the lists of one round are read in order
  // while the next round's are built). Per position: the node, its box, its rank in the round's
  // Morton order (which orders the members of a pair and gives the Morton neighbours).
  std::vector<std::uint32_t> active_, next_active_;
  std::vector<BoxF> active_box_, next_box_;
  std::vector<std::uint32_t> active_rank_, next_rank_;
  // Tie order: the smallest facet id below the node (as if positions kept the facets' order).
  std::vector<std::uint32_t> active_order_, next_order_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> morton_, morton_scratch_;
  // The candidate lists of the current round (positions 0..m-1) and those being built for the
  // next one.
  CandidateLists current_, next_;
  std::vector<std::uint32_t> stamp_;
  std::vector<std::uint32_t> partner_, stack_, group_, group_first_;
  BuildStats stats_;
};

}  // namespace

template <class Volume>
Tree<Volume> build_tree(std::shared_ptr<const TriangleMesh> mesh_ptr, const BuildSettings& settings,
                        BuildStats* stats) {
  if constexpr (is_hybrid_v<Volume>) {
    if (settings.hybrid_level < 1) throw Error("build_tree: a hybrid method needs hybrid_level >= 1");
    return make_hybrid(build_tree<typename Volume::Lower>(std::move(mesh_ptr), settings, stats), settings.hybrid_level,
                       settings.parent_fit == ParentFit::fit_facets);
  }
  const auto start = std::chrono::steady_clock::now();
  check_mesh<Volume>(mesh_ptr.get());
  if (settings.merge_rule) return build_by_rule<Volume>(std::move(mesh_ptr), settings.merge_rule, start, stats);
  check_greedy_settings(settings);
  GreedyBuild<Volume> build(*mesh_ptr, settings);
  TreeLayout<Volume> out = build.layout(build.pair_up());
  if constexpr (!std::is_same_v<Volume, Aabb> && !is_hybrid_v<Volume>) {
    if (settings.parent_fit == ParentFit::fit_facets) fit_parents_to_facets(out.volumes, out.links, settings.cost);
  }
  BuildStats local = build.stats();
  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return Tree<Volume>(std::move(mesh_ptr), std::move(out.volumes), std::move(out.links), out.height);
}

#define BOXTREE_INSTANTIATE_BUILD(V) \
  template Tree<V> build_tree<V>(std::shared_ptr<const TriangleMesh>, const BuildSettings&, BuildStats*);
BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_BUILD)

}  // namespace boxtree
