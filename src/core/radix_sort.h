// Stable LSD radix sort of (key, index) pairs by their key's low `key_bits` bits, 16 bits per
// pass: about twice as fast as std::sort for the 10^5 - 10^6 items of a scan. Private to the core.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace evidential_octomap {

template <typename Key, typename Value>
void radixSort(std::vector<std::pair<Key, Value>>* items, int key_bits,
               std::vector<std::pair<Key, Value>>* buffer) {
  buffer->resize(items->size());
  std::vector<size_t> offsets(1 << 16);
  for (int shift = 0; shift < key_bits; shift += 16) {
    std::fill(offsets.begin(), offsets.end(), 0);
    for (const auto& item : *items) ++offsets[(uint64_t(item.first) >> shift) & 0xFFFF];
    size_t sum = 0;
    for (size_t& offset : offsets) sum += std::exchange(offset, sum);
    for (const auto& item : *items) {
      (*buffer)[offsets[(uint64_t(item.first) >> shift) & 0xFFFF]++] = item;
    }
    items->swap(*buffer);
  }
}

}  // namespace evidential_octomap
