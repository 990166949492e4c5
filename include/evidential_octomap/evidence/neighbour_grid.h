// k-nearest neighbours within a radius, by a hash grid of cells of that radius: the query scans
// the 27 cells around a point. O(N) build, no dependency; fine for one LiDAR scan. The one kNN of
// the project: the learned evidence's point features and the derived knn-vote evidence use it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace evidential_octomap {

class NeighbourGrid {
 public:
  // `xyz`: N x 3 (borrowed, must outlive the grid); points with skip[i] != 0 are left out.
  NeighbourGrid(const float* xyz, size_t num_points, float radius,
                const std::vector<uint8_t>* skip = nullptr);

  // Up to k nearest points (the point itself included) within the radius of point i, as
  // (squared distance, index), nearest first. `out` is reused to avoid allocations.
  void nearest(size_t i, int k, std::vector<std::pair<float, uint32_t>>* out) const;

 private:
  struct Cell {
    int x, y, z;
  };
  Cell cellOf(const float* p) const;
  static uint64_t key(int x, int y, int z);

  const float* xyz_;
  float radius_, inv_radius_;
  std::vector<uint32_t> order_;  // point indices sorted by cell
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> cells_;  // [begin, end) in order_
};

}  // namespace evidential_octomap
