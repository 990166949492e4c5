// The autosave of a local map (local_map_snapshot.h): a snapshot taken at scan k and resumed
// later is the map of scans 0..k, voxel for voxel, although tiles moved to disk and back after
// it; killed writers' staging directories are never read; tiles of another tile size or ones the
// tree holds are refused. SYNTHETIC scans of synthetic_scene.h along a 60 m path and back.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <string>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/local_map.h"
#include "evidential_octomap/local_map_snapshot.h"
#include "synthetic_scene.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

namespace fs = std::filesystem;

std::string freshDirectory() {
  std::string name = (fs::temp_directory_path() / "local_map_snapshot_test.XXXXXX").string();
  if (!mkdtemp(name.data())) throw std::runtime_error("mkdtemp failed");
  return name;
}

SemanticConfig shortRange() {
  SemanticConfig config;
  config.max_range = 8.0;  // reach 10.35 m at 0.2 m
  return config;
}

octomap::point3d poseAt(int step) {  // out 60 m along x, then back
  const int x = step <= 60 ? step : 120 - step;
  return octomap::point3d(float(x) + 0.05f, 0.1f, 1.7f);
}

void insertStep(EvidentialOcTree* whole, LocalMap* local, int step) {
  test::SyntheticScene scene;
  const octomap::point3d origin = poseAt(step);
  scene.box_min = octomap::point3d(origin.x() + 3.0f, -0.9f, 0.1f);
  scene.box_max = octomap::point3d(origin.x() + 4.0f, 0.9f, 1.5f);
  const test::SyntheticScan scan = scene.scan(origin, unsigned(step + 1));
  if (whole) whole->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  if (local) local->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
}

std::string bytesOf(const EvidentialOcTree& tree) {  // as the node's autosave serialises
  std::ostringstream s;
  s << std::setprecision(17);
  tree.write(s);
  return s.str();
}

std::string snapshot(const LocalMap& local, const std::string& base) {
  const std::string staging = stageLocalMapSnapshot(local, base);
  return commitLocalMapSnapshot(staging, bytesOf(local.tree()), base);
}

TEST(LocalMapSnapshot, ResumesTheMapOfTheScansBeforeItWhateverMovedAfter) {
  const std::string tiles = freshDirectory(), base = freshDirectory() + "/autosave";
  EvidentialOcTree whole(0.2, 3, shortRange()), resident(0.2, 3, shortRange());
  LocalMap local(&resident, tiles + "/run1", 12.0);
  for (int step = 0; step <= 70; ++step) insertStep(&whole, &local, step);  // out and 10 m back
  ASSERT_GT(local.tilesOnDisk(), 3u);
  const std::string taken = snapshot(local, base);
  for (int step = 71; step <= 120; ++step) insertStep(nullptr, &local, step);  // tiles move on
  ASSERT_GT(local.tilesRead(), 3u);

  const LocalMapSnapshot found = newestLocalMapSnapshot(base);
  ASSERT_EQ(found.directory, taken);
  std::unique_ptr<EvidentialOcTree> resumed = loadMap(found.resident);
  LocalMap again(resumed.get(), tiles + "/run2", 12.0);
  again.adoptTiles(found.tiles);
  EXPECT_EQ(again.tilesOnDisk(), found.tiles.size());
  std::unique_ptr<EvidentialOcTree> global = again.globalMap();
  detail::TreeEditing::updateInnerNodes(whole);
  detail::TreeEditing::updateInnerNodes(*global);
  EXPECT_TRUE(test::compareTrees(*global, whole));
  EXPECT_DOUBLE_EQ(global->meanPointLogEvidence(), whole.meanPointLogEvidence());
  fs::remove_all(tiles);
  fs::remove_all(fs::path(base).parent_path());
}

TEST(LocalMapSnapshot, OnlyTheNewestCompleteSnapshotIsKeptAndRead) {
  const std::string tiles = freshDirectory(), base = freshDirectory() + "/autosave";
  EvidentialOcTree resident(0.2, 3, shortRange());
  LocalMap local(&resident, tiles, 12.0);
  for (int step = 0; step <= 40; ++step) insertStep(nullptr, &local, step);
  const std::string first = snapshot(local, base);
  insertStep(nullptr, &local, 41);
  const std::string second = snapshot(local, base);
  EXPECT_NE(first, second);
  EXPECT_FALSE(fs::exists(first));  // the older one is removed once the newer is in place
  // A writer killed after staging: its directory is never read, and is removed.
  const std::string abandoned = stageLocalMapSnapshot(local, base);
  ASSERT_TRUE(fs::exists(abandoned));
  EXPECT_EQ(newestLocalMapSnapshot(base).directory, second);
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_EQ(newestLocalMapSnapshot(tiles + "/nowhere").directory, "");
  fs::remove_all(tiles);
  fs::remove_all(fs::path(base).parent_path());
}

TEST(LocalMapSnapshot, TilesOfAnotherTileSizeOrHeldByTheTreeAreRefused) {
  const std::string tiles = freshDirectory(), base = freshDirectory() + "/autosave";
  EvidentialOcTree resident(0.2, 3, shortRange());
  LocalMap local(&resident, tiles + "/a", 12.0);
  for (int step = 0; step <= 40; ++step) insertStep(nullptr, &local, step);
  const LocalMapSnapshot found = newestLocalMapSnapshot(fs::path(snapshot(local, base)).parent_path());
  ASSERT_FALSE(found.tiles.empty());

  EvidentialOcTree empty(0.2, 3, shortRange());
  LocalMap wider(&empty, tiles + "/b", 40.0);  // larger tiles
  EXPECT_THROW(wider.adoptTiles(found.tiles), std::runtime_error);
  EXPECT_EQ(wider.tilesOnDisk(), 0u);

  std::unique_ptr<EvidentialOcTree> whole = local.globalMap();  // holds every tile itself
  LocalMap holding(whole.get(), tiles + "/c", 12.0);
  EXPECT_THROW(holding.adoptTiles(found.tiles), std::runtime_error);
  EXPECT_EQ(holding.tilesOnDisk(), 0u);
  fs::remove_all(tiles);
  fs::remove_all(fs::path(base).parent_path());
}

}  // namespace
}  // namespace evidential_octomap
