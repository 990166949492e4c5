// The first two phases of an insert, which only read the map: OctoMap ray casting for occupancy,
// then the scan's semantic points (threshold, down-sampling, opinions, supports), grouped by the
// subtrees they update. The tree applies them itself in one pass (the third phase,
// EvidentialOcTree::insertSemanticScan and batched_update.cpp), where the one kernel loop spreads
// every kept point's extended belief to the leaves within its support (docs/design.md).
#pragma once

#include <octomap/Pointcloud.h>

#include <memory>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

class SubtreeSource;

class ScanIntegrator {
 public:
  explicit ScanIntegrator(const SemanticConfig& config);
  ~ScanIntegrator();
  ScanIntegrator(const ScanIntegrator&) = delete;
  ScanIntegrator& operator=(const ScanIntegrator&) = delete;

  int threads() const;  // of the semantic pass: the settings' threads, or OpenMP's default
  // Bytes the scratch buffers kept for the next scan hold.
  size_t scratchBytes() const;

  // points_W: N points in the world (tree) frame.
  // evidence: N x C row-major evidence, C = tree.numClasses().
  // origin_W: sensor origin in the world frame, where every ray starts.
  // keep_unobserved: rows for voxels without a leaf are wanted (subtrees everywhere).
  // Returns the subtrees to update, valid until the next call; nullptr when no point lies inside
  // the map's key range. Throws std::invalid_argument, having read nothing into the map, for
  // evidence of the wrong size, a bad value or an origin outside the map.
  SubtreeSource* prepare(const octomap::Pointcloud& points_W, const std::vector<float>& evidence,
                         const octomap::point3d& origin_W, const EvidentialOcTree& tree,
                         bool keep_unobserved, InsertStats* stats);
  // After the tree applied them: the kernel loop ran inside the update pass, so its CPU time
  // moves to the kernel phase; scratch beyond this scan's needs is released.
  void finish(InsertStats* stats);

 private:
  struct Scratch;
  SemanticConfig config_;
  std::unique_ptr<Scratch> scratch_;
};

}  // namespace evidential_octomap
