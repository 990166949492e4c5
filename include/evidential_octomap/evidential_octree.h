// EvidentialOcTree: an OctoMap occupancy tree whose voxels also carry fused semantic evidence.
// Shaped like OctoMap's ColorOcTree (node type, tree type, static registration), with one
// difference: the C floats of semantic evidence live in a store owned by the tree and the node
// keeps a 32-bit reference into it. A node therefore costs exactly what an OcTreeNode costs
// (16 B); only leaves that received evidence pay for a payload, and only for the classes whose
// value differs from the rule's prior (a sparse slot; readers get all C floats decoded). An inner
// node stores no payload of its own: its reference names the payload of its richest leaf (see
// updateInnerNodes).
#pragma once

#include <octomap/OcTreeNode.h>
#include <octomap/OccupancyOcTreeBase.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/fusion_rule.h"
#include "evidential_octomap/semantic_config.h"
#include "evidential_octomap/sensor_model.h"

namespace evidential_octomap {

struct ClassTable;
class EvidentialOcTree;
class PayloadStore;
class ScanIntegrator;
class SubtreeSource;
struct SubtreeSeed;
struct DroppedRows;
class LogOddsTable;
class TiledMap;
struct NodeCoding;
struct VoxelUpdate;
namespace detail {
class TreeEditing;
}

class EvidentialOcTreeNode : public octomap::OcTreeNode {
 public:
  static constexpr uint32_t kNoPayload = 0xFFFFFFFFu;

  bool hasSemantics() const { return payload_ != kNoPayload; }

  // Nodes live in 16-byte cells of a pool (node_allocator.h), not in malloc's 32-byte chunks:
  // a third of a map's nodes-and-pointers memory. Every node of the tree is made by `new` and
  // freed by `delete` on this type (OctoMap and this library alike), so both come here.
  static void* operator new(size_t size);
  static void operator delete(void* node, size_t size);

  // Occupancy and payload slot are compared; the tree compares payload contents.
  bool operator==(const EvidentialOcTreeNode& rhs) const {
    return rhs.value == value && rhs.payload_ == payload_;
  }
  // OctoMap calls copyData when it expands or prunes; our tree overrides both and moves
  // payloads itself, so only occupancy is copied here (a copied slot would alias).
  void copyData(const EvidentialOcTreeNode& from) { value = from.value; }

 private:
  friend class EvidentialOcTree;
  // Children are made and deleted here, as OctoMap allocates and frees them, but without the
  // tree's node count, which the caller keeps: threads then edit disjoint subtrees at once.
  EvidentialOcTreeNode* addChild(unsigned i);
  void deleteLeafChildren();  // all eight children (leaves) and the child array
  // Deletes child i (not its children: the caller has emptied it) and the child array once no
  // child is left, so that the node reads as a leaf again only when it has none.
  void deleteChild(unsigned i);

  uint32_t payload_ = kNoPayload;
};

// What one call of insertSemanticScan did.
struct InsertStats {
  size_t points_in = 0;                 // points handed in
  size_t points_skipped = 0;            // non-finite coordinates or outside the tree's key range
  size_t points_beyond_range = 0;       // beyond max_range: free space only, no semantics
  size_t semantic_points = 0;           // points left after down-sampling
  size_t points_dropped_uncertain = 0;  // above the percentile threshold
  double uncertainty_threshold = 0.0;   // U_thr of this scan
  size_t voxels_updated = 0;            // leaves that received semantic evidence
  // Wall time of the three phases [ms]:
  double ms_occupancy = 0.0;  // ray casting (free and occupied voxels)
  double ms_kernel = 0.0;     // semantic points: threshold, down-sampling, opinions, supports
  double ms_update = 0.0;     // one parallel pass over the subtrees: each one's kernel rows (the
                              // kernel loop), then its leaves, inner nodes and pruning
  // Process CPU time (all threads) of the same phases [ms], the kernel loop counted in
  // cpu_ms_kernel although it runs inside the update pass.
  double cpu_ms_occupancy = 0.0;
  double cpu_ms_kernel = 0.0;
  double cpu_ms_update = 0.0;
};

class EvidentialOcTree : public octomap::OccupancyOcTreeBase<EvidentialOcTreeNode> {
 public:
  static constexpr int kMaxClasses = 255;
  // Resolutions a map may have: keys are 16 bit, so the map spans resolution * 65536, which must
  // stay a finite float extent with room for voxel centres.
  static constexpr double kMinResolution = 1e-6, kMaxResolution = 1e6;

  // num_classes in 1..255; class names default to "class_<i>". Throws std::invalid_argument.
  explicit EvidentialOcTree(double resolution, int num_classes = 1,
                            const SemanticConfig& config = SemanticConfig());
  EvidentialOcTree(const EvidentialOcTree& rhs);
  EvidentialOcTree& operator=(const EvidentialOcTree&) = delete;
  ~EvidentialOcTree() override;

  // --- AbstractOcTree -------------------------------------------------------------------
  EvidentialOcTree* create() const override;
  std::string getTreeType() const override { return "EvidentialOcTree"; }

  // --- semantic settings ----------------------------------------------------------------
  int numClasses() const { return num_classes_; }
  const std::vector<std::string>& classNames() const { return class_names_; }
  void setClassNames(const std::vector<std::string>& names);  // size must be C
  // Which classes are ground surfaces (ClassTable::ground): a point whose evidence's argmax is
  // one gets the flatter support SemanticConfig::ground_vertical_support. Size C, or empty
  // (none, the default). Stored in the .ot file.
  void setGroundClasses(const std::vector<bool>& ground);
  const std::vector<bool>& groundClasses() const { return ground_classes_; }
  bool isGroundClass(int c) const {
    return c >= 0 && size_t(c) < ground_classes_.size() && ground_classes_[c];
  }
  // Which classes move (ClassTable::movable: people, vehicles): a voxel that rays find empty
  // again forgets them after SemanticConfig::movable_clearing_observations clearings. Size C, or
  // empty (none, the default). An insertion property like the config's insertion settings: not
  // stored in the .ot file.
  void setMovableClasses(const std::vector<bool>& movable);
  const std::vector<bool>& movableClasses() const { return movable_classes_; }
  // A class table's names, ground and movable flags at once (its C must be this map's).
  void setClasses(const ClassTable& classes);
  const SemanticConfig& config() const { return config_; }
  // Throws std::invalid_argument for values SemanticConfig::problem() refuses. Changing the rule
  // re-interprets stored payloads, so it is refused (std::logic_error) while the map holds any.
  void setConfig(const SemanticConfig& config);
  const FusionRule& rule() const { return *rule_; }
  // The error model of a calibration file (calibration_file.h) that the read-out applies, kept
  // across setConfig; null removes it. A map's file does not store it: it belongs to the
  // network, not to the map. Throws std::invalid_argument unless the rule is dempster.
  void setErrorModel(std::shared_ptr<const ErrorModel> model);
  const std::shared_ptr<const ErrorModel>& errorModel() const { return error_model_; }
  // The dempster read-out cap in use: config().evidence_cap, or the adaptive cap of the
  // evidence inserted so far (SemanticConfig::kAdaptiveCap).
  double effectiveEvidenceCap() const;
  // Mean over the points inserted (and merged) so far of sum_c log1p(e^c / C), the statistic
  // the adaptive cap follows; 0 before the first insert.
  double meanPointLogEvidence() const {
    return evidence_points_ ? evidence_log_sum_ / double(evidence_points_) : 0.0;
  }
  // OctoMap's occupancy model, set as one checked value (std::invalid_argument outside
  // SensorModel's ranges). OctoMap's own setProbHit & co. stay available but unchecked: a tree
  // set outside the ranges through them is refused by writeData and saveMap.
  SensorModel sensorModel() const;
  void setSensorModel(const SensorModel& model);
  // "" when resolution, sensor model and semantic config are all inside the shared ranges, so
  // that what writeData writes, readData reads back; else what is wrong.
  std::string parameterProblem() const;
  // What insertSemanticScan checks before it changes anything: parameterProblem() (the text
  // saveMap gives after "cannot save <path>: "), except clamping bounds set through
  // setClampingThresLog (unbounded chunk maps, clamped before they are saved).
  std::string insertProblem() const;

  // --- integration ----------------------------------------------------------------------
  // Inserts one scan: occupancy by OctoMap ray casting from origin_W, semantics by the
  // adaptive sparse kernel. points_W are in the world (tree) frame; evidence is N x C,
  // row-major, one evidence vector per point (each value finite and >= 0).
  // Throws std::invalid_argument (and leaves the map unchanged) when evidence is malformed, the
  // kernel support is beyond what a scan may cost (SemanticConfig::supportProblem), or the map's
  // parameters are ones saveMap would refuse (insertProblem(): e.g. OctoMap's setProbHit(1.0),
  // setProbMiss(0), setClampingThresMin(0), NaN, or setResolution(0)), with saveMap's reason.
  // With `unobserved` (a map of equal resolution, C and rule), the evidence this map drops
  // because its voxel has not been observed yet (kernel updates outside known space,
  // kernel_creates_leaves off) is added there instead: what a later chunk of a sequence hands
  // to the chunks before it for an exact merge (addEvidence).
  InsertStats insertSemanticScan(const octomap::Pointcloud& points_W,
                                 const std::vector<float>& evidence,
                                 const octomap::point3d& origin_W,
                                 EvidentialOcTree* unobserved = nullptr);
  // Same, with points in the sensor frame and the sensor pose T_W_S.
  InsertStats insertSemanticScan(const octomap::Pointcloud& points_S,
                                 const std::vector<float>& evidence, const octomap::pose6d& T_W_S);
  // Bytes of the scratch buffers kept for the next insert (not part of memoryUsage()): what the
  // last scan needed; a buffer holding over twice that (and over 256 KiB) is released after the
  // scan. 0 before the first insert.
  size_t scratchBytes() const;

  // --- queries --------------------------------------------------------------------------
  VoxelOpinion opinion(const EvidentialOcTreeNode* node) const;  // node may be null
  // The node holding point_W (a leaf, or a pruned block), or nullptr where the map knows nothing.
  // Use it instead of OctoMap's search(point), which casts coordinate / resolution to int first:
  // undefined behaviour for NaN, inf and points beyond the map's extent, answered nullptr here.
  const EvidentialOcTreeNode* nodeAt(const octomap::point3d& point_W) const;
  // The map's answer at a point: the opinion of its voxel's own evidence, or, when the map keeps
  // its evidence on the surface (config().semantic_occupied_only) and the voxel is known without
  // any, the answer of the voxels with evidence within a point's full kernel support
  // (query_support.cpp; a free voxel's without the movable classes while they are cleared);
  // vacuous (label -1) in unknown space. A free voxel answers a movable class (clearing on) only
  // while an occupied voxel within the support answers it: a mover's ghost is not answered.
  VoxelOpinion query(const octomap::point3d& point_W) const;
  VoxelOpinion answer(const octomap::OcTreeKey& key) const;
  // The same answer as payload values (C floats into `out`); false where there is none.
  bool answerPayload(const octomap::OcTreeKey& key, float* out) const;
  // The node's own opinion at `key` and depth (OctoMap's search), without the support answer.
  VoxelOpinion query(const octomap::OcTreeKey& key, unsigned depth = 0) const;
  // The node's C floats (rule-specific, see fusion_rule.h) decoded into `out` (room for C
  // floats); false, leaving `out` untouched, if it has none (or node is null). For an inner
  // node, the payload of its richest leaf.
  bool payload(const EvidentialOcTreeNode* node, float* out) const;
  // The same as a vector: C floats, or empty if the node has none.
  std::vector<float> payload(const EvidentialOcTreeNode* node) const;
  // Leaves that hold semantic evidence (each owns one payload slot).
  size_t numSemanticNodes() const;

  // --- maps as a whole ------------------------------------------------------------------
  // Fuses another map of the same resolution, C and rule into this one. Occupancy log-odds add
  // (clamped) and payloads add, so a.merge(b) and b.merge(a) give equal maps.
  void merge(const EvidentialOcTree& other);
  // Adds the semantic evidence of `evidence` (a map of equal resolution, C and rule; occupancy
  // ignored) to the voxels this map has observed; the evidence of voxels it has not observed
  // goes to `rest` when given (else it is dropped, as the integrator drops it). With chunk maps
  // of a sequence built with `unobserved` maps, earlier.addEvidence(later_unobserved, &rest)
  // before earlier.merge(later) gives exactly the sequentially built map.
  void addEvidence(const EvidentialOcTree& evidence, EvidentialOcTree* rest);
  // Occupancy clamping bounds in log-odds. OctoMap's setters take probabilities, which cannot
  // say "unbounded": chunk maps that are merged later may keep unbounded log-odds
  // (-FLT_MAX, FLT_MAX), so the merged map is clamped once, at the end (clampOccupancy).
  void setClampingThresLog(float min_log_odds, float max_log_odds);
  // Clamps every node's log-odds to the current bounds, then recomputes inner nodes and prunes.
  void clampOccupancy();

  // --- OctoMap overrides ----------------------------------------------------------------
  bool isNodeCollapsible(const EvidentialOcTreeNode* node) const override;
  void expandNode(EvidentialOcTreeNode* node) override;
  bool pruneNode(EvidentialOcTreeNode* node) override;
  void prune() override;
  void clear() override;
  size_t memoryUsage() const override;
  // The data section (format in ot_format.cpp): semantic header, every node (log-odds, child
  // mask, and for leaves the payload), a CRC-32 of the section. writeData fails the stream,
  // writing nothing, when parameterProblem() is not "", and fails it part-way when an inner
  // node's occupancy is stale (OctoMap's lazy_eval updates or deleteNode without
  // updateInnerNodes()). readData reads files of formats 1 (no CRC), 2 (inner payloads stored)
  // and 3, checks the CRC, every parameter and every inner node against its children.
  std::istream& readData(std::istream& s) override;
  std::ostream& writeData(std::ostream& s) const override;
  // Why the last readData failed (empty after a good read). A failed read leaves the tree empty.
  const std::string& readError() const { return read_error_; }
  // True for a tree that AbstractOcTree::read created and never passed its data section: OctoMap
  // skips readData when the header says "size 0", leaving C, names, rule and parameters at their
  // defaults. readProblem() (io.h) checks this and readError() in one call.
  bool dataSectionSkipped() const { return created_for_read_; }

 private:
  // What one thread's edit of the tree changes besides the nodes themselves (tree_edit.h).
  struct Edit;
  struct UpdateBatch;
  struct UpdateTask;
  struct TopPass;
  friend class detail::TreeEditing;  // the editing calls below, for readers, tests and fuzzing
  friend class TiledMap;  // splits maps into tiles and streams tiles into one .ot (tiled_map.h)

  void setNumClasses(int num_classes);
  // The support answer of a voxel without evidence (query_support.cpp): the support length of a
  // point without uncertainty, the voxels it spans, and the kernel-weighted values.
  double queryLength() const;
  std::array<int, 3> querySupportReach() const;  // voxels on x, y, z
  double querySupportVertical() const;            // the tallest neighbour support / width
  // `free_voxel`: the voxel is free, so (movable clearing on) no movable class is answered.
  bool supportPayload(const octomap::OcTreeKey& key, bool free_voxel, float* out) const;
  // A free voxel's `values`: each movable class (clearing on) that no occupied voxel within the
  // support answers is set to the prior (a ghost of an object that has left).
  void dropMovableWithoutSurface(const octomap::OcTreeKey& key, float* values) const;
  // Editing: detail/tree_editing.h says what each does.
  EvidentialOcTreeNode* leafForUpdate(const octomap::OcTreeKey& key, bool create);
  void setPayload(EvidentialOcTreeNode* leaf, const float* values);
  void clearPayload(EvidentialOcTreeNode* node);
  size_t applyUpdates(std::vector<VoxelUpdate> updates, const std::vector<double>& increments,
                      bool create_semantic_leaves);
  size_t applySortedUpdates(const VoxelUpdate* updates, size_t count,
                            const std::vector<double>& increments, bool create_semantic_leaves);
  void updateInnerNodes();
  void compactPayloads();
  std::unique_ptr<EvidentialOcTree> detachSubtree(const octomap::OcTreeKey& key, unsigned depth);
  std::unique_ptr<EvidentialOcTree> emptyLike() const;  // equal settings, no nodes, no statistic
  void deleteDescendants(EvidentialOcTreeNode* node, Edit& edit);
  void checkCompatible(const EvidentialOcTree& other, const char* what) const;
  // into += from - prior per class, saturating at FLT_MAX (crafted files may hold huge values).
  void addPayload(float* into, const float* from) const;
  void commit(Edit& edit);
  EvidentialOcTreeNode* createChild(EvidentialOcTreeNode* node, unsigned i, Edit& edit);
  // A leaf's C floats into `out`: its payload, or the prior when it has none.
  void leafValues(const EvidentialOcTreeNode* leaf, float* out) const;
  void storeLeafValues(EvidentialOcTreeNode* leaf, const float* values, Edit& edit);
  // leaf's payload += from - prior (addPayload), stored.
  void addToLeaf(EvidentialOcTreeNode* leaf, const float* from, Edit& edit);
  void releaseLeafPayload(EvidentialOcTreeNode* leaf, Edit& edit);
  // How a clearing observation treats each class (clearing_discount.cpp): the factor it keeps
  // of the class's evidence, and whether the class is movable with its clearings on (then this
  // scan's kernel row does not protect it, nor adds to it). Empty when no class is ever cleared.
  struct ClearingRule {
    std::vector<double> keep;
    std::vector<char> movable;
    std::vector<uint32_t> discounted;  // the classes with keep < 1, one bit each (32 a word)
  };
  ClearingRule clearingRule() const;
  // Whether class c is movable with its clearing on (movable_clearing_observations > 0).
  bool clearsMovable(int c) const {
    return config_.movable_clearing_observations > 0 && size_t(c) < movable_classes_.size() &&
           movable_classes_[c];
  }
  // A clearing observation of a leaf: its payload discounted by the rule, released below
  // kReleasedEvidence (SemanticConfig::clearing_observations); `increments`: this scan's kernel
  // row for the leaf (C values), or nullptr. True when `values` (C floats) got the leaf's values
  // after it; false when nothing there is discounted (the leaf untouched, `values` not set).
  bool discountClearedLeaf(EvidentialOcTreeNode* leaf, const double* increments,
                           const ClearingRule& rule, float* values, Edit& edit);
  // Whether a clearing may change what `node` holds: evidence of a class the rule discounts.
  bool clearingMayChange(const EvidentialOcTreeNode* node, const ClearingRule& rule) const;
  bool discountsClearings() const { return discounts_clearings_; }
  void updateDiscountsClearings();
  void expandLeaf(EvidentialOcTreeNode* node, Edit& edit);
  bool pruneChildren(EvidentialOcTreeNode* node, Edit& edit);  // when isNodeCollapsible
  void collapseChildren(EvidentialOcTreeNode* node, Edit& edit);
  bool equalChildPayloads(const EvidentialOcTreeNode* node) const;
  void linkSummary(EvidentialOcTreeNode* node) const;
  void updateInnerNode(EvidentialOcTreeNode* node, Edit& edit);
  void updateInnerRecurs(EvidentialOcTreeNode* node, unsigned depth, Edit& edit);
  void linkSummariesRecurs(EvidentialOcTreeNode* node, unsigned depth) const;
  void copySubtree(const EvidentialOcTree& from, const EvidentialOcTreeNode* src,
                   EvidentialOcTreeNode* dst, Edit& edit);
  // The child whose payload an inner node summarises (largest sum, first on ties), or nullptr.
  const EvidentialOcTreeNode* richestChild(const EvidentialOcTreeNode* node) const;
  // The sum of a node's payload values, -inf when it has none (never the richest).
  double evidenceSum(const EvidentialOcTreeNode* node) const;
  // "" when an inner node's log-odds are its children's maximum (what updateInnerNode gives it),
  // else what differs. (Its summary is derived from the children and cannot differ.)
  std::string innerNodeProblem(const EvidentialOcTreeNode* node) const;
  // The batched update (batched_update.cpp): the subtrees `source` has updates for, in parallel;
  // rows for voxels the map has no leaf for go to `dropped` (one per thread) when given.
  size_t applySubtrees(SubtreeSource& source, bool create_semantic_leaves, int threads,
                       std::vector<DroppedRows>* dropped);
  // The rows another map dropped (voxels it has no leaf for), added here in one batch.
  void addDroppedRows(std::vector<DroppedRows>& dropped);
  void applyTopRecurs(EvidentialOcTreeNode* node, unsigned depth, bool is_new,
                      const SubtreeSeed* begin, const SubtreeSeed* end, TopPass& pass, Edit& edit);
  size_t applyUpdatesRecurs(EvidentialOcTreeNode* node, unsigned depth, bool is_new,
                            const VoxelUpdate* begin, const VoxelUpdate* end,
                            const UpdateBatch& batch, Edit& edit);
  // The last level of the recursion: the leaves of `node`, one update each, in a loop.
  size_t applyLeafUpdates(EvidentialOcTreeNode* node, const VoxelUpdate* begin,
                          const VoxelUpdate* end, const UpdateBatch& batch, Edit& edit);
  size_t updateLeaf(EvidentialOcTreeNode* leaf, const VoxelUpdate& update,
                    const UpdateBatch& batch, Edit& edit);
  void keepDropped(const VoxelUpdate* begin, const VoxelUpdate* end,
                   const UpdateBatch& batch) const;
  // The data section's bytes with their running CRC-32 (ot_format.cpp).
  class SectionWriter;
  class SectionReader;
  void writeHeader(SectionWriter& out) const;
  void readHeader(SectionReader& in, uint32_t version);
  bool writeNodes(const EvidentialOcTreeNode* root_node, const LogOddsTable& table,
                  SectionWriter& out) const;
  void writePayload(const EvidentialOcTreeNode* leaf, float prior, SectionWriter& out) const;
  void readNodesRecurs(EvidentialOcTreeNode* node, unsigned depth, const NodeCoding& coding,
                       SectionReader& in, Edit& edit);
  void readPayload(EvidentialOcTreeNode* leaf, uint8_t tag, SectionReader& in, Edit& edit);
  static NodeCoding readNodeCoding(SectionReader& in, uint32_t version);

  int num_classes_ = 1;
  std::vector<std::string> class_names_;
  std::vector<bool> ground_classes_;  // empty: no ground class
  std::vector<bool> movable_classes_;  // empty: no movable class
  bool discounts_clearings_ = false;   // some class's clearings are on (clearingRule())
  SemanticConfig config_;
  std::shared_ptr<const ErrorModel> error_model_;
  std::unique_ptr<FusionRule> rule_;
  std::unique_ptr<PayloadStore> pool_;  // one sparse payload per semantic leaf
  std::string read_error_;
  bool created_for_read_ = false;               // made by create(), readData not called yet
  // The bounds setClampingThresLog set, accepted by insertProblem() while they are in use.
  bool log_clamps_set_ = false;
  float log_clamp_min_ = 0.0f, log_clamp_max_ = 0.0f;
  std::unique_ptr<ScanIntegrator> integrator_;  // created on first insert; keeps scratch buffers
  // The adaptive cap's statistic over every point handed to insertSemanticScan.
  double evidence_log_sum_ = 0.0;
  size_t evidence_points_ = 0;
  void followEvidence(const std::vector<float>& evidence);  // adds a scan to the statistic
  void followEvidenceStatistic();                          // reads with the cap it gives
  std::unique_ptr<FusionRule> makeRule(const SemanticConfig& config) const;
  double capOf(const SemanticConfig& config) const;  // the cap `config` reads with here

  // Registers the tree type with AbstractOcTree (the ColorOcTree pattern).
  class StaticMemberInitializer {
   public:
    StaticMemberInitializer();
    void ensureLinking() {}
  };
  static StaticMemberInitializer evidential_octree_member_init_;
};

}  // namespace evidential_octomap
