#include "voxel_bricks.h"

#include <algorithm>
#include <cstring>

#include "kept_buffers.h"

namespace evidential_octomap {

BrickOffsets::BrickOffsets() {
  for (unsigned i = 0; i < 512; ++i) {
    xyz[i] = {static_cast<uint8_t>(compactBits3(i)), static_cast<uint8_t>(compactBits3(i >> 1)),
              static_cast<uint8_t>(compactBits3(i >> 2))};
  }
}

const BrickOffsets& brickOffsets() {
  static const BrickOffsets offsets;
  return offsets;
}

void VoxelBricks::clear() {
  codes_.clear();
  bricks_.clear();
  sorted_.clear();
  if (slots_.empty()) {
    slots_.assign(1024, kEmptySlot);
    shift_ = 64 - 10;
  } else {
    std::fill(slots_.begin(), slots_.end(), kEmptySlot);
  }
  last_coarse_ = ~0ull;
}

size_t VoxelBricks::capacityBytes() const {
  return vectorBytes(codes_) + vectorBytes(bricks_) + vectorBytes(slots_) + vectorBytes(sorted_);
}

void VoxelBricks::releaseExcess() {
  const size_t used = codes_.size();
  releaseOversized(&codes_, used);
  releaseOversized(&bricks_, used);
  releaseOversized(&sorted_, used);
  releaseOversized(&slots_, 2 * used);  // grow() keeps the table at most half full
  clear();
}

uint32_t VoxelBricks::find(uint64_t code) const {
  const size_t mask = slots_.size() - 1;
  for (size_t i = slotOf(code);; i = (i + 1) & mask) {
    const uint32_t index = slots_[i];
    if (index == kEmptySlot || codes_[index] == code) return index;
  }
}

uint32_t VoxelBricks::findOrAdd(uint64_t code) {
  const size_t mask = slots_.size() - 1;
  for (size_t i = slotOf(code);; i = (i + 1) & mask) {
    const uint32_t index = slots_[i];
    if (index != kEmptySlot && codes_[index] == code) return index;
    if (index == kEmptySlot) {
      const uint32_t added = static_cast<uint32_t>(codes_.size());
      codes_.push_back(code);
      bricks_.emplace_back();
      std::memset(&bricks_.back(), 0, sizeof(Brick));
      slots_[i] = added;
      if (2 * codes_.size() > slots_.size()) grow();
      return added;
    }
  }
}

void VoxelBricks::grow() {
  slots_.assign(slots_.size() * 2, kEmptySlot);
  --shift_;
  const size_t mask = slots_.size() - 1;
  for (uint32_t index = 0; index < codes_.size(); ++index) {
    size_t i = slotOf(codes_[index]);
    while (slots_[i] != kEmptySlot) i = (i + 1) & mask;
    slots_[i] = index;
  }
}

bool VoxelBricks::test(const octomap::OcTreeKey& key, int flag) const {
  const uint32_t brick = find(brickCode(key));
  if (brick == kEmptySlot) return false;
  const unsigned index = localIndex(key);
  return (bricks_[brick].bits[flag][index >> 6] >> (index & 63)) & 1u;
}

void VoxelBricks::merge(const VoxelBricks& other) {
  for (uint32_t from = 0; from < other.codes_.size(); ++from) {
    Brick& into = bricks_[findOrAdd(other.codes_[from])];
    const Brick& add = other.bricks_[from];
    for (int flag = 0; flag < kFlags; ++flag)
      for (int w = 0; w < 8; ++w) into.bits[flag][w] |= add.bits[flag][w];
  }
  last_coarse_ = ~0ull;
}

unsigned VoxelBricks::sortedFlags(size_t i) const {
  const Brick& brick = bricks_[sorted_[i].second];
  unsigned flags = 0;
  for (int flag = 0; flag < kFlags; ++flag) {
    uint64_t any = 0;
    for (int w = 0; w < 8; ++w) any |= brick.bits[flag][w];
    if (any) flags |= 1u << flag;
  }
  return flags;
}

bool VoxelBricks::sortedAnyWithout(size_t i, int flag, int without) const {
  const Brick& brick = bricks_[sorted_[i].second];
  for (int w = 0; w < 8; ++w) {
    if (brick.bits[flag][w] & ~brick.bits[without][w]) return true;
  }
  return false;
}

void VoxelBricks::sortBricks() {
  sorted_.resize(codes_.size());
  for (uint32_t i = 0; i < codes_.size(); ++i) sorted_[i] = {codes_[i], i};
  std::sort(sorted_.begin(), sorted_.end());
}

}  // namespace evidential_octomap
