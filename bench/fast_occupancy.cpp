#include "fast_occupancy.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "bench_data.h"

namespace evbench {
namespace {

inline uint64_t pack(const octomap::OcTreeKey& k) {
  return (uint64_t(k[0]) << 32) | (uint64_t(k[1]) << 16) | uint64_t(k[2]);
}
inline octomap::OcTreeKey unpack(uint64_t v) {
  return octomap::OcTreeKey(octomap::key_type(v >> 32), octomap::key_type(v >> 16),
                            octomap::key_type(v));
}

// Spreads the 16 bits of x to every third bit.
inline uint64_t spread3(uint64_t x) {
  x &= 0xFFFF;
  x = (x | (x << 32)) & 0x1F00000000FFFFull;
  x = (x | (x << 16)) & 0x1F0000FF0000FFull;
  x = (x | (x << 8)) & 0x100F00F00F00F00Full;
  x = (x | (x << 4)) & 0x10C30C30C30C30C3ull;
  x = (x | (x << 2)) & 0x1249249249249249ull;
  return x;
}
// Morton code with the tree's child order (x is bit 0, y bit 1, z bit 2 of each level).
inline uint64_t morton(uint64_t packed) {
  return spread3(packed >> 32) | (spread3(packed >> 16) << 1) | (spread3(packed) << 2);
}
inline uint64_t unmortonAxis(uint64_t m) {
  m &= 0x1249249249249249ull;
  m = (m ^ (m >> 2)) & 0x10C30C30C30C30C3ull;
  m = (m ^ (m >> 4)) & 0x100F00F00F00F00Full;
  m = (m ^ (m >> 8)) & 0x1F0000FF0000FFull;
  m = (m ^ (m >> 16)) & 0x1F00000000FFFFull;
  m = (m ^ (m >> 32)) & 0xFFFF;
  return m;
}
inline octomap::OcTreeKey fromMorton(uint64_t m) {
  return octomap::OcTreeKey(octomap::key_type(unmortonAxis(m)), octomap::key_type(unmortonAxis(m >> 1)),
                            octomap::key_type(unmortonAxis(m >> 2)));
}

// Open-addressing set of 48-bit keys (all-ones = empty), linear probing, grows at 50 % load.
class FlatKeySet {
 public:
  explicit FlatKeySet(size_t expected = 1024) { rehash(capacityFor(expected)); }
  bool insert(uint64_t key) {
    if ((size_ + 1) * 2 > slots_.size()) rehash(slots_.size() * 2);
    size_t i = hash(key) & mask_;
    while (true) {
      const uint64_t v = slots_[i];
      if (v == key) return false;
      if (v == kEmpty) {
        slots_[i] = key;
        ++size_;
        return true;
      }
      i = (i + 1) & mask_;
    }
  }
  bool contains(uint64_t key) const {
    size_t i = hash(key) & mask_;
    while (true) {
      const uint64_t v = slots_[i];
      if (v == key) return true;
      if (v == kEmpty) return false;
      i = (i + 1) & mask_;
    }
  }
  size_t size() const { return size_; }
  template <typename F>
  void forEach(F f) const {
    for (uint64_t v : slots_)
      if (v != kEmpty) f(v);
  }

 private:
  static constexpr uint64_t kEmpty = ~0ull;
  static size_t capacityFor(size_t n) {
    size_t c = 1024;
    while (c < 2 * n) c *= 2;
    return c;
  }
  static size_t hash(uint64_t k) { return size_t((k * 0x9E3779B97F4A7C15ull) >> 20); }
  void rehash(size_t capacity) {
    std::vector<uint64_t> old;
    old.swap(slots_);
    slots_.assign(capacity, kEmpty);
    mask_ = capacity - 1;
    size_ = 0;
    for (uint64_t v : old)
      if (v != kEmpty) insert(v);
  }
  std::vector<uint64_t> slots_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace

FastOccupancyTimes FastOccupancy::insert(octomap::OcTree* tree, const octomap::Pointcloud& points_W,
                                         const octomap::point3d& origin_W, double max_range,
                                         bool discretize) {
  FastOccupancyTimes times;
  auto start = Clock::now();
  // 1. End points (discretised to voxel centres when asked, as computeDiscreteUpdate does).
  std::vector<octomap::point3d> ends;
  ends.reserve(points_W.size());
  if (discretize) {
    FlatKeySet seen(points_W.size() / 2);
    for (size_t i = 0; i < points_W.size(); ++i) {
      const octomap::OcTreeKey k = tree->coordToKey(points_W.getPoint(i));
      if (seen.insert(pack(k))) ends.push_back(tree->keyToCoord(k));
    }
  } else {
    for (size_t i = 0; i < points_W.size(); ++i) ends.push_back(points_W.getPoint(i));
  }

  // 2. Rays in parallel, per-thread de-duplication.
  const int threads = threads_;
  std::vector<FlatKeySet> free_sets(threads, FlatKeySet(1 << 18));
  std::vector<std::vector<uint64_t>> occupied(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    FlatKeySet& free_local = free_sets[t];
    octomap::KeyRay ray;
#pragma omp for schedule(static, 1024)
    for (size_t i = 0; i < ends.size(); ++i) {
      const octomap::point3d& p = ends[i];
      octomap::point3d end = p;
      bool hit = true;
      if (max_range >= 0.0 && (p - origin_W).norm() > max_range) {
        end = origin_W + (p - origin_W).normalized() * float(max_range);
        hit = false;
      }
      if (tree->computeRayKeys(origin_W, end, ray)) {
        for (const auto& k : ray) free_local.insert(pack(k));
      }
      octomap::OcTreeKey key;
      if (hit && tree->coordToKeyChecked(p, key)) occupied[t].push_back(morton(pack(key)));
    }
  }
  // 3. Merge, occupied wins, Morton order.
  std::vector<uint64_t> occ;
  for (auto& v : occupied) occ.insert(occ.end(), v.begin(), v.end());
  std::sort(occ.begin(), occ.end());
  occ.erase(std::unique(occ.begin(), occ.end()), occ.end());
  std::vector<uint64_t> free_keys;
  {
    size_t total = 0;
    for (const auto& s : free_sets) total += s.size();
    free_keys.reserve(total);
    FlatKeySet& first = free_sets[0];
    first.forEach([&](uint64_t k) { free_keys.push_back(morton(k)); });
    for (int t = 1; t < threads; ++t) {
      free_sets[t].forEach([&](uint64_t k) {
        if (!first.contains(k)) free_keys.push_back(morton(k));
      });
    }
  }
  std::sort(free_keys.begin(), free_keys.end());
  {
    // free \ occupied (both sorted)
    std::vector<uint64_t> diff;
    diff.reserve(free_keys.size());
    std::set_difference(free_keys.begin(), free_keys.end(), occ.begin(), occ.end(),
                        std::back_inserter(diff));
    free_keys.swap(diff);
  }
  times.ms_keys = msSince(start);
  times.free_keys = free_keys.size();
  times.occupied_keys = occ.size();

  // 4. Tree update in Morton order (free first, then occupied, as OctoMap does).
  start = Clock::now();
  for (uint64_t m : free_keys) tree->updateNode(fromMorton(m), false, false);
  for (uint64_t m : occ) tree->updateNode(fromMorton(m), true, false);
  times.ms_update = msSince(start);
  return times;
}

MapFingerprint fingerprint(const octomap::OcTree& tree) {
  MapFingerprint f;
  const unsigned depth = tree.getTreeDepth();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const double volume = std::ldexp(1.0, 3 * int(depth - it.getDepth()));
    f.weighted_log_odds += volume * it->getLogOdds();
    f.known_voxels += volume;
    if (tree.isNodeOccupied(*it)) f.occupied_voxels += volume;
  }
  return f;
}

}  // namespace evbench
