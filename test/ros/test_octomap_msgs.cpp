// octomap_binary, octomap_full and evidential_octomap_full messages read back with octomap_msgs'
// own conversions.h, as MoveIt, the octomap rviz plugins and planners read them. Built only when
// octomap_msgs is found.
#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap_msgs/conversions.h>

#include <memory>
#include <set>
#include <tuple>

#include "evidential_octomap/io.h"
#include "octomap_msgs_conversions.h"
#include "test_maps.h"

using namespace evidential_octomap;

namespace {

using Key = std::tuple<int, int, int>;

template <typename Tree>
std::set<Key> occupiedKeys(Tree& tree) {
  tree.expand();
  std::set<Key> keys;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
    if (tree.isNodeOccupied(*it)) keys.insert({it.getKey()[0], it.getKey()[1], it.getKey()[2]});
  return keys;
}

}  // namespace

TEST(OctomapMsgs, BinaryMessageIsAPlainOcTreeWithOurOccupancy) {
  auto tree = ros_test::roadAndWall();
  const octomap_msgs::Octomap msg = toOctomapBinary(*tree, "map");
  EXPECT_TRUE(msg.binary);
  EXPECT_EQ(msg.id, "OcTree");
  EXPECT_EQ(msg.header.frame_id, "map");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap_msgs::msgToMap(msg));
  auto* plain = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(plain, nullptr);
  EXPECT_DOUBLE_EQ(plain->getResolution(), 0.2);
  const auto expected = occupiedKeys(*tree);
  ASSERT_GT(expected.size(), 100u);
  EXPECT_EQ(occupiedKeys(*plain), expected);
}

TEST(OctomapMsgs, FullMessageIsAColorOcTreeInClassColours) {
  auto tree = ros_test::roadAndWall();
  const ClassTable classes = ros_test::fourClasses();
  const octomap_msgs::Octomap msg = toOctomapFull(*tree, classes, ColorMode::kClass, "map");
  EXPECT_FALSE(msg.binary);
  EXPECT_EQ(msg.id, "ColorOcTree");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap_msgs::msgToMap(msg));
  auto* color = dynamic_cast<octomap::ColorOcTree*>(read.get());
  ASSERT_NE(color, nullptr);
  size_t checked = 0;
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    if (!tree->isNodeOccupied(*it) || !it->hasSemantics()) continue;
    const auto* node = color->search(it.getKey(), it.getDepth());
    ASSERT_NE(node, nullptr);
    const auto& expected = classes.colors[tree->opinion(&*it).label];
    EXPECT_EQ(node->getColor(),
              octomap::ColorOcTreeNode::Color(expected[0], expected[1], expected[2]));
    ++checked;
  }
  EXPECT_GT(checked, 100u);
}

TEST(OctomapMsgs, EvidentialMessageReadsBackAsOurTree) {
  auto tree = ros_test::roadAndWall();
  const octomap_msgs::Octomap msg = toOctomapEvidential(*tree, "map");
  EXPECT_EQ(msg.id, "EvidentialOcTree");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap_msgs::msgToMap(msg));
  auto* back = dynamic_cast<EvidentialOcTree*>(read.get());
  ASSERT_NE(back, nullptr);
  EXPECT_EQ(back->numClasses(), 4);
  EXPECT_EQ(back->getNumLeafNodes(), tree->getNumLeafNodes());
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    const VoxelOpinion a = tree->opinion(&*it), b = back->query(it.getKey(), it.getDepth());
    ASSERT_EQ(a.label, b.label);
    ASSERT_FLOAT_EQ(a.uncertainty, b.uncertainty);
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
