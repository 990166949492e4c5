// A set of voxel keys with up to three flags each, stored as bits in 8x8x8 bricks (the leaves
// below one node three levels above the leaf depth) and read back in Morton order, the order in
// which the tree update walks. One scan's rays touch ~13 M cells but only ~1.5 M distinct
// voxels in ~40 k bricks: a bit test in a brick that is usually the one the previous cell used
// is several times cheaper than a hash-set insert per cell. Not thread-safe: one per thread,
// merged afterwards, each on cache lines of its own: the ray loop writes last_coarse_ at every
// brick it enters, and a neighbour's writes on a shared line cost ~40 % of the ray casting in
// some heap layouts. Private to the core.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>
// OcTreeKey.h needs size_t, uint16_t and std::vector declared before it.
#include <octomap/OcTreeKey.h>

#include "morton.h"

namespace evidential_octomap {

class alignas(64) VoxelBricks {
 public:
  static constexpr int kFlags = 3;

  VoxelBricks() { clear(); }
  // Empties the set, keeping its memory for the next scan.
  void clear();
  bool empty() const { return codes_.empty(); }
  size_t numBricks() const { return codes_.size(); }
  // Bytes the buffers hold (capacity, kept from scan to scan), and the release of what the
  // last scan did not need (kept_buffers.h), which empties the set.
  size_t capacityBytes() const;
  void releaseExcess();

  // A key as one integer, x | y << 16 | z << 32: a ray steps it by adding a constant, and the
  // key of its brick is a mask.
  static uint64_t pack(const octomap::OcTreeKey& key) {
    return uint64_t(key[0]) | uint64_t(key[1]) << 16 | uint64_t(key[2]) << 32;
  }
  static octomap::OcTreeKey unpack(uint64_t packed) {
    return octomap::OcTreeKey(static_cast<octomap::key_type>(packed),
                              static_cast<octomap::key_type>(packed >> 16),
                              static_cast<octomap::key_type>(packed >> 32));
  }
  // Sets `flag` (0..kFlags-1) of `key`; returns whether it was set before.
  bool testAndSet(const octomap::OcTreeKey& key, int flag) { return testAndSet(pack(key), flag); }
  bool testAndSet(uint64_t packed, int flag) {
    uint64_t* word;
    const uint64_t bit = locate(packed, flag, &word);
    const bool was_set = (*word & bit) != 0;
    *word |= bit;
    return was_set;
  }
  bool test(const octomap::OcTreeKey& key, int flag) const;

  // Adds every flag of `other` to this set.
  void merge(const VoxelBricks& other);

  // Calls f(key, morton_code, flags) for every voxel with a flag, in Morton order; flags has
  // bit i set for flag i. sortBricks() must have been called after the last insertion.
  void sortBricks();
  template <typename F>
  void forEachSorted(F&& f) const {
    forEachSorted(0, sorted_.size(), f);
  }
  // The same for the sorted bricks first .. last - 1.
  template <typename F>
  void forEachSorted(size_t first, size_t last, F&& f) const;
  // The sorted bricks: Morton code of key >> 3 of the i-th, and which flags any of its voxels
  // has (bit i for flag i).
  uint64_t sortedCode(size_t i) const { return sorted_[i].first; }
  unsigned sortedFlags(size_t i) const;
  // Whether a voxel of the i-th sorted brick has `flag` but not `without`.
  bool sortedAnyWithout(size_t i, int flag, int without) const;

 private:
  struct Brick {
    uint64_t bits[kFlags][8];  // bit (local Morton index) of each voxel, per flag
  };
  static constexpr uint32_t kEmptySlot = 0xFFFFFFFFu;

  static uint64_t brickCode(const octomap::OcTreeKey& key) {
    return spreadBits3(key[2] >> 3) << 2 | spreadBits3(key[1] >> 3) << 1 | spreadBits3(key[0] >> 3);
  }
  static constexpr uint64_t kBrickMask = 0xFFF8FFF8FFF8ull;  // of a packed key
  // The local Morton index (0..511) of a packed key in its brick: one table lookup by its low
  // three bits per axis.
  static unsigned localIndex(uint64_t packed) {
    return kBrickLocalMorton[(packed & 7) | (packed >> 13 & 070) | (packed >> 26 & 0700)];
  }
  static unsigned localIndex(const octomap::OcTreeKey& key) { return localIndex(pack(key)); }
  // The word and bit of (key, flag), creating the brick when missing. Consecutive ray cells
  // mostly stay in one brick, so the brick of the previous call is tried first.
  uint64_t locate(uint64_t packed, int flag, uint64_t** word) {
    if ((packed & kBrickMask) != last_coarse_) {
      last_coarse_ = packed & kBrickMask;
      last_brick_ = &bricks_[findOrAdd(brickCode(unpack(packed)))];
    }
    const unsigned index = localIndex(packed);
    *word = &last_brick_->bits[flag][index >> 6];
    return uint64_t(1) << (index & 63);
  }
  uint32_t findOrAdd(uint64_t code);
  uint32_t find(uint64_t code) const;  // kEmptySlot when absent
  void grow();
  size_t slotOf(uint64_t code) const { return (code * 0x9E3779B97F4A7C15ull) >> shift_; }

  std::vector<uint64_t> codes_;  // brick code (Morton code of key >> 3) per brick
  std::vector<Brick> bricks_;
  std::vector<uint32_t> slots_;  // open addressing: brick index or kEmptySlot
  int shift_ = 64;
  uint64_t last_coarse_ = ~0ull;  // the packed key & kBrickMask of the brick found last
  Brick* last_brick_ = nullptr;    // that brick (findOrAdd may move the bricks: set after it)
  std::vector<std::pair<uint64_t, uint32_t>> sorted_;  // (code, brick) after sortBricks()
};

// Local Morton index (0..511) -> key offset inside the brick.
struct BrickOffsets {
  std::array<std::array<uint8_t, 3>, 512> xyz;
  BrickOffsets();
};
const BrickOffsets& brickOffsets();

template <typename F>
void VoxelBricks::forEachSorted(size_t first, size_t last, F&& f) const {
  const BrickOffsets& offsets = brickOffsets();
  for (size_t s = first; s < last; ++s) {
    const auto& [code, index] = sorted_[s];
    const octomap::OcTreeKey base = keyFromMorton(code);
    const Brick& brick = bricks_[index];
    for (unsigned w = 0; w < 8; ++w) {
      uint64_t any = 0;
      for (int flag = 0; flag < kFlags; ++flag) any |= brick.bits[flag][w];
      while (any) {
        const unsigned bit = static_cast<unsigned>(__builtin_ctzll(any));
        any &= any - 1;
        unsigned flags = 0;
        for (int flag = 0; flag < kFlags; ++flag)
          flags |= ((brick.bits[flag][w] >> bit) & 1u) << flag;
        const unsigned local = w * 64 + bit;
        const auto& o = offsets.xyz[local];
        f(octomap::OcTreeKey(static_cast<octomap::key_type>(base[0] * 8 + o[0]),
                             static_cast<octomap::key_type>(base[1] * 8 + o[1]),
                             static_cast<octomap::key_type>(base[2] * 8 + o[2])),
          code << 9 | local, flags);
      }
    }
  }
}

}  // namespace evidential_octomap
