// SPDX-License-Identifier: MIT
#pragma once
// Every volume kind the library is compiled for: each src/*.cpp instantiates its templates for
// this list, so adding a kind is one line here (plus its name in method.h).
#include "boxtree/volume/hybrid.h"
#include "boxtree/volume/volume.h"

#define BOXTREE_FOR_EACH_ORIENTED_VOLUME(X) \
  X(ObbAll)                                 \
  X(ObbMax)                                 \
  X(ObbMin)                                 \
  X(PieMax)                                 \
  X(PieMin)                                 \
  X(PieMaxGeneral)                          \
  X(PieMinGeneral)

#define BOXTREE_FOR_EACH_HYBRID_VOLUME(X) \
  X(Hybrid<ObbAll>)                       \
  X(Hybrid<ObbMax>)                       \
  X(Hybrid<ObbMin>)                       \
  X(Hybrid<PieMax>)                       \
  X(Hybrid<PieMin>)                       \
  X(Hybrid<PieMaxGeneral>)                \
  X(Hybrid<PieMinGeneral>)

// Every kind but Aabb (handy where a list needs a first element written out).
#define BOXTREE_FOR_EACH_NON_AABB_VOLUME(X) \
  BOXTREE_FOR_EACH_ORIENTED_VOLUME(X)       \
  BOXTREE_FOR_EACH_HYBRID_VOLUME(X)

#define BOXTREE_FOR_EACH_VOLUME(X) \
  X(Aabb)                          \
  BOXTREE_FOR_EACH_NON_AABB_VOLUME(X)
