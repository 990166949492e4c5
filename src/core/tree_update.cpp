// The batched scan update of EvidentialOcTree: one pass over the tree in Morton order, every
// touched leaf once, inner nodes above touched leaves once, subtrees in parallel.
#include <omp.h>

#include <algorithm>
#include <utility>

#include "evidential_octomap/evidential_octree.h"
#include "morton.h"
#include "payload_pool.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

// Stable LSD radix sort on the 48-bit Morton code: three 16-bit passes, about twice as fast as
// std::sort for the ~1.5 M updates of a scan (bench/README.md).
void radixSortByCode(std::vector<std::pair<uint64_t, uint32_t>>& items) {
  std::vector<std::pair<uint64_t, uint32_t>> buffer(items.size());
  std::vector<size_t> offsets(1 << 16);
  for (int shift = 0; shift < 48; shift += 16) {
    std::fill(offsets.begin(), offsets.end(), 0);
    for (const auto& item : items) ++offsets[(item.first >> shift) & 0xFFFF];
    size_t sum = 0;
    for (size_t& offset : offsets) sum += std::exchange(offset, sum);
    for (const auto& item : items) buffer[offsets[(item.first >> shift) & 0xFFFF]++] = item;
    items.swap(buffer);
  }
}

// Subtrees of 2^6 = 64 voxels a side (12.8 m at 0.2 m) are the parallel tasks: a scan spans a
// few hundred, enough to balance two threads with dynamic scheduling.
constexpr unsigned kTaskLevels = 6;
// Payload slots a thread takes from the pool at a time.
constexpr uint32_t kSlotBatch = 256;

// The end of the run of updates below `child` at `level`, starting at `first` (which is below
// it): runs are contiguous in Morton order, so a galloping search finds the end in O(log run)
// rather than one step per update at every level.
const VoxelUpdate* endOfChildRun(const VoxelUpdate* first, const VoxelUpdate* end, int level,
                                 unsigned child) {
  auto inRun = [&](const VoxelUpdate* u) {
    return octomap::computeChildIdx(u->key, level) == child;
  };
  const VoxelUpdate* in = first;  // known to be in the run
  size_t step = 1;
  const VoxelUpdate* out = end;  // known to be past the run (or end)
  while (size_t(end - in) > step) {
    if (!inRun(in + step)) {
      out = in + step;
      break;
    }
    in += step;
    step *= 2;
  }
  while (out - in > 1) {
    const VoxelUpdate* mid = in + (out - in) / 2;
    (inRun(mid) ? in : out) = mid;
  }
  return out;
}

}  // namespace

// A subtree to update: its root node at the split depth and its run of updates.
struct EvidentialOcTree::UpdateTask {
  EvidentialOcTreeNode* node;
  bool is_new;
  const VoxelUpdate* begin;
  const VoxelUpdate* end;
};

struct EvidentialOcTree::UpdateBatch {
  const std::vector<double>& increments;
  bool create_semantic_leaves;
  // Recursion above this depth collects tasks and the inner nodes on their paths (post-order)
  // instead of descending; > tree_depth means no split.
  unsigned split_depth;
  std::vector<UpdateTask>* tasks;
  std::vector<EvidentialOcTreeNode*>* above;
};

size_t EvidentialOcTree::applyUpdates(std::vector<VoxelUpdate> updates,
                                      const std::vector<double>& increments,
                                      bool create_semantic_leaves) {
  if (updates.empty()) return 0;
  std::vector<std::pair<uint64_t, uint32_t>> order(updates.size());
  for (size_t i = 0; i < updates.size(); ++i) order[i] = {mortonCode(updates[i].key), uint32_t(i)};
  radixSortByCode(order);
  // Sorted and merged per key: occupancy from the ray set, increments from the kernel.
  std::vector<VoxelUpdate> sorted;
  sorted.reserve(updates.size());
  for (size_t i = 0; i < order.size(); ++i) {
    const VoxelUpdate& u = updates[order[i].second];
    if (i > 0 && order[i].first == order[i - 1].first) {
      VoxelUpdate& merged = sorted.back();
      if (u.occupancy != 0) {  // 0 means "no occupancy update", not a value between miss and hit
        merged.occupancy =
            merged.occupancy == 0 ? u.occupancy : std::max(merged.occupancy, u.occupancy);
      }
      if (u.increments != VoxelUpdate::kNoIncrements) merged.increments = u.increments;
    } else {
      sorted.push_back(u);
    }
  }
  return applySortedUpdates(sorted.data(), sorted.size(), increments, create_semantic_leaves);
}

size_t EvidentialOcTree::applySortedUpdates(const VoxelUpdate* updates, size_t count,
                                            const std::vector<double>& increments,
                                            bool create_semantic_leaves) {
  if (count == 0) return 0;
  bool is_new = false;
  if (!root) {
    root = new EvidentialOcTreeNode();
    ++tree_size;
    is_new = true;
  }
  const int threads = config_.threads > 0 ? config_.threads : omp_get_max_threads();
  std::vector<UpdateTask> tasks;
  std::vector<EvidentialOcTreeNode*> above;
  const bool split = threads > 1;
  const UpdateBatch batch{increments, create_semantic_leaves,
                          split ? tree_depth - kTaskLevels : tree_depth + 1,
                          split ? &tasks : nullptr, split ? &above : nullptr};
  // 1. Serially down to the split depth: nodes on the way are made or split, tasks collected.
  Edit top(pool_.get(), 1);
  size_t changed = applyUpdatesRecurs(root, 0, is_new, updates, updates + count, batch, top);
  // 2. The subtrees, in parallel: each thread edits its own subtrees with its own Edit.
  const UpdateBatch within{increments, create_semantic_leaves, tree_depth + 1, nullptr, nullptr};
  std::vector<long long> nodes(threads, 0);
#pragma omp parallel num_threads(threads) reduction(+ : changed) if (tasks.size() > 1)
  {
    Edit edit(pool_.get(), kSlotBatch);
#pragma omp for schedule(dynamic, 1)
    for (size_t i = 0; i < tasks.size(); ++i) {
      const UpdateTask& t = tasks[i];
      changed += applyUpdatesRecurs(t.node, tree_depth - kTaskLevels, t.is_new, t.begin, t.end,
                                    within, edit);
    }
    edit.slots.flush();
    nodes[omp_get_thread_num()] = edit.nodes;
  }
  // 3. The inner nodes above the subtrees, bottom-up.
  for (EvidentialOcTreeNode* node : above) {
    if (nodeHasChildren(node)) updateInnerNode(node, top);
  }
  for (long long n : nodes) top.nodes += n;
  commit(top);
  return changed;
}

size_t EvidentialOcTree::applyUpdatesRecurs(EvidentialOcTreeNode* node, unsigned depth, bool is_new,
                                            const VoxelUpdate* begin, const VoxelUpdate* end,
                                            const UpdateBatch& batch, Edit& edit) {
  if (depth == batch.split_depth) {
    batch.tasks->push_back({node, is_new, begin, end});
    return 0;
  }
  if (depth == tree_depth) {  // one voxel, one merged update
    if (begin->occupancy != 0) {
      updateNodeLogOdds(node, begin->occupancy > 0 ? prob_hit_log : prob_miss_log);
    }
    if (begin->increments == VoxelUpdate::kNoIncrements) return 0;
    rule_->add(leafPayload(node, edit), &batch.increments[size_t(begin->increments) * num_classes_],
               num_classes_);
    return 1;
  }
  if (!is_new && !nodeHasChildren(node)) {
    // A pruned block: misses on a block at the lower clamp, or hits on one at the upper clamp,
    // change nothing (OctoMap's early abort); anything else splits it.
    const bool at_min = node->getLogOdds() <= clamping_thres_min;
    const bool at_max = node->getLogOdds() >= clamping_thres_max;
    bool unchanged = at_min || at_max;
    for (const VoxelUpdate* u = begin; unchanged && u != end; ++u) {
      unchanged = u->increments == VoxelUpdate::kNoIncrements &&
                  ((at_min && u->occupancy < 0) || (at_max && u->occupancy > 0));
    }
    if (unchanged) return 0;
    expandLeaf(node, edit);
  }
  const int level = static_cast<int>(tree_depth - 1 - depth);
  size_t changed = 0;
  for (const VoxelUpdate* first = begin; first != end;) {
    const unsigned child = octomap::computeChildIdx(first->key, level);
    const VoxelUpdate* last = endOfChildRun(first, end, level, child);
    bool created = false;
    if (!nodeChildExists(node, child) &&
        (batch.create_semantic_leaves ||
         std::any_of(first, last, [](const VoxelUpdate& u) { return u.occupancy != 0; }))) {
      createChild(node, child, edit);
      created = true;
    }
    if (nodeChildExists(node, child)) {
      changed += applyUpdatesRecurs(getNodeChild(node, child), depth + 1, created, first, last,
                                    batch, edit);
    }
    first = last;
  }
  if (depth < batch.split_depth && batch.above) {
    batch.above->push_back(node);  // after its children: post-order
  } else if (nodeHasChildren(node)) {
    updateInnerNode(node, edit);
  }
  return changed;
}

}  // namespace evidential_octomap
