// Ray casting of one scan, with the semantics of OctoMap's computeUpdate / computeDiscreteUpdate
// (free: voxels a ray crosses before its end voxel; occupied: end voxels within max range; a
// voxel that is both is occupied), but computed in parallel without OctoMap's shared lock.
// Private to the core (not installed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <octomap/OcTreeKey.h>
#include <octomap/Pointcloud.h>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

struct ScanKeys {
  std::vector<octomap::OcTreeKey> free;
  std::vector<octomap::OcTreeKey> occupied;
};

// points_W must be finite and inside the tree's key range.
ScanKeys castRays(const EvidentialOcTree& tree, const octomap::Pointcloud& points_W,
                  const octomap::point3d& origin_W, double max_range, bool discretize,
                  int threads);

}  // namespace evidential_octomap
