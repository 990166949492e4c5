// Clearing observations discount semantic evidence (SemanticConfig::clearing_observations): a
// voxel that a moving person or vehicle filled and that rays now pass through forgets its class.
// Dempster-Shafer discounting in the stored form: every class's evidence above the prior is
// scaled by one factor, so its shares, hence the argmax, stay; only the amount shrinks.
#include <algorithm>

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
  if (left >= SemanticConfig::kReleasedEvidence) {
    storeLeafValues(leaf, values, edit);
  } else if (config_.semantic_occupied_only) {
    // A surface map answers a voxel without a payload from the surface around it
    // (query_support.cpp), which is where a mover's evidence lingers: a vacuous payload keeps
    // this voxel, seen empty, answering no class, as the default map's released voxel does.
    std::fill_n(values, num_classes_, prior);
    storeLeafValues(leaf, values, edit);
  } else {
    releaseLeafPayload(leaf, edit);
  }
}

}  // namespace evidential_octomap
