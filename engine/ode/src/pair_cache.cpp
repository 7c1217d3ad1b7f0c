// SPDX-License-Identifier: MIT
// Mesh-vs-mesh coherence in ODE: the per-pair state (boxtree/collider.h's MeshPairCache) kept by
// geom pair, since ODE has no pair object and tells nobody when two geoms stop overlapping.
// Entries age by steps, which ODE does not announce either: a pair collided a second time since
// the step counter last moved means a new step began (a space's collide visits each overlapping
// pair once), so the counter moves and every entry unseen for kUnseenSteps steps is evicted.
// A program that collides one pair twice within its step only evicts earlier (a fresh descent,
// the same contacts). The registry is capped at kMaxPairs entries (a pair beyond it descends
// fresh) and each entry at MeshPairCache's own cap.
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
struct Entry {
  std::shared_ptr<MeshPairCache> cache;
  std::uint64_t last_step = 0;
};
struct Registry {
  std::mutex mutex;
  std::unordered_map<Key, Entry, KeyHash> entries;
  std::uint64_t step = 0;
  std::uint64_t evicted = 0;
};
// Never destroyed: geoms may be destroyed during static destruction.
Registry& registry() {
  static Registry* r = new Registry;
  return *r;
}

}  // namespace

std::shared_ptr<MeshPairCache> mesh_pair_cache(dGeomID mine, dGeomID other) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  auto found = r.entries.find(Key{mine, other});
  if (found != r.entries.end() && found->second.last_step == r.step) {
    // Seen already in this step: the next step began. Sweep out the pairs gone unseen.
    ++r.step;
    for (auto it = r.entries.begin(); it != r.entries.end();) {
      if (it->second.last_step + kUnseenSteps < r.step) {
        it = r.entries.erase(it);
        ++r.evicted;
      } else {
        ++it;
      }
    }
    found = r.entries.find(Key{mine, other});
  }
  if (found == r.entries.end()) {
    if (r.entries.size() >= kMaxPairs) return nullptr;
    found = r.entries.emplace(Key{mine, other}, Entry{std::make_shared<MeshPairCache>(), r.step}).first;
  }
  found->second.last_step = r.step;
  return found->second.cache;
}

void forget_mesh_pair_caches(dGeomID geom) {
  Registry& r = registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  for (auto it = r.entries.begin(); it != r.entries.end();) {
    if (it->first.mine == geom || it->first.other == geom) {
      it = r.entries.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace boxtree::ode::detail

namespace boxtree::ode {

MeshPairCacheInfo mesh_pair_cache_info() {
  detail::Registry& r = detail::registry();
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

void clear_mesh_pair_caches() {
  detail::Registry& r = detail::registry();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.entries.clear();
}

}  // namespace boxtree::ode
