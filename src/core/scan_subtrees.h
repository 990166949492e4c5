// One scan's updates, subtree by subtree (subtree_source.h): the voxels its rays crossed or
// ended in (VoxelBricks) merged in Morton order with the kernel rows that its semantic points
// give the subtree (KernelPass), computed when the tree update asks for the subtree. Private to
// the core.
#pragma once

#include <array>
#include <vector>

#include "kernel_pass.h"
#include "subtree_source.h"
#include "voxel_bricks.h"

namespace evidential_octomap {

class ScanSubtrees : public SubtreeSource {
 public:
  // Which voxels get kernel rows: every voxel of the supports (the map creates leaves for
  // them, or keeps the rows it drops), the voxels the map keeps (its leaves and this scan's
  // ray voxels: the same map, less work), or only occupied ones (SemanticConfig::
  // semantic_occupied_only: occupied leaves and this scan's end voxels).
  enum class Targets { kEverywhere, kKept, kOccupied };
  // rays: sorted, with the flags of ray_casting.h. points / kernel_points: the semantic points.
  // All must outlive the source.
  void build(const EvidentialOcTree& tree, const VoxelBricks& rays, const SemanticPoints& points,
             const std::vector<KernelPoint>& kernel_points, const KernelPass& kernel, int threads,
             Targets targets);
  const std::vector<SubtreeSeed>& seeds() const override { return seeds_; }
  SubtreeView updates(size_t i, int thread, const EvidentialOcTreeNode* existing) override;
  // Bytes the buffers hold (capacity, kept from scan to scan), and the release of what this
  // scan did not need (kept_buffers.h), after the tree update.
  size_t capacityBytes() const;
  void releaseExcess();
  // CPU time the threads spent in the kernel loop since build() [ms].
  double kernelCpuMs() const;

 private:
  struct Range {
    size_t first_brick, last_brick;  // in rays->sorted bricks
    size_t first_point, last_point;  // in point_subtrees_
  };
  struct alignas(64) PerThread {  // cache lines of its own, as VoxelBricks
    KernelRows kernel;
    std::vector<std::pair<uint32_t, uint32_t>> order;  // (local Morton code, row)
    std::vector<std::pair<uint32_t, uint32_t>> order_buffer;
    std::vector<VoxelUpdate> updates;
    // The 8^3 blocks (of 8^3 voxels) of the subtree at hand that one of its points may reach.
    std::array<uint64_t, 8> reached{};
    double kernel_cpu_ms = 0.0;
    // The most this scan's subtrees needed: rows while scattering (doubles), rows, updates.
    size_t most_row_values = 0, most_rows = 0, most_updates = 0;
  };
  void collectPointSubtrees();
  void mergeSeeds();
  // KernelRows::mask of subtree i: the leaves of `existing` and the voxels rays update, within
  // reach of its points (a map that knows the area holds many leaves no point reaches).
  void buildMask(size_t i, const EvidentialOcTreeNode* existing, PerThread* t) const;
  void markReachedBlocks(size_t i, PerThread* t) const;
  void markLeaves(const EvidentialOcTreeNode* node, int x, int y, int z, int size,
                  PerThread* t) const;

  const EvidentialOcTree* tree_ = nullptr;
  Targets targets_ = Targets::kEverywhere;
  const VoxelBricks* rays_ = nullptr;
  const SemanticPoints* points_ = nullptr;
  const std::vector<KernelPoint>* kernel_points_ = nullptr;
  const KernelPass* kernel_ = nullptr;
  std::vector<std::pair<uint64_t, uint32_t>> point_subtrees_;  // (subtree code, point), sorted
  std::vector<SubtreeSeed> seeds_;
  std::vector<Range> ranges_;
  std::vector<PerThread> threads_;
};

}  // namespace evidential_octomap
