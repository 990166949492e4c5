// Morton (z-order) codes of OcTree keys with OctoMap's child order: bit i of x, y, z lands at
// bit 3i, 3i+1, 3i+2, so a run of keys sorted by code is sorted by child index at every depth
// and every subtree is one contiguous run. Private to the core.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>
// OcTreeKey.h needs size_t, uint16_t and std::vector declared before it.
#include <octomap/OcTreeKey.h>

namespace evidential_octomap {

// The 16 bits of v spread to every third bit.
constexpr uint64_t spreadBits3(uint64_t v) {
  v &= 0xFFFF;
  v = (v | (v << 16)) & 0x0000FF0000FFull;
  v = (v | (v << 8)) & 0x00F00F00F00Full;
  v = (v | (v << 4)) & 0x0C30C30C30C3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}

inline uint64_t mortonCode(const octomap::OcTreeKey& k) {
  return spreadBits3(k[2]) << 2 | spreadBits3(k[1]) << 1 | spreadBits3(k[0]);
}

// octomap::computeChildIdx without its branches (a key's bits are as good as random to a
// branch predictor): bit `level` of x, y and z as the child index 0..7.
inline unsigned childIndex(const octomap::OcTreeKey& k, int level) {
  return ((k[0] >> level) & 1u) | ((k[1] >> level) & 1u) << 1 | ((k[2] >> level) & 1u) << 2;
}

// Inverse of spreadBits3: every third bit of v, packed.
inline uint64_t compactBits3(uint64_t v) {
  v &= 0x249249249249ull;
  v = (v | (v >> 2)) & 0x0C30C30C30C3ull;
  v = (v | (v >> 4)) & 0x00F00F00F00Full;
  v = (v | (v >> 8)) & 0x0000FF0000FFull;
  v = (v | (v >> 16)) & 0xFFFF;
  return v;
}

// The Morton index of the voxel x | y << 3 | z << 6 (0..7 each) of an 8x8x8 block.
constexpr std::array<uint16_t, 512> brickLocalMortonTable() {
  std::array<uint16_t, 512> table{};
  for (unsigned i = 0; i < 512; ++i)
    table[i] = uint16_t(spreadBits3(i & 7) | spreadBits3(i >> 3 & 7) << 1 |
                        spreadBits3(i >> 6) << 2);
  return table;
}
inline constexpr std::array<uint16_t, 512> kBrickLocalMorton = brickLocalMortonTable();

inline octomap::OcTreeKey keyFromMorton(uint64_t code) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(compactBits3(code)),
                            static_cast<octomap::key_type>(compactBits3(code >> 1)),
                            static_cast<octomap::key_type>(compactBits3(code >> 2)));
}

}  // namespace evidential_octomap
