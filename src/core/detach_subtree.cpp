// Moving one subtree out of a map into a map of its own (the tiles of local_map.h).
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "payload_store.h"
#include "tree_edit.h"

namespace evidential_octomap {

void EvidentialOcTreeNode::deleteChild(unsigned i) {
  delete static_cast<EvidentialOcTreeNode*>(children[i]);
  children[i] = nullptr;
  for (unsigned j = 0; j < 8; ++j) {
    if (children[j]) return;
  }
  delete[] children;
  children = nullptr;
}

std::unique_ptr<EvidentialOcTree> EvidentialOcTree::emptyLike() const {
  auto tree = std::make_unique<EvidentialOcTree>(resolution, num_classes_, config_);
  tree->class_names_ = class_names_;
  tree->ground_classes_ = ground_classes_;
  tree->setMovableClasses(movable_classes_);
  tree->clamping_thres_min = clamping_thres_min;
  tree->clamping_thres_max = clamping_thres_max;
  tree->prob_hit_log = prob_hit_log;
  tree->prob_miss_log = prob_miss_log;
  tree->occ_prob_thres_log = occ_prob_thres_log;
  tree->log_clamps_set_ = log_clamps_set_;
  tree->log_clamp_min_ = log_clamp_min_;
  tree->log_clamp_max_ = log_clamp_max_;
  return tree;
}

// Frees every node below `node` and the payloads of the leaves among them (and node's own when
// it is a leaf); node itself stays, as a leaf without payload.
void EvidentialOcTree::deleteDescendants(EvidentialOcTreeNode* node, Edit& edit) {
  if (!nodeHasChildren(node)) {
    releaseLeafPayload(node, edit);
    return;
  }
  for (unsigned i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    deleteDescendants(getNodeChild(node, i), edit);
    node->deleteChild(i);
    --edit.nodes;
  }
  node->payload_ = EvidentialOcTreeNode::kNoPayload;  // an inner node only named a leaf's slot
}

std::unique_ptr<EvidentialOcTree> EvidentialOcTree::detachSubtree(const octomap::OcTreeKey& key,
                                                                   unsigned depth) {
  if (!root || depth == 0 || depth > tree_depth) return nullptr;
  std::vector<EvidentialOcTreeNode*> path{root};  // path[d]: the node at depth d
  std::vector<unsigned> child_of;                  // child_of[d]: index of path[d + 1]
  for (unsigned d = 0; d < depth; ++d) {
    EvidentialOcTreeNode* node = path.back();
    const unsigned i = octomap::computeChildIdx(key, tree_depth - 1 - d);
    if (!nodeHasChildren(node) || !nodeChildExists(node, i)) return nullptr;
    child_of.push_back(i);
    path.push_back(getNodeChild(node, i));
  }

  std::unique_ptr<EvidentialOcTree> part = emptyLike();
  Edit part_edit(part->pool_.get(), 1024);
  part->root = new EvidentialOcTreeNode();
  part->tree_size = 1;
  EvidentialOcTreeNode* dst = part->root;
  for (unsigned i : child_of) dst = part->createChild(dst, i, part_edit);
  part->copySubtree(*this, path.back(), dst, part_edit);
  part->commit(part_edit);
  part->updateInnerNodes();

  Edit edit(pool_.get(), 1024);
  deleteDescendants(path.back(), edit);
  for (unsigned d = depth; d >= 1; --d) {  // the node, then ancestors left without children
    path[d - 1]->deleteChild(child_of[d - 1]);
    --edit.nodes;
    if (nodeHasChildren(path[d - 1])) break;
    path[d - 1]->payload_ = EvidentialOcTreeNode::kNoPayload;
  }
  if (!nodeHasChildren(root)) {
    delete root;
    root = nullptr;
    --edit.nodes;
  }
  commit(edit);
  return part;
}

}  // namespace evidential_octomap
