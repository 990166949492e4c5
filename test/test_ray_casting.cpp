// Our parallel ray casting must give exactly the occupancy OctoMap's own insertPointCloud gives,
// and its DDA exactly the keys of OctoMap's computeRayKeys.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <random>

#include "evidential_octomap/evidential_octree.h"
#include "ray_casting.h"  // private to the core: rayKeys, the DDA under test

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

// --- the DDA itself, ray by ray -------------------------------------------------------------

namespace {

// Random rays (synthetic): origins anywhere in a 40 m box, ends from 1 mm to 120 m away, some
// along an axis or a diagonal, some ending exactly on voxel borders or in the origin's voxel.
std::vector<std::pair<octomap::point3d, octomap::point3d>> randomRays(unsigned seed, int count) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-20.0f, 20.0f), unit(-1.0f, 1.0f);
  std::uniform_real_distribution<float> distance(0.001f, 120.0f);
  std::uniform_int_distribution<int> kind(0, 5), cells(-300, 300);
  std::vector<std::pair<octomap::point3d, octomap::point3d>> rays;
  for (int i = 0; i < count; ++i) {
    octomap::point3d origin(coordinate(rng), coordinate(rng), coordinate(rng));
    octomap::point3d direction(unit(rng), unit(rng), unit(rng));
    switch (kind(rng)) {
      case 0:
        direction = octomap::point3d(unit(rng), 0.0f, 0.0f);
        break;  // along an axis
      case 1:
        direction = octomap::point3d(1.0f, 1.0f, -1.0f);
        break;  // diagonal
      case 2:
        origin = octomap::point3d(0.2f * cells(rng), 0.2f * cells(rng), 0.1f);
        break;
      default:
        break;
    }
    if (direction.norm() < 1e-3) direction = octomap::point3d(0.3f, -0.2f, 0.1f);
    octomap::point3d end = origin + direction.normalized() * distance(rng);
    if (i % 7 == 0) end = octomap::point3d(0.2f * cells(rng), 0.2f * cells(rng), 0.2f * cells(rng));
    rays.emplace_back(origin, end);
  }
  return rays;
}

}  // namespace

TEST(RayCasting, EveryRayVisitsOctoMapsKeysInOctoMapsOrder) {
  for (double resolution : {0.2, 0.05, 1.0}) {
    EvidentialOcTree tree(resolution, 1);
    octomap::KeyRay expected;
    std::vector<octomap::OcTreeKey> ours;
    size_t keys = 0;
    for (const auto& [origin, end] : randomRays(unsigned(resolution * 100), 3000)) {
      const bool theirs_ok = tree.computeRayKeys(origin, end, expected);
      ASSERT_EQ(evidential_octomap::rayKeys(tree, origin, end, &ours), theirs_ok);
      ASSERT_EQ(ours.size(), expected.size()) << "ray " << origin << " -> " << end;
      size_t i = 0;
      for (const octomap::OcTreeKey& key : expected) {
        ASSERT_EQ(ours[i], key) << "cell " << i << " of ray " << origin << " -> " << end;
        ++i;
      }
      keys += ours.size();
    }
    EXPECT_GT(keys, 100000u) << "resolution " << resolution;
  }
}

// --- fast free space (SemanticConfig::fast_free_space): approximate by design ----------------

namespace {

EvidentialOcTree mapOneScan(const octomap::Pointcloud& cloud, bool fast, double max_range) {
  SemanticConfig config;
  config.fast_free_space = fast;
  config.max_range = max_range;
  config.threads = 2;
  EvidentialOcTree tree(0.2, 3, config);
  tree.insertSemanticScan(cloud, std::vector<float>(cloud.size() * 3, 0.0f),
                          octomap::point3d(0.3f, -0.2f, 0.1f));
  tree.expand();  // leaf by leaf at the finest depth
  return tree;
}

struct FreeSpaceComparison {
  size_t exact_free = 0, fast_free = 0, fast_free_not_exact = 0;
  size_t exact_occupied = 0, occupied_differ = 0;
};

FreeSpaceComparison compareWithExact(const octomap::Pointcloud& cloud, double max_range) {
  const EvidentialOcTree exact = mapOneScan(cloud, false, max_range);
  const EvidentialOcTree fast = mapOneScan(cloud, true, max_range);
  FreeSpaceComparison c;
  for (auto it = exact.begin_leafs(); it != exact.end_leafs(); ++it) {
    const bool occupied = exact.isNodeOccupied(*it);
    (occupied ? c.exact_occupied : c.exact_free) += 1;
    const auto* other = fast.search(it.getKey());
    if (occupied && (!other || !fast.isNodeOccupied(*other))) ++c.occupied_differ;
  }
  for (auto it = fast.begin_leafs(); it != fast.end_leafs(); ++it) {
    if (fast.isNodeOccupied(*it)) {
      if (!exact.search(it.getKey())) ++c.occupied_differ;
      continue;
    }
    ++c.fast_free;
    const auto* other = exact.search(it.getKey());
    if (!other || exact.isNodeOccupied(*other)) ++c.fast_free_not_exact;
  }
  return c;
}

}  // namespace

// In one scan the fast mode marks the same voxels occupied, clears only voxels the exact mode
// clears (up to the reversed DDA's rounding at cell corners) and most of them; the rays overlap
// near the sensor, which is the work it skips.
TEST(RayCasting, FastFreeSpaceKeepsHitsAndClearsMostOfTheExactFreeSpace) {
  for (double max_range : {-1.0, 20.0}) {
    const FreeSpaceComparison c = compareWithExact(syntheticRoomScan(5), max_range);
    EXPECT_GT(c.exact_occupied, 1000u);
    EXPECT_EQ(c.occupied_differ, 0u) << "max range " << max_range;
    EXPECT_LE(c.fast_free, c.exact_free);
    EXPECT_GE(c.fast_free, c.exact_free * 7 / 10) << "max range " << max_range;
    // The reversed DDA leaves a ray through a cell corner by the other neighbour: ~0.1 %.
    EXPECT_LE(c.fast_free_not_exact, c.fast_free / 200) << "max range " << max_range;
    std::printf("max range %g: exact free %zu, fast free %zu, fast free not exact %zu\n", max_range,
                c.exact_free, c.fast_free, c.fast_free_not_exact);
  }
}

// A lone ray has no other ray to stop at: it clears what the exact ray clears.
TEST(RayCasting, FastFreeSpaceCastsALoneRayWhole) {
  octomap::Pointcloud cloud;
  cloud.push_back(octomap::point3d(17.3f, 5.1f, -2.2f));
  const FreeSpaceComparison c = compareWithExact(cloud, -1.0);
  EXPECT_GT(c.exact_free, 80u);
  EXPECT_EQ(c.occupied_differ, 0u);
  EXPECT_LE(c.fast_free_not_exact, 2u);
  EXPECT_GE(c.fast_free + 2, c.exact_free);
}

// Rays are split among the threads in fixed chunks, so the map does not depend on timing.
TEST(RayCasting, FastFreeSpaceIsDeterministic) {
  const octomap::Pointcloud cloud = syntheticRoomScan(9);
  const EvidentialOcTree a = mapOneScan(cloud, true, -1.0);
  const EvidentialOcTree b = mapOneScan(cloud, true, -1.0);
  ASSERT_EQ(a.size(), b.size());
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    const auto* other = b.search(it.getKey());
    ASSERT_NE(other, nullptr);
    ASSERT_EQ(other->getLogOdds(), it->getLogOdds());
  }
}
