// EvidentialOcTree in ColorOcTree.cpp's order: node part (header only), tree part, static member.
// The file format (readData / writeData) is in ot_format.cpp.
#include "evidential_octomap/evidential_octree.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <sstream>
#include <utility>
#include <stdexcept>

#include "evidential_octomap/scan_integrator.h"

namespace evidential_octomap {

// --- construction and settings -----------------------------------------------------------------

EvidentialOcTree::EvidentialOcTree(double resolution, int num_classes,
                                   const SemanticConfig& config)
    : OccupancyOcTreeBase<EvidentialOcTreeNode>(resolution) {
  setNumClasses(num_classes);
  setConfig(config);
  evidential_octree_member_init_.ensureLinking();
}

EvidentialOcTree* EvidentialOcTree::create() const {
  // Only AbstractOcTree::read calls create(), and it may skip readData (header "size 0").
  auto* tree = new EvidentialOcTree(resolution);
  tree->created_for_read_ = true;
  return tree;
}

EvidentialOcTree::EvidentialOcTree(const EvidentialOcTree& rhs)
    : OccupancyOcTreeBase<EvidentialOcTreeNode>(rhs.resolution),
      num_classes_(rhs.num_classes_),
      class_names_(rhs.class_names_),
      config_(rhs.config_),
      rule_(FusionRule::create(rhs.config_.rule, rhs.config_.sbki_prior)) {
  // OctoMap's own copy constructor slices derived nodes, so the nodes are copied here.
  clamping_thres_min = rhs.clamping_thres_min;
  clamping_thres_max = rhs.clamping_thres_max;
  prob_hit_log = rhs.prob_hit_log;
  prob_miss_log = rhs.prob_miss_log;
  occ_prob_thres_log = rhs.occ_prob_thres_log;
  if (rhs.root) {
    root = new EvidentialOcTreeNode();
    tree_size = 1;
    copySubtree(rhs, rhs.root, root);
  }
}

void EvidentialOcTree::copySubtree(const EvidentialOcTree& from, const EvidentialOcTreeNode* src,
                                   EvidentialOcTreeNode* dst) {
  dst->setValue(src->getValue());
  if (src->hasSemantics()) std::copy_n(from.slot(src->payload_), num_classes_, payloadForUpdate(dst));
  for (unsigned i = 0; i < 8; ++i) {
    if (from.nodeChildExists(src, i)) copySubtree(from, from.getNodeChild(src, i), createNodeChild(dst, i));
  }
}

void EvidentialOcTree::setNumClasses(int num_classes) {
  if (num_classes < 1 || num_classes > kMaxClasses) {
    throw std::invalid_argument("number of classes must be in 1..255, got " +
                                std::to_string(num_classes));
  }
  clear();
  num_classes_ = num_classes;
  class_names_.clear();
  for (int c = 0; c < num_classes; ++c) class_names_.push_back("class_" + std::to_string(c));
}

void EvidentialOcTree::setClassNames(const std::vector<std::string>& names) {
  if (static_cast<int>(names.size()) != num_classes_) {
    throw std::invalid_argument("expected " + std::to_string(num_classes_) + " class names, got " +
                                std::to_string(names.size()));
  }
  class_names_ = names;
}

void EvidentialOcTree::setConfig(const SemanticConfig& config) {
  const std::string problem = config.problem();
  if (!problem.empty()) throw std::invalid_argument("semantic config: " + problem);
  auto rule = FusionRule::create(config.rule, config.sbki_prior);
  const bool meaning_changes = config.rule != config_.rule || config.sbki_prior != config_.sbki_prior;
  if (rule_ && meaning_changes && payload_count_ > 0) {
    throw std::logic_error("cannot change the fusion rule of a map that holds semantic evidence ('" +
                           config_.rule + "' -> '" + config.rule + "')");
  }
  config_ = config;
  rule_ = std::move(rule);
}

SensorModel EvidentialOcTree::sensorModel() const {
  return {getProbHit(), getProbMiss(), getClampingThresMin(), getClampingThresMax(),
          getOccupancyThres()};
}

void EvidentialOcTree::setSensorModel(const SensorModel& model) {
  const std::string problem = model.problem();
  if (!problem.empty()) throw std::invalid_argument(problem);
  setProbHit(model.hit);
  setProbMiss(model.miss);
  setClampingThresMin(model.clamp_min);
  setClampingThresMax(model.clamp_max);
  setOccupancyThres(model.occupancy_threshold);
}

// --- integration and queries -----------------------------------------------------------------

InsertStats EvidentialOcTree::insertSemanticScan(const octomap::Pointcloud& points_W,
                                                 const std::vector<float>& evidence,
                                                 const octomap::point3d& origin_W,
                                                 EvidentialOcTree* unobserved) {
  if (unobserved) checkCompatible(*unobserved, "unobserved evidence");
  return ScanIntegrator(config_).integrate(points_W, evidence, origin_W, this, unobserved);
}

InsertStats EvidentialOcTree::insertSemanticScan(const octomap::Pointcloud& points_S,
                                                 const std::vector<float>& evidence,
                                                 const octomap::pose6d& T_W_S) {
  octomap::Pointcloud points_W(points_S);
  points_W.transform(T_W_S);
  return insertSemanticScan(points_W, evidence, T_W_S.trans());
}

const float* EvidentialOcTree::payload(const EvidentialOcTreeNode* node) const {
  return (node && node->hasSemantics()) ? slot(node->payload_) : nullptr;
}

VoxelOpinion EvidentialOcTree::opinion(const EvidentialOcTreeNode* node) const {
  if (const float* data = payload(node)) return rule_->readout(data, num_classes_);
  const std::vector<float> prior(num_classes_, rule_->prior());
  return rule_->readout(prior.data(), num_classes_);
}

VoxelOpinion EvidentialOcTree::query(const octomap::point3d& point_W) const {
  // OctoMap's coordToKeyChecked casts coordinate / resolution to int: undefined for NaN, inf
  // and anything beyond the tree's extent, so those are answered here.
  const double extent = resolution * tree_max_val;
  for (unsigned i = 0; i < 3; ++i) {
    if (!(std::fabs(point_W(i)) < extent)) return opinion(nullptr);
  }
  octomap::OcTreeKey key;
  if (!coordToKeyChecked(point_W, key)) return opinion(nullptr);
  return query(key);
}

VoxelOpinion EvidentialOcTree::query(const octomap::OcTreeKey& key, unsigned depth) const {
  return opinion(search(key, depth));
}

// --- editing -------------------------------------------------------------------------------------

uint32_t EvidentialOcTree::allocatePayload() {
  uint32_t index;
  if (!free_payloads_.empty()) {
    index = free_payloads_.back();
    free_payloads_.pop_back();
  } else {
    const size_t slots = payloads_.size() / num_classes_;
    if (slots >= EvidentialOcTreeNode::kNoPayload) throw std::length_error("payload pool is full");
    index = static_cast<uint32_t>(slots);
    payloads_.resize(payloads_.size() + num_classes_);
  }
  std::fill_n(slot(index), num_classes_, rule_->prior());
  ++payload_count_;
  return index;
}

void EvidentialOcTree::releasePayload(EvidentialOcTreeNode* node) {
  if (!node->hasSemantics()) return;
  free_payloads_.push_back(node->payload_);
  node->payload_ = EvidentialOcTreeNode::kNoPayload;
  --payload_count_;
}

float* EvidentialOcTree::payloadForUpdate(EvidentialOcTreeNode* node) {
  if (!node->hasSemantics()) node->payload_ = allocatePayload();
  return slot(node->payload_);
}

void EvidentialOcTree::clearPayload(EvidentialOcTreeNode* node) { releasePayload(node); }

EvidentialOcTreeNode* EvidentialOcTree::leafForUpdate(const octomap::OcTreeKey& key, bool create) {
  bool created = false;
  if (!root) {
    if (!create) return nullptr;
    root = new EvidentialOcTreeNode();
    ++tree_size;
    created = true;
  }
  EvidentialOcTreeNode* node = root;
  for (unsigned depth = 0; depth < tree_depth; ++depth) {
    const unsigned child = octomap::computeChildIdx(key, tree_depth - 1 - depth);
    if (!nodeChildExists(node, child)) {
      if (!created && !nodeHasChildren(node)) {
        expandNode(node);  // a pruned leaf stands for this voxel: split it
      } else {
        if (!create) return nullptr;
        createNodeChild(node, child);
        created = true;
      }
    }
    node = getNodeChild(node, child);
  }
  return node;
}

void EvidentialOcTree::updateInnerNodes() {
  if (root) updateInnerRecurs(root, 0);
}

void EvidentialOcTree::updateInnerRecurs(EvidentialOcTreeNode* node, unsigned depth) {
  if (!nodeHasChildren(node)) return;
  if (depth + 1 < tree_depth) {
    for (unsigned i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) updateInnerRecurs(getNodeChild(node, i), depth + 1);
    }
  }
  updateInnerNode(node);
}

const EvidentialOcTreeNode* EvidentialOcTree::richestChild(const EvidentialOcTreeNode* node) const {
  const EvidentialOcTreeNode* richest = nullptr;
  double richest_sum = -std::numeric_limits<double>::infinity();
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    const EvidentialOcTreeNode* child = getNodeChild(node, i);
    if (!child->hasSemantics()) continue;
    const float* data = slot(child->payload_);
    const double sum = std::accumulate(data, data + num_classes_, 0.0);
    if (sum > richest_sum) {
      richest_sum = sum;
      richest = child;
    }
  }
  return richest;
}

void EvidentialOcTree::updateInnerNode(EvidentialOcTreeNode* node) {
  const EvidentialOcTreeNode* richest = richestChild(node);
  node->updateOccupancyChildren();
  if (richest) {
    float* dst = payloadForUpdate(node);  // may reallocate the pool: read the source after it
    std::copy_n(slot(richest->payload_), num_classes_, dst);
  } else {
    releasePayload(node);
  }
  pruneNode(node);
}

// --- batched scan update ---------------------------------------------------------------------

namespace {
uint64_t spreadBits(uint64_t v) {  // the 16 bits of v to every third bit
  v &= 0xFFFF;
  v = (v | (v << 16)) & 0x0000FF0000FFull;
  v = (v | (v << 8)) & 0x00F00F00F00Full;
  v = (v | (v << 4)) & 0x0C30C30C30C3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}
// Morton code with OctoMap's child order (z, y, x from most to least significant), so that a
// sorted run of keys is also sorted by child index at every depth.
uint64_t mortonCode(const octomap::OcTreeKey& k) {
  return spreadBits(k[2]) << 2 | spreadBits(k[1]) << 1 | spreadBits(k[0]);
}
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
}  // namespace

struct EvidentialOcTree::UpdateBatch {
  const std::vector<double>& increments;
  bool create_semantic_leaves;
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
        merged.occupancy = merged.occupancy == 0 ? u.occupancy : std::max(merged.occupancy, u.occupancy);
      }
      if (u.increments != VoxelUpdate::kNoIncrements) merged.increments = u.increments;
    } else {
      sorted.push_back(u);
    }
  }
  bool is_new = false;
  if (!root) {
    root = new EvidentialOcTreeNode();
    ++tree_size;
    is_new = true;
  }
  const UpdateBatch batch{increments, create_semantic_leaves};
  const size_t changed =
      applyUpdatesRecurs(root, 0, is_new, sorted.data(), sorted.data() + sorted.size(), batch);
  size_changed = true;
  return changed;
}

size_t EvidentialOcTree::applyUpdatesRecurs(EvidentialOcTreeNode* node, unsigned depth,
                                            bool is_new, const VoxelUpdate* begin,
                                            const VoxelUpdate* end, const UpdateBatch& batch) {
  if (depth == tree_depth) {  // one voxel, one merged update
    if (begin->occupancy != 0) {
      updateNodeLogOdds(node, begin->occupancy > 0 ? prob_hit_log : prob_miss_log);
    }
    if (begin->increments == VoxelUpdate::kNoIncrements) return 0;
    float* payload = payloadForUpdate(node);
    const double* add = &batch.increments[size_t(begin->increments) * num_classes_];
    for (int c = 0; c < num_classes_; ++c) payload[c] += static_cast<float>(add[c]);
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
    expandNode(node);
  }
  const int level = static_cast<int>(tree_depth - 1 - depth);
  size_t changed = 0;
  for (const VoxelUpdate* first = begin; first != end;) {
    const unsigned child = octomap::computeChildIdx(first->key, level);
    const VoxelUpdate* last = first;
    bool needs_leaf = false;
    while (last != end && octomap::computeChildIdx(last->key, level) == child) {
      needs_leaf |= last->occupancy != 0 || batch.create_semantic_leaves;
      ++last;
    }
    bool created = false;
    if (!nodeChildExists(node, child) && needs_leaf) {
      createNodeChild(node, child);
      created = true;
    }
    if (nodeChildExists(node, child)) {
      changed += applyUpdatesRecurs(getNodeChild(node, child), depth + 1, created, first, last, batch);
    }
    first = last;
  }
  if (nodeHasChildren(node)) updateInnerNode(node);
  return changed;
}

void EvidentialOcTree::compactPayloads() {
  std::vector<float> packed;
  packed.reserve(payload_count_ * num_classes_);
  std::vector<EvidentialOcTreeNode*> stack;
  if (root) stack.push_back(root);
  while (!stack.empty()) {
    EvidentialOcTreeNode* node = stack.back();
    stack.pop_back();
    if (node->hasSemantics()) {
      const float* data = slot(node->payload_);
      node->payload_ = static_cast<uint32_t>(packed.size() / num_classes_);
      packed.insert(packed.end(), data, data + num_classes_);
    }
    for (unsigned i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) stack.push_back(getNodeChild(node, i));
    }
  }
  payloads_.swap(packed);
  payloads_.shrink_to_fit();
  free_payloads_.clear();
  payload_count_ = payloads_.size() / num_classes_;
}

// --- merge ---------------------------------------------------------------------------------------

namespace {
float clampLogOdds(float value, float lo, float hi) { return std::min(std::max(value, lo), hi); }
}  // namespace

void EvidentialOcTree::checkCompatible(const EvidentialOcTree& other, const char* what) const {
  if (other.resolution != resolution || other.num_classes_ != num_classes_ ||
      other.config_.rule != config_.rule || other.config_.sbki_prior != config_.sbki_prior) {
    throw std::invalid_argument(std::string(what) +
                                " needs maps of equal resolution, class count and rule");
  }
}

void EvidentialOcTree::addPayload(float* into, const float* from) const {
  const float prior = rule_->prior();
  for (int c = 0; c < num_classes_; ++c) {
    into[c] = static_cast<float>(
        std::min(double(into[c]) + from[c] - prior, double(std::numeric_limits<float>::max())));
  }
}

void EvidentialOcTree::addEvidence(const EvidentialOcTree& evidence, EvidentialOcTree* rest) {
  checkCompatible(evidence, "addEvidence");
  if (rest) checkCompatible(*rest, "addEvidence");
  for (auto it = evidence.begin_leafs(); it != evidence.end_leafs(); ++it) {
    const float* from = evidence.payload(&*it);
    if (!from) continue;
    // A pruned block of the source stands for each of its voxels.
    const unsigned level = tree_depth - it.getDepth();
    const octomap::key_type mask = static_cast<octomap::key_type>(~((1u << level) - 1u));
    const octomap::OcTreeKey base(it.getKey()[0] & mask, it.getKey()[1] & mask,
                                  it.getKey()[2] & mask);
    const unsigned span = 1u << level;
    for (unsigned dx = 0; dx < span; ++dx)
      for (unsigned dy = 0; dy < span; ++dy)
        for (unsigned dz = 0; dz < span; ++dz) {
          const octomap::OcTreeKey key(base[0] + dx, base[1] + dy, base[2] + dz);
          if (search(key)) {
            addPayload(payloadForUpdate(leafForUpdate(key, false)), from);
          } else if (rest) {
            rest->addPayload(rest->payloadForUpdate(rest->leafForUpdate(key, true)), from);
          }
        }
  }
  updateInnerNodes();
  if (rest) rest->updateInnerNodes();
}

void EvidentialOcTree::merge(const EvidentialOcTree& other) {
  checkCompatible(other, "merge");
  if (!other.root) return;
  if (!root) {
    root = new EvidentialOcTreeNode();
    tree_size = 1;
    copySubtree(other, other.root, root);
    return;
  }
  // Leaf-level fusion: log-odds add (clamped), payload increments add. Both are commutative.
  auto fuseLeaf = [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src) {
    dst->setLogOdds(clampLogOdds(dst->getLogOdds() + src->getLogOdds(), clamping_thres_min,
                                 clamping_thres_max));
    if (src->hasSemantics()) addPayload(payloadForUpdate(dst), other.slot(src->payload_));
  };
  // Applies src (a leaf) to every leaf below dst; children dst lacks become copies of src.
  std::function<void(EvidentialOcTreeNode*, const EvidentialOcTreeNode*, unsigned)> spread =
      [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src, unsigned depth) {
        if (!nodeHasChildren(dst)) return fuseLeaf(dst, src);
        for (unsigned i = 0; i < 8; ++i) {
          if (nodeChildExists(dst, i)) {
            spread(getNodeChild(dst, i), src, depth + 1);
          } else {
            copySubtree(other, src, createNodeChild(dst, i));
          }
        }
      };
  std::function<void(EvidentialOcTreeNode*, const EvidentialOcTreeNode*, unsigned)> mergeRecurs =
      [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src, unsigned depth) {
        if (!other.nodeHasChildren(src)) return spread(dst, src, depth);
        if (!nodeHasChildren(dst)) expandNode(dst);  // dst is a (pruned) leaf: refine it
        for (unsigned i = 0; i < 8; ++i) {
          if (!other.nodeChildExists(src, i)) continue;
          if (nodeChildExists(dst, i)) {
            mergeRecurs(getNodeChild(dst, i), other.getNodeChild(src, i), depth + 1);
          } else {
            copySubtree(other, other.getNodeChild(src, i), createNodeChild(dst, i));
          }
        }
      };
  mergeRecurs(root, other.root, 0);
  updateInnerNodes();
}

// --- OctoMap overrides -----------------------------------------------------------------------

bool EvidentialOcTree::isNodeCollapsible(const EvidentialOcTreeNode* node) const {
  if (!nodeChildExists(node, 0)) return false;
  const EvidentialOcTreeNode* first = getNodeChild(node, 0);
  if (nodeHasChildren(first)) return false;
  const float* first_payload = payload(first);
  for (unsigned i = 1; i < 8; ++i) {
    if (!nodeChildExists(node, i)) return false;
    const EvidentialOcTreeNode* child = getNodeChild(node, i);
    if (nodeHasChildren(child) || child->getValue() != first->getValue()) return false;
    // Unlike ColorOcTree, semantics must be identical too, so pruning never changes a query.
    const float* child_payload = payload(child);
    if ((first_payload == nullptr) != (child_payload == nullptr)) return false;
    if (first_payload && !std::equal(first_payload, first_payload + num_classes_, child_payload)) {
      return false;
    }
  }
  return true;
}

void EvidentialOcTree::expandNode(EvidentialOcTreeNode* node) {
  OccupancyOcTreeBase<EvidentialOcTreeNode>::expandNode(node);
  if (!node->hasSemantics()) return;
  for (unsigned i = 0; i < 8; ++i) {
    EvidentialOcTreeNode* child = getNodeChild(node, i);
    float* dst = payloadForUpdate(child);  // may reallocate: read the parent's slot after it
    std::copy_n(slot(node->payload_), num_classes_, dst);
  }
}

bool EvidentialOcTree::pruneNode(EvidentialOcTreeNode* node) {
  if (!isNodeCollapsible(node)) return false;
  EvidentialOcTreeNode* first = getNodeChild(node, 0);
  if (first->hasSemantics()) {
    float* dst = payloadForUpdate(node);
    std::copy_n(slot(first->payload_), num_classes_, dst);
  } else {
    releasePayload(node);
  }
  for (unsigned i = 0; i < 8; ++i) releasePayload(getNodeChild(node, i));
  // Children are now identical and payload-free: the base deletes them and copies occupancy.
  return OccupancyOcTreeBase<EvidentialOcTreeNode>::pruneNode(node);
}

void EvidentialOcTree::clear() {
  OccupancyOcTreeBase<EvidentialOcTreeNode>::clear();
  payloads_.clear();
  free_payloads_.clear();
  payload_count_ = 0;
}

size_t EvidentialOcTree::memoryUsage() const {
  return OccupancyOcTreeBase<EvidentialOcTreeNode>::memoryUsage() +
         payloads_.capacity() * sizeof(float) + free_payloads_.capacity() * sizeof(uint32_t);
}

// --- registration with AbstractOcTree (the ColorOcTree pattern) -----------------------------

EvidentialOcTree::StaticMemberInitializer::StaticMemberInitializer() {
  auto* tree = new EvidentialOcTree(0.1);
  tree->clearKeyRays();
  AbstractOcTree::registerTreeType(tree);
}

EvidentialOcTree::StaticMemberInitializer EvidentialOcTree::evidential_octree_member_init_;

}  // namespace evidential_octomap
