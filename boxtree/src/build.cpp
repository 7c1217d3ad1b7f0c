// Bottom-up boxtree construction (paper, Sections 2-3).
//
// Round structure:
//   1. candidates = contracted mesh adjacency (facets sharing a vertex, welded by position)
//                 + "near" pairs: neighbours along a Morton curve of the node centres;
//   2. each candidate costs the surface area (or volume) of the merged volume;
//   3. greedy maximal matching, cheapest first (ties broken by node order: deterministic);
//   4. matched pairs become parents, unmatched nodes are carried; adjacency is contracted.
// Why the Morton pairs: the Morton order is a path through all active nodes, and a maximal
// matching on a graph containing a path over all m nodes leaves an independent set of that path
// unmatched, i.e. at most ceil(m/2) nodes, so each round pairs >= m/4 nodes and the height is at
// most log_{4/3} n. On meshes, adjacency pairs almost everything and the height is ~log2 n.
#include "boxtree/build.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <numeric>
#include <optional>
#include <type_traits>

#include "boxtree/detail/volume_kinds.h"
#include "internal.h"
#include "boxtree/planar/terrain.h"

namespace boxtree {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

void sort_unique(std::vector<std::uint64_t>& keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

// Facet pairs that share a vertex position (welding bit-identical coordinates, so triangle soups
// such as PQP's env.obj still get their adjacency). A vertex shared by more than `max_fan`
// facets links them in a chain instead of all pairs, bounding the work at high-valence vertices.
std::vector<std::uint64_t> facet_adjacency(const TriangleMesh& mesh, int max_fan) {
  const std::size_t vertex_count = mesh.vertices.size();
  std::vector<VertexId> order(vertex_count);
  std::iota(order.begin(), order.end(), VertexId{0});
  auto less_xyz = [&](VertexId a, VertexId b) {
    const Vec3& p = mesh.vertices[a];
    const Vec3& q = mesh.vertices[b];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  };
  std::sort(order.begin(), order.end(), less_xyz);
  std::vector<VertexId> welded(vertex_count);
  VertexId next = 0;
  for (std::size_t i = 0; i < vertex_count; ++i) {
    if (i > 0 && mesh.vertices[order[i]] != mesh.vertices[order[i - 1]]) ++next;
    welded[order[i]] = next;
  }
  const std::size_t welded_count = vertex_count == 0 ? 0 : std::size_t(next) + 1;

  // Incident facets per welded vertex (CSR), facets in increasing id order.
  std::vector<std::uint32_t> offsets(welded_count + 1, 0);
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      // A facet repeating a vertex lists it once.
      const VertexId w = welded[t[k]];
      if ((k > 0 && welded[t[0]] == w) || (k > 1 && welded[t[1]] == w)) continue;
      ++offsets[w + 1];
    }
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<FacetId> incident(offsets.back());
  std::vector<std::uint32_t> cursor(offsets.begin(), offsets.end() - 1);
  for (FacetId f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const VertexId w = welded[t[k]];
      if ((k > 0 && welded[t[0]] == w) || (k > 1 && welded[t[1]] == w)) continue;
      incident[cursor[w]++] = f;
    }
  }

  std::vector<std::uint64_t> edges;
  edges.reserve(mesh.triangles.size() * 8);
  for (std::size_t w = 0; w < welded_count; ++w) {
    const std::uint32_t begin = offsets[w];
    const std::uint32_t end = offsets[w + 1];
    const std::uint32_t fan = end - begin;
    if (fan <= std::uint32_t(max_fan)) {
      for (std::uint32_t i = begin; i < end; ++i)
        for (std::uint32_t j = i + 1; j < end; ++j) edges.push_back(edge_key(incident[i], incident[j]));
    } else {
      for (std::uint32_t i = begin; i + 1 < end; ++i) edges.push_back(edge_key(incident[i], incident[i + 1]));
    }
  }
  sort_unique(edges);
  return edges;
}

// 63-bit Morton code of a point quantized to 21 bits per axis inside [lo, hi].
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

std::uint64_t morton_code(const Vec3& p, const Vec3& lo, const Vec3& scale) {
  std::uint64_t code = 0;
  for (int i = 0; i < 3; ++i) {
    const Real q = std::clamp((p[i] - lo[i]) * scale[i], Real(0), Real(0x1fffff));
    code |= spread_bits(std::uint64_t(q)) << i;
  }
  return code;
}

struct Candidate {
  Real cost;
  Real tie;  // secondary cost: surface area when the primary is volume (flat volumes tie at 0)
  std::uint32_t a, b;
  bool operator<(const Candidate& o) const {
    if (cost != o.cost) return cost < o.cost;
    if (tie != o.tie) return tie < o.tie;
    if (a != o.a) return a < o.a;
    return b < o.b;
  }
};

// The greedy matching (take candidates cheapest first, skip those touching a matched node)
// without sorting all candidates: with a strict total order on candidates, greedy equals
// repeatedly matching "locally dominant" pairs, each the cheapest remaining candidate of both
// its nodes (Preis, STACS 1999). Each node's list is sorted (short lists) and scanned with a
// cursor; a node whose best partner prefers someone else defers to that partner first, so
// chains follow strictly decreasing costs and end in a mutual pair. O(E log degree) instead of
// O(E log E), and the same result as the global sort.
struct Matcher {
  struct Slot {
    std::uint32_t neighbor;
    std::uint32_t candidate;  // index into the candidate list
  };
  std::vector<std::uint32_t> offsets;
  std::vector<Slot> slots;
  std::vector<std::uint32_t> cursor;
  std::vector<std::uint32_t> stack;
};

void greedy_matching(const std::vector<Candidate>& candidates, std::size_t m, std::vector<std::uint32_t>& partner,
                     Matcher& w) {
  w.offsets.assign(m + 1, 0);
  for (const Candidate& c : candidates) {
    ++w.offsets[c.a + 1];
    ++w.offsets[c.b + 1];
  }
  std::partial_sum(w.offsets.begin(), w.offsets.end(), w.offsets.begin());
  w.slots.resize(w.offsets.back());
  w.cursor.assign(w.offsets.begin(), w.offsets.end() - 1);
  for (std::uint32_t i = 0; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    w.slots[w.cursor[c.a]++] = {c.b, i};
    w.slots[w.cursor[c.b]++] = {c.a, i};
  }
  for (std::size_t u = 0; u < m; ++u) {
    std::sort(w.slots.begin() + w.offsets[u], w.slots.begin() + w.offsets[u + 1],
              [&](const Matcher::Slot& x, const Matcher::Slot& y) { return candidates[x.candidate] < candidates[y.candidate]; });
    w.cursor[u] = w.offsets[u];
  }
  partner.assign(m, kNone);
  // The best remaining partner of u, or kNone.
  auto best = [&](std::uint32_t u) {
    std::uint32_t& c = w.cursor[u];
    while (c < w.offsets[u + 1] && partner[w.slots[c].neighbor] != kNone) ++c;
    return c < w.offsets[u + 1] ? w.slots[c].neighbor : kNone;
  };
  w.stack.clear();
  for (std::size_t u = m; u-- > 0;) w.stack.push_back(std::uint32_t(u));
  while (!w.stack.empty()) {
    const std::uint32_t u = w.stack.back();
    if (partner[u] != kNone) {
      w.stack.pop_back();
      continue;
    }
    const std::uint32_t v = best(u);
    if (v == kNone) {
      w.stack.pop_back();
      continue;
    }
    if (best(v) == u) {
      w.stack.pop_back();
      partner[u] = v;
      partner[v] = u;
    } else {
      w.stack.push_back(v);  // v prefers a cheaper pair: settle v first, then come back to u
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

  // Build-order storage: leaves are 0..n-1 (node i is facet i); parents are appended.
  std::vector<Volume> volumes;
  std::vector<std::uint32_t> first(n, kNone), second(n, kNone);
  std::vector<int> heights(n, 0);
  volumes.reserve(2 * n - 1);
  first.reserve(2 * n - 1);
  second.reserve(2 * n - 1);
  heights.reserve(2 * n - 1);
  for (FacetId f = 0; f < n; ++f) volumes.push_back(Volume::from_triangle(mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2)));

  auto cost_of = [&](const Volume& v) -> std::pair<Real, Real> {
    const Real area = surface_area(v);
    if (settings.cost == MergeCost::volume) return {volume(v), area};
    return {area, 0};
  };

  // Active nodes, by position; adjacency edges are between positions.
  std::vector<std::uint32_t> active(n);
  std::iota(active.begin(), active.end(), 0u);
  std::vector<std::uint64_t> adjacency = facet_adjacency(mesh, settings.max_neighbors);

  BuildStats local;
  std::vector<Candidate> candidates;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> morton;
  std::vector<std::uint32_t> partner;
  Matcher matcher;
  std::vector<std::uint32_t> new_position;
  while (active.size() > 1) {
    const std::size_t m = active.size();
    ++local.rounds;

    // 1. Candidates: contracted adjacency + Morton neighbours.
    Aabb centres;
    for (std::uint32_t node : active) centres.expand(center(volumes[node]));
    const Vec3 extent = centres.extent();
    Vec3 scale;
    for (int i = 0; i < 3; ++i) scale[i] = extent[i] > 0 ? Real(0x1fffff) / extent[i] : 0;
    morton.resize(m);
    for (std::uint32_t p = 0; p < m; ++p) morton[p] = {morton_code(center(volumes[active[p]]), centres.min, scale), p};
    std::sort(morton.begin(), morton.end());

    candidates.clear();
    candidates.reserve(adjacency.size() + m * settings.near_window);
    auto add_candidate = [&](std::uint32_t pa, std::uint32_t pb) {
      if (pa > pb) std::swap(pa, pb);
      const auto [cost, tie] = cost_of(Volume::enclosing(volumes[active[pa]], volumes[active[pb]]));
      candidates.push_back({cost, tie, pa, pb});
    };
    for (std::uint64_t key : adjacency) add_candidate(std::uint32_t(key >> 32), std::uint32_t(key));
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = i + 1; j <= i + std::size_t(settings.near_window) && j < m; ++j)
        add_candidate(morton[i].second, morton[j].second);
    local.candidate_pairs += candidates.size();

    // 2-3. Greedy maximal matching, cheapest merged volume first.
    greedy_matching(candidates, m, partner, matcher);

    // 4. Parents for pairs, carried nodes as they are; positions keep the old order.
    new_position.assign(m, kNone);
    std::vector<std::uint32_t> next_active;
    next_active.reserve(m);
    for (std::uint32_t p = 0; p < m; ++p) {
      if (new_position[p] != kNone) continue;
      const std::uint32_t q = partner[p];
      new_position[p] = std::uint32_t(next_active.size());
      if (q == kNone) {
        next_active.push_back(active[p]);
        continue;
      }
      new_position[q] = new_position[p];
      const std::uint32_t a = active[p], b = active[q];
      const std::uint32_t parent = std::uint32_t(volumes.size());
      volumes.push_back(Volume::enclosing(volumes[a], volumes[b]));
      first.push_back(a);
      second.push_back(b);
      heights.push_back(1 + std::max(heights[a], heights[b]));
      next_active.push_back(parent);
    }
    BOXTREE_ASSERT(next_active.size() < m, "a round always pairs at least one node");

    for (std::uint64_t& key : adjacency) {
      const std::uint32_t a = new_position[std::uint32_t(key >> 32)];
      const std::uint32_t b = new_position[std::uint32_t(key)];
      key = a == b ? ~std::uint64_t(0) : edge_key(a, b);
    }
    sort_unique(adjacency);
    if (!adjacency.empty() && adjacency.back() == ~std::uint64_t(0)) adjacency.pop_back();
    active.swap(next_active);
  }

  // Final layout: depth-first from the root, the two children of a node in adjacent slots.
  const std::size_t node_count = volumes.size();
  BOXTREE_ASSERT(node_count == 2 * n - 1, "a binary tree over n leaves has 2n-1 nodes");
  std::vector<Volume> out_volumes;
  std::vector<std::uint32_t> out_links;
  detail::depth_first_layout(volumes, first, second, active[0], n, Tree<Volume>::kLeafFlag, out_volumes, out_links);
  const int height = heights[active[0]];
  if constexpr (!std::is_same_v<Volume, Aabb> && !is_hybrid_v<Volume>) {
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
