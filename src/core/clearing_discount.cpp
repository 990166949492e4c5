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
#include "payload_store.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

// A class this share of the row's largest increment, or more, is shown by the scan.
constexpr double kShownShare = 0.25;

}  // namespace

EvidentialOcTree::ClearingRule EvidentialOcTree::clearingRule() const {
  if (!discountsClearings()) return {};
  ClearingRule rule{std::vector<double>(num_classes_), std::vector<char>(num_classes_),
                    std::vector<uint32_t>((num_classes_ + 31) / 32, 0)};
  for (int c = 0; c < num_classes_; ++c) {
    const bool movable = size_t(c) < movable_classes_.size() && movable_classes_[c];
    rule.keep[c] = InsertSettings::clearingKeep(config_.clearingsOf(movable));
    rule.movable[c] = clearsMovable(c);
    if (rule.keep[c] < 1.0) rule.discounted[c / 32] |= uint32_t(1) << (c % 32);
  }
  return rule;
}

void EvidentialOcTree::updateDiscountsClearings() {
  const bool any_movable =
      std::find(movable_classes_.begin(), movable_classes_.end(), true) != movable_classes_.end();
  discounts_clearings_ = config_.clearingsOf(any_movable) > 0;
}

bool EvidentialOcTree::discountClearedLeaf(EvidentialOcTreeNode* leaf, const double* increments,
                                           const ClearingRule& rule, float* values, Edit& edit) {
  // Most cleared voxels hold no class the rule discounts (by default, no movable class): a look
  // at the payload's class mask, nothing decoded, stored or released.
  if (!clearingMayChange(leaf, rule)) return false;
  leafValues(leaf, values);
  const float prior = rule_->prior();
  double largest = 0.0;  // of the row as it is added: without movable classes
  for (int c = 0; increments && c < num_classes_; ++c)
    if (!rule.movable[c]) largest = std::max(largest, increments[c]);
  double left = 0.0;
  bool changed = false;
  for (int c = 0; c < num_classes_; ++c) {
    const bool shown =
        !rule.movable[c] && largest > 0.0 && increments[c] >= kShownShare * largest;
    if (!shown && rule.keep[c] < 1.0 && values[c] != prior) {
      const float kept = prior + float(rule.keep[c] * (double(values[c]) - prior));
      changed |= kept != values[c];
      values[c] = kept;
    }
    left += double(values[c]) - prior;
  }
  if (!changed) return true;  // what it holds, the scan still shows
  if (left >= SemanticConfig::kReleasedEvidence) {
    storeLeafValues(leaf, values, edit);
    return true;
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
  return true;
}

bool EvidentialOcTree::clearingMayChange(const EvidentialOcTreeNode* node,
                                         const ClearingRule& rule) const {
  return node->hasSemantics() && pool_->holdsAny(node->payload_, rule.discounted.data());
}

}  // namespace evidential_octomap
