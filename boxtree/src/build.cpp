// Bottom-up boxtree construction (paper, Sections 2-3).
//
// Round structure (m active nodes, positions = their Morton order, renewed every round):
//   1. candidates = contracted mesh adjacency (facets sharing a vertex, welded by position)
//                 + "near" pairs: the `near_window` neighbours on each side along the Morton curve
//                 of the node centres;
//   2. each candidate's key: the surface area (or volume) of the merged volume (for the oriented
//      kinds with PairRanking::bounding_box, of the merged bounding box), computed once per pair;
//   3. greedy maximal matching, cheapest first (ties broken by the nodes' smallest facet ids:
//      deterministic), found without sorting (Preis' locally dominant pairs, see greedy_matching);
//   4. matched pairs become parents, unmatched nodes are carried; adjacency is contracted.
// Everything per round is linear in the candidates (short per-node lists, radix-sorted Morton
// codes, buffers reused between rounds), as in PLOC (Meister & Bittner, "Parallel Locally-Ordered
// Clustering for Bounding Volume Hierarchy Construction", TVCG 2018), which also merges each node
// with its cheapest neighbour along a Morton order; here the neighbours include the mesh adjacency
// and the matching is the paper's greedy one.
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
#include <numeric>
#include <optional>
#include <type_traits>

#include "boxtree/detail/volume_kinds.h"
#include "internal.h"
#include "boxtree/planar/terrain.h"

namespace boxtree {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

// Lists of neighbours in CSR form: the neighbours of i are items[offsets[i] .. offsets[i + 1]),
// sorted increasing, without duplicates or i itself.
struct Adjacency {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> items;
};

// Sorts [begin, end) and drops duplicates and `self`; returns the new end. The lists are short
// (a dozen entries on meshes), where insertion sort beats std::sort.
std::uint32_t* sort_unique_list(std::uint32_t* begin, std::uint32_t* end, std::uint32_t self) {
  if (begin == end) return end;  // also a null `begin` (an empty vector's data()): no arithmetic on it
  if (end - begin > 48) {
    std::sort(begin, end);
  } else {
    for (std::uint32_t* i = begin + 1; i < end; ++i) {
      const std::uint32_t x = *i;
      std::uint32_t* j = i;
      for (; j > begin && *(j - 1) > x; --j) *j = *(j - 1);
      *j = x;
    }
  }
  std::uint32_t* out = begin;
  for (std::uint32_t* i = begin; i < end; ++i)
    if (*i != self && (out == begin || *(out - 1) != *i)) *out++ = *i;
  return out;
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
// as PQP's env.obj still get their adjacency), as lists between positions: facet f is at
// position[f]. A vertex shared by more than `max_fan` facets links them in a chain (in facet
// order) instead of all pairs, bounding the work at high-valence vertices.
Adjacency facet_adjacency(const TriangleMesh& mesh, int max_fan, const std::vector<std::uint32_t>& position) {
  const std::size_t n = mesh.triangles.size();
  const std::vector<VertexId> welded = weld_vertices(mesh);
  std::size_t welded_count = 0;
  for (VertexId w : welded) welded_count = std::max(welded_count, std::size_t(w) + 1);
  const auto corners = [&](FacetId f, std::array<VertexId, 3>& out) {
    // A facet repeating a vertex lists it once.
    int k = 0;
    for (int i = 0; i < 3; ++i) {
      const VertexId w = welded[mesh.triangles[f][i]];
      if ((k > 0 && out[0] == w) || (k > 1 && out[1] == w)) continue;
      out[k++] = w;
    }
    return k;
  };

  // Incident facets per welded vertex (CSR), facets in increasing id order.
  std::vector<std::uint32_t> offsets(welded_count + 1, 0);
  std::array<VertexId, 3> c;
  for (FacetId f = 0; f < n; ++f)
    for (int k = 0, count = corners(f, c); k < count; ++k) ++offsets[c[k] + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<FacetId> incident(offsets.back());
  {
    std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (FacetId f = 0; f < n; ++f)
      for (int k = 0, count = corners(f, c); k < count; ++k) incident[cursor[c[k]]++] = f;
  }

  // Per position: the positions of the facets in its vertices' fans (or its chain neighbours).
  std::vector<FacetId> facet_at(n);
  for (FacetId f = 0; f < n; ++f) facet_at[position[f]] = f;
  std::size_t bound = 0;
  for (FacetId f = 0; f < n; ++f)
    for (int k = 0, count = corners(f, c); k < count; ++k) bound += std::min<std::size_t>(offsets[c[k] + 1] - offsets[c[k]], 2 + std::size_t(max_fan));
  Adjacency adj;
  adj.offsets.resize(n + 1);
  adj.items.resize(bound);
  std::vector<std::uint32_t> stamp(n, kNone);
  std::uint32_t* out = adj.items.data();
  for (std::uint32_t p = 0; p < n; ++p) {
    const FacetId f = facet_at[p];
    std::uint32_t* begin = out;
    adj.offsets[p] = std::uint32_t(begin - adj.items.data());
    stamp[p] = p;
    const auto add = [&](FacetId g) {
      const std::uint32_t q = position[g];
      if (stamp[q] == p) return;
      stamp[q] = p;
      *out++ = q;
    };
    for (int k = 0, count = corners(f, c); k < count; ++k) {
      const std::uint32_t vb = offsets[c[k]], ve = offsets[c[k] + 1];
      if (ve - vb <= std::uint32_t(max_fan)) {
        for (std::uint32_t i = vb; i < ve; ++i) add(incident[i]);
      } else {
        const std::uint32_t i = std::uint32_t(std::lower_bound(incident.begin() + vb, incident.begin() + ve, f) - incident.begin());
        if (i > vb) add(incident[i - 1]);
        if (i + 1 < ve) add(incident[i + 1]);
      }
    }
    out = sort_unique_list(begin, out, p);
  }
  adj.items.resize(std::size_t(out - adj.items.data()));
  adj.offsets[n] = std::uint32_t(adj.items.size());
  return adj;
}

// 30-bit Morton code of a point quantized to 10 bits per axis inside [lo, lo + 1024 / scale].
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0x3ff;
  x = (x | x << 16) & 0x030000ffu;
  x = (x | x << 8) & 0x0300f00fu;
  x = (x | x << 4) & 0x030c30c3u;
  x = (x | x << 2) & 0x09249249u;
  return x;
}

std::uint32_t morton_code(const Vec3& p, const Vec3& lo, const Vec3& scale) {
  std::uint32_t code = 0;
  for (int i = 0; i < 3; ++i) {
    const Real q = std::clamp((p[i] - lo[i]) * scale[i], Real(0), Real(0x3ff));
    code |= spread_bits(std::uint32_t(q)) << i;
  }
  return code;
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
// volumes tie at volume 0. Pairs of equal keys are ordered by their node positions.
struct Key {
  float cost;
  float tie;
  bool operator<(const Key& o) const { return cost < o.cost || (cost == o.cost && tie < o.tie); }
  bool operator==(const Key& o) const { return cost == o.cost && tie == o.tie; }
};

// One round's candidate graph: for node position u, slots [offsets[u], offsets[u + 1]) hold its
// candidate partners (sorted increasing) and the pair's key, the same key in both nodes' slots.
struct Candidates {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> neighbor;
  std::vector<Key> key;
  std::vector<std::uint32_t> reverse;  // fill cursor for the lower half of each list
};

// The greedy matching (take candidates cheapest first, skip those touching a matched node)
// without sorting any candidates: with a strict total order on candidates (key, then the pair of
// positions), greedy equals repeatedly matching "locally dominant" pairs, each the cheapest
// remaining candidate of both its nodes (Preis, STACS 1999). A node's best remaining partner is
// found by a scan of its list and kept until that partner is matched; a node whose best partner
// prefers someone else defers to that partner first, so chains follow strictly decreasing keys
// and end in a mutual pair. The same result as the global sort, in O(E) scans on meshes.
void greedy_matching(const Candidates& c, const std::vector<std::uint32_t>& order, std::size_t m,
                     std::vector<std::uint32_t>& partner, std::vector<std::uint32_t>& best_slot,
                     std::vector<std::uint32_t>& stack) {
  partner.assign(m, kNone);
  best_slot.assign(m, kNone);
  // The best remaining partner of u, or kNone. Pairs of equal keys are ordered by their nodes'
  // `order` (smaller, then larger), i.e. for a fixed u by the partner's order.
  auto best = [&](std::uint32_t u) {
    std::uint32_t s = best_slot[u];
    if (s != kNone && partner[c.neighbor[s]] == kNone) return c.neighbor[s];
    s = kNone;
    for (std::uint32_t i = c.offsets[u], end = c.offsets[u + 1]; i < end; ++i) {
      if (partner[c.neighbor[i]] != kNone) continue;
      if (s == kNone || c.key[i] < c.key[s] || (c.key[i] == c.key[s] && order[c.neighbor[i]] < order[c.neighbor[s]])) s = i;
    }
    best_slot[u] = s;
    return s == kNone ? kNone : c.neighbor[s];
  };
  stack.clear();
  for (std::size_t u = m; u-- > 0;) stack.push_back(std::uint32_t(u));
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

}  // namespace

template <class Volume>
Tree<Volume> build_tree(std::shared_ptr<const TriangleMesh> mesh_ptr, const BuildSettings& settings,
                        BuildStats* stats) {
  if constexpr (is_hybrid_v<Volume>) {
    if (settings.hybrid_level < 1) throw Error("build_tree: a hybrid method needs hybrid_level >= 1");
    return make_hybrid(build_tree<typename Volume::Lower>(std::move(mesh_ptr), settings, stats), settings.hybrid_level,
                       settings.parent_fit == ParentFit::fit_facets);
  }
  if (settings.strategy == BuildStrategy::terrain) return planar::build_terrain_tree<Volume>(std::move(mesh_ptr), stats);
  const auto start = std::chrono::steady_clock::now();
  if (!mesh_ptr) throw Error("build_tree: no mesh given");
  const TriangleMesh& mesh = *mesh_ptr;
  validate_mesh(mesh);
  const std::size_t n = mesh.facet_count();
  if (n > Tree<Volume>::kMaxFacets) throw Error("build_tree: too many facets");
  if (settings.near_window < 1) throw Error("build_tree: near_window must be at least 1");
  if (settings.max_neighbors < 2) throw Error("build_tree: max_neighbors must be at least 2");

  // Nodes in build order: leaves 0..n-1 (node i is facet i), parents appended, children
  // first/second. The rounds work on axis-aligned bounding boxes only (for boxes, the volumes
  // themselves): volumes of another kind are fitted during the rounds only for
  // PairRanking::merged_volume, which ranks candidates by them; otherwise once per parent, in the
  // final layout.
  constexpr bool kIsAabb = std::is_same_v<Volume, Aabb>;
  const bool fit_during_rounds = !kIsAabb && settings.ranking == PairRanking::merged_volume;
  std::vector<Volume> volumes;  // by build index, when fit_during_rounds
  std::vector<std::uint32_t> first(n, kNone), second(n, kNone);
  first.reserve(2 * n - 1);
  second.reserve(2 * n - 1);
  if (fit_during_rounds) {
    volumes.reserve(2 * n - 1);
    for (FacetId f = 0; f < n; ++f) volumes.push_back(Volume::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)));
  }
  std::vector<Aabb> leaf_boxes(n);
  Aabb bounds;
  for (FacetId f = 0; f < n; ++f) {
    leaf_boxes[f] = Aabb::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
    bounds = Aabb::enclosing(bounds, leaf_boxes[f]);
  }

  // Keys are floats, costs divided by the mesh's size (its largest extent squared for areas,
  // cubed for volumes) to stay in float range; rounding to float keeps the order of costs up to
  // ties, which the positions break.
  const bool volume_cost = settings.cost == MergeCost::volume;
  const Real max_extent = bounds.extent().maxCoeff();
  const Real inv_extent = max_extent > 0 && std::isfinite(1 / max_extent) ? 1 / max_extent : 1;
  const Real area_scale = inv_extent * inv_extent;
  const Real volume_scale = area_scale * inv_extent;
  const auto make_key = [&](Real area, Real vol) -> Key {
    if (volume_cost) return {float(vol * volume_scale), float(area * area_scale)};
    return {float(area * area_scale), 0.0f};
  };

  // Per position (copied in Morton order each round, so that a node's candidates are near in
  // memory): the node, its bounding box, its subtree height.
  std::vector<std::uint32_t> active, next_active;
  std::vector<Aabb> active_box, next_box;
  std::vector<int> active_height, next_height;
  // Tie order: the smallest facet id below the node (as if positions kept the facets' order).
  std::vector<std::uint32_t> active_order, next_order;
  // The rank of merging the nodes at positions p < q.
  const auto pair_key = [&](std::uint32_t p, std::uint32_t q) -> Key {
    if constexpr (!kIsAabb) {
      if (fit_during_rounds) {
        const Volume merged = Volume::enclosing(volumes[active[p]], volumes[active[q]]);
        return make_key(surface_area(merged), volume_cost ? volume(merged) : 0);
      }
    }
    const Aabb merged = Aabb::enclosing(active_box[p], active_box[q]);
    return make_key(surface_area(merged), volume_cost ? volume(merged) : 0);
  };

  BuildStats local;
  // Positions are the Morton order of the nodes' box centres, renewed every round; the mesh
  // adjacency (contracted) is kept between positions.
  // morton[i] = (code, index into boxes) in Morton order of the boxes' centres.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> morton, morton_scratch;
  const auto morton_order = [&](const Aabb* boxes, std::uint32_t count) {
    Aabb centres;
    for (std::uint32_t i = 0; i < count; ++i) centres.expand(boxes[i].center());
    const Vec3 extent = centres.extent();
    Vec3 scale;
    for (int i = 0; i < 3; ++i) scale[i] = extent[i] > 0 ? Real(0x3ff) / extent[i] : 0;
    morton.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) morton[i] = {morton_code(boxes[i].center(), centres.min, scale), i};
    radix_sort(morton, morton_scratch);
  };

  Adjacency adjacency, next_adjacency;
  {
    morton_order(leaf_boxes.data(), std::uint32_t(n));
    std::vector<std::uint32_t> position(n);
    active.resize(n);
    active_box.resize(n);
    active_height.assign(n, 0);
    active_order.resize(n);
    for (std::uint32_t p = 0; p < n; ++p) {
      active[p] = morton[p].second;
      active_order[p] = active[p];
      active_box[p] = leaf_boxes[active[p]];
      position[morton[p].second] = p;
    }
    leaf_boxes = std::vector<Aabb>();
    adjacency = facet_adjacency(mesh, settings.max_neighbors, position);
  }
  Candidates cand;
  std::vector<std::uint32_t> partner, best_slot, stack, group, group_members, rank, stamp;
  const std::uint32_t window = std::uint32_t(settings.near_window);
  std::uint32_t next_node = std::uint32_t(n);
  while (active.size() > 1) {
    const std::uint32_t m = std::uint32_t(active.size());
    ++local.rounds;

    // 1. Candidates of each position: its contracted adjacency and its `window` neighbours on
    // each side in the Morton order, merged into one sorted list.
    cand.offsets.resize(m + 1);
    cand.neighbor.resize(adjacency.items.size() + std::size_t(m) * 2 * window);
    std::uint32_t write = 0;
    for (std::uint32_t p = 0; p < m; ++p) {
      cand.offsets[p] = write;
      const std::uint32_t* a = adjacency.items.data() + adjacency.offsets[p];
      const std::uint32_t* a_end = adjacency.items.data() + adjacency.offsets[p + 1];
      std::uint32_t w = p >= window ? p - window : 0;
      const std::uint32_t w_end = std::min(m, p + window + 1);
      std::uint32_t* out = cand.neighbor.data() + write;
      while (a < a_end || w < w_end) {
        if (w == p) {
          ++w;
          continue;
        }
        std::uint32_t x;
        if (w >= w_end || (a < a_end && *a < w)) {
          x = *a++;
        } else {
          if (a < a_end && *a == w) ++a;
          x = w++;
        }
        *out++ = x;
      }
      write = std::uint32_t(out - cand.neighbor.data());
    }
    cand.offsets[m] = write;
    cand.neighbor.resize(write);
    local.candidate_pairs += write / 2;

    // 2. Each pair's key, computed once (by the node at the smaller position) and stored in both
    // lists: the lower part of each list is filled in increasing order of the partner.
    cand.key.resize(write);
    cand.reverse.assign(cand.offsets.begin(), cand.offsets.end() - 1);
    for (std::uint32_t p = 0; p < m; ++p) {
      for (std::uint32_t i = cand.offsets[p], end = cand.offsets[p + 1]; i < end; ++i) {
        const std::uint32_t q = cand.neighbor[i];
        if (q < p) continue;
        const Key key = pair_key(p, q);
        cand.key[i] = key;
        const std::uint32_t r = cand.reverse[q]++;
        BOXTREE_ASSERT(cand.neighbor[r] == p, "candidate lists are symmetric");
        cand.key[r] = key;
      }
    }

    // 3. Greedy maximal matching, cheapest first.
    greedy_matching(cand, active_order, m, partner, best_slot, stack);

    // 4. Parents for pairs, carried nodes as they are (group g, in the order of their first
    // position), then the groups in Morton order as the next round's positions.
    group.assign(m, kNone);
    group_members.clear();
    next_active.clear();
    next_box.clear();
    next_height.clear();
    next_order.clear();
    for (std::uint32_t p = 0; p < m; ++p) {
      if (group[p] != kNone) continue;
      const std::uint32_t q = partner[p];
      const std::uint32_t g = std::uint32_t(next_active.size());
      group[p] = g;
      group_members.push_back(p);
      group_members.push_back(q);
      if (q == kNone) {
        next_active.push_back(active[p]);
        next_box.push_back(active_box[p]);
        next_height.push_back(active_height[p]);
        next_order.push_back(active_order[p]);
        continue;
      }
      group[q] = g;
      const std::uint32_t a = active[p], b = active[q];
      if (fit_during_rounds) volumes.push_back(Volume::enclosing(volumes[a], volumes[b]));
      first.push_back(a);
      second.push_back(b);
      next_active.push_back(next_node++);
      next_box.push_back(Aabb::enclosing(active_box[p], active_box[q]));
      next_height.push_back(1 + std::max(active_height[p], active_height[q]));
      next_order.push_back(std::min(active_order[p], active_order[q]));
    }
    const std::uint32_t next_m = std::uint32_t(next_active.size());
    BOXTREE_ASSERT(next_m < m, "a round always pairs at least one node");
    if (next_m == 1) {
      active.swap(next_active);
      active_height.swap(next_height);
      break;
    }
    morton_order(next_box.data(), next_m);
    rank.resize(next_m);
    for (std::uint32_t i = 0; i < next_m; ++i) rank[morton[i].second] = i;
    for (std::uint32_t p = 0; p < m; ++p) group[p] = rank[group[p]];  // old position -> new position
    stamp.assign(next_m, kNone);

    // Contracted adjacency: a group's neighbours are its members' neighbours' groups.
    next_adjacency.offsets.resize(next_m + 1);
    next_adjacency.items.resize(adjacency.items.size());
    write = 0;
    active.resize(next_m);
    active_box.resize(next_m);
    active_height.resize(next_m);
    active_order.resize(next_m);
    for (std::uint32_t i = 0; i < next_m; ++i) {
      const std::uint32_t g = morton[i].second;
      active[i] = next_active[g];
      active_box[i] = next_box[g];
      active_height[i] = next_height[g];
      active_order[i] = next_order[g];
      next_adjacency.offsets[i] = write;
      std::uint32_t* begin = next_adjacency.items.data() + write;
      std::uint32_t* end = begin;
      stamp[i] = i;  // drops i itself
      for (int k = 0; k < 2; ++k) {
        const std::uint32_t p = group_members[2 * g + k];
        if (p == kNone) break;
        for (std::uint32_t j = adjacency.offsets[p]; j < adjacency.offsets[p + 1]; ++j) {
          const std::uint32_t r = group[adjacency.items[j]];
          if (stamp[r] == i) continue;
          stamp[r] = i;
          *end++ = r;
        }
      }
      write = std::uint32_t(sort_unique_list(begin, end, i) - next_adjacency.items.data());
    }
    next_adjacency.offsets[next_m] = write;
    next_adjacency.items.resize(write);
    std::swap(adjacency, next_adjacency);
  }

  // Final layout: depth-first from the root, the two children of a node in adjacent slots;
  // children have larger slots than their parent, so a backward pass fits parents after their
  // children.
  const std::size_t node_count = first.size();
  BOXTREE_ASSERT(node_count == 2 * n - 1, "a binary tree over n leaves has 2n-1 nodes");
  const std::uint32_t leaf_flag = Tree<Volume>::kLeafFlag;
  std::vector<std::uint32_t> out_links, out_nodes;
  detail::depth_first_order(first, second, active[0], node_count, n, leaf_flag, out_links, out_nodes);
  std::vector<Volume> out_volumes(node_count);
  if (fit_during_rounds) {
    for (std::size_t slot = 0; slot < node_count; ++slot) out_volumes[slot] = volumes[out_nodes[slot]];
  } else {
    for (std::size_t slot = node_count; slot-- > 0;) {
      const std::uint32_t link = out_links[slot];
      if (link & leaf_flag) {
        const FacetId f = link & ~leaf_flag;
        out_volumes[slot] = Volume::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
      } else {
        out_volumes[slot] = Volume::enclosing(out_volumes[link], out_volumes[link + 1]);
      }
    }
  }
  const int height = active_height[0];
  if constexpr (!kIsAabb && !is_hybrid_v<Volume>) {
    if (settings.parent_fit == ParentFit::fit_facets) fit_parents_to_facets(out_volumes, out_links, settings.cost);
  }

  local.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = local;
  return Tree<Volume>(std::move(mesh_ptr), std::move(out_volumes), std::move(out_links), height);
}

#define BOXTREE_INSTANTIATE_BUILD(V) \
  template Tree<V> build_tree<V>(std::shared_ptr<const TriangleMesh>, const BuildSettings&, BuildStats*);
BOXTREE_FOR_EACH_VOLUME(BOXTREE_INSTANTIATE_BUILD)

}  // namespace boxtree
