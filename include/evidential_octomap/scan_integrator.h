// One scan into the map: OctoMap ray casting for occupancy, then one kernel loop that spreads
// every kept point's extended belief to the leaves within its support, aggregated per voxel key
// for the whole scan before each touched leaf is updated once (docs/design.md).
#pragma once

#include <octomap/Pointcloud.h>

#include <memory>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

class ScanIntegrator {
 public:
  explicit ScanIntegrator(const SemanticConfig& config);
  ~ScanIntegrator();
  ScanIntegrator(const ScanIntegrator&) = delete;
  ScanIntegrator& operator=(const ScanIntegrator&) = delete;

  const SemanticConfig& config() const { return config_; }
  // Bytes the scratch buffers kept for the next scan hold.
  size_t scratchBytes() const;

  // points_W: N points in the world (tree) frame.
  // evidence: N x C row-major evidence, C = tree->numClasses().
  // origin_W: sensor origin in the world frame, where every ray starts.
  // tree:     the map to update; the fusion rule is the tree's own.
  // unobserved: optional; receives the evidence the kernel spreads to voxels `tree` has not
  //           observed (which `tree` drops unless kernel_creates_leaves), see
  //           EvidentialOcTree::addEvidence.
  // Throws std::invalid_argument before touching the map when evidence is malformed or the
  // kernel support exceeds SemanticConfig::kMaxSupportLeaves (supportProblem()).
  // Scratch buffers are kept from one call to the next (one integrator per thread).
  InsertStats integrate(const octomap::Pointcloud& points_W, const std::vector<float>& evidence,
                        const octomap::point3d& origin_W, EvidentialOcTree* tree,
                        EvidentialOcTree* unobserved = nullptr);

 private:
  struct Scratch;
  SemanticConfig config_;
  std::unique_ptr<Scratch> scratch_;
};

}  // namespace evidential_octomap
