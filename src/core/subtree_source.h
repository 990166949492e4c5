// A scan's updates handed to the tree one subtree at a time: the tree update pass asks for the
// updates of each subtree of 64^3 voxels that has any, from several threads at once, so no list
// of a whole scan's updates (1.5 M voxels, ~250 k rows of C doubles) is ever built. Private to
// the core.
#pragma once

#include <cstdint>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// Subtrees of 2^6 = 64 voxels a side (12.8 m at 0.2 m) are the parallel tasks: a scan spans a
// few hundred, enough to balance two threads with dynamic scheduling.
constexpr unsigned kSubtreeLevels = 6;

// A subtree that may receive updates, and what kinds (for the pass above it, which creates and
// splits the nodes down to it).
struct SubtreeSeed {
  enum Flags : uint8_t { kHasMiss = 1, kHasHit = 2, kMayHaveRows = 4 };
  octomap::OcTreeKey key;  // a voxel inside the subtree
  uint8_t flags = 0;
};

// The updates of one subtree, in Morton order, one per key; `rows` holds the C increments of
// each row their `increments` field names.
struct SubtreeView {
  const VoxelUpdate* begin = nullptr;
  const VoxelUpdate* end = nullptr;
  const double* rows = nullptr;
};

class SubtreeSource {
 public:
  virtual ~SubtreeSource() = default;
  // Sorted in Morton order, one per subtree.
  virtual const std::vector<SubtreeSeed>& seeds() const = 0;
  // The updates of seeds()[i]. Called concurrently with distinct `thread` indices (0 ..
  // threads - 1); the view stays valid until that thread's next call. `existing` is the
  // subtree's root node as it was before this update (nullptr when the subtree is new): a
  // source may skip the rows of voxels that neither exist there nor get an occupancy update,
  // since the map would drop them.
  virtual SubtreeView updates(size_t i, int thread, const EvidentialOcTreeNode* existing) = 0;
};

// Evidence the map dropped (kernel rows for voxels it has no leaf for), per thread.
struct DroppedRows {
  std::vector<VoxelUpdate> updates;
  std::vector<double> rows;
};

}  // namespace evidential_octomap
