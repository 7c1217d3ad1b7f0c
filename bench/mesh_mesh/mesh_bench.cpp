// SPDX-License-Identifier: MIT
// Issue 7, section 2: mesh vs mesh. boxtree's tree-vs-tree collide (every --methods method)
// against FCL 0.7 (BVHModel with AABB, OBB, RSS, OBBRSS, kIOS), Bullet GImpact and ODE's
// trimesh-trimesh collider, in the same process on the same meshes and poses:
//   - the paper's concentric sphere pairs (spheres-556/1996/9996, gaps 0 to 10% of the radius)
//     and interleaved combs, at the identity pose;
//   - bunny vs bunny (stanford_bunny_res3.obj, 3,851 facets) at random overlapping poses;
//   - PQP's env vs rob at random poses (random rotation, translation within env's bounds).
// Trees are built before the queries (build time reported apart); a query finds every
// intersecting facet pair. Pair lists must agree: every boxtree method, every FCL volume and
// GImpact's exact pairs against the first method, on every pose; brute force (all pairs,
// triangles_intersect) on the first pose of every case with at most 3e7 facet pairs, and on
// further poses while the summed products stay within a budget (3e7 full, 1e7 --quick).
//
// What is counted and timed
//   volume_tests  boxtree: QueryStats::volume_tests (every volume pair tested, leaf pairs
//                 included); FCL: num_bv_tests (FCL skips the volume test of leaf-leaf pairs,
//                 which favours it slightly). GImpact and ODE expose no counter.
//   seconds       the queries alone: the sum over the poses of each pose's fastest of --repeats
//                 runs (the least disturbed on a shared machine). boxtree: AnyTree::collide with a visitor that
//                 stores the pairs (the packed forms for aabb and plain pie slices; `-exact`: Tree<V>).
//                 FCL: fcl::detail::initialize + collide (for AABB, initialize re-builds b's tree
//                 in a's frame at every non-identity pose: FCL's own way, see fcl_peer.h).
//                 GImpact: btGImpactQuantizedBvh::find_collision + triangles_intersect on the
//                 candidates. ODE: dCollide with room for 0xffff contacts.
//   build_seconds mean of the two trees' build times.
//   pairs         intersecting facet pairs summed over the poses (touching counts). ODE gives
//                 contact points, not facet pairs: its rows have metric "contacts".
//
// JSON rows (--json; section "mesh_vs_mesh"; ratio = boxtree / peer_value, lower is better for
// boxtree on volume_tests, seconds and build_seconds):
//   - per case and boxtree method: volume_tests vs the best FCL volume on that case (peer named
//     e.g. "fcl-RSS"), seconds and build_seconds vs the fastest FCL volume, bullet-gimpact and
//     ode-trimesh, and exact_tests (triangle tests run) vs GImpact's candidate pairs;
//   - per case and peer (each FCL volume, GImpact, ODE): its own value against boxtree's best
//     method for that metric (boxtree_method names that method);
//   - pairs: boxtree's pairs (boxtree_method "all": they agree across methods, else see below)
//     vs each FCL volume, bullet-gimpact (exact pairs), "bullet-gimpact candidates" (metric
//     "candidate_pairs"), brute force (peer "brute-force (N poses)", boxtree counted on the same
//     poses) and ODE (metric "contacts");
//   - pairs_disagree: number of (source, pose) pair lists differing from the reference; 0
//     expected (peer "all sources", peer_value 0, ratio null).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>

#include "bench_report.h"
#include "boxtree/any_tree.h"
#include "boxtree/build.h"
#include "boxtree/collide.h"
#include "boxtree/error.h"
#include "boxtree/generate.h"
#include "boxtree/geometry.h"
#include "boxtree/io.h"
#include "boxtree/method.h"
#include "mesh_peers.h"
#include "peers/fcl_peer.h"
#include "scenes/paper_models.h"

#ifndef BOXTREE_REPO_DIR
#define BOXTREE_REPO_DIR "."
#endif

namespace {

using namespace boxtree;
using bench::Clock;
using bench::seconds_since;
using PairList = std::vector<std::pair<FacetId, FacetId>>;
using PosePairs = std::vector<PairList>;

constexpr const char* kSection = "mesh_vs_mesh";

struct Case {
  std::string name;
  std::shared_ptr<const TriangleMesh> a, b;
  std::vector<RigidTransform> poses;  // a_from_b, one query each
  int repeats = 1;
  bool show_build = false;  // in the markdown build table
  double gimpact_margin = 0;
};

// ---- random poses (fixed seed, the same on every machine: generate.h's splitmix64, whose
// mapping to doubles is the one this file's former copy had, so the poses are unchanged) ----
struct Random : boxtree::Random {
  using boxtree::Random::Random;
  // Uniform rotation (Shoemake, Graphics Gems III: uniform random rotations).
  Mat3 rotation() {
    const double u1 = uniform(), u2 = 2 * M_PI * uniform(), u3 = 2 * M_PI * uniform();
    const Eigen::Quaterniond q(std::sqrt(u1) * std::cos(u3), std::sqrt(1 - u1) * std::sin(u2),
                               std::sqrt(1 - u1) * std::cos(u2), std::sqrt(u1) * std::sin(u3));
    return q.normalized().toRotationMatrix();
  }
};

void bounds(const TriangleMesh& m, Vec3& lo, Vec3& hi) {
  lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Triangle& t : m.triangles)
    for (VertexId v : t) lo = lo.cwiseMin(m.vertices[v]), hi = hi.cwiseMax(m.vertices[v]);
}

// b (a copy of a) rotated about a's box centre, then moved by up to `fraction` of the box's
// size along each axis.
std::vector<RigidTransform> overlapping_poses(const TriangleMesh& a, int count, double fraction, std::uint64_t seed) {
  Vec3 lo, hi;
  bounds(a, lo, hi);
  const Vec3 c = (lo + hi) / 2, size = hi - lo;
  Random rng(seed);
  std::vector<RigidTransform> poses;
  for (int i = 0; i < count; ++i) {
    RigidTransform t;
    t.rotation = rng.rotation();
    Vec3 offset;
    for (int k = 0; k < 3; ++k) offset[k] = rng.uniform(-fraction, fraction) * size[k];
    t.translation = c - t.rotation * c + offset;
    poses.push_back(t);
  }
  return poses;
}

// PQP's benchmark style: random rotation, translation uniform within env's bounding box.
std::vector<RigidTransform> poses_within(const TriangleMesh& env, int count, std::uint64_t seed) {
  Vec3 lo, hi;
  bounds(env, lo, hi);
  Random rng(seed);
  std::vector<RigidTransform> poses;
  for (int i = 0; i < count; ++i) {
    RigidTransform t;
    t.rotation = rng.rotation();
    for (int k = 0; k < 3; ++k) t.translation[k] = rng.uniform(lo[k], hi[k]);
    poses.push_back(t);
  }
  return poses;
}

// ---- brute force: every facet pair, triangles_intersect (a closed-box reject first: a
// triangle lies in its box, so disjoint boxes cannot hold intersecting triangles) ----
PairList brute_force(const TriangleMesh& a, const TriangleMesh& b, const RigidTransform& a_from_b) {
  std::vector<Vec3> bv(b.vertices.size());
  for (std::size_t i = 0; i < bv.size(); ++i) bv[i] = a_from_b.apply(b.vertices[i]);
  auto box = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    return std::pair<Vec3, Vec3>(p.cwiseMin(q).cwiseMin(r), p.cwiseMax(q).cwiseMax(r));
  };
  std::vector<std::pair<Vec3, Vec3>> boxes_b;
  for (const Triangle& t : b.triangles) boxes_b.push_back(box(bv[t[0]], bv[t[1]], bv[t[2]]));
  PairList pairs;
  for (FacetId fa = 0; fa < a.facet_count(); ++fa) {
    const Vec3 &p = a.corner(fa, 0), &q = a.corner(fa, 1), &r = a.corner(fa, 2);
    const auto [lo, hi] = box(p, q, r);
    for (FacetId fb = 0; fb < b.facet_count(); ++fb) {
      const auto& [blo, bhi] = boxes_b[fb];
      if ((lo.array() > bhi.array()).any() || (blo.array() > hi.array()).any()) continue;
      const Triangle& t = b.triangles[fb];
      if (triangles_intersect(p, q, r, bv[t[0]], bv[t[1]], bv[t[2]])) pairs.emplace_back(fa, fb);
    }
  }
  return pairs;
}

// ---- boxtree ----
struct BoxtreeResult {
  std::string method;
  std::uint64_t volume_tests = 0, leaf_tests = 0, pairs = 0;
  double seconds = 0, build_seconds = 0;
};

// The fastest of the repeated runs: on a shared machine the least disturbed one.
double fastest(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

// A boxtree method as the bench names it: `aabb` and the plain pie-slice methods run the packed
// forms AnyTree holds (what the engine adapters collide), and the same name + `-exact` (e.g.
// `aabb-exact`, `pie-min-general-tight-exact`) runs the exact Tree<V> beside them; the other
// methods have only their exact trees.
struct BenchMethod {
  Method method;
  bool exact = false;
  std::string name;
};

BenchMethod parse_bench_method(const std::string& name) {
  const bench::ExactSuffix split = bench::split_exact_suffix(name);
  const Method method = parse_method(split.method);
  // As ray_bench and build_bench: elsewhere the exact tree is what the plain name runs already.
  if (split.exact && !bench::has_packed_form(method))
    throw Error("--methods: '" + name + "': -exact applies to aabb and the plain pie-slice methods");
  return {method, split.exact, name};
}

// Trees by (mesh, method), so that a mesh shared by several cases (a sphere against each gap's
// sphere, the bunny against itself) is built once; each entry keeps its build time.
class TreeCache {
 public:
  std::pair<std::shared_ptr<const AnyTree>, double> get(const std::shared_ptr<const TriangleMesh>& mesh,
                                                        const BenchMethod& m) {
    Entry& e = entries_[{mesh.get(), m.name}];
    if (!e.tree) {
      const auto start = Clock::now();
      if (m.exact) {
        e.tree = with_method(m.method, [&](auto tag) {
          using V = typename decltype(tag)::type;
          return std::make_shared<const AnyTree>(build_tree<V>(mesh, settings_for(m.method)), m.method);
        });
      } else {
        e.tree = std::make_shared<const AnyTree>(AnyTree::build(mesh, m.method));
      }
      e.seconds = seconds_since(start);
    }
    return {e.tree, e.seconds};
  }
  // Drops the trees of every mesh not in `keep`.
  void keep_only(const std::vector<const TriangleMesh*>& keep) {
    for (auto it = entries_.begin(); it != entries_.end();)
      it = std::find(keep.begin(), keep.end(), it->first.first) == keep.end() ? entries_.erase(it) : std::next(it);
  }

 private:
  struct Entry {
    std::shared_ptr<const AnyTree> tree;
    double seconds = 0;
  };
  std::map<std::pair<const TriangleMesh*, std::string>, Entry> entries_;
};

BoxtreeResult run_boxtree(const BenchMethod& method, const Case& c, TreeCache& cache, PosePairs* pose_pairs) {
  BoxtreeResult r;
  r.method = method.name;
  const auto [a, seconds_a] = cache.get(c.a, method);
  const auto [b, seconds_b] = cache.get(c.b, method);
  r.build_seconds = (seconds_a + seconds_b) / 2;
  pose_pairs->assign(c.poses.size(), {});
  std::vector<FacetPair> found;
  for (std::size_t p = 0; p < c.poses.size(); ++p) {
    std::vector<double> times;
    for (int rep = 0; rep < std::max(1, c.repeats); ++rep) {
      found.clear();
      QueryStats stats;
      const auto start = Clock::now();
      a->collide(
          *b, c.poses[p], [&](const FacetPair& pair) { return found.push_back(pair), true; }, &stats);
      times.push_back(seconds_since(start));
      if (rep > 0) continue;
      r.volume_tests += stats.volume_tests;
      r.leaf_tests += stats.leaf_tests;
      r.pairs += found.size();
      PairList& list = (*pose_pairs)[p];
      for (const FacetPair& f : found) list.emplace_back(f.a, f.b);
      std::sort(list.begin(), list.end());
    }
    r.seconds += fastest(times);
  }
  return r;
}

// ---- output helpers ----
std::string fmt(const char* f, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, x);
  return buf;
}
std::string ms(double seconds) { return seconds < 0 ? "-" : fmt(seconds * 1e3 < 10 ? "%.3f" : "%.1f", seconds * 1e3); }
std::string count(std::uint64_t n) {
  std::string s = std::to_string(n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

struct CaseResult {
  std::string name;
  std::size_t facets_a = 0, facets_b = 0, poses = 0, poses_hit = 0;
  std::vector<BoxtreeResult> boxtree;
  std::map<std::string, peers::FclResult> fcl;  // by volume name
  bool has_gimpact = false, has_ode = false;
  peers::GImpactResult gimpact;
  peers::OdeResult ode;
  std::size_t brute_poses = 0;
  std::uint64_t brute_pairs = 0, boxtree_pairs_on_brute_poses = 0;
  int disagreements = 0;
  bool show_build = false;
};

// Compares one source's pair lists with the reference, pose by pose; prints every mismatch.
int check_pairs(const std::string& case_name, const std::string& source, const PosePairs& reference,
                const PosePairs& got, std::size_t poses) {
  int bad = 0;
  for (std::size_t p = 0; p < poses && p < got.size(); ++p) {
    if (got[p] == reference[p]) continue;
    ++bad;
    std::fprintf(stderr, "!!! PAIRS DISAGREE: %s, pose %zu: %s has %zu pairs, reference (boxtree %s) has %zu\n",
                 case_name.c_str(), p, source.c_str(), got[p].size(), "first method", reference[p].size());
  }
  return bad;
}

CaseResult run_case(const Case& c, const std::vector<BenchMethod>& methods, TreeCache& cache, bool with_fcl,
                    bool with_gimpact, bool with_ode, double brute_budget) {
  CaseResult r;
  r.name = c.name;
  r.facets_a = c.a->facet_count();
  r.facets_b = c.b->facet_count();
  r.poses = c.poses.size();
  r.show_build = c.show_build;
  PosePairs reference, got;
  for (std::size_t m = 0; m < methods.size(); ++m) {
    r.boxtree.push_back(run_boxtree(methods[m], c, cache, m == 0 ? &reference : &got));
    if (m > 0) r.disagreements += check_pairs(c.name, "boxtree " + r.boxtree.back().method, reference, got, r.poses);
  }
  for (const PairList& l : reference) r.poses_hit += l.empty() ? 0 : 1;
  if (with_fcl)
    for (const std::string& bv : peers::fcl_bv_names()) {
      r.fcl[bv] = peers::fcl_collide_poses(*c.a, *c.b, c.poses, bv, c.repeats, &got);
      r.disagreements += check_pairs(c.name, "fcl-" + bv, reference, got, r.poses);
    }
  if (with_gimpact) {
    peers::GImpactPair pair(*c.a, *c.b, c.gimpact_margin);
    r.gimpact = pair.run(c.poses, c.repeats, &got);
    r.has_gimpact = true;
    r.disagreements += check_pairs(c.name, "bullet-gimpact", reference, got, r.poses);
  }
  if (with_ode) {
    peers::OdeTriMeshPair pair(*c.a, *c.b);
    r.ode = pair.run(c.poses, c.repeats);
    r.has_ode = true;
    if (r.ode.poses_at_cap > 0)
      std::fprintf(stderr, "note: %s: ODE filled its 0xffff contact array on %llu poses\n", c.name.c_str(),
                   (unsigned long long)r.ode.poses_at_cap);
  }
  // Brute force on the first poses, within the budget of facet pairs, and always on the first
  // pose when it has at most 3e7 facet pairs.
  const double per_pose = double(r.facets_a) * double(r.facets_b);
  PosePairs brute;
  for (std::size_t p = 0; p < r.poses && (p == 0 ? per_pose <= 3e7 : double(p + 1) * per_pose <= brute_budget); ++p) {
    brute.push_back(brute_force(*c.a, *c.b, c.poses[p]));
    r.brute_pairs += brute.back().size();
    r.boxtree_pairs_on_brute_poses += reference[p].size();
  }
  r.brute_poses = brute.size();
  r.disagreements += check_pairs(c.name, "brute force", reference, brute, brute.size());
  return r;
}

std::vector<BenchMethod> parse_methods(const std::string& text) {
  std::vector<BenchMethod> methods;
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    if (comma > start) methods.push_back(parse_bench_method(text.substr(start, comma - start)));
    start = comma + 1;
  }
  if (methods.empty()) throw Error("--methods: no method given");
  return methods;
}

// ---- rows ----
void add_rows(const CaseResult& r, std::vector<bench::Row>& rows) {
  auto add = [&](const std::string& metric, const std::string& method, double boxtree, const std::string& peer,
                 double peer_value) {
    rows.push_back(bench::compare(kSection, r.name, metric, method, boxtree, peer, peer_value));
  };
  // Peers' values per metric (name -> value), and boxtree's best method per metric.
  struct PeerValue {
    std::string name;
    double value;
  };
  std::vector<PeerValue> tests, seconds, build;
  for (const auto& [bv, f] : r.fcl) {
    tests.push_back({"fcl-" + bv, double(f.bv_tests)});
    seconds.push_back({"fcl-" + bv, f.seconds});
    build.push_back({"fcl-" + bv, f.build_seconds});
  }
  auto best_of = [](const std::vector<PeerValue>& v) {
    return *std::min_element(v.begin(), v.end(),
                             [](const PeerValue& x, const PeerValue& y) { return x.value < y.value; });
  };
  std::vector<PeerValue> best_seconds_peers, best_build_peers;
  if (!r.fcl.empty()) best_seconds_peers.push_back(best_of(seconds)), best_build_peers.push_back(best_of(build));
  if (r.has_gimpact) {
    const double g = r.gimpact.midphase_seconds + r.gimpact.exact_seconds;
    seconds.push_back({"bullet-gimpact", g}), best_seconds_peers.push_back(seconds.back());
    build.push_back({"bullet-gimpact", r.gimpact.build_seconds}), best_build_peers.push_back(build.back());
  }
  if (r.has_ode) {
    seconds.push_back({"ode-trimesh", r.ode.seconds}), best_seconds_peers.push_back(seconds.back());
    build.push_back({"ode-trimesh", r.ode.build_seconds}), best_build_peers.push_back(build.back());
  }
  for (const BoxtreeResult& b : r.boxtree) {
    if (!tests.empty()) {
      const PeerValue best = best_of(tests);
      add("volume_tests", b.method, double(b.volume_tests), best.name, best.value);
    }
    for (const PeerValue& p : best_seconds_peers) add("seconds", b.method, b.seconds, p.name, p.value);
    for (const PeerValue& p : best_build_peers) add("build_seconds", b.method, b.build_seconds, p.name, p.value);
    if (r.has_gimpact)
      add("exact_tests", b.method, double(b.leaf_tests), "bullet-gimpact candidates", double(r.gimpact.candidates));
  }
  auto best_boxtree = [&](auto value) {
    return *std::min_element(r.boxtree.begin(), r.boxtree.end(),
                             [&](const BoxtreeResult& x, const BoxtreeResult& y) { return value(x) < value(y); });
  };
  const BoxtreeResult& bt_tests = best_boxtree([](const BoxtreeResult& b) { return double(b.volume_tests); });
  const BoxtreeResult& bt_seconds = best_boxtree([](const BoxtreeResult& b) { return b.seconds; });
  const BoxtreeResult& bt_build = best_boxtree([](const BoxtreeResult& b) { return b.build_seconds; });
  for (const PeerValue& p : tests) add("volume_tests", bt_tests.method, double(bt_tests.volume_tests), p.name, p.value);
  for (const PeerValue& p : seconds) add("seconds", bt_seconds.method, bt_seconds.seconds, p.name, p.value);
  for (const PeerValue& p : build) add("build_seconds", bt_build.method, bt_build.build_seconds, p.name, p.value);
  // Pairs.
  const double pairs = double(r.boxtree.front().pairs);
  for (const auto& [bv, f] : r.fcl) add("pairs", "all", pairs, "fcl-" + bv, double(f.pairs));
  if (r.has_gimpact) {
    add("pairs", "all", pairs, "bullet-gimpact", double(r.gimpact.pairs));
    add("candidate_pairs", "all", pairs, "bullet-gimpact candidates", double(r.gimpact.candidates));
  }
  if (r.brute_poses > 0)
    add("pairs", "all", double(r.boxtree_pairs_on_brute_poses),
        "brute-force (" + std::to_string(r.brute_poses) + (r.brute_poses == 1 ? " pose)" : " poses)"),
        double(r.brute_pairs));
  if (r.has_ode) add("contacts", "all", pairs, "ode-trimesh", double(r.ode.contacts));
  bench::Row d = bench::compare(kSection, r.name, "pairs_disagree", "all", double(r.disagreements), "all sources", 0);
  d.ratio.reset();
  rows.push_back(d);
}

// ---- tables (markdown; also printed on stdout) ----
std::string tables(const std::vector<CaseResult>& results) {
  if (results.empty()) return "";
  std::ostringstream s;
  const std::vector<BoxtreeResult>& m0 = results.front().boxtree;
  std::vector<std::string> bvs;
  for (const auto& [bv, f] : results.front().fcl) bvs.push_back(bv);
  const bool gimpact = results.front().has_gimpact, ode = results.front().has_ode;

  s << "\n**Volume tests** (summed over the poses; FCL: num_bv_tests, leaf-leaf pairs not counted)\n\n| case |";
  for (const BoxtreeResult& b : m0) s << ' ' << b.method << " |";
  for (const std::string& bv : bvs) s << " fcl-" << bv << " |";
  s << " best boxtree / best FCL |\n|---|";
  for (std::size_t i = 0; i < m0.size() + bvs.size() + 1; ++i) s << "---:|";
  s << '\n';
  for (const CaseResult& r : results) {
    s << "| " << r.name << " |";
    std::uint64_t best = ~0ull, best_fcl = ~0ull;
    for (const BoxtreeResult& b : r.boxtree)
      s << ' ' << count(b.volume_tests) << " |", best = std::min(best, b.volume_tests);
    for (const auto& [bv, f] : r.fcl) s << ' ' << count(f.bv_tests) << " |", best_fcl = std::min(best_fcl, f.bv_tests);
    s << ' ' << (r.fcl.empty() ? "-" : fmt("%.2f", double(best) / double(best_fcl))) << " |\n";
  }

  s << "\n**Query time, ms** (summed over the poses; trees built before)\n\n| case |";
  for (const BoxtreeResult& b : m0) s << ' ' << b.method << " |";
  for (const std::string& bv : bvs) s << " fcl-" << bv << " |";
  if (gimpact) s << " bullet-gimpact |";
  if (ode) s << " ode-trimesh |";
  s << " best boxtree / best peer |\n|---|";
  for (std::size_t i = 0; i < m0.size() + bvs.size() + gimpact + ode + 1; ++i) s << "---:|";
  s << '\n';
  for (const CaseResult& r : results) {
    s << "| " << r.name << " |";
    double best = 1e300, best_peer = 1e300;
    for (const BoxtreeResult& b : r.boxtree) s << ' ' << ms(b.seconds) << " |", best = std::min(best, b.seconds);
    for (const auto& [bv, f] : r.fcl) s << ' ' << ms(f.seconds) << " |", best_peer = std::min(best_peer, f.seconds);
    if (r.has_gimpact) {
      const double g = r.gimpact.midphase_seconds + r.gimpact.exact_seconds;
      s << ' ' << ms(g) << " |", best_peer = std::min(best_peer, g);
    }
    if (r.has_ode) s << ' ' << ms(r.ode.seconds) << " |", best_peer = std::min(best_peer, r.ode.seconds);
    s << ' ' << fmt("%.2f", best / best_peer) << " |\n";
  }

  s << "\n**Pairs** (intersecting facet pairs summed over the poses; ODE: contact points)\n\n"
       "| case | facets | poses (intersecting) | boxtree pairs | boxtree triangle tests (min-max over methods) | "
       "FCL pairs | GImpact candidates | GImpact exact pairs | GImpact midphase ms | ODE contacts | brute force: "
       "poses, pairs | disagreements |\n"
       "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const CaseResult& r : results) {
    std::uint64_t lo = ~0ull, hi = 0;
    for (const BoxtreeResult& b : r.boxtree) lo = std::min(lo, b.leaf_tests), hi = std::max(hi, b.leaf_tests);
    std::string fcl_pairs = "-";
    for (const auto& [bv, f] : r.fcl) {
      const std::string v = count(f.pairs);
      if (fcl_pairs == "-")
        fcl_pairs = v;
      else if (fcl_pairs != v)
        fcl_pairs = "differ";
    }
    s << "| " << r.name << " | " << r.facets_a << " x " << r.facets_b << " | " << r.poses << " (" << r.poses_hit
      << ") | " << count(r.boxtree.front().pairs) << " | " << count(lo) << "-" << count(hi) << " | " << fcl_pairs
      << " | " << (r.has_gimpact ? count(r.gimpact.candidates) : "-") << " | "
      << (r.has_gimpact ? count(r.gimpact.pairs) : "-") << " | "
      << (r.has_gimpact ? ms(r.gimpact.midphase_seconds) : "-") << " | "
      << (r.has_ode ? count(r.ode.contacts) + (r.ode.poses_at_cap ? " (cap hit)" : "") +
                          (r.ode.messages ? " (" + count(r.ode.messages) + " warnings)" : "")
                    : "-")
      << " | " << (r.brute_poses ? std::to_string(r.brute_poses) + ", " + count(r.brute_pairs) : "-") << " | "
      << (r.disagreements ? "**" + std::to_string(r.disagreements) + "**" : "0") << " |\n";
  }

  s << "\n**Build time, ms** (mean of the two meshes' trees)\n\n| case |";
  for (const BoxtreeResult& b : m0) s << ' ' << b.method << " |";
  for (const std::string& bv : bvs) s << " fcl-" << bv << " |";
  if (gimpact) s << " bullet-gimpact |";
  if (ode) s << " ode-trimesh |";
  s << "\n|---|";
  for (std::size_t i = 0; i < m0.size() + bvs.size() + gimpact + ode; ++i) s << "---:|";
  s << '\n';
  for (const CaseResult& r : results) {
    if (!r.show_build) continue;
    s << "| " << r.name << " |";
    for (const BoxtreeResult& b : r.boxtree) s << ' ' << ms(b.build_seconds) << " |";
    for (const auto& [bv, f] : r.fcl) s << ' ' << ms(f.build_seconds) << " |";
    if (r.has_gimpact) s << ' ' << ms(r.gimpact.build_seconds) << " |";
    if (r.has_ode) s << ' ' << ms(r.ode.build_seconds) << " |";
    s << '\n';
  }
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Mesh vs mesh (issue 7, section 2): boxtree vs FCL, Bullet GImpact and ODE trimesh"};
  std::string json_path, markdown_path;
  std::string mesh_dir = std::string(BOXTREE_REPO_DIR) + "/../shared/meshes";
  std::string methods_text =
      "aabb,aabb-exact,obb-min,obb-min-tight,pie-min-general-tight,obb-all-tight,obb-min-tight+aabb@6";
  std::string bunny_file = "stanford_bunny_res3.obj";
  bool quick = false, with_fcl = true, with_gimpact = true, with_ode = true;
  int repeats = 5, bunny_poses = 50, env_poses = 100;
  app.add_flag("--quick", quick, "CI size: spheres-556, combs, 10 bunny and 20 env poses");
  app.add_option("--json", json_path, "Write the result rows (JSON array) here");
  app.add_option("--markdown", markdown_path, "Write a markdown fragment (tables, notes, machine) here");
  app.add_option("--meshes", mesh_dir, "Folder with stanford_bunny_res3.obj, env.obj, rob.obj")->capture_default_str();
  app.add_option("--methods", methods_text, "Comma-separated boxtree methods (the first one is the pair reference)")
      ->capture_default_str();
  app.add_option("--bunny", bunny_file, "Bunny file in --meshes")->capture_default_str();
  app.add_option("--repeats", repeats, "Timed runs of every query (the fastest per pose is summed)")
      ->capture_default_str();
  app.add_option("--bunny-poses", bunny_poses, "Poses of bunny vs bunny")->capture_default_str();
  app.add_option("--env-poses", env_poses, "Poses of env vs rob")->capture_default_str();
  app.add_flag("!--no-fcl", with_fcl, "Skip FCL");
  app.add_flag("!--no-gimpact", with_gimpact, "Skip Bullet GImpact");
  app.add_flag("!--no-ode", with_ode, "Skip ODE");
  CLI11_PARSE(app, argc, argv);

  try {
    const auto wall_start = Clock::now();
    const std::vector<BenchMethod> methods = parse_methods(methods_text);
    with_gimpact = with_gimpact && peers::gimpact_available();
    with_ode = with_ode && peers::ode_available();
    if (quick) bunny_poses = std::min(bunny_poses, 10), env_poses = std::min(env_poses, 20);
    const double brute_budget = quick ? 1e7 : 3e7;

    // ---- cases ----
    std::vector<Case> cases;
    auto share = [](TriangleMesh m) { return std::make_shared<const TriangleMesh>(std::move(m)); };
    std::vector<std::pair<int, int>> spheres = {{280, 556}};
    if (!quick) spheres.push_back({1000, 1996}), spheres.push_back({5000, 9996});
    for (const auto& [points, facets] : spheres) {
      const auto a = share(scenes::random_sphere(points, 11));
      bool first = true;
      for (double gap : {0.0, 0.001, 0.003, 0.01, 0.03, 0.1}) {
        std::string gap_name = gap == 0 ? "0" : fmt("%g%%", gap * 100);
        cases.push_back({"spheres-" + std::to_string(facets) + " gap " + gap_name,
                         a,
                         share(scenes::random_sphere(points, 12, 1 + gap)),
                         {RigidTransform::identity()},
                         repeats,
                         first,
                         1e-5});
        first = false;
      }
    }
    for (double gap : {0.01, 0.1})
      cases.push_back({"combs gap " + fmt("%g", gap),
                       share(scenes::comb()),
                       share(scenes::interleaved_comb(gap)),
                       {RigidTransform::identity()},
                       repeats,
                       gap == 0.01,
                       1e-4});
    const std::string bunny_path = mesh_dir + "/" + bunny_file;
    if (std::filesystem::exists(bunny_path)) {
      const auto bunny = share(load_mesh(bunny_path));
      const std::string tag = std::filesystem::path(bunny_file).stem().string();
      const std::string short_tag = tag.rfind("stanford_", 0) == 0 ? tag.substr(9) : tag;
      Vec3 lo, hi;
      bounds(*bunny, lo, hi);
      cases.push_back({short_tag + " x " + short_tag + ", " + std::to_string(bunny_poses) + " poses", bunny, bunny,
                       overlapping_poses(*bunny, bunny_poses, 0.5, 7), repeats, true, 1e-5 * (hi - lo).norm()});
    } else {
      std::printf("skipped bunny vs bunny: %s not found\n", bunny_path.c_str());
    }
    if (std::filesystem::exists(mesh_dir + "/env.obj") && std::filesystem::exists(mesh_dir + "/rob.obj")) {
      const auto env = share(load_mesh(mesh_dir + "/env.obj"));
      const auto rob = share(load_mesh(mesh_dir + "/rob.obj"));
      Vec3 lo, hi;
      bounds(*env, lo, hi);
      cases.push_back({"env x rob, " + std::to_string(env_poses) + " poses", env, rob, poses_within(*env, env_poses, 5),
                       repeats, true, 1e-5 * (hi - lo).norm()});
    } else {
      std::printf("skipped env vs rob: env.obj / rob.obj not found in %s\n", mesh_dir.c_str());
    }

    // ---- run ----
    std::vector<CaseResult> results;
    std::vector<bench::Row> rows;
    int disagreements = 0;
    TreeCache cache;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const Case& c = cases[i];
      const auto start = Clock::now();
      results.push_back(run_case(c, methods, cache, with_fcl, with_gimpact, with_ode, brute_budget));
      if (i + 1 < cases.size()) cache.keep_only({cases[i + 1].a.get(), cases[i + 1].b.get()});
      add_rows(results.back(), rows);
      disagreements += results.back().disagreements;
      std::printf("%-34s %6zu x %-6zu %3zu poses (%3zu intersecting), %9s pairs, %.1f s\n", c.name.c_str(),
                  results.back().facets_a, results.back().facets_b, c.poses.size(), results.back().poses_hit,
                  count(results.back().boxtree.front().pairs).c_str(), seconds_since(start));
      std::fflush(stdout);
    }
    const std::string body = tables(results);
    std::printf("%s\n", body.c_str());
    const double wall = seconds_since(wall_start);
    if (disagreements > 0)
      std::printf("!!!!!! PAIR LISTS DISAGREE in %d (source, pose) cases: see the messages above !!!!!!\n",
                  disagreements);
    else
      std::printf("pair lists agree: every boxtree method, FCL volume, GImpact and brute force (where run)\n");
    std::printf("total %.1f s%s\n", wall, quick ? " (--quick)" : "");

    if (!json_path.empty()) bench::write_json(json_path, rows);
    if (!markdown_path.empty()) {
      std::ostringstream md;
      md << "## Mesh vs mesh (issue 7, section 2)" << (quick ? " — quick mode" : "") << "\n\n"
         << "`mesh_bench" << (quick ? " --quick" : "") << "`: boxtree's `collide` with each method against FCL 0.7 "
         << "(`BVHModel`, five volumes), Bullet GImpact and ODE's trimesh-trimesh collider, in one process on the same "
            "meshes and poses; every query finds all intersecting facet pairs (touching counts). Spheres: the paper's "
            "concentric pairs (radius 1 and 1 + gap, seeds 11 and 12); combs: `scenes::comb` and "
            "`interleaved_comb(gap)` (they never touch); bunny: `"
         << bunny_file << "` against itself, rotated about its box centre by a uniform random rotation and moved by "
         << "up to half its box size per axis; env x rob: PQP's pair, rob at a uniform random rotation and a "
            "translation uniform in env's box. Poses from a fixed seed.\n\n"
         << "Notes:\n"
            "- boxtree runs `AnyTree::collide` on the form `AnyTree::build` holds, what the engine adapters collide: "
            "for `aabb` and the plain pie-slice methods the packed trees (4-wide 16-bit boxes; float prisms), for the "
            "others the exact `Tree<V>`; a name + `-exact` (e.g. `aabb-exact`) is the exact `Tree<V>` of that method, "
            "whose volume tests are the binary tree's (the packed aabb tree tests up to four children per split).\n"
            "- Volume tests: boxtree counts every volume pair it tests, leaf pairs included; FCL's num_bv_tests skips "
            "leaf-leaf pairs (it goes straight to the triangle test), so FCL is slightly favoured.\n"
            "- Times are the queries alone: the sum over the poses of each pose's fastest of "
         << repeats
         << " runs (trees built before; a tree of a mesh shared by cases is built once). FCL-AABB re-builds b's tree "
            "in a's frame at every non-identity pose (FCL's own AABB traversal "
            "works in one frame; fcl::collide does the same); that is in its time. GImpact = "
            "`btGImpactQuantizedBvh::find_collision` between the two shapes' box sets (what "
            "btGImpactCollisionAlgorithm does for two GImpact meshes) + boxtree's exact `triangles_intersect` on its "
            "candidates, so that its pairs compare; margin 1e-5 of the mesh's box diagonal (1e-4 for the combs) "
            "instead of Bullet's 0.01 absolute default, single-precision Bullet. ODE: one `dCollide` per pose with "
            "room for 0xffff contacts; ODE reports contact points, not facet pairs, and its trimesh-trimesh collider "
            "merges close contacts in a hash table (its overflow warnings are counted in the pairs table) ("
         << peers::ode_configuration() << ").\n"
         << "- Pairs: all boxtree methods, every FCL volume and GImpact's exact pairs are compared pose by pose with "
            "the "
            "first method's sorted pair list; brute force (all facet pairs, `triangles_intersect`) on the first pose "
            "of every case with at "
            "most 3e7 facet pairs and on further poses within "
         << fmt("%.0e", brute_budget) << " facet pairs per case (spheres-9996 is not brute-forced). Disagreements: "
         << (disagreements ? "**" + std::to_string(disagreements) + " (see the table)**" : std::string("none")) << ".\n"
         << "- Run time of the whole program: " << fmt("%.0f", wall) << " s.\n"
         << body << "\n"
         << bench::machine_markdown(std::string("FCL 0.7 (libfcl-dev), ") + peers::gimpact_version() + ", ODE " +
                                    "0.16 (libode-dev)");
      bench::write_text(markdown_path, md.str());
    }
    return disagreements > 0 ? 2 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_bench: error: %s\n", e.what());
    return 1;
  }
}
