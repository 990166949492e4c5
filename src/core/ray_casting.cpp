#include "ray_casting.h"

#include <omp.h>

#include <algorithm>
#include <cstdint>

namespace evidential_octomap {
namespace {

uint64_t pack(const octomap::OcTreeKey& k) {
  return (uint64_t(k[0]) << 32) | (uint64_t(k[1]) << 16) | uint64_t(k[2]);
}
octomap::OcTreeKey unpack(uint64_t v) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(v >> 32),
                            static_cast<octomap::key_type>(v >> 16),
                            static_cast<octomap::key_type>(v));
}

// Open-addressing set of packed keys; ~10x faster than std::unordered_set for the tens of
// millions of ray keys a scan produces. Packed keys use 48 bits, so all-ones marks empty.
class KeySet {
 public:
  static constexpr uint64_t kEmpty = ~0ull;
  explicit KeySet(size_t expected = 1024) { rehash(std::max<size_t>(64, expected * 2)); }

  void insert(uint64_t key) {
    if (2 * (size_ + 1) > slots_.size()) rehash(slots_.size() * 2);
    size_t i = index(key);
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return;
      i = (i + 1) & mask_;
    }
    slots_[i] = key;
    ++size_;
  }
  bool contains(uint64_t key) const {
    size_t i = index(key);
    while (slots_[i] != kEmpty) {
      if (slots_[i] == key) return true;
      i = (i + 1) & mask_;
    }
    return false;
  }
  template <typename F>
  void forEach(F&& f) const {
    for (uint64_t v : slots_)
      if (v != kEmpty) f(v);
  }
  size_t size() const { return size_; }

 private:
  size_t index(uint64_t key) const { return (key * 0x9E3779B97F4A7C15ull) >> shift_; }
  void rehash(size_t capacity) {
    size_t pow2 = 64;
    int bits = 6;
    while (pow2 < capacity) {
      pow2 <<= 1;
      ++bits;
    }
    std::vector<uint64_t> old(pow2, kEmpty);
    old.swap(slots_);
    mask_ = pow2 - 1;
    shift_ = 64 - bits;
    size_ = 0;
    for (uint64_t v : old)
      if (v != kEmpty) insert(v);
  }
  std::vector<uint64_t> slots_;
  size_t mask_ = 0;
  int shift_ = 0;
  size_t size_ = 0;
};

}  // namespace

ScanKeys castRays(const EvidentialOcTree& tree, const octomap::Pointcloud& points_W,
                  const octomap::point3d& origin_W, double max_range, bool discretize,
                  int threads) {
  // Ray end points: every point, or one per end voxel (its centre) when discretizing.
  std::vector<octomap::point3d> ends;
  ends.reserve(points_W.size());
  if (discretize) {
    KeySet seen(points_W.size());
    for (size_t i = 0; i < points_W.size(); ++i) {
      const octomap::OcTreeKey key = tree.coordToKey(points_W.getPoint(i));
      const size_t before = seen.size();
      seen.insert(pack(key));
      if (seen.size() != before) ends.push_back(tree.keyToCoord(key));
    }
  } else {
    for (size_t i = 0; i < points_W.size(); ++i) ends.push_back(points_W.getPoint(i));
  }

  std::vector<KeySet> free_sets(threads, KeySet(1 << 20));
  std::vector<std::vector<uint64_t>> occupied_lists(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    octomap::KeyRay ray;
    KeySet& free_set = free_sets[t];
#pragma omp for schedule(dynamic, 512)
    for (size_t i = 0; i < ends.size(); ++i) {
      const octomap::point3d& end = ends[i];
      const bool within_range = max_range < 0.0 || (end - origin_W).norm() <= max_range;
      const octomap::point3d ray_end =
          within_range ? end : origin_W + (end - origin_W).normalized() * float(max_range);
      if (tree.computeRayKeys(origin_W, ray_end, ray)) {
        for (const octomap::OcTreeKey& key : ray) free_set.insert(pack(key));
      }
      octomap::OcTreeKey key;
      if (within_range && tree.coordToKeyChecked(end, key)) occupied_lists[t].push_back(pack(key));
    }
  }

  KeySet occupied(ends.size());
  for (const auto& list : occupied_lists)
    for (uint64_t v : list) occupied.insert(v);
  KeySet& free_all = free_sets[0];
  for (int t = 1; t < threads; ++t) free_sets[t].forEach([&](uint64_t v) { free_all.insert(v); });

  ScanKeys keys;
  keys.free.reserve(free_all.size());
  free_all.forEach([&](uint64_t v) {
    if (!occupied.contains(v)) keys.free.push_back(unpack(v));  // occupied wins
  });
  keys.occupied.reserve(occupied.size());
  occupied.forEach([&](uint64_t v) { keys.occupied.push_back(unpack(v)); });
  return keys;
}

}  // namespace evidential_octomap
