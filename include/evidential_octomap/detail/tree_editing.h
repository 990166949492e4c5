// Direct edits of a map's leaves, below the public tree: for the core's readers and box
// clearing, and for tests, fuzz targets and benchmarks that build a map voxel by voxel. A
// library user inserts scans (insertSemanticScan), merges maps (merge) or clears boxes
// (map_editing.h); nothing here checks that the map stays what its settings say it is.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// One voxel's share of a scan: an occupancy update and/or a row of semantic increments.
struct VoxelUpdate {
  static constexpr uint32_t kNoIncrements = 0xFFFFFFFFu;
  octomap::OcTreeKey key;
  int8_t occupancy = 0;                 // -1 miss, +1 hit, 0 none
  uint32_t increments = kNoIncrements;  // row of C values in the increments array
};

namespace detail {

class TreeEditing {
 public:
  // Leaf at full depth for `key`, expanding pruned nodes; created (log-odds 0) when missing and
  // `create`, else nullptr.
  static EvidentialOcTreeNode* leafForUpdate(EvidentialOcTree& tree,
                                             const octomap::OcTreeKey& key, bool create) {
    return tree.leafForUpdate(key, create);
  }
  // Sets the leaf's C floats (allocating its payload if it had none). The summaries above it
  // follow at updateInnerNodes(). Throws std::invalid_argument for an inner node.
  static void setPayload(EvidentialOcTree& tree, EvidentialOcTreeNode* leaf,
                         const float* values) {
    tree.setPayload(leaf, values);
  }
  static void clearPayload(EvidentialOcTree& tree, EvidentialOcTreeNode* node) {
    tree.clearPayload(node);
  }
  // Applies a whole scan in one pass over the tree: updates are sorted in Morton order (so every
  // subtree is visited once), missing leaves are created for occupancy updates (and for
  // semantic ones when `create_semantic_leaves`), pruned blocks are split only where something
  // changes, and only the inner nodes above touched leaves are recomputed (and pruned).
  // `increments` holds C values per row. Subtrees are updated in parallel (config().threads).
  // Returns the number of leaves whose payload changed.
  static size_t applyUpdates(EvidentialOcTree& tree, std::vector<VoxelUpdate> updates,
                             const std::vector<double>& increments, bool create_semantic_leaves) {
    return tree.applyUpdates(std::move(updates), increments, create_semantic_leaves);
  }
  // The same for updates already sorted in Morton order (z, y, x bits interleaved, OctoMap's
  // child order) with one update per key.
  static size_t applySortedUpdates(EvidentialOcTree& tree, const VoxelUpdate* updates,
                                   size_t count, const std::vector<double>& increments,
                                   bool create_semantic_leaves) {
    return tree.applySortedUpdates(updates, count, increments, create_semantic_leaves);
  }
  // Recomputes inner occupancy and inner semantic summaries bottom-up, then prunes.
  // Inner summary: the payload of the child holding the most evidence (largest sum; the first
  // such child on ties), i.e. of the leaf reached by following the richest child downwards. It
  // is not copied: the inner node names that leaf's slot.
  static void updateInnerNodes(EvidentialOcTree& tree) { tree.updateInnerNodes(); }
  // Rebuilds the payload store from the nodes that are still in the tree (after deleteNode),
  // each payload in the smallest slot that holds it.
  static void compactPayloads(EvidentialOcTree& tree) { tree.compactPayloads(); }
  // Moves the subtree of the node at `depth` (1..tree depth) that holds `key` out of `tree` into
  // a new map of equal settings (class names, sensor model, clamping; no evidence statistic),
  // at the same keys; ancestors left without children go too. nullptr, changing nothing, when
  // the map has no node at that depth there (nothing known, or a pruned block above it).
  // Inner nodes above follow at updateInnerNodes().
  static std::unique_ptr<EvidentialOcTree> detachSubtree(EvidentialOcTree& tree,
                                                         const octomap::OcTreeKey& key,
                                                         unsigned depth) {
    return tree.detachSubtree(key, depth);
  }
  // Gives `part` (a subtree detached from `whole`) the evidence statistic of `whole`, so that
  // it reads out (effectiveEvidenceCap) as the same voxels of `whole` do.
  static void readOutLike(const EvidentialOcTree& whole, EvidentialOcTree& part) {
    part.evidence_log_sum_ = whole.evidence_log_sum_;
    part.evidence_points_ = whole.evidence_points_;
    part.followEvidenceStatistic();
  }
};

}  // namespace detail
}  // namespace evidential_octomap
