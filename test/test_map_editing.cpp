// clearBox: every known voxel inside becomes free without evidence; every voxel outside keeps
// its occupancy and semantics, also where a pruned (coarse) free-space leaf straddles the box;
// a box with a non-finite corner or min > max is refused and changes nothing.
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "evidential_octomap/map_editing.h"

using namespace evidential_octomap;

namespace {

constexpr int kC = 3;

// A wall of class 1 at x = 6 seen from the origin: long rays give large pruned free leaves.
std::unique_ptr<EvidentialOcTree> wallMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, kC);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float y = -2.f; y <= 2.f; y += 0.1f)
    for (float z = -1.f; z <= 1.f; z += 0.1f) {
      points.push_back(6.05f, y, z);
      for (int c = 0; c < kC; ++c) evidence.push_back(c == 1 ? 30.f : 0.f);
    }
  tree->insertSemanticScan(points, evidence, octomap::point3d(0, 0, 0));
  return tree;
}

struct Voxel {
  bool known = false;
  float log_odds = 0.f;
  int label = -1;
  float uncertainty = 1.f;
};

Voxel at(const EvidentialOcTree& tree, const octomap::point3d& p) {
  Voxel v;
  const EvidentialOcTreeNode* node = tree.search(p);
  if (!node) return v;
  v.known = true;
  v.log_odds = node->getLogOdds();
  const VoxelOpinion o = tree.opinion(node);
  v.label = o.label;
  v.uncertainty = o.uncertainty;
  return v;
}

}  // namespace

TEST(ClearBox, InsideBecomesFreeWithoutEvidenceOutsideIsUntouched) {
  auto tree = wallMap();
  const auto before = EvidentialOcTree(*tree);
  // Cuts through free space near the sensor (coarse leaves) and through the wall.
  const octomap::point3d min(1.3f, -0.5f, -0.3f), max(6.5f, 0.7f, 0.5f);
  octomap::OcTreeKey kmin = tree->coordToKey(min), kmax = tree->coordToKey(max);
  size_t coarse = 0;  // pruned leaves the box reaches: the case that needs splitting
  for (auto it = before.begin_leafs_bbx(kmin, kmax); it != before.end_leafs_bbx(); ++it)
    coarse += it.getDepth() < before.getTreeDepth();
  ASSERT_GT(coarse, 0u);
  const uint32_t cleared = clearBox(tree.get(), min, max);
  EXPECT_GT(cleared, 0u);

  size_t inside = 0, outside = 0, wall_outside = 0;
  for (float x = 0.1f; x < 7.f; x += 0.2f)
    for (float y = -2.5f; y < 2.5f; y += 0.2f)
      for (float z = -1.3f; z < 1.3f; z += 0.2f) {
        const octomap::point3d p(x, y, z);
        const octomap::OcTreeKey k = tree->coordToKey(p);
        bool in = true;
        for (int i = 0; i < 3; ++i) in = in && k[i] >= kmin[i] && k[i] <= kmax[i];
        const Voxel old = at(before, p), now = at(*tree, p);
        if (in) {
          EXPECT_EQ(now.known, old.known) << p;  // unknown space stays unknown
          if (old.known) {
            ++inside;
            EXPECT_FLOAT_EQ(now.log_odds, tree->getClampingThresMinLog()) << p;
            EXPECT_EQ(now.label, -1) << p;
          }
        } else {
          ASSERT_EQ(now.known, old.known) << p;
          if (!old.known) continue;
          ++outside;
          if (old.label == 1) ++wall_outside;
          EXPECT_FLOAT_EQ(now.log_odds, old.log_odds) << p;
          EXPECT_EQ(now.label, old.label) << p;
          EXPECT_FLOAT_EQ(now.uncertainty, old.uncertainty) << p;
        }
      }
  EXPECT_GT(inside, 100u);
  EXPECT_GT(outside, 100u);
  EXPECT_GT(wall_outside, 10u);
}

TEST(ClearBox, EmptyTreeAndEmptyBoxClearNothing) {
  EvidentialOcTree empty(0.2, kC);
  EXPECT_EQ(clearBox(&empty, octomap::point3d(-1, -1, -1), octomap::point3d(1, 1, 1)), 0u);
  auto tree = wallMap();
  EXPECT_EQ(clearBox(tree.get(), octomap::point3d(50, 50, 50), octomap::point3d(51, 51, 51)), 0u);
}


// Issue 16 item 3: max = NaN cleared a wall, max = (NaN, 1000, 1000) the whole map (NaN compares
// false with every bound). Such boxes, and inverted ones, are refused with the map unchanged.
TEST(ClearBox, NonFiniteAndInvertedBoxesAreRefusedAndChangeNothing) {
  auto tree = wallMap();
  std::ostringstream before;
  tree->write(before);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const octomap::point3d lo(4.f, -1.f, -1.f), hi(7.f, 1.f, 1.f);
  const std::pair<octomap::point3d, octomap::point3d> bad[] = {
      {lo, octomap::point3d(nan, nan, nan)},
      {lo, octomap::point3d(nan, 1000.f, 1000.f)},
      {octomap::point3d(-1000.f, nan, -1000.f), hi},
      {lo, octomap::point3d(inf, 1.f, 1.f)},
      {octomap::point3d(-inf, -1.f, -1.f), hi},
      {hi, lo},                                                     // inverted on every axis
      {octomap::point3d(4.f, 2.f, -1.f), octomap::point3d(7.f, 1.f, 1.f)},  // inverted in y
  };
  for (const auto& [min, max] : bad) {
    EXPECT_FALSE(boxProblem(min, max).empty()) << min << " .. " << max;
    EXPECT_THROW(clearBox(tree.get(), min, max), std::invalid_argument) << min << " .. " << max;
  }
  std::ostringstream after;
  tree->write(after);
  EXPECT_TRUE(before.str() == after.str()) << "a refused box changed the map";
  // A box beyond the map's extent is fine: it is cut to the map.
  EXPECT_EQ(boxProblem(octomap::point3d(-1e30f, -1e30f, -1e30f), octomap::point3d(1e30f, 1e30f, 1e30f)),
            "");
  EXPECT_GT(clearBox(tree.get(), octomap::point3d(-1e30f, -1e30f, -1e30f),
                     octomap::point3d(1e30f, 1e30f, 1e30f)),
            0u);
  EXPECT_EQ(tree->numSemanticNodes(), 0u);
}
