// The leaves of a map depth-first in the order of OctoMap's leaf iterator (child 0 first), by
// recursion instead of the iterator's stack of keys, and able to skip a subtree whole: the
// readers that copy or project every leaf (the views, the 2-D maps) visit a million of them per
// publication.
#pragma once

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap::detail {

// Asks for the node's children at once: a walk goes node -> child by pointer, each a likely
// cache miss, and a node's children are read one after the other.
inline void prefetchChildren(const EvidentialOcTree& tree, const EvidentialOcTreeNode* node) {
  for (unsigned i = 0; i < 8; ++i)
    if (tree.nodeChildExists(node, i)) __builtin_prefetch(tree.getNodeChild(node, i));
}

// `descend(node, corner, depth)` says whether to enter an inner node; `visit(leaf, corner, depth)`
// sees every leaf reached; `corner` is the key of a node's lowest cell (a pruned block is one
// leaf of its depth). OctoMap keeps an inner node's log-odds at its children's maximum, so a
// free inner node has no occupied leaf below it: `descend` may skip it.
template <typename Descend, typename Visit>
void walkLeaves(const EvidentialOcTree& tree, Descend&& descend, Visit&& visit) {
  const EvidentialOcTreeNode* root = tree.getRoot();
  if (root == nullptr) return;
  const unsigned tree_depth = tree.getTreeDepth();
  auto recurse = [&](auto&& self, const EvidentialOcTreeNode* node, octomap::OcTreeKey corner,
                     unsigned depth) -> void {
    if (!tree.nodeHasChildren(node)) {
      visit(*node, corner, depth);
      return;
    }
    if (!descend(*node, corner, depth)) return;
    prefetchChildren(tree, node);
    const octomap::key_type half = octomap::key_type(1) << (tree_depth - depth - 1);
    for (unsigned i = 0; i < 8; ++i) {
      if (!tree.nodeChildExists(node, i)) continue;
      octomap::OcTreeKey child = corner;
      for (unsigned axis = 0; axis < 3; ++axis)
        if (i & (1u << axis)) child[axis] += half;
      self(self, tree.getNodeChild(node, i), child, depth + 1);
    }
  };
  recurse(recurse, root, octomap::OcTreeKey(0, 0, 0), 0);
}

}  // namespace evidential_octomap::detail
