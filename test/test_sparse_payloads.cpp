// Sparse payloads in the tree: random sequences of batched updates, hand edits, merges,
// addEvidence, pruning and expansion, compaction, copies and file round trips leave every
// voxel's payload bit for bit what a dense reference kept here says (per voxel: C floats,
// updated with the rule's own add), and every inner summary its richest child's.
#include <gtest/gtest.h>
#include <octomap/octomap.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <tuple>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

using KeyTuple = std::tuple<int, int, int>;
using Dense = std::map<KeyTuple, std::vector<float>>;  // voxel -> its C floats
KeyTuple tupleOf(const octomap::OcTreeKey& k) { return {k[0], k[1], k[2]}; }

constexpr int kSide = 12;  // voxels per axis of the region the sequence edits

class Sequence {
 public:
  Sequence(const std::string& rule, int num_classes, unsigned seed)
      : rng_(seed), num_classes_(num_classes) {
    config_.rule = rule;
    config_.threads = 1;  // the parallel update has its own tests
    tree_ = std::make_unique<EvidentialOcTree>(0.2, num_classes, config_);
  }
  EvidentialOcTree& tree() { return *tree_; }
  const Dense& reference() const { return reference_; }

  void step() {
    const double op = unit();
    if (op < 0.35) return update();
    if (op < 0.5) return handEdit();
    if (op < 0.6) return mergeRandomMap();
    if (op < 0.7) return addRandomEvidence();
    if (op < 0.8) return tree_->prune();
    if (op < 0.85) return tree_->expand();
    if (op < 0.9) return detail::TreeEditing::compactPayloads(*tree_);
    if (op < 0.95) return roundTrip();
    tree_ = std::make_unique<EvidentialOcTree>(*tree_);  // copy constructor
  }

 private:
  double unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }
  octomap::OcTreeKey randomKey() {
    auto axis = [&] { return octomap::key_type(32768 - kSide / 2 + int(rng_() % kSide)); };
    return octomap::OcTreeKey(axis(), axis(), axis());
  }
  // Increments with a few non-zero classes (sometimes all, sometimes a huge one that makes the
  // dempster rule scale the whole payload down to its bound).
  std::vector<double> row() {
    std::vector<double> r(num_classes_, 0.0);
    const bool dense = unit() < 0.1;
    const int count = 1 + int(rng_() % 3);
    for (int i = 0; i < (dense ? num_classes_ : count); ++i) {
      const int c = dense ? i : int(rng_() % num_classes_);
      r[c] = unit() < 0.05 ? 800.0 : unit() * 3.0;
    }
    return r;
  }
  std::vector<float> priorValues() const {
    return std::vector<float>(num_classes_, tree_->rule().prior());
  }
  std::vector<float>& voxel(Dense& dense, const octomap::OcTreeKey& key) const {
    auto it = dense.find(tupleOf(key));
    return it != dense.end() ? it->second : (dense[tupleOf(key)] = priorValues());
  }
  // What addEvidence and merge do to a voxel holding `into`: += from - prior, the rule's add.
  void addPayload(std::vector<float>& into, const std::vector<float>& from) const {
    std::vector<double> increments(from.begin(), from.end());
    for (double& v : increments) v -= tree_->rule().prior();
    tree_->rule().add(into.data(), increments.data(), num_classes_);
  }

  void update() {
    std::map<KeyTuple, VoxelUpdate> unique;  // one update per key
    std::vector<double> rows;
    const int n = 1 + int(rng_() % 60);
    for (int i = 0; i < n; ++i) {
      VoxelUpdate u;
      u.key = randomKey();
      u.occupancy = int8_t(int(rng_() % 3) - 1);
      if (unit() < 0.8) {
        u.increments = uint32_t(rows.size() / num_classes_);
        const std::vector<double> r = row();
        rows.insert(rows.end(), r.begin(), r.end());
      }
      unique[tupleOf(u.key)] = u;
    }
    std::vector<VoxelUpdate> updates;
    for (const auto& [key, u] : unique) {
      updates.push_back(u);
      if (u.increments == VoxelUpdate::kNoIncrements) continue;
      tree_->rule().add(voxel(reference_, u.key).data(), rows.data() + u.increments * num_classes_,
                        num_classes_);
    }
    detail::TreeEditing::applyUpdates(*tree_, updates, rows, true);
  }

  void handEdit() {
    const octomap::OcTreeKey key = randomKey();
    std::vector<float> values = priorValues();
    for (int c = 0; c < num_classes_; ++c) {
      if (unit() < 0.2) values[c] += float(unit() * 5.0);
    }
    detail::TreeEditing::setPayload(*tree_, detail::TreeEditing::leafForUpdate(*tree_, key, true), values.data());
    reference_[tupleOf(key)] = values;
    detail::TreeEditing::updateInnerNodes(*tree_);
  }

  // A map of the same settings with payloads on random voxels (and its dense form).
  std::unique_ptr<EvidentialOcTree> randomMap(Dense* dense) {
    auto map = std::make_unique<EvidentialOcTree>(0.2, num_classes_, config_);
    const int n = 1 + int(rng_() % 40);
    for (int i = 0; i < n; ++i) {
      const octomap::OcTreeKey key = randomKey();
      std::vector<float> values = priorValues();
      for (int c = 0; c < num_classes_; ++c) {
        if (unit() < 0.15) values[c] += float(unit() * 4.0);
      }
      detail::TreeEditing::setPayload(*map, detail::TreeEditing::leafForUpdate(*map, key, true), values.data());
      (*dense)[tupleOf(key)] = values;
    }
    detail::TreeEditing::updateInnerNodes(*map);  // prunes equal siblings: blocks stand for their voxels
    return map;
  }

  void mergeRandomMap() {
    Dense other;
    const auto map = randomMap(&other);
    for (const auto& [key, values] : other) {
      const octomap::OcTreeKey k(std::get<0>(key), std::get<1>(key), std::get<2>(key));
      if (tree_->search(k)) {
        addPayload(voxel(reference_, k), values);
      } else {
        reference_[key] = values;  // a node this map lacks is copied
      }
    }
    tree_->merge(*map);
  }

  void addRandomEvidence() {
    Dense other;
    const auto map = randomMap(&other);
    for (const auto& [key, values] : other) {
      const octomap::OcTreeKey k(std::get<0>(key), std::get<1>(key), std::get<2>(key));
      if (tree_->search(k)) addPayload(voxel(reference_, k), values);
    }
    tree_->addEvidence(*map, nullptr);
  }

  void roundTrip() {
    std::stringstream file;
    ASSERT_TRUE(tree_->write(file));
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(file));
    ASSERT_NE(dynamic_cast<EvidentialOcTree*>(read.get()), nullptr);
    tree_.reset(static_cast<EvidentialOcTree*>(read.release()));
    SemanticConfig config = tree_->config();  // threads are not stored in a file
    config.threads = 1;
    tree_->setConfig(config);
  }

  std::mt19937 rng_;
  int num_classes_;
  SemanticConfig config_;
  std::unique_ptr<EvidentialOcTree> tree_;
  Dense reference_;
};

// Every voxel's payload (pruned blocks expanded in a copy) against the reference.
void expectVoxelsMatch(const EvidentialOcTree& tree, const Dense& reference,
                       const std::string& where) {
  EvidentialOcTree expanded(tree);
  expanded.expand();
  Dense got;
  for (auto it = expanded.begin_leafs(); it != expanded.end_leafs(); ++it) {
    if (it->hasSemantics()) got[tupleOf(it.getKey())] = expanded.payload(&*it);
  }
  ASSERT_EQ(got.size(), reference.size()) << where;
  for (const auto& [key, values] : reference) {
    const auto it = got.find(key);
    ASSERT_NE(it, got.end()) << where;
    for (size_t c = 0; c < values.size(); ++c) {
      ASSERT_TRUE(test::sameBits(it->second[c], values[c]))
          << where << ": class " << c << " " << it->second[c] << " vs " << values[c];
    }
  }
  EXPECT_EQ(tree.numSemanticNodes(),
            size_t(std::count_if(tree.begin_leafs(), tree.end_leafs(),
                                 [](const EvidentialOcTreeNode& n) { return n.hasSemantics(); })))
      << where;
}

// Every inner node reads its richest child's payload (largest sum, first on ties).
void expectSummaries(const EvidentialOcTree& tree, const std::string& where) {
  for (auto it = tree.begin_tree(); it != tree.end_tree(); ++it) {
    if (it.isLeaf()) continue;
    std::vector<float> richest;
    double best = 0.0;
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree.nodeChildExists(&*it, i)) continue;
      const std::vector<float> p = tree.payload(tree.getNodeChild(&*it, i));
      if (p.empty()) continue;
      const double sum = std::accumulate(p.begin(), p.end(), 0.0);
      if (richest.empty() || sum > best) richest = p, best = sum;
    }
    ASSERT_EQ(tree.payload(&*it), richest) << where << ": inner node at depth " << it.getDepth();
  }
}

TEST(SparsePayloads, RandomSequencesMatchADenseReference) {
  // OctoMap's tree constructor opens an OpenMP region; its idle threads would spin-wait through
  // the many small trees made here.
  omp_set_num_threads(1);
  for (const std::string rule : {"dempster", "sbki", "ebs"}) {
    for (int num_classes : {3, 20, 40}) {
      Sequence sequence(rule, num_classes, unsigned(num_classes * 31 + rule.size()));
      for (int step = 0; step < 300; ++step) {
        sequence.step();
        if (::testing::Test::HasFatalFailure()) return;
        if (step % 10 != 9) continue;
        const std::string where =
            rule + " C=" + std::to_string(num_classes) + " step " + std::to_string(step);
        expectVoxelsMatch(sequence.tree(), sequence.reference(), where);
        expectSummaries(sequence.tree(), where);
        if (::testing::Test::HasFatalFailure()) return;
      }
    }
  }
}

}  // namespace
}  // namespace evidential_octomap
