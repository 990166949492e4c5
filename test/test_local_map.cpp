// A local map with bounded memory (local_map.h): tiles leave for disk behind the sensor and come
// back when it returns, and the global map equals the map built without tiles, node for node.
// SYNTHETIC scans of synthetic_scene.h (a ground and a box) along a 60 m path and back.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/local_map.h"
#include "synthetic_scene.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

namespace fs = std::filesystem;

std::string freshDirectory() {
  std::string name = (fs::temp_directory_path() / "local_map_test.XXXXXX").string();
  if (!mkdtemp(name.data())) throw std::runtime_error("mkdtemp failed");
  return name;
}

SemanticConfig shortRange() {
  SemanticConfig config;
  config.max_range = 8.0;  // reach 8 + 2 + 0.35 m at 0.2 m
  return config;
}

// Sensor positions out along x and back, 1 m apart.
std::vector<octomap::point3d> outAndBack(int metres) {
  std::vector<octomap::point3d> path;
  for (int x = 0; x <= metres; ++x) path.emplace_back(float(x) + 0.05f, 0.1f, 1.7f);
  for (int x = metres - 1; x >= 0; --x) path.emplace_back(float(x) + 0.05f, 0.1f, 1.7f);
  return path;
}

test::SyntheticScan scanAt(const octomap::point3d& origin, unsigned seed) {
  test::SyntheticScene scene;
  scene.box_min = octomap::point3d(origin.x() + 3.0f, -0.9f, 0.1f);  // a box ahead of the sensor
  scene.box_max = octomap::point3d(origin.x() + 4.0f, 0.9f, 1.5f);
  return scene.scan(origin, seed);
}

TEST(LocalMap, GlobalMapEqualsTheMapBuiltWithoutTiles) {
  const std::string dir = freshDirectory();
  EvidentialOcTree whole(0.2, 3, shortRange());
  EvidentialOcTree resident(0.2, 3, shortRange());
  LocalMap local(&resident, dir, 12.0);
  const auto path = outAndBack(60);
  for (size_t i = 0; i < path.size(); ++i) {
    const test::SyntheticScan scan = scanAt(path[i], unsigned(i + 1));
    whole.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    local.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  EXPECT_GT(local.tilesWritten(), 10u);
  EXPECT_GT(local.tilesRead(), 5u);  // the way back read tiles again
  EXPECT_GT(local.tilesOnDisk(), 0u);
  EXPECT_LT(resident.size(), whole.size() / 2);
  std::unique_ptr<EvidentialOcTree> global = local.globalMap();
  detail::TreeEditing::updateInnerNodes(whole);  // both fully pruned before comparing
  detail::TreeEditing::updateInnerNodes(*global);
  EXPECT_TRUE(test::compareTrees(*global, whole));
  EXPECT_DOUBLE_EQ(global->meanPointLogEvidence(), whole.meanPointLogEvidence());
  fs::remove_all(dir);
}

TEST(LocalMap, TheTreeHoldsOnlyTilesNearTheSensor) {
  const std::string dir = freshDirectory();
  EvidentialOcTree resident(0.2, 3, shortRange());
  LocalMap local(&resident, dir, 12.0);
  std::vector<size_t> sizes;
  for (int x = 0; x <= 80; ++x) {
    const octomap::point3d origin(float(x) + 0.05f, 0.1f, 1.7f);
    const test::SyntheticScan scan = scanAt(origin, unsigned(x + 1));
    local.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    sizes.push_back(resident.size());
    const double bound = local.radius() + 2.0 * local.tileEdge() * std::sqrt(3.0);
    for (auto it = resident.begin_leafs(), end = resident.end_leafs(); it != end; ++it) {
      ASSERT_LE((it.getCoordinate() - origin).norm(), bound) << "scan " << x;
    }
  }
  // Memory is flat once the first radius is filled: the last 20 scans hold no more nodes than
  // 1.1 times the most of scans 30..49.
  const size_t middle = *std::max_element(sizes.begin() + 30, sizes.begin() + 50);
  const size_t last = *std::max_element(sizes.end() - 20, sizes.end());
  EXPECT_LE(double(last), 1.1 * double(middle));
  fs::remove_all(dir);
}

TEST(LocalMap, MapAtAnswersQueriesFromTilesOnDisk) {
  const std::string dir = freshDirectory();
  EvidentialOcTree whole(0.2, 3, shortRange());
  EvidentialOcTree resident(0.2, 3, shortRange());
  LocalMap local(&resident, dir, 12.0);
  for (int x = 0; x <= 60; ++x) {  // out only: the start is on disk at the end
    const test::SyntheticScan scan =
        scanAt(octomap::point3d(float(x) + 0.05f, 0.1f, 1.7f), unsigned(x + 1));
    whole.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    local.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  ASSERT_GT(local.tilesOnDisk(), 0u);
  size_t from_disk = 0, labelled = 0;
  for (float x = 0.1f; x < 64.f; x += 0.5f) {
    for (float z : {0.05f, 0.7f}) {  // ground and box
      const octomap::point3d p(x, 0.1f, z);
      const EvidentialOcTree& map = local.mapAt(p);
      from_disk += &map != &resident;
      const VoxelOpinion got = map.query(p), want = whole.query(p);
      labelled += want.label >= 0;
      ASSERT_EQ(got.label, want.label) << "x " << x << " z " << z;
      ASSERT_FLOAT_EQ(got.uncertainty, want.uncertainty) << "x " << x << " z " << z;
      const auto* node = map.search(p);
      ASSERT_EQ(node != nullptr, whole.search(p) != nullptr);
      if (node) {
        ASSERT_EQ(map.isNodeOccupied(node), whole.isNodeOccupied(whole.search(p)));
      }
    }
  }
  EXPECT_GT(from_disk, 40u);  // the first ~35 m were answered from tiles
  EXPECT_GT(labelled, 100u);
  EXPECT_EQ(&local.mapAt(octomap::point3d(1e7f, 0.f, 0.f)), &resident);  // off the map
  EXPECT_EQ(&local.mapAt(octomap::point3d(std::nanf(""), 0.f, 0.f)), &resident);
  fs::remove_all(dir);
}

TEST(LocalMap, ARadiusBelowAScansReachIsRefused) {
  const std::string dir = freshDirectory();
  EvidentialOcTree tree(0.2, 3, shortRange());
  try {
    LocalMap local(&tree, dir, 9.0);
    FAIL() << "radius 9 m accepted for a reach of 10.35 m";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("must be at least the reach of a scan"), std::string::npos)
        << e.what();
  }
  EvidentialOcTree unlimited(0.2, 3);  // max_range < 0
  EXPECT_THROW(LocalMap(&unlimited, dir, 1000.0), std::invalid_argument);
  EXPECT_NO_THROW(LocalMap(&tree, dir, 10.4));
  fs::remove_all(dir);
}

TEST(LocalMap, ADirectoryHoldingTilesIsRefused) {
  const std::string dir = freshDirectory();
  {
    EvidentialOcTree tree(0.2, 3, shortRange());
    LocalMap local(&tree, dir, 12.0);
    for (int x = 0; x <= 40; ++x) {
      const test::SyntheticScan scan = scanAt(octomap::point3d(float(x), 0.1f, 1.7f), 1);
      local.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    }
    ASSERT_GT(local.tilesOnDisk(), 0u);
  }
  EvidentialOcTree other(0.2, 3, shortRange());
  EXPECT_THROW(LocalMap(&other, dir, 12.0), std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace evidential_octomap
