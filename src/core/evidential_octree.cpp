// EvidentialOcTree in ColorOcTree.cpp's order: node part, tree part, static member. The batched
// scan update is in batched_update.cpp, the file format in ot_format.cpp.
#include "evidential_octomap/evidential_octree.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/safe_key.h"
#include "node_allocator.h"
#include "payload_store.h"
#include "phase_timer.h"
#include "scan_integrator.h"
#include "subtree_source.h"
#include "tree_edit.h"

namespace evidential_octomap {

// --- node ----------------------------------------------------------------------------------------

static_assert(sizeof(EvidentialOcTreeNode) == NodeAllocator::kCellBytes,
              "a node fills one allocator cell");

void* EvidentialOcTreeNode::operator new(size_t size) {
  // A derived node type (none in this library) would be larger: malloc serves it.
  return size == NodeAllocator::kCellBytes ? NodeAllocator::allocate() : ::operator new(size);
}

void EvidentialOcTreeNode::operator delete(void* node, size_t size) {
  if (!node) return;
  if (size == NodeAllocator::kCellBytes) {
    NodeAllocator::deallocate(node);
  } else {
    ::operator delete(node);
  }
}

EvidentialOcTreeNode* EvidentialOcTreeNode::addChild(unsigned i) {
  if (!children) {
    children = new octomap::AbstractOcTreeNode*[8];
    std::fill_n(children, 8, nullptr);
  }
  auto* child = new EvidentialOcTreeNode();
  children[i] = child;
  return child;
}

void EvidentialOcTreeNode::deleteLeafChildren() {
  for (unsigned i = 0; i < 8; ++i) delete static_cast<EvidentialOcTreeNode*>(children[i]);
  delete[] children;
  children = nullptr;
}

// --- construction and settings -----------------------------------------------------------------

EvidentialOcTree::EvidentialOcTree(double resolution, int num_classes, const SemanticConfig& config)
    : OccupancyOcTreeBase<EvidentialOcTreeNode>(resolution),
      pool_(std::make_unique<PayloadStore>(1, 0.0f)) {
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
      ground_classes_(rhs.ground_classes_),
      movable_classes_(rhs.movable_classes_),
      discounts_clearings_(rhs.discounts_clearings_),
      config_(rhs.config_),
      error_model_(rhs.error_model_),
      rule_(rhs.makeRule(rhs.config_)),
      pool_(std::make_unique<PayloadStore>(rhs.num_classes_, rhs.rule_->prior())),
      evidence_log_sum_(rhs.evidence_log_sum_),
      evidence_points_(rhs.evidence_points_) {
  // OctoMap's own copy constructor slices derived nodes, so the nodes are copied here.
  clamping_thres_min = rhs.clamping_thres_min;
  clamping_thres_max = rhs.clamping_thres_max;
  prob_hit_log = rhs.prob_hit_log;
  prob_miss_log = rhs.prob_miss_log;
  occ_prob_thres_log = rhs.occ_prob_thres_log;
  if (rhs.root) {
    root = new EvidentialOcTreeNode();
    tree_size = 1;
    Edit edit(pool_.get(), 1024);
    copySubtree(rhs, rhs.root, root, edit);
    commit(edit);
    linkSummariesRecurs(root, 0);
  }
}

EvidentialOcTree::~EvidentialOcTree() = default;

void EvidentialOcTree::setNumClasses(int num_classes) {
  if (num_classes < 1 || num_classes > kMaxClasses) {
    throw std::invalid_argument("number of classes must be in 1..255, got " +
                                std::to_string(num_classes));
  }
  clear();
  num_classes_ = num_classes;
  pool_->reset(num_classes, pool_->prior());
  class_names_.clear();
  for (int c = 0; c < num_classes; ++c) class_names_.push_back("class_" + std::to_string(c));
  ground_classes_.clear();
  movable_classes_.clear();
  updateDiscountsClearings();
}

void EvidentialOcTree::setClassNames(const std::vector<std::string>& names) {
  if (static_cast<int>(names.size()) != num_classes_) {
    throw std::invalid_argument("expected " + std::to_string(num_classes_) + " class names, got " +
                                std::to_string(names.size()));
  }
  class_names_ = names;
}

void EvidentialOcTree::setGroundClasses(const std::vector<bool>& ground) {
  if (!ground.empty() && static_cast<int>(ground.size()) != num_classes_) {
    throw std::invalid_argument("expected " + std::to_string(num_classes_) +
                                " ground flags (or none), got " + std::to_string(ground.size()));
  }
  ground_classes_ = ground;
}

void EvidentialOcTree::setClasses(const ClassTable& classes) {
  setClassNames(classes.names);
  setGroundClasses(classes.ground);
  setMovableClasses(classes.movable);
}

void EvidentialOcTree::setMovableClasses(const std::vector<bool>& movable) {
  if (!movable.empty() && static_cast<int>(movable.size()) != num_classes_) {
    throw std::invalid_argument("expected " + std::to_string(num_classes_) +
                                " movable flags (or none), got " + std::to_string(movable.size()));
  }
  movable_classes_ = movable;
  updateDiscountsClearings();
}

void EvidentialOcTree::setConfig(const SemanticConfig& config) {
  const std::string problem = config.problem();
  if (!problem.empty()) throw std::invalid_argument("semantic config: " + problem);
  auto rule = makeRule(config);
  const bool meaning_changes =
      config.rule != config_.rule || config.sbki_prior != config_.sbki_prior;
  if (rule_ && meaning_changes && numSemanticNodes() > 0) {
    throw std::logic_error(
        "cannot change the fusion rule of a map that holds semantic evidence ('" + config_.rule +
        "' -> '" + config.rule + "')");
  }
  config_ = config;
  updateDiscountsClearings();
  rule_ = std::move(rule);
  pool_->setPrior(rule_->prior());  // refused above while payloads depend on it
  integrator_.reset();
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
  // A parameter set through OctoMap's unchecked setters is refused here, where it would take
  // effect, rather than after hours of mapping by saveMap (with the same reason).
  const std::string problem = insertProblem();
  if (!problem.empty()) throw std::invalid_argument(problem);
  if (unobserved) checkCompatible(*unobserved, "unobserved evidence");
  if (!integrator_) integrator_ = std::make_unique<ScanIntegrator>(config_);
  InsertStats stats;
  // 1-2. Occupancy rays and semantic points, grouped by subtree (reads the map only).
  const bool keep = unobserved && !config_.kernel_creates_leaves;
  SubtreeSource* subtrees = integrator_->prepare(points_W, evidence, origin_W, *this, keep, &stats);
  if (subtrees) {
    // 3. One pass over the tree, subtree by subtree in parallel: each subtree's kernel rows (the
    //    one kernel loop), merged with its ray voxels, then its leaves and inner nodes.
    PhaseTimer timer;
    std::vector<DroppedRows> dropped;
    stats.voxels_updated = applySubtrees(*subtrees, config_.kernel_creates_leaves,
                                         integrator_->threads(), keep ? &dropped : nullptr);
    if (keep) unobserved->addDroppedRows(dropped);
    timer.stop(&stats.ms_update, &stats.cpu_ms_update);
    integrator_->finish(&stats);
  }
  followEvidence(evidence);
  return stats;
}

void EvidentialOcTree::followEvidence(const std::vector<float>& evidence) {
  // Kept whatever the cap, so that a map built with a fixed cap can be read adaptively later.
  if (config_.rule != "dempster") return;
  // Every 4th point is plenty for a mean over a scan and keeps this off the insert's cost.
  const size_t C = static_cast<size_t>(num_classes_), n = evidence.size() / C;
  for (size_t i = 0; i < n; i += 4) {
    const float* e = evidence.data() + i * C;
    double sum = 0.0;
    for (size_t c = 0; c < C; ++c) {
      if (e[c] > 0.0f) sum += std::log1p(double(e[c]) / double(C));
    }
    if (sum > 0.0) evidence_log_sum_ += sum, ++evidence_points_;
  }
  followEvidenceStatistic();
}

void EvidentialOcTree::followEvidenceStatistic() {
  if (config_.evidence_cap == SemanticConfig::kAdaptiveCap) rule_ = makeRule(config_);
}

double EvidentialOcTree::effectiveEvidenceCap() const {
  return capOf(config_);
}

std::unique_ptr<FusionRule> EvidentialOcTree::makeRule(const SemanticConfig& config) const {
  SemanticConfig resolved = config;
  resolved.evidence_cap = capOf(config);
  auto rule = FusionRule::create(resolved);
  if (rule->type() == FusionRuleType::kDempster) rule->setErrorModel(error_model_);
  return rule;
}

void EvidentialOcTree::setErrorModel(std::shared_ptr<const ErrorModel> model) {
  rule_->setErrorModel(model);
  error_model_ = std::move(model);
}

double EvidentialOcTree::capOf(const SemanticConfig& config) const {
  if (config.evidence_cap != SemanticConfig::kAdaptiveCap) return config.evidence_cap;
  return evidence_points_ ? SemanticConfig::adaptiveEvidenceCap(meanPointLogEvidence())
                          : SemanticConfig::kCapWithoutStatistic;
}

InsertStats EvidentialOcTree::insertSemanticScan(const octomap::Pointcloud& points_S,
                                                 const std::vector<float>& evidence,
                                                 const octomap::pose6d& T_W_S) {
  octomap::Pointcloud points_W(points_S);
  points_W.transform(T_W_S);
  return insertSemanticScan(points_W, evidence, T_W_S.trans());
}

size_t EvidentialOcTree::scratchBytes() const {
  return integrator_ ? integrator_->scratchBytes() : 0;
}

bool EvidentialOcTree::payload(const EvidentialOcTreeNode* node, float* out) const {
  if (!node || !node->hasSemantics()) return false;
  pool_->decode(node->payload_, out);
  return true;
}

std::vector<float> EvidentialOcTree::payload(const EvidentialOcTreeNode* node) const {
  std::vector<float> values(num_classes_);
  if (!payload(node, values.data())) values.clear();
  return values;
}

size_t EvidentialOcTree::numSemanticNodes() const { return pool_->inUse(); }

VoxelOpinion EvidentialOcTree::opinion(const EvidentialOcTreeNode* node) const {
  float values[kMaxClasses];
  if (!payload(node, values)) std::fill_n(values, num_classes_, rule_->prior());
  return rule_->readout(values, num_classes_);
}

const EvidentialOcTreeNode* EvidentialOcTree::nodeAt(const octomap::point3d& point_W) const {
  octomap::OcTreeKey key;
  return safeCoordToKey(*this, point_W, &key) ? search(key) : nullptr;
}

VoxelOpinion EvidentialOcTree::query(const octomap::point3d& point_W) const {
  octomap::OcTreeKey key;
  return safeCoordToKey(*this, point_W, &key) ? answer(key) : opinion(nullptr);
}

VoxelOpinion EvidentialOcTree::query(const octomap::OcTreeKey& key, unsigned depth) const {
  return opinion(search(key, depth));
}

// --- edits: every change of nodes and payloads goes through an Edit ------------------------------

void EvidentialOcTree::commit(Edit& edit) {
  tree_size = static_cast<size_t>(static_cast<long long>(tree_size) + edit.nodes);
  edit.nodes = 0;
  edit.slots.flush();
  size_changed = true;
}

EvidentialOcTreeNode* EvidentialOcTree::createChild(EvidentialOcTreeNode* node, unsigned i,
                                                    Edit& edit) {
  ++edit.nodes;
  return node->addChild(i);
}

void EvidentialOcTree::leafValues(const EvidentialOcTreeNode* leaf, float* out) const {
  if (!payload(leaf, out)) std::fill_n(out, num_classes_, rule_->prior());
}

// The leaf's reference may change (a larger slot): the summaries above follow at their update.
void EvidentialOcTree::storeLeafValues(EvidentialOcTreeNode* leaf, const float* values,
                                       Edit& edit) {
  leaf->payload_ = edit.slots.store(leaf->payload_, values);
}

void EvidentialOcTree::addToLeaf(EvidentialOcTreeNode* leaf, const float* from, Edit& edit) {
  float values[kMaxClasses];
  leafValues(leaf, values);
  addPayload(values, from);
  storeLeafValues(leaf, values, edit);
}

void EvidentialOcTree::releaseLeafPayload(EvidentialOcTreeNode* leaf, Edit& edit) {
  if (!leaf->hasSemantics()) return;
  edit.slots.release(leaf->payload_);
  leaf->payload_ = EvidentialOcTreeNode::kNoPayload;
}

// A pruned leaf becomes eight equal leaves; child 0 keeps the slot, so anything that named it
// (the summaries above) still reads the same payload.
void EvidentialOcTree::expandLeaf(EvidentialOcTreeNode* node, Edit& edit) {
  for (unsigned i = 0; i < 8; ++i) {
    EvidentialOcTreeNode* child = createChild(node, i, edit);
    child->copyData(*node);
    if (!node->hasSemantics()) continue;
    child->payload_ = i == 0 ? node->payload_ : edit.slots.copy(node->payload_);
  }
}

bool EvidentialOcTree::pruneChildren(EvidentialOcTreeNode* node, Edit& edit) {
  if (!isNodeCollapsible(node)) return false;
  collapseChildren(node, edit);
  return true;
}

// Eight equal leaves become one; it keeps child 0's slot (the one a summary names on ties).
void EvidentialOcTree::collapseChildren(EvidentialOcTreeNode* node, Edit& edit) {
  EvidentialOcTreeNode* first = getNodeChild(node, 0);
  node->copyData(*first);
  node->payload_ = first->payload_;
  first->payload_ = EvidentialOcTreeNode::kNoPayload;
  for (unsigned i = 1; i < 8; ++i) releaseLeafPayload(getNodeChild(node, i), edit);
  node->deleteLeafChildren();
  edit.nodes -= 8;
}

// --- the editing API -----------------------------------------------------------------------------

void EvidentialOcTree::setPayload(EvidentialOcTreeNode* leaf, const float* values) {
  if (nodeHasChildren(leaf)) {
    throw std::invalid_argument(
        "setPayload needs a leaf; inner summaries follow their leaves (updateInnerNodes)");
  }
  Edit edit(pool_.get(), 1);
  storeLeafValues(leaf, values, edit);
  commit(edit);
}

void EvidentialOcTree::clearPayload(EvidentialOcTreeNode* node) {
  if (nodeHasChildren(node)) {  // a summary only names a leaf's slot
    node->payload_ = EvidentialOcTreeNode::kNoPayload;
    return;
  }
  Edit edit(pool_.get(), 1);
  releaseLeafPayload(node, edit);
  commit(edit);
}

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

// --- inner nodes -------------------------------------------------------------------------------

double EvidentialOcTree::evidenceSum(const EvidentialOcTreeNode* node) const {
  return node->hasSemantics() ? pool_->sum(node->payload_) : -std::numeric_limits<double>::infinity();
}

const EvidentialOcTreeNode* EvidentialOcTree::richestChild(const EvidentialOcTreeNode* node) const {
  const EvidentialOcTreeNode* richest = nullptr;
  double richest_sum = -std::numeric_limits<double>::infinity();
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    const double sum = evidenceSum(getNodeChild(node, i));
    if (sum > richest_sum) {  // the first child wins ties
      richest = getNodeChild(node, i);
      richest_sum = sum;
    }
  }
  return richest;
}

// An inner node names the slot of its richest child, so its summary is that leaf's payload.
void EvidentialOcTree::linkSummary(EvidentialOcTreeNode* node) const {
  const EvidentialOcTreeNode* richest = richestChild(node);
  node->payload_ = richest ? richest->payload_ : EvidentialOcTreeNode::kNoPayload;
}

// One pass over the children gives what pruneChildren, updateOccupancyChildren and linkSummary
// would each read them for: the update visits every inner node above the changed voxels.
void EvidentialOcTree::updateInnerNode(EvidentialOcTreeNode* node, Edit& edit) {
  float max_log_odds = -std::numeric_limits<float>::max();  // OctoMap's getMaxChildLogOdds
  const EvidentialOcTreeNode* richest = nullptr;            // richestChild
  double richest_sum = -std::numeric_limits<double>::infinity();
  const EvidentialOcTreeNode* first = nodeChildExists(node, 0) ? getNodeChild(node, 0) : nullptr;
  bool equal_leaves = first != nullptr;  // isNodeCollapsible's first half
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) {
      equal_leaves = false;
      continue;
    }
    const EvidentialOcTreeNode* child = getNodeChild(node, i);
    // Selections rather than branches where the data decides (which child is richest).
    max_log_odds = std::max(max_log_odds, child->getLogOdds());
    equal_leaves = equal_leaves && !nodeHasChildren(child) &&
                   child->getValue() == first->getValue() &&
                   child->hasSemantics() == first->hasSemantics();
    const double sum = evidenceSum(child);
    const bool richer = sum > richest_sum;  // the first child wins ties
    richest = richer ? child : richest;
    richest_sum = richer ? sum : richest_sum;
  }
  if (equal_leaves && equalChildPayloads(node)) {
    collapseChildren(node, edit);
    return;
  }
  node->setLogOdds(max_log_odds);
  node->payload_ = richest ? richest->payload_ : EvidentialOcTreeNode::kNoPayload;
}

void EvidentialOcTree::updateInnerNodes() {
  if (!root) return;
  Edit edit(pool_.get(), 1);
  updateInnerRecurs(root, 0, edit);
  commit(edit);
}

void EvidentialOcTree::updateInnerRecurs(EvidentialOcTreeNode* node, unsigned depth, Edit& edit) {
  if (!nodeHasChildren(node)) return;
  if (depth + 1 < tree_depth) {
    for (unsigned i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) updateInnerRecurs(getNodeChild(node, i), depth + 1, edit);
    }
  }
  updateInnerNode(node, edit);
}

void EvidentialOcTree::linkSummariesRecurs(EvidentialOcTreeNode* node, unsigned depth) const {
  if (!nodeHasChildren(node)) return;
  for (unsigned i = 0; i < 8; ++i) {
    if (nodeChildExists(node, i)) linkSummariesRecurs(getNodeChild(node, i), depth + 1);
  }
  linkSummary(node);
}

void EvidentialOcTree::compactPayloads() {
  auto packed = std::make_unique<PayloadStore>(num_classes_, rule_->prior());
  float values[kMaxClasses];
  {
    Edit edit(packed.get(), 1024);
    std::vector<EvidentialOcTreeNode*> stack;
    if (root) stack.push_back(root);
    while (!stack.empty()) {
      EvidentialOcTreeNode* node = stack.back();
      stack.pop_back();
      if (!nodeHasChildren(node) && node->hasSemantics()) {
        pool_->decode(node->payload_, values);
        node->payload_ = edit.slots.store(PayloadStore::kNone, values);
      }
      for (unsigned i = 0; i < 8; ++i) {
        if (nodeChildExists(node, i)) stack.push_back(getNodeChild(node, i));
      }
    }
  }
  pool_.swap(packed);
  if (root) linkSummariesRecurs(root, 0);
}

// --- copy and merge
// --------------------------------------------------------------------------------

void EvidentialOcTree::copySubtree(const EvidentialOcTree& from, const EvidentialOcTreeNode* src,
                                   EvidentialOcTreeNode* dst, Edit& edit) {
  dst->setValue(src->getValue());
  if (!from.nodeHasChildren(src)) {
    float values[kMaxClasses];
    if (from.payload(src, values)) storeLeafValues(dst, values, edit);
    return;
  }
  for (unsigned i = 0; i < 8; ++i) {
    if (from.nodeChildExists(src, i)) {
      copySubtree(from, from.getNodeChild(src, i), createChild(dst, i, edit), edit);
    }
  }
}

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
  std::vector<double> increments(from, from + num_classes_);
  for (double& v : increments) v -= rule_->prior();
  rule_->add(into, increments.data(), num_classes_);  // saturating, bounded like a scan's update
}

void EvidentialOcTree::addEvidence(const EvidentialOcTree& evidence, EvidentialOcTree* rest) {
  checkCompatible(evidence, "addEvidence");
  if (rest) checkCompatible(*rest, "addEvidence");
  Edit edit(pool_.get(), 1024);
  std::optional<Edit> rest_edit;
  if (rest) rest_edit.emplace(rest->pool_.get(), 1024);
  float from[kMaxClasses];
  for (auto it = evidence.begin_leafs(); it != evidence.end_leafs(); ++it) {
    if (!evidence.payload(&*it, from)) continue;
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
            addToLeaf(leafForUpdate(key, false), from, edit);
          } else if (rest) {
            rest->addToLeaf(rest->leafForUpdate(key, true), from, *rest_edit);
          }
        }
  }
  commit(edit);
  updateInnerNodes();
  if (rest) {
    rest->commit(*rest_edit);
    rest->updateInnerNodes();
  }
}

void EvidentialOcTree::setClampingThresLog(float min_log_odds, float max_log_odds) {
  if (!(min_log_odds <= 0.0f && max_log_odds >= 0.0f) || !std::isfinite(min_log_odds) ||
      !std::isfinite(max_log_odds)) {
    throw std::invalid_argument("clamping bounds must be finite log-odds with min <= 0 <= max");
  }
  clamping_thres_min = min_log_odds;
  clamping_thres_max = max_log_odds;
  log_clamps_set_ = true;
  log_clamp_min_ = min_log_odds;
  log_clamp_max_ = max_log_odds;
}

void EvidentialOcTree::clampOccupancy() {
  for (auto it = begin_leafs(); it != end_leafs(); ++it) {
    it->setLogOdds(clampLogOdds(it->getLogOdds(), clamping_thres_min, clamping_thres_max));
  }
  updateInnerNodes();
}

void EvidentialOcTree::merge(const EvidentialOcTree& other) {
  checkCompatible(other, "merge");
  evidence_log_sum_ += other.evidence_log_sum_;  // the merged map reads as the sequential one
  evidence_points_ += other.evidence_points_;
  followEvidenceStatistic();
  if (!other.root) return;
  Edit edit(pool_.get(), 1024);
  if (!root) {
    root = new EvidentialOcTreeNode();
    tree_size = 1;
    copySubtree(other, other.root, root, edit);
    commit(edit);
    linkSummariesRecurs(root, 0);
    return;
  }
  // Leaf-level fusion: log-odds add (clamped), payload increments add. Both are commutative.
  auto fuseLeaf = [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src) {
    dst->setLogOdds(clampLogOdds(dst->getLogOdds() + src->getLogOdds(), clamping_thres_min,
                                 clamping_thres_max));
    float from[kMaxClasses];
    if (other.payload(src, from)) addToLeaf(dst, from, edit);
  };
  // Applies src (a leaf) to every leaf below dst; children dst lacks become copies of src.
  std::function<void(EvidentialOcTreeNode*, const EvidentialOcTreeNode*)> spread =
      [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src) {
        if (!nodeHasChildren(dst)) return fuseLeaf(dst, src);
        for (unsigned i = 0; i < 8; ++i) {
          if (nodeChildExists(dst, i)) {
            spread(getNodeChild(dst, i), src);
          } else {
            copySubtree(other, src, createChild(dst, i, edit), edit);
          }
        }
      };
  std::function<void(EvidentialOcTreeNode*, const EvidentialOcTreeNode*)> mergeRecurs =
      [&](EvidentialOcTreeNode* dst, const EvidentialOcTreeNode* src) {
        if (!other.nodeHasChildren(src)) return spread(dst, src);
        if (!nodeHasChildren(dst)) expandLeaf(dst, edit);  // dst is a (pruned) leaf: refine it
        for (unsigned i = 0; i < 8; ++i) {
          if (!other.nodeChildExists(src, i)) continue;
          if (nodeChildExists(dst, i)) {
            mergeRecurs(getNodeChild(dst, i), other.getNodeChild(src, i));
          } else {
            copySubtree(other, other.getNodeChild(src, i), createChild(dst, i, edit), edit);
          }
        }
      };
  mergeRecurs(root, other.root);
  updateInnerRecurs(root, 0, edit);
  commit(edit);
}

// --- OctoMap overrides -----------------------------------------------------------------------

bool EvidentialOcTree::isNodeCollapsible(const EvidentialOcTreeNode* node) const {
  if (!nodeChildExists(node, 0)) return false;
  const EvidentialOcTreeNode* first = getNodeChild(node, 0);
  if (nodeHasChildren(first)) return false;
  for (unsigned i = 1; i < 8; ++i) {
    if (!nodeChildExists(node, i)) return false;
    const EvidentialOcTreeNode* child = getNodeChild(node, i);
    if (nodeHasChildren(child) || child->getValue() != first->getValue()) return false;
    // Unlike ColorOcTree, semantics must be identical too, so pruning never changes a query.
    if (first->hasSemantics() != child->hasSemantics()) return false;
  }
  return equalChildPayloads(node);
}

// Of eight leaves that agree on occupancy and on having semantics.
bool EvidentialOcTree::equalChildPayloads(const EvidentialOcTreeNode* node) const {
  const EvidentialOcTreeNode* first = getNodeChild(node, 0);
  if (!first->hasSemantics()) return true;
  float first_values[kMaxClasses], child_values[kMaxClasses];
  pool_->decode(first->payload_, first_values);
  for (unsigned i = 1; i < 8; ++i) {
    pool_->decode(getNodeChild(node, i)->payload_, child_values);
    if (!std::equal(first_values, first_values + num_classes_, child_values)) return false;
  }
  return true;
}

void EvidentialOcTree::expandNode(EvidentialOcTreeNode* node) {
  Edit edit(pool_.get(), 8);
  expandLeaf(node, edit);
  commit(edit);
}

bool EvidentialOcTree::pruneNode(EvidentialOcTreeNode* node) {
  Edit edit(pool_.get(), 1);
  const bool pruned = pruneChildren(node, edit);
  commit(edit);
  return pruned;
}

void EvidentialOcTree::prune() {
  OccupancyOcTreeBase<EvidentialOcTreeNode>::prune();
  if (root) linkSummariesRecurs(root, 0);  // summaries may name slots pruning released
}

void EvidentialOcTree::clear() {
  OccupancyOcTreeBase<EvidentialOcTreeNode>::clear();
  if (pool_) pool_->reset(num_classes_, pool_->prior());
  evidence_log_sum_ = 0.0;
  evidence_points_ = 0;
}

size_t EvidentialOcTree::memoryUsage() const {
  return OccupancyOcTreeBase<EvidentialOcTreeNode>::memoryUsage() + pool_->bytes();
}

// --- registration with AbstractOcTree (the ColorOcTree pattern) -----------------------------

EvidentialOcTree::StaticMemberInitializer::StaticMemberInitializer() {
  auto* tree = new EvidentialOcTree(0.1);
  tree->clearKeyRays();
  AbstractOcTree::registerTreeType(tree);
}

EvidentialOcTree::StaticMemberInitializer EvidentialOcTree::evidential_octree_member_init_;

}  // namespace evidential_octomap
