// The convex hulls of collision meshes already computed, for loaders that load the same meshes again (the node's
// ~spawn, ~delete and ~load_scene re-load the whole world). Keyed by the mesh file's content (not its name or time),
// the scale and the face cap, so an edited file is hulled again and a copy under another name is not. Thread-safe: the
// node loads on the physics thread and on service threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>

#include "implicit_sim/core/geometry/shapes.h"

namespace implicit_sim {

class MeshHullCache {
 public:
  // At most this many hulls are kept; one more clears the cache (a world rarely holds more distinct meshes).
  static constexpr size_t kMaxEntries = 512;

  struct Key {
    uint64_t content_hash = 0;  // FNV-1a of the file's bytes
    uint64_t size = 0;          // the file's size (bytes)
    double scale_x = 1.0, scale_y = 1.0, scale_z = 1.0;
    int max_faces = 0;
    bool operator<(const Key& o) const {
      return std::tie(content_hash, size, scale_x, scale_y, scale_z, max_faces) <
             std::tie(o.content_hash, o.size, o.scale_x, o.scale_y, o.scale_z, o.max_faces);
    }
  };

  // The hull of `key` into *shape; false when it is not cached.
  bool Find(const Key& key, ConvexShape* shape) const;
  void Insert(const Key& key, const ConvexShape& shape);
  size_t size() const;
  // Hulls computed (misses) and reused (hits) so far.
  size_t misses() const;
  size_t hits() const;

 private:
  mutable std::mutex mutex_;
  std::map<Key, ConvexShape> hulls_;
  mutable size_t hits_ = 0;
  size_t misses_ = 0;
};

}  // namespace implicit_sim
