#include "ray_casting.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace evidential_octomap {
namespace {

// Calls visit(key); its bool result when it returns one, else true (go on).
template <typename Visit>
bool visitKey(Visit& visit, const octomap::OcTreeKey& key) {
  if constexpr (std::is_same_v<decltype(visit(key)), bool>) {
    return visit(key);
  } else {
    visit(key);
    return true;
  }
}

// Calls visit(key) for every key OctoMap's computeRayKeys(origin, end) returns, in the same
// order: the same 3-D DDA (Amanatides & Woo) with the same float and double arithmetic, step
// for step, so the voxels are bit-for-bit OctoMap's (test_ray_casting checks it ray by ray).
// Written out here so that each cell goes straight into the brick set instead of a KeyRay.
// visit may return bool: false stops the ray there (the fast free-space mode).
template <typename Visit>
bool traceRay(const EvidentialOcTree& tree, const octomap::point3d& origin,
              const octomap::point3d& end, Visit&& visit) {
  octomap::OcTreeKey key_origin, key_end;
  if (!tree.coordToKeyChecked(origin, key_origin) || !tree.coordToKeyChecked(end, key_end)) {
    return false;
  }
  if (key_origin == key_end) return true;
  if (!visitKey(visit, key_origin)) return true;
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
    if (!visitKey(visit, current)) return true;
  }
}

// The end of the ray to `end` (the voxel centre under discretize), cut at max_range.
struct RayEnd {
  octomap::point3d end;      // where the free cells stop
  bool occupied;             // the end voxel is a hit within max range
};
RayEnd rayEnd(const EvidentialOcTree& tree, octomap::point3d end, const octomap::point3d& origin,
              double max_range, bool discretize) {
  if (discretize) end = tree.keyToCoord(tree.coordToKey(end));
  const bool within_range = max_range < 0.0 || (end - origin).norm() <= max_range;
  if (within_range) return {end, true};
  return {origin + (end - origin).normalized() * float(max_range), false};
}

// Exact: every ray from the origin, OctoMap's cells.
void castExact(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
               const octomap::point3d& origin_W, double max_range, bool discretize,
               VoxelBricks* bricks) {
  const auto mark_free = [bricks](const octomap::OcTreeKey& key) {
    bricks->testAndSet(key, kRayFree);
  };
#pragma omp for schedule(dynamic, 512)
  for (size_t i = 0; i < points_W.size(); ++i) {
    // discretize: one ray per end voxel, to its centre (OctoMap's computeDiscreteUpdate).
    if (discretize && bricks->testAndSet(tree.coordToKey(points_W[i]), kRayEndCast)) continue;
    const RayEnd ray = rayEnd(tree, points_W[i], origin_W, max_range, discretize);
    traceRay(tree, origin_W, ray.end, mark_free);
    octomap::OcTreeKey key;
    if (ray.occupied && tree.coordToKeyChecked(ray.end, key)) bricks->testAndSet(key, kRayOccupied);
  }
}

// Fast: each ray is traced from its end back towards the origin and stops after
// kFastFreeCollisions consecutive cells this thread has already marked free in this scan (the
// voxblox "fast" integrator's rule): near the sensor the rays of a scan overlap, so most of a
// ray's cells repeat those of its neighbours. Cells a stopped ray would have reached alone stay
// unobserved this scan. Static chunks, so the map does not depend on thread timing.
void castFast(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
              const octomap::point3d& origin_W, double max_range, bool discretize,
              VoxelBricks* bricks) {
  octomap::OcTreeKey origin_key;
  if (!tree.coordToKeyChecked(origin_W, origin_key)) return;
#pragma omp for schedule(static, 512)
  for (size_t i = 0; i < points_W.size(); ++i) {
    if (discretize && bricks->testAndSet(tree.coordToKey(points_W[i]), kRayEndCast)) continue;
    const RayEnd ray = rayEnd(tree, points_W[i], origin_W, max_range, discretize);
    octomap::OcTreeKey end_key;
    if (!tree.coordToKeyChecked(ray.end, end_key)) continue;
    if (end_key != origin_key) bricks->testAndSet(origin_key, kRayFree);
    // Reversed, the first cell is the end voxel (not free) and the origin's is not visited.
    int collisions = 0;
    traceRay(tree, ray.end, origin_W, [&](const octomap::OcTreeKey& key) {
      if (key == end_key) return true;
      collisions = bricks->testAndSet(key, kRayFree) ? collisions + 1 : 0;
      return collisions < kFastFreeCollisions;
    });
    if (ray.occupied) bricks->testAndSet(end_key, kRayOccupied);
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
              bool fast_free_space, std::vector<VoxelBricks>* per_thread) {
  const int threads = static_cast<int>(per_thread->size());
#pragma omp parallel num_threads(threads)
  {
    VoxelBricks& bricks = (*per_thread)[omp_get_thread_num()];
    bricks.clear();
    if (fast_free_space) {
      castFast(tree, points_W, origin_W, max_range, discretize, &bricks);
    } else {
      castExact(tree, points_W, origin_W, max_range, discretize, &bricks);
    }
  }
  VoxelBricks& all = (*per_thread)[0];
  for (int t = 1; t < threads; ++t) all.merge((*per_thread)[t]);
  all.sortBricks();
}

}  // namespace evidential_octomap
