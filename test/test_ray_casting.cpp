// Our parallel ray casting must give exactly the occupancy OctoMap's own insertPointCloud gives.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>

#include "evidential_octomap/evidential_octree.h"

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::SemanticConfig;

namespace {

// Synthetic scan (labelled synthetic): a room of walls and floor seen from a sensor, plus far
// points to exercise max range.
octomap::Pointcloud syntheticRoomScan(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> angle(-3.14159f, 3.14159f), elevation(-0.5f, 0.3f);
  octomap::Pointcloud cloud;
  for (int i = 0; i < 8000; ++i) {
    const float a = angle(rng), e = elevation(rng);
    const octomap::point3d dir(std::cos(a) * std::cos(e), std::sin(a) * std::cos(e), std::sin(e));
    // Floor at z = -1.5, walls at |x| = 6 / |y| = 9, open beyond 30 m in one sector.
    float t = 100.0f;
    if (dir.z() < 0) t = std::min(t, -1.5f / dir.z());
    if (std::abs(dir.x()) > 1e-6f) t = std::min(t, 6.0f / std::abs(dir.x()));
    if (std::abs(dir.y()) > 1e-6f) t = std::min(t, 9.0f / std::abs(dir.y()));
    if (a > 2.5f) t = 35.0f;
    cloud.push_back(dir * t);
  }
  return cloud;
}

void expectSameOccupancy(const EvidentialOcTree& ours, const octomap::OcTree& plain) {
  size_t compared = 0;
  for (auto it = plain.begin_leafs(); it != plain.end_leafs(); ++it) {
    const auto* node = ours.search(it.getKey(), it.getDepth());
    ASSERT_NE(node, nullptr);
    EXPECT_FLOAT_EQ(node->getLogOdds(), it->getLogOdds());
    ++compared;
  }
  for (auto it = ours.begin_leafs(); it != ours.end_leafs(); ++it) {
    const auto* node = plain.search(it.getKey(), it.getDepth());
    ASSERT_NE(node, nullptr);
    EXPECT_FLOAT_EQ(node->getLogOdds(), it->getLogOdds());
  }
  EXPECT_GT(compared, 1000u);
}

void checkAgainstOctoMap(double max_range, bool discretize) {
  SemanticConfig config;
  config.kernel_creates_leaves = false;  // occupancy from rays only, as in plain OctoMap
  config.max_range = max_range;
  config.discretize = discretize;
  EvidentialOcTree ours(0.2, 3, config);
  octomap::OcTree plain(0.2);
  const octomap::point3d origin(0.3f, -0.2f, 0.1f);
  for (unsigned scan = 0; scan < 3; ++scan) {
    const octomap::Pointcloud cloud = syntheticRoomScan(scan);
    ours.insertSemanticScan(cloud, std::vector<float>(cloud.size() * 3, 0.0f), origin);
    plain.insertPointCloud(cloud, origin, max_range, /*lazy_eval=*/false, discretize);
  }
  expectSameOccupancy(ours, plain);
}

}  // namespace

TEST(RayCasting, MatchesOctoMapInsertPointCloudDiscretized) { checkAgainstOctoMap(-1.0, true); }
TEST(RayCasting, MatchesOctoMapInsertPointCloudEveryPoint) { checkAgainstOctoMap(-1.0, false); }
TEST(RayCasting, MatchesOctoMapWithMaxRange) { checkAgainstOctoMap(20.0, true); }
