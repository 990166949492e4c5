#include "evidential_octomap/evidence/neighbour_grid.h"

#include <algorithm>
#include <cmath>

namespace evidential_octomap {

NeighbourGrid::NeighbourGrid(const float* xyz, size_t num_points, float radius,
                             const std::vector<uint8_t>* skip)
    : xyz_(xyz), radius_(radius), inv_radius_(1.0f / radius) {
  std::vector<std::pair<uint64_t, uint32_t>> keyed;
  keyed.reserve(num_points);
  for (size_t i = 0; i < num_points; ++i) {
    if (skip && (*skip)[i]) continue;
    const Cell c = cellOf(xyz + 3 * i);
    keyed.emplace_back(key(c.x, c.y, c.z), uint32_t(i));
  }
  std::sort(keyed.begin(), keyed.end());
  order_.resize(keyed.size());
  cells_.reserve(keyed.size() / 4 + 1);
  for (size_t b = 0; b < keyed.size();) {
    size_t e = b;
    while (e < keyed.size() && keyed[e].first == keyed[b].first) {
      order_[e] = keyed[e].second;
      ++e;
    }
    cells_.emplace(keyed[b].first, std::make_pair(uint32_t(b), uint32_t(e)));
    b = e;
  }
}

NeighbourGrid::Cell NeighbourGrid::cellOf(const float* p) const {
  return {int(std::floor(p[0] * inv_radius_)), int(std::floor(p[1] * inv_radius_)),
          int(std::floor(p[2] * inv_radius_))};
}

uint64_t NeighbourGrid::key(int x, int y, int z) {
  return (uint64_t(uint32_t(x) & 0x1FFFFF) << 42) | (uint64_t(uint32_t(y) & 0x1FFFFF) << 21) |
         uint64_t(uint32_t(z) & 0x1FFFFF);
}

void NeighbourGrid::nearest(size_t i, int k, std::vector<std::pair<float, uint32_t>>* out) const {
  out->clear();
  const float* p = xyz_ + 3 * i;
  const Cell c = cellOf(p);
  const float r2 = radius_ * radius_;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = cells_.find(key(c.x + dx, c.y + dy, c.z + dz));
        if (it == cells_.end()) continue;
        for (uint32_t s = it->second.first; s < it->second.second; ++s) {
          const float* q = xyz_ + 3 * size_t(order_[s]);
          const float ddx = q[0] - p[0], ddy = q[1] - p[1], ddz = q[2] - p[2];
          const float d2 = ddx * ddx + ddy * ddy + ddz * ddz;
          if (d2 <= r2) out->emplace_back(d2, order_[s]);
        }
      }
  if (int(out->size()) > k) {
    std::nth_element(out->begin(), out->begin() + (k - 1), out->end());
    out->resize(size_t(k));
  }
  std::sort(out->begin(), out->end());
}

}  // namespace evidential_octomap
