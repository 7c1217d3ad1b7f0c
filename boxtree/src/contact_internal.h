// SPDX-License-Identifier: MIT
#pragma once
// Helpers shared by the narrowphase's source files (contact.h); not part of the public API.
#include "boxtree/shapes.h"

namespace boxtree::detail {

// Sutherland-Hodgman clipping of a convex polygon by one half-space (Sutherland, Hodgman,
// "Reentrant polygon clipping", CACM 17(1), 1974): writes the part of in[0..n) where
// signed_distance(x) <= 0 to `out` and returns its corner count, at most n + 1. A crossing edge
// is cut at the linear interpolation of the two distances' zero.
template <class SignedDistance>
int clip_polygon(const Vec3* in, int n, const SignedDistance& signed_distance, Vec3* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3& cur = in[i];
    const Vec3& next = in[(i + 1) % n];
    const Real dc = signed_distance(cur);
    const Real dn = signed_distance(next);
    if (dc <= 0) out[m++] = cur;
    if ((dc < 0 && dn > 0) || (dc > 0 && dn < 0)) out[m++] = cur + (dc / (dc - dn)) * (next - cur);
  }
  return m;
}

}  // namespace boxtree::detail
