// SPDX-License-Identifier: MIT
// Temporal coherence in ODE: the per-pair state of boxtree/collider.h (MeshPairCache for mesh vs
// mesh, ConvexPairCache for a convex geom) kept by geom pair, since ODE has no pair object and
// tells nobody when two geoms stop overlapping. One registry per kind of state. Entries age by
// steps, which ODE does not announce either: a pair looked up a second time since the registry's
// step counter last moved means a new step began (a space's collide visits each overlapping pair
// once), so the counter moves and every entry unseen for kUnseenSteps steps is evicted. A
// program that collides one pair twice within its step only evicts earlier (the pair's next call
// collides afresh: the same contacts). Each registry is capped (a pair beyond the cap collides
// without state) and each entry at its state's own bound.
#include <algorithm>
#include <mutex>
#include <unordered_map>

#include "internal.h"

namespace boxtree::ode::detail {
namespace {

struct Key {
  dGeomID mine, other;
  bool operator==(const Key& k) const { return mine == k.mine && other == k.other; }
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    const std::hash<const void*> h;
    return h(k.mine) * 31 + h(k.other);
  }
};
template <class Cache>
struct Entry {
  std::shared_ptr<Cache> cache;
  std::uint64_t last_step = 0;
};
template <class Cache>
struct Registry {
  std::mutex mutex;
  std::unordered_map<Key, Entry<Cache>, KeyHash> entries;
  std::uint64_t step = 0;
  std::uint64_t evicted = 0;
  std::size_t cap = 0;

  std::shared_ptr<Cache> lookup(dGeomID mine, dGeomID other) {
    std::lock_guard<std::mutex> lock(mutex);
    auto found = entries.find(Key{mine, other});
    if (found != entries.end() && found->second.last_step == step) {
      // Seen already in this step: the next step began. Sweep out the pairs gone unseen.
      ++step;
      for (auto it = entries.begin(); it != entries.end();) {
        if (it->second.last_step + kUnseenSteps < step) {
          it = entries.erase(it);
          ++evicted;
        } else {
          ++it;
        }
      }
      found = entries.find(Key{mine, other});
    }
    if (found == entries.end()) {
      if (entries.size() >= cap) return nullptr;
      found = entries.emplace(Key{mine, other}, Entry<Cache>{std::make_shared<Cache>(), step}).first;
    }
    found->second.last_step = step;
    return found->second.cache;
  }

  void forget(dGeomID geom) {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = entries.begin(); it != entries.end();) {
      if (it->first.mine == geom || it->first.other == geom) {
        it = entries.erase(it);
      } else {
        ++it;
      }
    }
  }

  void clear() {
    std::lock_guard<std::mutex> lock(mutex);
    entries.clear();
  }
};

// Never destroyed: geoms may be destroyed during static destruction.
Registry<MeshPairCache>& mesh_registry() {
  static auto* r = new Registry<MeshPairCache>{{}, {}, 0, 0, kMaxMeshPairs};
  return *r;
}
Registry<ConvexPairCache>& convex_registry() {
  static auto* r = new Registry<ConvexPairCache>{{}, {}, 0, 0, kMaxConvexPairs};
  return *r;
}

}  // namespace

std::shared_ptr<MeshPairCache> mesh_pair_cache(dGeomID mine, dGeomID other) {
  return mesh_registry().lookup(mine, other);
}

std::shared_ptr<ConvexPairCache> convex_pair_cache(dGeomID mine, dGeomID other) {
  return convex_registry().lookup(mine, other);
}

void forget_pair_caches(dGeomID geom) {
  mesh_registry().forget(geom);
  convex_registry().forget(geom);
}

}  // namespace boxtree::ode::detail

namespace boxtree::ode {

MeshPairCacheInfo mesh_pair_cache_info() {
  auto& r = detail::mesh_registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  MeshPairCacheInfo info;
  info.pairs = r.entries.size();
  info.steps = r.step;
  info.evicted = r.evicted;
  for (const auto& [key, entry] : r.entries) {
    info.bytes += entry.cache->memory_bytes();
    info.largest_front = std::max(info.largest_front, entry.cache->front().size());
  }
  return info;
}

ConvexPairCacheInfo convex_pair_cache_info() {
  auto& r = detail::convex_registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  ConvexPairCacheInfo info;
  info.pairs = r.entries.size();
  info.steps = r.step;
  info.evicted = r.evicted;
  for (const auto& [key, entry] : r.entries) info.bytes += entry.cache->memory_bytes();
  return info;
}

void clear_mesh_pair_caches() { detail::mesh_registry().clear(); }

void clear_convex_pair_caches() { detail::convex_registry().clear(); }

}  // namespace boxtree::ode
