// Stable LSD radix sort of (key, index) pairs by their key's low `key_bits` bits, kDigitBits
// bits per pass: 16 for the 10^5 - 10^6 items of a scan (about twice as fast as std::sort), fewer
// for the few thousand rows of a subtree, whose counts then fit on the stack (one call per
// subtree, no allocation). Private to the core.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace evidential_octomap {

template <int kDigitBits = 16, typename Key, typename Value>
void radixSort(std::vector<std::pair<Key, Value>>* items, int key_bits,
               std::vector<std::pair<Key, Value>>* buffer) {
  constexpr size_t kBuckets = size_t(1) << kDigitBits;
  constexpr uint64_t kMask = kBuckets - 1;
  std::conditional_t<(kDigitBits <= 12), std::array<size_t, kBuckets>, std::vector<size_t>>
      offsets{};
  if constexpr (kDigitBits > 12) offsets.resize(kBuckets);
  buffer->resize(items->size());
  for (int shift = 0; shift < key_bits; shift += kDigitBits) {
    std::fill(offsets.begin(), offsets.end(), 0);
    for (const auto& item : *items) ++offsets[(uint64_t(item.first) >> shift) & kMask];
    size_t sum = 0;
    for (size_t& offset : offsets) sum += std::exchange(offset, sum);
    for (const auto& item : *items)
      (*buffer)[offsets[(uint64_t(item.first) >> shift) & kMask]++] = item;
    items->swap(*buffer);
  }
}

}  // namespace evidential_octomap
