#include "ray_casting.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace evidential_octomap {
namespace {

// Calls visit(key) for every key OctoMap's computeRayKeys(origin, end) returns, in the same
// order: the same 3-D DDA (Amanatides & Woo) with the same float and double arithmetic, step
// for step, so the voxels are bit-for-bit OctoMap's (test_ray_casting checks it ray by ray).
// Written out here so that each cell goes straight into the brick set instead of a KeyRay.
template <typename Visit>
bool traceRay(const EvidentialOcTree& tree, const octomap::point3d& origin,
              const octomap::point3d& end, Visit&& visit) {
  octomap::OcTreeKey key_origin, key_end;
  if (!tree.coordToKeyChecked(origin, key_origin) || !tree.coordToKeyChecked(end, key_end)) {
    return false;
  }
  if (key_origin == key_end) return true;
  visit(key_origin);
  octomap::point3d direction = (end - origin);
  const float length = (float)direction.norm();
  direction /= length;
  const double resolution = tree.getResolution();
  int step[3];
  double t_max[3];
  double t_delta[3];
  octomap::OcTreeKey current = key_origin;
  for (unsigned i = 0; i < 3; ++i) {
    if (direction(i) > 0.0) {
      step[i] = 1;
    } else if (direction(i) < 0.0) {
      step[i] = -1;
    } else {
      step[i] = 0;
    }
    if (step[i] != 0) {
      double voxel_border = tree.keyToCoord(current[i]);
      voxel_border += (float)(step[i] * resolution * 0.5);
      t_max[i] = (voxel_border - origin(i)) / direction(i);
      t_delta[i] = resolution / std::fabs(direction(i));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  while (true) {
    unsigned dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    current[dim] += step[dim];
    t_max[dim] += t_delta[dim];
    if (current == key_end) return true;
    // Past the end point without reaching its voxel (rounding): OctoMap stops here too.
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) return true;
    visit(current);
  }
}

}  // namespace

bool rayKeys(const EvidentialOcTree& tree, const octomap::point3d& origin,
             const octomap::point3d& end, std::vector<octomap::OcTreeKey>* keys) {
  keys->clear();
  return traceRay(tree, origin, end, [&](const octomap::OcTreeKey& key) { keys->push_back(key); });
}

void castRays(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
              const octomap::point3d& origin_W, double max_range, bool discretize,
              std::vector<VoxelBricks>* per_thread) {
  const int threads = static_cast<int>(per_thread->size());
  const size_t n = points_W.size();
#pragma omp parallel num_threads(threads)
  {
    VoxelBricks& bricks = (*per_thread)[omp_get_thread_num()];
    bricks.clear();
    const auto mark_free = [&bricks](const octomap::OcTreeKey& key) {
      bricks.testAndSet(key, kRayFree);
    };
#pragma omp for schedule(dynamic, 512)
    for (size_t i = 0; i < n; ++i) {
      octomap::point3d end = points_W[i];
      if (discretize) {
        // One ray per end voxel, to its centre (OctoMap's computeDiscreteUpdate).
        const octomap::OcTreeKey key = tree.coordToKey(end);
        if (bricks.testAndSet(key, kRayEndCast)) continue;
        end = tree.keyToCoord(key);
      }
      const bool within_range = max_range < 0.0 || (end - origin_W).norm() <= max_range;
      const octomap::point3d ray_end =
          within_range ? end : origin_W + (end - origin_W).normalized() * float(max_range);
      traceRay(tree, origin_W, ray_end, mark_free);
      octomap::OcTreeKey key;
      if (within_range && tree.coordToKeyChecked(end, key)) bricks.testAndSet(key, kRayOccupied);
    }
  }
  VoxelBricks& all = (*per_thread)[0];
  for (int t = 1; t < threads; ++t) all.merge((*per_thread)[t]);
  all.sortBricks();
}

}  // namespace evidential_octomap
