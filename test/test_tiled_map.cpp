// A map stored as tiles (tiled_map.h): split into tiles and read back it is the same map node for
// node, its streamed .ot is saveMap's of the whole map byte for byte, and a query reads only the
// tile it touches. SYNTHETIC scans of synthetic_scene.h (a ground and a box) along a 40 m path.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/tiled_map.h"
#include "synthetic_scene.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

namespace fs = std::filesystem;

std::string freshDirectory() {
  std::string name = (fs::temp_directory_path() / "tiled_map_test.XXXXXX").string();
  if (!mkdtemp(name.data())) throw std::runtime_error("mkdtemp failed");
  return name;
}

std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// A 40 m drive past boxes, mapped at 0.2 m with an 8 m range.
EvidentialOcTree drive() {
  SemanticConfig config;
  config.max_range = 8.0;
  EvidentialOcTree tree(0.2, 3, config);
  for (int x = 0; x <= 40; x += 2) {
    test::SyntheticScene scene;
    scene.box_min = octomap::point3d(float(x) + 3.0f, -0.9f, 0.1f);
    scene.box_max = octomap::point3d(float(x) + 4.0f, 0.9f, 1.5f);
    const octomap::point3d origin(float(x) + 0.05f, 0.1f, 1.7f);
    const test::SyntheticScan scan = scene.scan(origin, unsigned(x + 1));
    tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  detail::TreeEditing::updateInnerNodes(tree);
  return tree;
}

// The tree split into tiles of depth `depth` under a fresh directory, with its manifest.
std::string tile(const EvidentialOcTree& whole, unsigned depth) {
  const std::string dir = freshDirectory();
  EvidentialOcTree consumed(whole);
  const WrittenTiles written = TiledMap::writeTiles(consumed, depth, dir);
  EXPECT_EQ(consumed.size(), 0u);  // every node went into a tile
  writeTiledMapManifest(dir, {whole.getResolution(), depth, whole.classNames(), whole.config().rule,
                              written.evidence_log_sum, written.evidence_points, written.tiles});
  return dir;
}

TEST(TiledMap, TilesReadBackAsTheWholeMapAndStreamItsBytes) {
  const EvidentialOcTree whole = drive();
  const unsigned depth = TiledMap::tileDepthForEdge(0.2, 6.4);  // 32 voxels: many tiles
  EXPECT_EQ(depth, 11u);
  const std::string dir = tile(whole, depth);
  const TiledMap tiled(dir);
  EXPECT_GT(tiled.manifest().tiles.size(), 8u);
  std::unique_ptr<EvidentialOcTree> global = tiled.globalMap();
  detail::TreeEditing::updateInnerNodes(*global);
  EXPECT_TRUE(test::compareTrees(*global, whole));
  EXPECT_DOUBLE_EQ(global->meanPointLogEvidence(), whole.meanPointLogEvidence());

  saveMap(whole, dir + "/whole.ot");
  tiled.writeGlobalMap(dir + "/streamed.ot");
  const std::string expected = fileBytes(dir + "/whole.ot");
  EXPECT_GT(expected.size(), 1000u);
  EXPECT_TRUE(fileBytes(dir + "/streamed.ot") == expected);
  EXPECT_TRUE(test::compareTrees(*loadMap(dir + "/streamed.ot"), whole));
  fs::remove_all(dir);
}

TEST(TiledMap, AQueryReadsOnlyTheTileItTouchesAndAnswersAsTheWholeMap) {
  const EvidentialOcTree whole = drive();
  const std::string dir = tile(whole, TiledMap::tileDepthForEdge(0.2, 6.4));
  const TiledMap tiled(dir);
  size_t compared = 0;
  for (auto it = whole.begin_leafs(), end = whole.end_leafs(); it != end; ++it) {
    if (!it->hasSemantics() || compared % 7 != 0) {
      compared += it->hasSemantics();
      continue;
    }
    ++compared;
    const octomap::point3d p = it.getCoordinate();
    const VoxelOpinion a = whole.query(p), b = tiled.mapAt(p).query(p);
    ASSERT_EQ(a.label, b.label);
    ASSERT_EQ(a.belief, b.belief);
    ASSERT_EQ(whole.isNodeOccupied(*it), tiled.mapAt(p).isNodeOccupied(tiled.mapAt(p).nodeAt(p)));
  }
  EXPECT_GT(compared, 100u);
  const TiledMap fresh(dir);
  fresh.mapAt(octomap::point3d(20.05f, 0.1f, 0.1f));
  EXPECT_EQ(fresh.tilesLoaded(), 2u);  // the settings' tile, then the touched one
  fresh.mapAt(octomap::point3d(20.15f, 0.1f, 0.1f));
  EXPECT_EQ(fresh.tilesLoaded(), 2u);  // cached
  EXPECT_EQ(fresh.mapAt(octomap::point3d(500.0f, 0.0f, 0.0f)).size(), 0u);  // no tile: unknown
  fs::remove_all(dir);
}

TEST(TiledMap, RefusesMissingManifestsTilesAndForeignTiles) {
  const EvidentialOcTree whole = drive();
  const std::string empty = freshDirectory();
  EXPECT_THROW(TiledMap{empty}, std::runtime_error);
  const std::string dir = tile(whole, 11);
  const TiledMapManifest manifest = readTiledMapManifest(dir);
  fs::remove(dir + "/" + tileFileName(11, manifest.tiles.front()));
  EXPECT_THROW(TiledMap{dir}, std::runtime_error);
  TiledMapManifest other = manifest;
  other.class_names = {"a", "b", "c"};
  other.tiles.erase(other.tiles.begin());
  writeTiledMapManifest(dir, other);
  EXPECT_THROW(TiledMap(dir).globalMap(), std::runtime_error);  // its tiles name other classes
  EvidentialOcTree any(0.2, 3);
  EXPECT_THROW(TiledMap::writeTiles(any, 0, dir), std::invalid_argument);
  fs::remove_all(empty);
  fs::remove_all(dir);
}

TEST(TiledMap, TileFileNamesRoundTrip) {
  unsigned depth = 0;
  TileIndex t{};
  EXPECT_EQ(tileFileName(9, {255, 256, 3}), "tile_9_255_256_3.ot");
  EXPECT_TRUE(parseTileFileName("/a/b/tile_9_255_256_3.ot", &depth, &t));
  EXPECT_EQ(depth, 9u);
  EXPECT_EQ(t, (TileIndex{255, 256, 3}));
  EXPECT_FALSE(parseTileFileName("tile_9_255_256.ot", &depth, &t));
  EXPECT_FALSE(parseTileFileName("tile_9_1_2_3.otx", &depth, &t));
  EXPECT_FALSE(parseTileFileName("tile_9_1_2_70000.ot", &depth, &t));
}

}  // namespace
}  // namespace evidential_octomap
