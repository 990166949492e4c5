#include "ray_casting.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <limits>

namespace evidential_octomap {
namespace {

// A 3-D DDA (Amanatides & Woo) along the ray from `from` in the unit direction `dir` over a grid
// of cubes of edge `cell`: per axis the step, the ray parameter t at which the next face is
// crossed and the t between faces. `centre` is the start cube's centre.
struct Dda {
  int step[3];
  double t_max[3], t_delta[3];
  double t_entry = 0.0;  // where the ray entered the current cube

  Dda(const octomap::point3d& from, const octomap::point3d& dir, const double centre[3],
      double cell) {
    for (unsigned i = 0; i < 3; ++i) {
      step[i] = dir(i) > 0.0 ? 1 : (dir(i) < 0.0 ? -1 : 0);
      if (step[i] == 0) {
        t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
        continue;
      }
      double border = centre[i];
      border += (float)(step[i] * cell * 0.5);
      t_max[i] = (border - from(i)) / dir(i);
      t_delta[i] = cell / std::fabs(dir(i));
    }
  }
  // Crosses the nearest face; returns its axis.
  unsigned advance() {
    unsigned dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    t_entry = t_max[dim];
    t_max[dim] += t_delta[dim];
    return dim;
  }
  double exit() const { return std::min(std::min(t_max[0], t_max[1]), t_max[2]); }
  // After advance() along `dim`: the cube the ray touches at an edge or corner of the grid as it
  // crosses that face (another axis's face crossed within `eps` of it), else false. There the
  // exact DDA may have taken either neighbour; walks that do not start from the origin touch
  // both.
  bool touchedAtEdge(unsigned dim, double eps, octomap::OcTreeKey* key) const {
    for (unsigned j = 0; j < 3; ++j) {
      if (j == dim || !(t_max[j] - t_entry < eps)) continue;
      (*key)[dim] -= step[dim];
      (*key)[j] += step[j];
      return true;
    }
    return false;
  }
};

// Within this of a voxel edge (in t, metres per resolution), a walk touches both neighbours.
constexpr double kEdgeTolerance = 1e-4;

Dda voxelDda(const EvidentialOcTree& tree, const octomap::point3d& from,
             const octomap::point3d& dir, const octomap::OcTreeKey& key) {
  const double centre[3] = {tree.keyToCoord(key[0]), tree.keyToCoord(key[1]),
                            tree.keyToCoord(key[2])};
  return Dda(from, dir, centre, tree.getResolution());
}

// Calls visit(packed key, VoxelBricks::pack) for every key OctoMap's computeRayKeys(origin,
// end) returns, in the same order: the same DDA with the same float and double arithmetic, step
// for step, so the voxels are bit-for-bit OctoMap's (test_ray_casting checks it ray by ray).
// Written out here so that each cell goes straight into the brick set instead of a KeyRay, with
// the ray state in registers (the step is a branch per axis rather than an indexed store that
// the next step must load) and the key one integer that a step adds a constant to.
template <typename Visit>
bool traceRay(const EvidentialOcTree& tree, const octomap::point3d& origin,
              const octomap::point3d& end, Visit&& visit) {
  octomap::OcTreeKey key_origin, key_end;
  if (!tree.coordToKeyChecked(origin, key_origin) || !tree.coordToKeyChecked(end, key_end)) {
    return false;
  }
  if (key_origin == key_end) return true;
  uint64_t current = VoxelBricks::pack(key_origin);
  const uint64_t last = VoxelBricks::pack(key_end);
  visit(current);
  octomap::point3d direction = (end - origin);
  const float length = (float)direction.norm();
  direction /= length;
  const Dda dda = voxelDda(tree, origin, direction, key_origin);
  double tx = dda.t_max[0], ty = dda.t_max[1], tz = dda.t_max[2];
  const double dx = dda.t_delta[0], dy = dda.t_delta[1], dz = dda.t_delta[2];
  // A step of -1 adds 2^64 - 2^(16 a): the same key in 64-bit wrap-around arithmetic.
  const uint64_t sx = uint64_t(int64_t(dda.step[0])), sy = uint64_t(int64_t(dda.step[1])) << 16,
                 sz = uint64_t(int64_t(dda.step[2])) << 32;
  while (true) {
    if (tx < ty) {
      if (tx < tz) {
        current += sx;
        tx += dx;
      } else {
        current += sz;
        tz += dz;
      }
    } else if (ty < tz) {
      current += sy;
      ty += dy;
    } else {
      current += sz;
      tz += dz;
    }
    if (current == last) return true;
    // Past the end point without reaching its voxel (rounding): OctoMap stops here too.
    if (std::min(std::min(tx, ty), tz) > length) return true;
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
  const auto mark_free = [bricks](uint64_t packed) { bricks->testAndSet(packed, kRayFree); };
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

// The voxels of an 8x8x8 block of the tree (a brick of voxel_bricks.h) that are occupied or hold
// semantics, read from the map as it was before the scan; nullptr for a block that holds none
// (read from the node three levels above the leaves alone: an inner node's log-odds is its
// children's maximum and it carries a payload when any leaf below it does). One direct-mapped
// cache per thread and scan: neighbouring rays cross the same blocks.
class HeldVoxels {
 public:
  struct Block {
    uint64_t bits[8];    // word z, bit 8 y + x of the local key
    int lo[3], hi[3];    // the box of the held voxels, in local keys (0..7)
    bool isSet(const octomap::OcTreeKey& key) const {
      return bits[key[2] & 7] >> ((key[1] & 7) * 8 + (key[0] & 7)) & 1;
    }
  };

  explicit HeldVoxels(const EvidentialOcTree& tree)
      : tree_(tree), codes_(kSlots, kEmpty), blocks_(kSlots) {}

  const Block* block(const octomap::OcTreeKey& key) {
    const uint64_t code = uint64_t(key[0] >> 3) | uint64_t(key[1] >> 3) << 13 |
                          uint64_t(key[2] >> 3) << 26;
    const size_t slot = (code * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits);
    Block& block = blocks_[slot];
    if (codes_[slot] != code) {
      codes_[slot] = code;
      const EvidentialOcTreeNode* node = tree_.search(key, tree_.getTreeDepth() - 3);
      held_[slot] = node && holds(node);
      if (held_[slot]) {
        block = Block{{0}, {8, 8, 8}, {-1, -1, -1}};
        addHeld(node, 3, {0, 0, 0}, &block);
      }
    }
    return held_[slot] ? &block : nullptr;
  }

 private:
  bool holds(const EvidentialOcTreeNode* node) const {
    return tree_.isNodeOccupied(node) || node->hasSemantics();
  }
  // The held voxels below `node`, `levels` above the leaves, whose first voxel is `at`.
  void addHeld(const EvidentialOcTreeNode* node, int levels, std::array<int, 3> at,
               Block* block) const {
    if (!tree_.nodeHasChildren(node)) {
      if (!holds(node)) return;
      const int size = 1 << levels;
      const uint64_t row = ((uint64_t(1) << size) - 1) << at[0];
      for (int dz = 0; dz < size; ++dz)
        for (int dy = 0; dy < size; ++dy) block->bits[at[2] + dz] |= row << ((at[1] + dy) * 8);
      for (int a = 0; a < 3; ++a) {
        block->lo[a] = std::min(block->lo[a], at[a]);
        block->hi[a] = std::max(block->hi[a], at[a] + size - 1);
      }
      return;
    }
    const int half = 1 << (levels - 1);
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree_.nodeChildExists(node, i)) continue;
      const EvidentialOcTreeNode* child = tree_.getNodeChild(node, i);
      if (!holds(child)) continue;
      addHeld(child, levels - 1,
              {at[0] + (i & 1 ? half : 0), at[1] + (i & 2 ? half : 0), at[2] + (i & 4 ? half : 0)},
              block);
    }
  }

  static constexpr int kSlotBits = 14;
  static constexpr size_t kSlots = size_t(1) << kSlotBits;
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  const EvidentialOcTree& tree_;
  std::vector<uint64_t> codes_;
  std::vector<Block> blocks_;
  std::bitset<kSlots> held_;
};

// Fast free space, first phase: the ray's cells from its end back towards the origin, marked
// free until kFastFreeCollisions consecutive cells were already marked in this scan by this
// thread (the voxblox "fast" integrator's rule: near the sensor the rays of a scan overlap).
// Returns the ray parameter (from the origin) up to which the rest is left to the second
// phase, or a negative value when the walk reached the origin's cell.
double walkBackFromEnd(const EvidentialOcTree& tree, const octomap::point3d& end,
                       const octomap::OcTreeKey& end_key, const octomap::OcTreeKey& origin_key,
                       const octomap::point3d& dir, float length, VoxelBricks* bricks) {
  Dda back = voxelDda(tree, end, -dir, end_key);
  const double edge = kEdgeTolerance * tree.getResolution();
  octomap::OcTreeKey key = end_key;
  int collisions = 0;
  while (true) {
    const unsigned dim = back.advance();
    key[dim] += back.step[dim];
    if (key == origin_key || back.t_entry > length) return -1.0;
    octomap::OcTreeKey touched = key;
    if (back.touchedAtEdge(dim, edge, &touched)) bricks->testAndSet(touched, kRayFree);
    collisions = bricks->testAndSet(key, kRayFree) ? collisions + 1 : 0;
    if (collisions >= kFastFreeCollisions) return length - back.t_entry;
  }
}

// The part [t_a, t_b] of the ray that lies in the box of the held voxels of `block` (its first
// key `corner`); false when the ray misses the box.
bool clipToHeldBox(const EvidentialOcTree& tree, const octomap::point3d& origin,
                   const octomap::point3d& dir, const octomap::OcTreeKey& corner,
                   const HeldVoxels::Block& block, double* t_a, double* t_b) {
  const double half = tree.getResolution() / 2.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = tree.keyToCoord(octomap::key_type(corner[a] + block.lo[a])) - half - origin(a);
    const double hi = tree.keyToCoord(octomap::key_type(corner[a] + block.hi[a])) + half - origin(a);
    if (dir(a) == 0.0f) {
      if (lo > 0.0 || hi < 0.0) return false;
      continue;
    }
    const double t0 = lo / dir(a), t1 = hi / dir(a);
    *t_a = std::max(*t_a, std::min(t0, t1));
    *t_b = std::min(*t_b, std::max(t0, t1));
  }
  return *t_a <= *t_b;
}

// The held voxels of one block that the ray crosses between t_a and t_b, marked free. The walk
// starts a hair before t_a, so that where the ray crosses a voxel face at about the same t as
// t_a it takes the exact DDA's road (a start rounded onto the face could put it one voxel on).
void clearInBlock(const EvidentialOcTree& tree, const octomap::point3d& origin,
                  const octomap::point3d& dir, const octomap::OcTreeKey& corner,
                  const HeldVoxels::Block& block, double t_a, double t_b, VoxelBricks* bricks) {
  const float t_start = float(std::max(t_a - 1e-3 * tree.getResolution(), 0.0));
  octomap::OcTreeKey key = tree.coordToKey(origin + dir * t_start);
  Dda voxels = voxelDda(tree, origin, dir, key);
  const double edge = kEdgeTolerance * tree.getResolution();
  const auto clear = [&](const octomap::OcTreeKey& k) {
    const bool in_block = (k[0] >> 3) == (corner[0] >> 3) && (k[1] >> 3) == (corner[1] >> 3) &&
                          (k[2] >> 3) == (corner[2] >> 3);
    if (in_block && block.isSet(k)) bricks->testAndSet(k, kRayFree);
  };
  while (true) {
    clear(key);
    if (voxels.exit() >= t_b) return;
    const unsigned dim = voxels.advance();
    key[dim] += voxels.step[dim];
    octomap::OcTreeKey touched = key;
    if (voxels.touchedAtEdge(dim, edge, &touched)) clear(touched);
  }
}

// Second phase: from the origin to t_stop, block by block (8x8x8 voxels), the voxels the ray
// crosses that hold something (HeldVoxels) are marked free, so that an occupied voxel or class
// evidence a mover left behind is cleared as in the exact mode; a block that holds nothing is
// crossed in one step, and in a block that does only the box of what it holds is walked. Free
// space without semantics is what it skips: voxels only a shortcut ray crosses there stay
// unobserved this scan.
void clearHeldUpTo(const EvidentialOcTree& tree, const octomap::point3d& origin,
                   const octomap::OcTreeKey& origin_key, const octomap::point3d& dir,
                   double t_stop, HeldVoxels* held, VoxelBricks* bricks) {
  const double resolution = tree.getResolution();
  octomap::OcTreeKey corner;  // the first key of the block at hand
  double centre[3];
  for (int a = 0; a < 3; ++a) {
    corner[a] = octomap::key_type(origin_key[a] & ~7);
    centre[a] = tree.keyToCoord(corner[a]) + 3.5 * resolution;
  }
  Dda blocks(origin, dir, centre, 8 * resolution);
  double t_in = 0.0;
  while (t_in <= t_stop) {
    double t_a = t_in, t_b = std::min(blocks.exit(), t_stop);
    const HeldVoxels::Block* block = held->block(corner);
    if (block && clipToHeldBox(tree, origin, dir, corner, *block, &t_a, &t_b))
      clearInBlock(tree, origin, dir, corner, *block, t_a, t_b, bricks);
    const unsigned dim = blocks.advance();
    corner[dim] = octomap::key_type(corner[dim] + 8 * blocks.step[dim]);
    t_in = blocks.t_entry;
  }
}

// Fast: each ray's cells are walked from its end back towards the origin until its shortcut
// (walkBackFromEnd), and past it only the voxels that hold something are cleared
// (clearHeldUpTo). Static chunks, so the map does not depend on thread timing.
void castFast(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
              const octomap::point3d& origin_W, double max_range, bool discretize,
              VoxelBricks* bricks) {
  HeldVoxels held(tree);
  octomap::OcTreeKey origin_key;
  if (!tree.coordToKeyChecked(origin_W, origin_key)) return;
#pragma omp for schedule(static, 512)
  for (size_t i = 0; i < points_W.size(); ++i) {
    if (discretize && bricks->testAndSet(tree.coordToKey(points_W[i]), kRayEndCast)) continue;
    const RayEnd ray = rayEnd(tree, points_W[i], origin_W, max_range, discretize);
    octomap::OcTreeKey end_key;
    if (!tree.coordToKeyChecked(ray.end, end_key)) continue;
    if (ray.occupied) bricks->testAndSet(end_key, kRayOccupied);
    if (end_key == origin_key) continue;
    bricks->testAndSet(origin_key, kRayFree);
    octomap::point3d dir = ray.end - origin_W;
    const float length = (float)dir.norm();
    dir /= length;
    const double t_stop = walkBackFromEnd(tree, ray.end, end_key, origin_key, dir, length, bricks);
    if (t_stop >= 0.0) clearHeldUpTo(tree, origin_W, origin_key, dir, t_stop, &held, bricks);
  }
}

}  // namespace

bool rayKeys(const EvidentialOcTree& tree, const octomap::point3d& origin,
             const octomap::point3d& end, std::vector<octomap::OcTreeKey>* keys) {
  keys->clear();
  return traceRay(tree, origin, end,
                  [&](uint64_t packed) { keys->push_back(VoxelBricks::unpack(packed)); });
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
