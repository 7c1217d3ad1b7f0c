// SPDX-License-Identifier: MIT
// reduce_contacts (contact.h) and its array form reduce_in_place (contact_internal.h): merging
// near-duplicate contacts, then keeping the deepest and greedily the points that spread the set
// the most (the area of their convex hull, convex_hull_2d of internal.h, across the deepest
// contact's normal).
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "boxtree/contact.h"
#include "contact_internal.h"
#include "internal.h"

namespace boxtree {
namespace detail {
namespace {

// Twice the signed area of the triangle (o, a, b): positive when it turns counter-clockwise.
Real cross_2d(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Twice the area that each candidate (x[i], y[i]), i in [0, n), adds to the convex polygon `hull`
// (counter-clockwise, h vertices; a segment or a point when h < 3), in added[i]: the triangles
// from the candidate to the edges that face it, i.e. the sum over the hull's edges (o, b), in
// their order, of -c for the cross products c = (b.x - o.x) (q.y - o.y) - (b.y - o.y) (q.x - o.x)
// that are negative. Each loop runs over the candidates without a branch, two at a time with
// SSE2: an edge that does not face the candidate (c >= 0, or NaN) adds +0, which leaves the sum
// as it is.
void added_areas_2d(const Vec2* hull, int h, const Real* x, const Real* y, int n, Real* added) {
  std::fill(added, added + n, Real(0));
  if (h == 1) return;
  for (int e = 0; e < h; ++e) {
    const Vec2& o = hull[e];
    const Vec2& b = hull[e + 1 == h ? 0 : e + 1];
    const Real ex = b.x() - o.x();
    const Real ey = b.y() - o.y();
    if (h == 2) {  // a segment: the triangle on it
      for (int i = 0; i < n; ++i) added[i] = std::abs(ex * (y[i] - o.y()) - ey * (x[i] - o.x()));
      return;
    }
    int i = 0;
#if defined(__SSE2__)
    // Two candidates per instruction (GCC does not vectorize the loop at -O2), with the same
    // operations: maxpd(v, 0) is v > 0 ? v : 0, which is std::max(Real(0), v) (+0 for a NaN or
    // a -0 in both), and flipping the sign bit is the negation.
    const __m128d ex2 = _mm_set1_pd(ex);
    const __m128d ey2 = _mm_set1_pd(ey);
    const __m128d ox = _mm_set1_pd(o.x());
    const __m128d oy = _mm_set1_pd(o.y());
    const __m128d sign = _mm_set1_pd(Real(-0.0));
    for (; i + 1 < n; i += 2) {
      const __m128d c = _mm_sub_pd(_mm_mul_pd(ex2, _mm_sub_pd(_mm_loadu_pd(y + i), oy)),
                                   _mm_mul_pd(ey2, _mm_sub_pd(_mm_loadu_pd(x + i), ox)));
      const __m128d facing = _mm_max_pd(_mm_xor_pd(c, sign), _mm_setzero_pd());
      _mm_storeu_pd(added + i, _mm_add_pd(_mm_loadu_pd(added + i), facing));
    }
#endif
    for (; i < n; ++i) {
      const Real c = ex * (y[i] - o.y()) - ey * (x[i] - o.x());
      added[i] += std::max(Real(0), -c);  // x - c is x + (-c)
    }
  }
}

// The order std::sort(contacts, contacts + count, deeper first) leaves them in, as indices in
// keys[0..count): std::sort's comparisons and moves depend only on the outcomes of earlier
// comparisons, so sorting (depth, index) pairs with the same comparison moves every index to
// where its contact would go, ties included, with 16-byte moves instead of 64-byte ones.
struct DepthKey {
  Real depth;
  int index;
};
void sort_deepest_first(const ContactPoint* contacts, int count, DepthKey* keys) {
  for (int i = 0; i < count; ++i) keys[i] = {contacts[i].depth, i};
  std::sort(keys, keys + count, [](const DepthKey& x, const DepthKey& y) { return x.depth > y.depth; });
}

const auto deeper_first = [](const ContactPoint& x, const ContactPoint& y) { return x.depth > y.depth; };

// Merges near-duplicates (same place within `merge_distance`, normals within ~10 degrees) of
// sorted(0), sorted(1), ... sorted(count - 1) (deepest first); the deeper one (earlier) stays.
// Writes the kept ones to `kept_out` in order and returns how many they are; kept_out may be the
// array sorted(i) reads at index i (its position k is written after sorted(k) is read). A contact
// can only duplicate a kept one whose x lies within the merge distance of its own, so the kept
// contacts are indexed in x order and each contact is tested against that window only (O(n log n)
// for spread contacts instead of O(n * kept)); the window is wider than the distance by more than
// rounding, so the test decides as the full scan does.
template <class Sorted>
int merge_near_duplicates(const Sorted& sorted, int count, Real merge_distance, ContactPoint* kept_out) {
  const Real cos_merge = std::cos(Real(10) * Real(3.14159265358979323846) / 180);
  const Real merge_squared = merge_distance * merge_distance;
  const auto duplicates = [&](const ContactPoint& c, const ContactPoint& other) {
    return (c.position - other.position).squaredNorm() <= merge_squared && c.normal.dot(other.normal) >= cos_merge;
  };
  // Few contacts, or no order to index by: the full scan.
  bool scan = count <= 32 || !std::isfinite(merge_squared);
  for (int i = 0; i < count && !scan; ++i) scan = !std::isfinite(sorted(i).position.x());
  if (scan) {
    int kept = 0;
    for (int i = 0; i < count; ++i) {
      const ContactPoint& c = sorted(i);
      bool duplicate = false;
      for (int j = 0; j < kept && !duplicate; ++j) duplicate = duplicates(c, kept_out[j]);
      if (!duplicate) kept_out[kept++] = c;
    }
    return kept;
  }
  std::array<int, 256> small;
  std::vector<int> large;
  int* by_x = small.data();  // indices of the kept contacts [0, kept), ascending x
  if (count > int(small.size())) {
    large.resize(std::size_t(count));
    by_x = large.data();
  }
  const auto x_of = [kept_out](int k) { return kept_out[k].position.x(); };
  int kept = 0;
  for (int i = 0; i < count; ++i) {
    const ContactPoint& c = sorted(i);
    const Real x = c.position.x();
    const Real window = merge_distance * (1 + 1e-9) + 1e-15 * std::abs(x);
    int* p = std::lower_bound(by_x, by_x + kept, x - window, [&](int k, Real v) { return x_of(k) < v; });
    bool duplicate = false;
    for (; p != by_x + kept && x_of(*p) <= x + window && !duplicate; ++p) duplicate = duplicates(c, kept_out[*p]);
    if (duplicate) continue;
    kept_out[kept] = c;
    int* at = std::upper_bound(by_x, by_x + kept, x, [&](Real v, int k) { return v < x_of(k); });
    std::copy_backward(at, by_x + kept, by_x + kept + 1);
    *at = kept++;
  }
  return kept;
}

}  // namespace

int reduce_in_place(ContactPoint* contacts, int count, int max_count, Real merge_distance, int* merged) {
  if (merged) *merged = 0;
  if (count <= 0) return 0;
  int kept = 0;
  if (count <= 16) {
    // A narrowphase's few contacts: sorted as they are (keys would cost more than they save).
    std::sort(contacts, contacts + count, deeper_first);
    kept = merge_near_duplicates([contacts](int i) -> const ContactPoint& { return contacts[i]; }, count,
                                 merge_distance, contacts);
  } else {
    // Per thread, so that a warm call does not allocate: the sorted keys and the kept contacts.
    thread_local std::vector<DepthKey> keys;
    thread_local std::vector<ContactPoint> kept_contacts;
    if (keys.size() < std::size_t(count)) {
      keys.resize(std::size_t(count));
      kept_contacts.resize(std::size_t(count));
    }
    sort_deepest_first(contacts, count, keys.data());
    const DepthKey* sorted = keys.data();
    kept = merge_near_duplicates([contacts, sorted](int i) -> const ContactPoint& { return contacts[sorted[i].index]; },
                                 count, merge_distance, kept_contacts.data());
    std::copy(kept_contacts.begin(), kept_contacts.begin() + kept, contacts);
  }
  if (merged) *merged = count - kept;
  if (kept <= max_count) return kept;

  // Keep the deepest, then greedily the point that makes the largest hull (in the plane across
  // the deepest contact's normal), ties (collinear sets) broken by the distance to the chosen set.
  // The hull of the chosen set is kept, so a candidate costs the area it adds (its visible edges)
  // and its distance is updated once per choice: O(max_count * n * hull) in all.
  Vec3 u;
  Vec3 w;
  detail::orthonormal_completion(contacts[0].normal.normalized(), u, w);
  const int n = std::min(kept, 64);
  std::array<Real, 64> planar_x;
  std::array<Real, 64> planar_y;
  std::array<Real, 64> added;     // twice the area each candidate adds to the chosen set's hull
  std::array<Real, 64> distance;  // squared, to the nearest chosen point
  std::array<bool, 64> chosen{};
  Real extent_squared = 0;
  for (int i = 0; i < n; ++i) {
    planar_x[i] = contacts[i].position.dot(u);
    planar_y[i] = contacts[i].position.dot(w);
    distance[i] = (contacts[i].position - contacts[0].position).squaredNorm();
    extent_squared = std::max(extent_squared, distance[i]);
  }
  std::array<int, 64> order{};
  std::array<Vec2, 64> points;
  std::array<Vec2, 128> hull;  // room for 2 x 64 points (convex_hull_2d)
  chosen[0] = true;
  order[0] = 0;
  int selected = 1;
  int h = 1;
  hull[0] = Vec2(planar_x[0], planar_y[0]);
  Real area = 0;  // twice the chosen set's hull area
  while (selected < std::min(max_count, n)) {
    added_areas_2d(hull.data(), h, planar_x.data(), planar_y.data(), n, added.data());
    int best = -1;
    Real best_area = -1;
    Real best_distance = -1;
    // Areas compare with a slack (relative, and to the set's size for collinear sets, whose
    // areas are rounding noise) so that rounding does not beat a real spread.
    Real slack = 1e-9 * std::max(best_area, Real(0)) + 1e-12 * extent_squared;
    for (int i = 0; i < n; ++i) {
      if (chosen[i]) continue;
      const Real candidate_area = area + added[i];
      const bool better =
          candidate_area > best_area + slack || (candidate_area >= best_area - slack && distance[i] > best_distance);
      if (better) {
        best = i;
        best_area = candidate_area;
        best_distance = distance[i];
        slack = 1e-9 * std::max(best_area, Real(0)) + 1e-12 * extent_squared;
      }
    }
    if (best < 0) break;
    chosen[best] = true;
    order[selected++] = best;
    for (int i = 0; i < n; ++i) {
      distance[i] = std::min(distance[i], (contacts[i].position - contacts[best].position).squaredNorm());
    }
    for (int s = 0; s < selected; ++s) points[s] = Vec2(planar_x[order[s]], planar_y[order[s]]);
    h = detail::convex_hull_2d(points.data(), selected, hull.data());
    area = 0;
    for (int i = 0; h >= 3 && i < h; ++i) area += cross_2d(hull[0], hull[i], hull[i + 1 == h ? 0 : i + 1]);
  }
  std::array<ContactPoint, 64> result;
  for (int s = 0; s < selected; ++s) result[s] = contacts[order[s]];
  std::sort(result.begin(), result.begin() + selected, deeper_first);
  std::copy(result.begin(), result.begin() + selected, contacts);
  return selected;
}

}  // namespace detail

ReductionCounts reduce_contacts(std::vector<ContactPoint>& contacts, std::size_t max_count, Real merge_distance) {
  // More than 64 contacts: the area-greedy selection looks at the deepest 64 (after merging).
  const int limit = static_cast<int>(std::clamp<std::size_t>(max_count, 1, 1 << 20));
  const std::size_t before = contacts.size();
  int merged = 0;
  contacts.resize(std::size_t(
      detail::reduce_in_place(contacts.data(), static_cast<int>(contacts.size()), limit, merge_distance, &merged)));
  ReductionCounts counts;
  counts.merged = std::size_t(merged);
  counts.dropped = before - std::size_t(merged) - contacts.size();
  return counts;
}

}  // namespace boxtree
