// projected_map and projected_cost_map against a brute-force projection: every cell is judged
// by searching the tree at each voxel height of its column (an independent route from the leaf
// walk with key arithmetic that the code under test uses).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>

#include "projected_map.h"
#include "test_maps.h"

using namespace evidential_octomap;

namespace {

// Cost of column (x, y) over the voxel heights in [min_z, max_z]: max over occupied voxels of
// cost_of(voxel); 0 when the column has only free voxels there; -1 when nothing is known.
template <typename CostOf>
int bruteForceCell(const EvidentialOcTree& tree, double x, double y, const HeightBand& band,
                   CostOf cost_of) {
  double min_x, min_y, min_z, max_x, max_y, max_z;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const double res = tree.getResolution();
  int cell = -1;
  for (double z = min_z + 0.5 * res; z < max_z; z += res) {
    if (!band.contains(z)) continue;
    const EvidentialOcTreeNode* node = tree.search(x, y, z);
    if (!node) continue;
    if (tree.isNodeOccupied(node))
      cell = std::max(cell, cost_of(node));
    else if (cell == -1)
      cell = 0;
  }
  return cell;
}

// Checks every cell of `grid` against bruteForceCell at its centre; returns how many cells are
// occupied / free / unknown so callers can check the scene shows up.
template <typename CostOf>
std::array<int, 3> expectGridMatches(const nav_msgs::OccupancyGrid& grid,
                                     const EvidentialOcTree& tree, const HeightBand& band,
                                     CostOf cost_of) {
  std::array<int, 3> counts{0, 0, 0};
  const double res = tree.getResolution();
  EXPECT_FLOAT_EQ(grid.info.resolution, float(res));
  for (unsigned j = 0; j < grid.info.height; ++j)
    for (unsigned i = 0; i < grid.info.width; ++i) {
      const double x = grid.info.origin.position.x + (i + 0.5) * res;
      const double y = grid.info.origin.position.y + (j + 0.5) * res;
      const int expected = bruteForceCell(tree, x, y, band, cost_of);
      const int got = grid.data[j * grid.info.width + i];
      EXPECT_EQ(got, expected) << "cell " << i << ", " << j << " at " << x << ", " << y;
      ++counts[got > 0 ? 0 : got == 0 ? 1 : 2];
    }
  return counts;
}

// The grid spans the x-y extent of all the map's leaves, as OctoMap's own bounds give it.
void expectGridSpansTheMap(const nav_msgs::OccupancyGrid& grid, const EvidentialOcTree& tree) {
  double min_x, min_y, min_z, max_x, max_y, max_z;
  tree.getMetricMin(min_x, min_y, min_z);
  tree.getMetricMax(max_x, max_y, max_z);
  const double res = grid.info.resolution;
  EXPECT_NEAR(grid.info.origin.position.x, min_x, 1e-4);
  EXPECT_NEAR(grid.info.origin.position.y, min_y, 1e-4);
  EXPECT_NEAR(grid.info.origin.position.x + grid.info.width * res, max_x, 1e-4);
  EXPECT_NEAR(grid.info.origin.position.y + grid.info.height * res, max_y, 1e-4);
}

}  // namespace

TEST(ProjectedMap, EveryCellMatchesTheColumnsVoxels) {
  auto tree = ros_test::roadAndWall();
  tree->expand();  // full-depth leaves: a leaf's centre height is its voxel's height
  const HeightBand all;
  const auto grid = projectOccupancy(*tree, all, "map");
  EXPECT_EQ(grid.header.frame_id, "map");
  expectGridSpansTheMap(grid, *tree);
  const auto counts =
      expectGridMatches(grid, *tree, all, [](const EvidentialOcTreeNode*) { return 100; });
  EXPECT_GT(counts[0], 100);  // wall and road
  EXPECT_GT(counts[1], 10);   // free space in front of the wall seen from above the road
  EXPECT_GT(counts[2], 10);   // unknown behind the wall
}

TEST(ProjectedMap, HeightBandLeavesTheRoadOut) {
  auto tree = ros_test::roadAndWall();
  tree->expand();
  HeightBand above_road;
  above_road.min_z = -0.8;  // the road voxels (z = -1.1) are below
  const auto grid = projectOccupancy(*tree, above_road, "map");
  expectGridSpansTheMap(grid, *tree);  // of every leaf, not only the band's
  expectGridMatches(grid, *tree, above_road, [](const EvidentialOcTreeNode*) { return 100; });
  // A road cell is free (rays passed above it), a wall cell occupied.
  auto cell = [&](double x, double y) {
    const int i = int((x - grid.info.origin.position.x) / grid.info.resolution);
    const int j = int((y - grid.info.origin.position.y) / grid.info.resolution);
    return grid.data[j * grid.info.width + i];
  };
  EXPECT_EQ(cell(2.5, 0.05), 0);
  EXPECT_EQ(cell(4.05, 0.05), 100);
}

TEST(ProjectedMap, PrunedTreeGivesTheSameGridAsTheExpandedOne) {
  auto pruned = ros_test::roadAndWall();
  auto expanded = ros_test::roadAndWall();
  expanded->expand();
  const HeightBand all;
  const auto a = projectOccupancy(*pruned, all, "map"), b = projectOccupancy(*expanded, all, "map");
  expectGridSpansTheMap(a, *pruned);
  EXPECT_EQ(a.info.width, b.info.width);
  EXPECT_EQ(a.info.height, b.info.height);
  EXPECT_EQ(a.data, b.data);
}

TEST(ProjectedCostMap, EachCellCostsItsWorstClass) {
  auto tree = ros_test::roadAndWall();
  tree->expand();
  const ClassTable classes = ros_test::fourClasses();
  const std::vector<int8_t> costs = classCosts(classes, {{"road", 0}, {"building", 100}}, 70);
  ASSERT_EQ(costs, (std::vector<int8_t>{0, 100, 70, 70}));
  const HeightBand all;
  const auto grid = projectClassCosts(*tree, all, costs, 55, "map");
  const auto counts = expectGridMatches(grid, *tree, all, [&](const EvidentialOcTreeNode* node) {
    const int label = node->hasSemantics() ? tree->opinion(node).label : -1;
    return label < 0 ? 55 : int(costs[label]);
  });
  EXPECT_GE(counts[0], 10);   // the wall: 10 cells of 0.2 m across y in [-1, 1]
  EXPECT_GT(counts[1], 100);  // free space and the road (cost 0)
}

TEST(ProjectedCostMap, UnknownClassNamesAndBadCostsAreRefused) {
  const ClassTable classes = ros_test::fourClasses();
  EXPECT_THROW(classCosts(classes, {{"lava", 100}}, 100), std::invalid_argument);
  EXPECT_THROW(classCosts(classes, {{"road", 101}}, 100), std::invalid_argument);
  EXPECT_THROW(classCosts(classes, {}, -1), std::invalid_argument);
}

TEST(ProjectedMap, EmptyTreeGivesAnEmptyGrid) {
  EvidentialOcTree tree(0.2, 4);
  const auto grid = projectOccupancy(tree, HeightBand(), "map");
  EXPECT_EQ(grid.data.size(), 0u);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
