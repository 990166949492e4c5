// Clearing observations discount semantic evidence (SemanticConfig::clearing_observations): a
// voxel that a moving person or vehicle filled and that rays now pass through forgets its class.
// Dempster-Shafer contextual discounting in the stored form: the evidence above the prior of
// every class that this scan's points around the voxel do not show is scaled by one factor, so
// the shares among them stay; a class the scan's kernel row still gives the voxel (a static
// surface beside it, seen again) keeps what it had. A movable class (a class table's person or
// vehicle) is never protected so: a mover's own points spread it into the voxels it has just
// left, which rays may not cross again once it has gone.
#include <algorithm>

#include "evidential_octomap/evidential_octree.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

// A class this share of the row's largest increment, or more, is shown by the scan.
constexpr double kShownShare = 0.25;

}  // namespace

EvidentialOcTree::ClearingRule EvidentialOcTree::clearingRule() const {
  if (!discountsClearings()) return {};
  ClearingRule rule{std::vector<double>(num_classes_), std::vector<char>(num_classes_)};
  for (int c = 0; c < num_classes_; ++c) {
    const bool movable = size_t(c) < movable_classes_.size() && movable_classes_[c];
    rule.keep[c] = InsertSettings::clearingKeep(config_.clearingsOf(movable));
    rule.movable[c] = movable && config_.movable_clearing_observations > 0;
  }
  return rule;
}

void EvidentialOcTree::updateDiscountsClearings() {
  const bool any_movable =
      std::find(movable_classes_.begin(), movable_classes_.end(), true) != movable_classes_.end();
  discounts_clearings_ = config_.clearingsOf(any_movable) > 0;
}

void EvidentialOcTree::discountClearedLeaf(EvidentialOcTreeNode* leaf, const double* increments,
                                           const ClearingRule& rule, float* values, Edit& edit) {
  leafValues(leaf, values);
  if (!leaf->hasSemantics()) return;
  const float prior = rule_->prior();
  double largest = 0.0;  // of the row as it is added: without movable classes
  for (int c = 0; increments && c < num_classes_; ++c)
    if (!rule.movable[c]) largest = std::max(largest, increments[c]);
  double left = 0.0;
  bool changed = false;
  for (int c = 0; c < num_classes_; ++c) {
    const bool shown =
        !rule.movable[c] && largest > 0.0 && increments[c] >= kShownShare * largest;
    if (!shown && values[c] != prior) {
      const float kept = prior + float(rule.keep[c] * (double(values[c]) - prior));
      changed |= kept != values[c];
      values[c] = kept;
    }
    left += double(values[c]) - prior;
  }
  if (left >= SemanticConfig::kReleasedEvidence) {
    // Most cleared voxels hold no movable class and only those are discounted by default:
    // nothing to store.
    if (changed) storeLeafValues(leaf, values, edit);
    return;
  }
  std::fill_n(values, num_classes_, prior);
  if (config_.semantic_occupied_only) {
    // A surface map answers a voxel without a payload from the surface around it
    // (query_support.cpp), which is where a mover's evidence lingers: a vacuous payload keeps
    // this voxel, seen empty, answering no class, as the default map's released voxel does.
    storeLeafValues(leaf, values, edit);
  } else {
    releaseLeafPayload(leaf, edit);
  }
}

}  // namespace evidential_octomap
