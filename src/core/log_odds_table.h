// The distinct occupancy log-odds of a map, so that `.ot` format 5 stores each node's log-odds as
// a 1- or 2-byte index instead of 4 bytes. OctoMap's updates add one of two constants and clamp,
// so a map holds few distinct values (81 among the 3.5 M nodes of the bundled 10-scan map):
// lossless, and a third of the file. Private to the core (ot_format.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace evidential_octomap {

class LogOddsTable {
 public:
  static constexpr uint32_t kMaxValues = 65536;  // beyond: plain f32 (width 4)

  // Records a value; after the first non-finite one or the (kMaxValues + 1)-th distinct one the
  // table gives up and width() is 4.
  void add(float value) {
    if (overflow_) return;
    if (!std::isfinite(value)) {
      overflow_ = true;
      return;
    }
    const uint32_t bits = bitsOf(value);
    if (bits == last_) return;  // runs of equal values are common (free space)
    last_ = bits;
    const size_t slot = find(bits);
    if (keys_[slot] != kEmpty) return;
    if (values_.size() == kMaxValues) {
      overflow_ = true;
      return;
    }
    keys_[slot] = bits;
    values_.push_back(value);
    if (2 * values_.size() > keys_.size()) grow();
  }

  // The order of the file's table: increasing, -0 before +0.
  static bool before(float a, float b) { return a < b || (a == b && bitsOf(a) > bitsOf(b)); }

  // Sorts the values and indexes them.
  void finish() {
    codes_.assign(keys_.size(), 0);
    if (overflow_) return values_.clear();
    std::sort(values_.begin(), values_.end(), before);
    for (uint32_t i = 0; i < values_.size(); ++i) codes_[find(bitsOf(values_[i]))] = i;
  }

  // Bytes per node: 1 (<= 256 values), 2 (<= 65536) or 4 (f32 as in format 4).
  int width() const { return overflow_ ? 4 : (values_.size() <= 256 ? 1 : 2); }
  const std::vector<float>& values() const { return values_; }
  // The index of a value added before finish().
  uint32_t code(float value) const { return codes_[find(bitsOf(value))]; }

 private:
  static constexpr uint32_t kEmpty = 0xFFFFFFFFu;  // a NaN: never a key (add() stops at NaN)
  // The hash table starts small (a map's tile or a tiny map is written often) and doubles to
  // stay at most half full: 2^17 slots for kMaxValues.
  static constexpr int kInitialSlotBits = 8;

  static uint32_t bitsOf(float value) {
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    return bits;
  }
  // The slot of `bits`, or the empty slot where it would go (linear probing).
  size_t find(uint32_t bits) const {
    size_t slot = (bits * 0x9E3779B1u) >> (32 - slot_bits_);
    while (keys_[slot] != kEmpty && keys_[slot] != bits) slot = (slot + 1) & (keys_.size() - 1);
    return slot;
  }

  void grow() {
    std::vector<uint32_t> old(keys_.size() * 2, kEmpty);
    old.swap(keys_);
    ++slot_bits_;
    for (uint32_t bits : old) {
      if (bits != kEmpty) keys_[find(bits)] = bits;
    }
  }

  int slot_bits_ = kInitialSlotBits;
  std::vector<uint32_t> keys_ = std::vector<uint32_t>(size_t(1) << kInitialSlotBits, kEmpty);
  std::vector<uint32_t> codes_;  // filled by finish()
  std::vector<float> values_;
  uint32_t last_ = kEmpty;
  bool overflow_ = false;
};

}  // namespace evidential_octomap
