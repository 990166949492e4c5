// detail::walkLeaves against OctoMap's own leaf iterator (the reference: the readers used it
// before), on a SYNTHETIC map with pruned free blocks; the inner nodes descend() is asked about;
// and the skip of free inner nodes, which must leave out no occupied leaf.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "evidential_octomap/detail/leaf_walk.h"
#include "evidential_octomap/evidential_octree.h"
#include "synthetic_scene.h"

using namespace evidential_octomap;

namespace {

struct SeenLeaf {
  const EvidentialOcTreeNode* node;
  double x, y, z, size;
  unsigned depth;
  bool operator==(const SeenLeaf& o) const {
    return node == o.node && x == o.x && y == o.y && z == o.z && size == o.size &&
           depth == o.depth;
  }
};

std::unique_ptr<EvidentialOcTree> scannedMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, 3);
  test::SyntheticScene scene;
  for (int i = 0; i < 3; ++i) {
    const auto scan = scene.scan(octomap::point3d(0.05f + 0.4f * i, 0.1f, 1.7f), 10 + i);
    tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  return tree;
}

std::vector<SeenLeaf> byIterator(const EvidentialOcTree& tree, bool occupied_only) {
  std::vector<SeenLeaf> seen;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (occupied_only && !tree.isNodeOccupied(*it)) continue;
    seen.push_back({&*it, it.getX(), it.getY(), it.getZ(), it.getSize(), it.getDepth()});
  }
  return seen;
}

std::vector<SeenLeaf> byWalk(const EvidentialOcTree& tree, bool occupied_only) {
  std::vector<SeenLeaf> seen;
  detail::walkLeaves(
      tree,
      [&](const EvidentialOcTreeNode& node, const octomap::OcTreeKey&, unsigned) {
        return !occupied_only || tree.isNodeOccupied(node);
      },
      [&](const EvidentialOcTreeNode& leaf, const octomap::OcTreeKey& corner, unsigned depth) {
        if (occupied_only && !tree.isNodeOccupied(leaf)) return;
        seen.push_back({&leaf, tree.keyToCoord(corner[0], depth),
                        tree.keyToCoord(corner[1], depth), tree.keyToCoord(corner[2], depth),
                        tree.getNodeSize(depth), depth});
      });
  return seen;
}

}  // namespace

TEST(LeafWalk, VisitsTheIteratorsLeavesInItsOrderAtItsCentres) {
  const auto tree = scannedMap();
  const auto expected = byIterator(*tree, false);
  size_t pruned = 0;
  for (const SeenLeaf& s : expected) pruned += s.depth < tree->getTreeDepth();
  ASSERT_GT(pruned, 5u);  // pruned blocks, not only voxels
  EXPECT_EQ(byWalk(*tree, false), expected);
}

TEST(LeafWalk, SkippingFreeInnerNodesKeepsEveryOccupiedLeaf) {
  const auto tree = scannedMap();
  const auto expected = byIterator(*tree, true);
  ASSERT_GT(expected.size(), 100u);
  ASSERT_LT(expected.size() * 4, tree->getNumLeafNodes());  // mostly free space to skip
  EXPECT_EQ(byWalk(*tree, true), expected);
}

// descend() is told where each inner node is: the readers that look within a box skip by it.
TEST(LeafWalk, DescendSeesEveryInnerNodeAtTheIteratorsCentre) {
  const auto tree = scannedMap();
  std::vector<SeenLeaf> expected, seen;
  for (auto it = tree->begin_tree(); it != tree->end_tree(); ++it)
    if (tree->nodeHasChildren(&*it))
      expected.push_back({&*it, it.getX(), it.getY(), it.getZ(), it.getSize(), it.getDepth()});
  ASSERT_GT(expected.size(), 100u);
  detail::walkLeaves(
      *tree,
      [&](const EvidentialOcTreeNode& node, const octomap::OcTreeKey& corner, unsigned depth) {
        seen.push_back({&node, tree->keyToCoord(corner[0], depth),
                        tree->keyToCoord(corner[1], depth), tree->keyToCoord(corner[2], depth),
                        tree->getNodeSize(depth), depth});
        return true;
      },
      [](const EvidentialOcTreeNode&, const octomap::OcTreeKey&, unsigned) {});
  EXPECT_EQ(seen, expected);
}

TEST(LeafWalk, AnEmptyMapHasNoLeaves) {
  const EvidentialOcTree tree(0.2, 3);
  EXPECT_TRUE(byWalk(tree, false).empty());
}
