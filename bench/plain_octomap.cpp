#include "plain_octomap.h"

#include "bench_data.h"

#ifdef _OPENMP
#error "plain_octomap.cpp must be compiled without OpenMP (see bench/CMakeLists.txt)"
#endif

namespace evbench {

__attribute__((noinline)) double plainInsert(octomap::OcTree& tree,
                                             const octomap::Pointcloud& points_W,
                                             const octomap::point3d& origin_W, double max_range,
                                             bool discretize) {
  const auto start = Clock::now();
  tree.insertPointCloud(points_W, origin_W, max_range, /*lazy_eval=*/false, discretize);
  return msSince(start);
}

}  // namespace evbench

#include "fast_occupancy.h"

namespace evbench {

FastOccupancyTimes plainInsertPhases(octomap::OcTree* tree, const octomap::Pointcloud& points_W,
                                     const octomap::point3d& origin_W, double max_range,
                                     bool discretize) {
  FastOccupancyTimes times;
  auto start = Clock::now();
  octomap::KeySet free_cells, occupied_cells;
  if (discretize) {
    tree->computeDiscreteUpdate(points_W, origin_W, free_cells, occupied_cells, max_range);
  } else {
    tree->computeUpdate(points_W, origin_W, free_cells, occupied_cells, max_range);
  }
  times.ms_keys = msSince(start);
  times.free_keys = free_cells.size();
  times.occupied_keys = occupied_cells.size();
  start = Clock::now();
  for (const auto& k : free_cells) tree->updateNode(k, false, false);
  for (const auto& k : occupied_cells) tree->updateNode(k, true, false);
  times.ms_update = msSince(start);
  return times;
}

}  // namespace evbench
