// Ray casting of one scan, with the semantics of OctoMap's computeUpdate / computeDiscreteUpdate
// (free: voxels a ray crosses before its end voxel; occupied: end voxels within max range; a
// voxel that is both is occupied), computed in parallel without OctoMap's shared key sets.
// Private to the core (not installed).
#pragma once

#include <octomap/Pointcloud.h>

#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "voxel_bricks.h"

namespace evidential_octomap {

// Flags of VoxelBricks that ray casting sets.
enum RayFlag : int {
  kRayFree = 0,      // crossed by a ray
  kRayOccupied = 1,  // an end voxel within max range
  kRayEndCast = 2,   // discretize: a ray to this voxel's centre was cast already
};

// The keys OctoMap's computeRayKeys(origin, end) returns, in its order, computed by the same
// arithmetic (exposed for the test that proves it); false when an end is outside the key range.
bool rayKeys(const EvidentialOcTree& tree, const octomap::point3d& origin,
             const octomap::point3d& end, std::vector<octomap::OcTreeKey>* keys);

// Fast free space: a ray traced back from its end takes the shortcut after this many
// consecutive cells already marked free in the same scan; past it, it clears only the voxels it
// crosses that are occupied or hold semantics.
constexpr int kFastFreeCollisions = 2;

// Casts the rays of points_W (finite, inside the tree's key range) from origin_W. per_thread
// holds one VoxelBricks per thread, reused across scans; the result is in per_thread[0], bricks
// sorted (forEachSorted). fast_free_space: SemanticConfig::fast_free_space.
void castRays(const EvidentialOcTree& tree, const std::vector<octomap::point3d>& points_W,
              const octomap::point3d& origin_W, double max_range, bool discretize,
              bool fast_free_space, std::vector<VoxelBricks>* per_thread);

}  // namespace evidential_octomap
