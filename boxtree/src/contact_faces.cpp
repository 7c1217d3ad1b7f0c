// SPDX-License-Identifier: MIT
// contact_triangle_faces (contact.h): mesh-vs-mesh contacts along face normals.
#include <algorithm>
#include <cmath>
#include <utility>

#include "boxtree/contact.h"
#include "boxtree/geometry.h"
#include "contact_internal.h"

namespace boxtree {
namespace {

// Points of triangle `t` inside the prism over face `f` (unit normal n) within `margin` of its
// front: (point, signed height over the face).
int clip_to_prism(const Vec3* t, const Vec3* f, const Vec3& n, Real margin, Vec3* points, Real* heights) {
  // A triangle clipped by three planes has at most 6 corners.
  Vec3 buffer_a[6] = {t[0], t[1], t[2]};
  Vec3 buffer_b[6];
  Vec3* in = buffer_a;
  Vec3* next = buffer_b;
  int corners = 3;
  for (int k = 0; k < 3 && corners > 0; ++k) {
    const Vec3& origin = f[k];
    const Vec3 outward = (f[(k + 1) % 3] - f[k]).cross(n);  // the side plane of a counter-clockwise face
    corners = detail::clip_polygon(
        in, corners, [&](const Vec3& x) { return (x - origin).dot(outward); }, next);
    std::swap(in, next);
  }
  int count = 0;
  for (int i = 0; i < corners; ++i) {
    const Real h = (in[i] - f[0]).dot(n);
    if (h <= margin) {
      points[count] = in[i];
      heights[count++] = h;
    }
  }
  return count;
}

}  // namespace

int contact_triangle_faces(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                           const Vec3& b2, const ContactOptions& options, ContactPoint* out, FixedSurface fixed) {
  const Vec3 a[3] = {a0, a1, a2}, b[3] = {b0, b1, b2};
  Vec3 na = (a1 - a0).cross(a2 - a0), nb = (b1 - b0).cross(b2 - b0);
  const Real la = na.norm(), lb = nb.norm();
  if (!(la > 0) || !(lb > 0) || !std::isfinite(la) || !std::isfinite(lb)) return 0;  // degenerate: no face
  na /= la;
  nb /= lb;
  const Real margin = std::max(options.margin, Real(0));
  Vec3 on_b[9], on_a[9];
  Real h_b[9], h_a[9];
  // a's points over b's face, and b's points over a's face.
  int count_b = clip_to_prism(a, b, nb, margin, on_b, h_b);
  int count_a = clip_to_prism(b, a, na, margin, on_a, h_a);
  // Points behind a face count as inside its mesh only when the triangles meet; triangles apart
  // (within the margin) give only the points near the face's plane.
  if (!triangles_intersect(a0, a1, a2, b0, b1, b2)) {
    auto near_plane = [&](Vec3* p, Real* h, int count) {
      int kept = 0;
      for (int i = 0; i < count; ++i) {
        if (h[i] >= -margin) p[kept] = p[i], h[kept++] = h[i];
      }
      return kept;
    };
    count_b = near_plane(on_b, h_b, count_b);
    count_a = near_plane(on_a, h_a, count_a);
  }
  const Real deepest_b = count_b ? -*std::min_element(h_b, h_b + count_b) : 0;
  const Real deepest_a = count_a ? -*std::min_element(h_a, h_a + count_a) : 0;
  // A clearly larger face gives the normal: against a much smaller triangle it acts as the
  // surface, and the small one's steep faces (a rock's sides on the ground) would push sideways
  // (choosing the shallower side there let a resting rock wander). Between faces of similar
  // size, the shallower side is the better guess (a cube's wall against a floor cell).
  bool use_b;
  if (count_a == 0 || count_b == 0) {
    use_b = count_b > 0;
  } else if (fixed != FixedSurface::neither && na.dot(nb) > 0) {
    use_b = fixed == FixedSurface::b;
  } else if (lb >= 2 * la || la >= 2 * lb) {
    use_b = lb > la;
  } else {
    use_b = deepest_b <= deepest_a;
  }
  int n = 0;
  if (use_b) {
    for (int i = 0; i < count_b && n < kMaxTriangleFaceContacts; ++i) {
      out[n].position = on_b[i] - h_b[i] * nb;  // projected onto b
      out[n].normal = nb;
      out[n].depth = -h_b[i];
      ++n;
    }
  } else {
    for (int i = 0; i < count_a && n < kMaxTriangleFaceContacts; ++i) {
      out[n].position = on_a[i];  // b's own point
      out[n].normal = -na;
      out[n].depth = -h_a[i];
      ++n;
    }
  }
  return n;
}

}  // namespace boxtree
