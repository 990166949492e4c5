// Clearing observations discount semantic evidence (SemanticConfig::clearing_observations): a
// voxel that a moving person or vehicle filled and that rays now pass through forgets its class.
// Dempster-Shafer contextual discounting in the stored form: the evidence above the prior of
// every class that this scan's points around the voxel do not show is scaled by one factor, so
// the shares among them stay; a class the scan's kernel row still gives the voxel (a static
// surface beside it, seen again) keeps what it had.
#include <algorithm>

#include "evidential_octomap/evidential_octree.h"
#include "tree_edit.h"

namespace evidential_octomap {
namespace {

// A class this share of the row's largest increment, or more, is shown by the scan.
constexpr double kShownShare = 0.25;

}  // namespace

void EvidentialOcTree::discountClearedLeaf(EvidentialOcTreeNode* leaf, const double* increments,
                                           Edit& edit) {
  if (!leaf->hasSemantics()) return;
  const double keep = config_.clearingKeep();
  const float prior = rule_->prior();
  const double largest =
      increments ? *std::max_element(increments, increments + num_classes_) : 0.0;
  float values[kMaxClasses];
  leafValues(leaf, values);
  double left = 0.0;
  for (int c = 0; c < num_classes_; ++c) {
    const bool shown = largest > 0.0 && increments[c] >= kShownShare * largest;
    if (!shown) values[c] = prior + float(keep * (double(values[c]) - prior));
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
