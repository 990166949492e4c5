#include "ray_casting.h"

#include <omp.h>

#include <algorithm>
#include <bitset>
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

// Which 8x8x8 blocks of the tree (the bricks of voxel_bricks.h) hold a voxel that is occupied or
// has semantics, read from the node three levels above the leaves: an inner node's log-odds is
// its children's maximum and it carries a payload when any leaf below it does. The map as it was
// before the scan; one direct-mapped cache per thread and scan (a ray stays in a block for
// several cells, and neighbouring rays cross the same blocks).
class HeldBlocks {
 public:
  explicit HeldBlocks(const EvidentialOcTree& tree) : tree_(tree), codes_(kSlots, kEmpty) {}
  bool holds(const octomap::OcTreeKey& key) {
    const uint64_t code = uint64_t(key[0] >> 3) | uint64_t(key[1] >> 3) << 13 |
                          uint64_t(key[2] >> 3) << 26;
    const size_t slot = (code * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits);
    if (codes_[slot] != code) {
      const EvidentialOcTreeNode* node = tree_.search(key, tree_.getTreeDepth() - 3);
      codes_[slot] = code;
      held_[slot] = node && (tree_.isNodeOccupied(node) || node->hasSemantics());
    }
    return held_[slot];
  }

 private:
  static constexpr int kSlotBits = 14;
  static constexpr size_t kSlots = size_t(1) << kSlotBits;
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  const EvidentialOcTree& tree_;
  std::vector<uint64_t> codes_;
  std::bitset<kSlots> held_;
};

// Fast: each ray's cells (OctoMap's, as in the exact mode) are walked from its end back towards
// the origin, and the walk takes the shortcut after kFastFreeCollisions consecutive cells this
// thread has already marked free in this scan (the voxblox "fast" integrator's rule): near the
// sensor the rays of a scan overlap, so most of a ray's cells repeat those of its neighbours.
// Past the shortcut the ray still clears every cell in a block that holds something
// (HeldBlocks): an occupied voxel or class evidence that a mover left behind is cleared as in
// the exact mode; only space that is free and holds no semantics is skipped (cells only a
// shortcut ray crosses there stay unobserved this scan). Static chunks, so the map does not
// depend on thread timing.
void castFast(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
              const octomap::point3d& origin_W, double max_range, bool discretize,
              VoxelBricks* bricks) {
  HeldBlocks held(tree);
  std::vector<octomap::OcTreeKey> keys;
  keys.reserve(1024);
#pragma omp for schedule(static, 512)
  for (size_t i = 0; i < points_W.size(); ++i) {
    if (discretize && bricks->testAndSet(tree.coordToKey(points_W[i]), kRayEndCast)) continue;
    const RayEnd ray = rayEnd(tree, points_W[i], origin_W, max_range, discretize);
    octomap::OcTreeKey end_key;
    if (!tree.coordToKeyChecked(ray.end, end_key)) continue;
    keys.clear();
    traceRay(tree, origin_W, ray.end, [&](const octomap::OcTreeKey& key) { keys.push_back(key); });
    int collisions = 0;
    for (size_t k = keys.size(); k-- > 1;) {
      if (collisions < kFastFreeCollisions) {
        collisions = bricks->testAndSet(keys[k], kRayFree) ? collisions + 1 : 0;
      } else if (held.holds(keys[k])) {
        bricks->testAndSet(keys[k], kRayFree);
      }
    }
    if (!keys.empty()) bricks->testAndSet(keys[0], kRayFree);  // the origin's cell
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
