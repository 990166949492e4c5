// Clearing observations discount semantic evidence (SemanticConfig::clearing_observations): a
// voxel that a moving person or vehicle filled and that rays now pass through forgets its class.
// Dempster-Shafer discounting in the stored form: every class's evidence above the prior is
// scaled by one factor, so its shares, hence the argmax, stay; only the amount shrinks.
#include "evidential_octomap/evidential_octree.h"
#include "tree_edit.h"

namespace evidential_octomap {

void EvidentialOcTree::discountClearedLeaf(EvidentialOcTreeNode* leaf, Edit& edit) {
  if (!leaf->hasSemantics()) return;
  const double keep = config_.clearingKeep();
  const float prior = rule_->prior();
  float values[kMaxClasses];
  leafValues(leaf, values);
  double left = 0.0;
  for (int c = 0; c < num_classes_; ++c) {
    values[c] = prior + float(keep * (double(values[c]) - prior));
    left += double(values[c]) - prior;
  }
  if (left < SemanticConfig::kReleasedEvidence) {
    releaseLeafPayload(leaf, edit);
  } else {
    storeLeafValues(leaf, values, edit);
  }
}

}  // namespace evidential_octomap
