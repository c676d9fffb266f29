#include "implicit_sim/core/model/mesh_hull_cache.h"

namespace implicit_sim {

bool MeshHullCache::Find(const Key& key, ConvexShape* shape) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = hulls_.find(key);
  if (it == hulls_.end()) return false;
  *shape = it->second;
  ++hits_;
  return true;
}

void MeshHullCache::Insert(const Key& key, const ConvexShape& shape) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (hulls_.size() >= kMaxEntries) hulls_.clear();
  hulls_[key] = shape;
  ++misses_;
}

size_t MeshHullCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return hulls_.size();
}

size_t MeshHullCache::misses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
}

size_t MeshHullCache::hits() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}

}  // namespace implicit_sim
