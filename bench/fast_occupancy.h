// Bench-only prototype (not library code): the same occupancy update as OctoMap's
// insertPointCloud(..., discretize) on a plain octomap::OcTree, restructured for speed, to measure
// what the lead's hot path could gain:
//   1. end points discretised and de-duplicated in a flat open-addressing hash set;
//   2. rays cast in parallel (OpenMP), free keys de-duplicated per thread in flat hash sets
//      (OctoMap: one std::unordered_set behind an omp critical section);
//   3. free minus occupied, every key list sorted in Morton order, so consecutive updateNode
//      calls walk almost the same root-to-leaf path (OctoMap: hash order, a cache miss per level).
// The resulting map is the same as OctoMap's (checked by evidential_bench --verify-prototype).
#pragma once

#include <cstdint>
#include <vector>

#include <octomap/OcTree.h>

namespace evbench {

struct FastOccupancyTimes {
  double ms_keys = 0.0;    // end points, ray casting, de-duplication, sorting
  double ms_update = 0.0;  // updateNode calls (with inner-node updates, lazy_eval = false)
  size_t free_keys = 0, occupied_keys = 0;
};

class FastOccupancy {
 public:
  explicit FastOccupancy(int threads) : threads_(threads > 0 ? threads : 1) {}
  FastOccupancyTimes insert(octomap::OcTree* tree, const octomap::Pointcloud& points_W,
                            const octomap::point3d& origin_W, double max_range, bool discretize);

 private:
  int threads_;
};

// OctoMap's own insertPointCloud split into its two phases (computeUpdate / computeDiscreteUpdate,
// then the updateNode loops), in the non-OpenMP translation unit: where plain OctoMap spends time.
FastOccupancyTimes plainInsertPhases(octomap::OcTree* tree, const octomap::Pointcloud& points_W,
                                     const octomap::point3d& origin_W, double max_range,
                                     bool discretize);

// Order-independent fingerprint of a map's leaves: (volume-weighted log-odds sum, occupied volume
// in voxels, leaf count). Equal maps give equal fingerprints.
struct MapFingerprint {
  double weighted_log_odds = 0.0;
  double occupied_voxels = 0.0;
  double known_voxels = 0.0;
};
MapFingerprint fingerprint(const octomap::OcTree& tree);

}  // namespace evbench
