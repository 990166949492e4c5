// The batched scan update of EvidentialOcTree: one pass over the tree in Morton order, every
// touched leaf once, inner nodes above touched leaves once. The pass walks serially down to the
// subtrees that receive updates (subtree_source.h), updates those in parallel, each with the
// updates its source computes for it, then fixes the inner nodes above them.
#include <omp.h>

#include <algorithm>
#include <utility>

#include "evidential_octomap/detail/leaf_walk.h"
#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "morton.h"
#include "payload_store.h"
#include "radix_sort.h"
#include "subtree_source.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

// Payload slots a thread takes from the pool at a time.
constexpr uint32_t kSlotBatch = 256;

// The end of the run of items below `child` at `level`, starting at `first` (which is below
// it): runs are contiguous in Morton order, so a galloping search finds the end in O(log run)
// rather than one step per item at every level.
template <typename Item>
const Item* endOfChildRun(const Item* first, const Item* end, int level, unsigned child) {
  auto inRun = [&](const Item* u) { return childIndex(u->key, level) == child; };
  const Item* in = first;  // known to be in the run
  size_t step = 1;
  const Item* out = end;  // known to be past the run (or end)
  while (size_t(end - in) > step) {
    if (!inRun(in + step)) {
      out = in + step;
      break;
    }
    in += step;
    step *= 2;
  }
  while (out - in > 1) {
    const Item* mid = in + (out - in) / 2;
    (inRun(mid) ? in : out) = mid;
  }
  return out;
}

uint64_t subtreeCode(const octomap::OcTreeKey& key) {
  return mortonCode(key) >> (3 * kSubtreeLevels);
}

// A caller's sorted update list as a source: its runs per subtree.
class ListSource : public SubtreeSource {
 public:
  ListSource(const VoxelUpdate* updates, size_t count, const double* rows) : rows_(rows) {
    for (size_t i = 0; i < count; ++i) {
      if (i == 0 || subtreeCode(updates[i].key) != subtreeCode(updates[i - 1].key)) {
        seeds_.push_back({updates[i].key, 0});
        runs_.push_back(updates + i);
      }
      SubtreeSeed& seed = seeds_.back();
      if (updates[i].occupancy < 0) seed.flags |= SubtreeSeed::kHasMiss;
      if (updates[i].occupancy > 0) seed.flags |= SubtreeSeed::kHasHit;
      if (updates[i].increments != VoxelUpdate::kNoIncrements)
        seed.flags |= SubtreeSeed::kMayHaveRows;
    }
    runs_.push_back(updates + count);
  }
  const std::vector<SubtreeSeed>& seeds() const override { return seeds_; }
  SubtreeView updates(size_t i, int, const EvidentialOcTreeNode*) override {
    return {runs_[i], runs_[i + 1], rows_};
  }

 private:
  const double* rows_;
  std::vector<SubtreeSeed> seeds_;
  std::vector<const VoxelUpdate*> runs_;
};

}  // namespace

// A subtree to update: its root node at the split depth (nullptr when it has none and gets
// none: its rows are dropped) and its seed.
struct EvidentialOcTree::UpdateTask {
  EvidentialOcTreeNode* node;
  bool is_new;
  size_t seed;
};

// What the recursion inside one subtree needs besides the updates.
struct EvidentialOcTree::UpdateBatch {
  const double* rows;
  bool create_semantic_leaves;
  DroppedRows* dropped;  // nullptr: dropped rows are not kept
  const ClearingRule* clearing;  // nullptr: no clearings
};

// The serial walk down to the subtrees.
struct EvidentialOcTree::TopPass {
  const SubtreeSeed* seeds;
  bool create_semantic_leaves;
  bool keep_dropped;
  const ClearingRule* clearing;  // nullptr: no clearings
  std::vector<UpdateTask> tasks;
  std::vector<EvidentialOcTreeNode*> above;  // inner nodes above the subtrees, post-order
};

size_t EvidentialOcTree::applyUpdates(std::vector<VoxelUpdate> updates,
                                      const std::vector<double>& increments,
                                      bool create_semantic_leaves) {
  if (updates.empty()) return 0;
  std::vector<std::pair<uint64_t, uint32_t>> order(updates.size());
  for (size_t i = 0; i < updates.size(); ++i) order[i] = {mortonCode(updates[i].key), uint32_t(i)};
  std::vector<std::pair<uint64_t, uint32_t>> buffer;
  radixSort(&order, 48, &buffer);
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
  ListSource source(updates, count, increments.data());
  const int threads = config_.threads > 0 ? config_.threads : omp_get_max_threads();
  return applySubtrees(source, create_semantic_leaves, threads, nullptr);
}

void EvidentialOcTree::addDroppedRows(std::vector<DroppedRows>& dropped) {
  std::vector<VoxelUpdate> updates;
  std::vector<double> rows;
  for (DroppedRows& d : dropped) {
    const uint32_t offset = static_cast<uint32_t>(rows.size() / num_classes_);
    for (VoxelUpdate u : d.updates) {
      u.increments += offset;
      updates.push_back(u);
    }
    rows.insert(rows.end(), d.rows.begin(), d.rows.end());
  }
  applyUpdates(std::move(updates), rows, true);
}

size_t EvidentialOcTree::applySubtrees(SubtreeSource& source, bool create_semantic_leaves,
                                       int threads, std::vector<DroppedRows>* dropped) {
  const std::vector<SubtreeSeed>& seeds = source.seeds();
  if (dropped) dropped->assign(threads, DroppedRows());
  if (seeds.empty()) return 0;
  bool is_new = false;
  if (!root) {
    root = new EvidentialOcTreeNode();
    ++tree_size;
    is_new = true;
  }
  // 1. Serially down to the subtrees: nodes on the way are made or split, tasks collected.
  Edit top(pool_.get(), 1);
  const ClearingRule clearing = clearingRule();
  const ClearingRule* clears = clearing.keep.empty() ? nullptr : &clearing;
  TopPass pass{seeds.data(), create_semantic_leaves, dropped != nullptr, clears, {}, {}};
  applyTopRecurs(root, 0, is_new, seeds.data(), seeds.data() + seeds.size(), pass, top);
  // 2. The subtrees, in parallel: each thread edits its own subtrees with its own Edit.
  size_t changed = 0;
  std::vector<long long> nodes(threads, 0);
#pragma omp parallel num_threads(threads) reduction(+ : changed)
  {
    const int thread = omp_get_thread_num();
    Edit edit(pool_.get(), kSlotBatch);
    DroppedRows* keep = dropped ? &(*dropped)[thread] : nullptr;
#pragma omp for schedule(dynamic, 1)
    for (size_t i = 0; i < pass.tasks.size(); ++i) {
      const UpdateTask& task = pass.tasks[i];
      const SubtreeView view = source.updates(task.seed, thread, task.is_new ? nullptr : task.node);
      const UpdateBatch batch{view.rows, create_semantic_leaves, keep, clears};
      if (task.node) {
        changed += applyUpdatesRecurs(task.node, tree_depth - kSubtreeLevels, task.is_new,
                                      view.begin, view.end, batch, edit);
      } else {
        keepDropped(view.begin, view.end, batch);
      }
    }
    edit.slots.flush();
    nodes[thread] = edit.nodes;
  }
  // 3. The inner nodes above the subtrees, bottom-up.
  for (EvidentialOcTreeNode* node : pass.above) {
    if (nodeHasChildren(node)) updateInnerNode(node, top);
  }
  for (long long n : nodes) top.nodes += n;
  commit(top);
  return changed;
}

void EvidentialOcTree::applyTopRecurs(EvidentialOcTreeNode* node, unsigned depth, bool is_new,
                                      const SubtreeSeed* begin, const SubtreeSeed* end,
                                      TopPass& pass, Edit& edit) {
  if (depth == tree_depth - kSubtreeLevels) {  // one subtree, one seed
    pass.tasks.push_back({node, is_new, size_t(begin - pass.seeds)});
    return;
  }
  if (!is_new && !nodeHasChildren(node)) {
    // A pruned block: misses on a block at the lower clamp, or hits on one at the upper clamp,
    // change nothing (OctoMap's early abort); anything else splits it.
    const bool at_min = node->getLogOdds() <= clamping_thres_min;
    const bool at_max = node->getLogOdds() >= clamping_thres_max;
    bool unchanged =
        (at_min || at_max) && !(pass.clearing && clearingMayChange(node, *pass.clearing));
    for (const SubtreeSeed* s = begin; unchanged && s != end; ++s) {
      unchanged = !(s->flags & SubtreeSeed::kMayHaveRows) &&
                  !(at_min && (s->flags & SubtreeSeed::kHasHit)) &&
                  !(at_max && (s->flags & SubtreeSeed::kHasMiss));
    }
    if (unchanged) return;
    expandLeaf(node, edit);
  }
  const int level = static_cast<int>(tree_depth - 1 - depth);
  for (const SubtreeSeed* first = begin; first != end;) {
    const unsigned child = childIndex(first->key, level);
    const SubtreeSeed* last = endOfChildRun(first, end, level, child);
    bool created = false;
    if (!nodeChildExists(node, child) &&
        (pass.create_semantic_leaves || std::any_of(first, last, [](const SubtreeSeed& s) {
           return (s.flags & (SubtreeSeed::kHasMiss | SubtreeSeed::kHasHit)) != 0;
         }))) {
      createChild(node, child, edit);
      created = true;
    }
    if (nodeChildExists(node, child)) {
      applyTopRecurs(getNodeChild(node, child), depth + 1, created, first, last, pass, edit);
    } else if (pass.keep_dropped) {  // nothing there: the subtrees' rows are dropped
      for (const SubtreeSeed* s = first; s != last; ++s) {
        pass.tasks.push_back({nullptr, false, size_t(s - pass.seeds)});
      }
    }
    first = last;
  }
  pass.above.push_back(node);  // after its children: post-order
}

void EvidentialOcTree::keepDropped(const VoxelUpdate* begin, const VoxelUpdate* end,
                                   const UpdateBatch& batch) const {
  if (!batch.dropped) return;
  for (const VoxelUpdate* u = begin; u != end; ++u) {
    if (u->increments == VoxelUpdate::kNoIncrements) continue;
    const double* row = batch.rows + size_t(u->increments) * num_classes_;
    auto& rows = batch.dropped->rows;
    batch.dropped->updates.push_back(
        {u->key, 0, static_cast<uint32_t>(rows.size() / num_classes_)});
    rows.insert(rows.end(), row, row + num_classes_);
  }
}

size_t EvidentialOcTree::applyUpdatesRecurs(EvidentialOcTreeNode* node, unsigned depth, bool is_new,
                                            const VoxelUpdate* begin, const VoxelUpdate* end,
                                            const UpdateBatch& batch, Edit& edit) {
  // Never called at the leaf depth: the subtrees start kSubtreeLevels >= 1 above it, and the
  // level above the leaves hands them to applyLeafUpdates.
  static_assert(kSubtreeLevels >= 1);
  if (!is_new && !nodeHasChildren(node)) {
    // A pruned block: misses on a block at the lower clamp, or hits on one at the upper clamp,
    // change nothing (OctoMap's early abort); anything else splits it.
    const bool at_min = node->getLogOdds() <= clamping_thres_min;
    const bool at_max = node->getLogOdds() >= clamping_thres_max;
    bool unchanged =
        (at_min || at_max) && !(batch.clearing && clearingMayChange(node, *batch.clearing));
    for (const VoxelUpdate* u = begin; unchanged && u != end; ++u) {
      unchanged = u->increments == VoxelUpdate::kNoIncrements &&
                  ((at_min && u->occupancy < 0) || (at_max && u->occupancy > 0));
    }
    if (unchanged) return 0;
    expandLeaf(node, edit);
  }
  // The children (updateInnerNode reads all of them) and, while a child is updated, the next
  // one's children array are asked for ahead: each is a likely cache miss.
  detail::prefetchChildren(*this, node);
  if (depth + 1 == tree_depth) return applyLeafUpdates(node, begin, end, batch, edit);
  const int level = static_cast<int>(tree_depth - 1 - depth);
  size_t changed = 0;
  for (const VoxelUpdate* first = begin; first != end;) {
    const unsigned child = childIndex(first->key, level);
    const VoxelUpdate* last = endOfChildRun(first, end, level, child);
    if (last != end && nodeChildExists(node, childIndex(last->key, level))) {
      const auto* next = getNodeChild(node, childIndex(last->key, level));
      if (next->children) __builtin_prefetch(next->children);
    }
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
    } else {
      keepDropped(first, last, batch);  // rows for voxels the map does not have
    }
    first = last;
  }
  if (nodeHasChildren(node)) updateInnerNode(node, edit);
  return changed;
}

size_t EvidentialOcTree::applyLeafUpdates(EvidentialOcTreeNode* node, const VoxelUpdate* begin,
                                          const VoxelUpdate* end, const UpdateBatch& batch,
                                          Edit& edit) {
  size_t changed = 0;
  for (const VoxelUpdate* u = begin; u != end;) {  // merged per voxel, in child order
    const unsigned child = childIndex(u->key, 0);
    const VoxelUpdate* next = u + 1;
    while (next != end && childIndex(next->key, 0) == child) ++next;  // (none when merged)
    if (!nodeChildExists(node, child)) {
      if (!batch.create_semantic_leaves && u->occupancy == 0) {
        keepDropped(u, next, batch);  // rows for a voxel the map does not have
        u = next;
        continue;
      }
      createChild(node, child, edit);
    }
    changed += updateLeaf(getNodeChild(node, child), *u, batch, edit);
    u = next;
  }
  if (nodeHasChildren(node)) updateInnerNode(node, edit);
  return changed;
}

size_t EvidentialOcTree::updateLeaf(EvidentialOcTreeNode* leaf, const VoxelUpdate& update,
                                    const UpdateBatch& batch, Edit& edit) {
  if (update.occupancy != 0) {
    // OctoMap's updateNodeLogOdds (add, then clamp), with the clamp as min and max instead of
    // branches: whether a voxel is at a clamp is the data's.
    const float added = leaf->getLogOdds() + (update.occupancy > 0 ? prob_hit_log : prob_miss_log);
    leaf->setLogOdds(std::min(std::max(added, clamping_thres_min), clamping_thres_max));
  }
  // A surface that a ray grazes stays occupied and keeps its class; a voxel the clearings freed
  // (a mover has gone) forgets it.
  const bool cleared = update.occupancy < 0 && discountsClearings() && !isNodeOccupied(leaf);
  float values[kMaxClasses];
  if (update.increments == VoxelUpdate::kNoIncrements) {
    if (cleared) discountClearedLeaf(leaf, nullptr, *batch.clearing, values, edit);
    return 0;
  }
  // What the voxel held before this scan is discounted, but for the classes this scan's points
  // around it still show; their kernel evidence is what a surface next to it gives its free
  // space now.
  const double* increments = batch.rows + size_t(update.increments) * num_classes_;
  double kept_row[kMaxClasses];
  if (cleared) {
    if (!discountClearedLeaf(leaf, increments, *batch.clearing, values, edit))
      leafValues(leaf, values);
    // A voxel seen empty takes no evidence of a movable class: a mover beside it spreads it.
    for (int c = 0; c < num_classes_; ++c)
      kept_row[c] = batch.clearing->movable[c] ? 0.0 : increments[c];
    increments = kept_row;
  } else {
    leafValues(leaf, values);
  }
  rule_->add(values, increments, num_classes_);
  storeLeafValues(leaf, values, edit);
  return 1;
}

}  // namespace evidential_octomap
