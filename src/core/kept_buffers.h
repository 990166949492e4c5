// The scratch buffers the integrator keeps from one scan to the next: what they cost and the
// rule that bounds them. Keeping them saves allocating and page-faulting them every scan, but a
// buffer that grew for one huge scan would hold that memory for ever; so at the end of a scan a
// buffer holding more than twice what the scan needed (and more than kKeptSlackBytes) is released,
// and the next scan allocates what it needs. Private to the core.
#pragma once

#include <cstddef>
#include <vector>

namespace evidential_octomap {

constexpr size_t kKeptSlackBytes = size_t(256) << 10;

template <typename T>
size_t vectorBytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

// `used`: the most elements the buffer held during the scan. Its contents are dropped.
template <typename T>
void releaseOversized(std::vector<T>* v, size_t used) {
  if (vectorBytes(*v) > kKeptSlackBytes && v->capacity() > 2 * used) std::vector<T>().swap(*v);
}

}  // namespace evidential_octomap
