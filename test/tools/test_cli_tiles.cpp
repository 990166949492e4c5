// `evidential_octomap tiles`: a tiled map's summary, answers at points from the tiles they touch,
// and its export as one .ot. The tiled map is a SYNTHETIC wall, tiled by the library.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/tiled_map.h"
#include "test_helpers.h"

namespace evidential_octomap {
namespace {

using tools_test::CliResult;
using tools_test::freshDir;
using tools_test::runCli;

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A wall 4 m ahead of a sensor at the origin, class 1 of {free, wall}, 0.2 m.
EvidentialOcTree wall() {
  SemanticConfig config;
  config.max_range = 10.0;
  EvidentialOcTree tree(0.2, 2, config);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (float y = -2.0f; y < 2.0f; y += 0.05f)
    for (float z = 0.0f; z < 1.5f; z += 0.05f) {
      points.push_back(4.0f, y, z);
      evidence.insert(evidence.end(), {0.5f, 8.0f});
    }
  tree.insertSemanticScan(points, evidence, octomap::point3d(0.05f, 0.05f, 0.5f));
  detail::TreeEditing::updateInnerNodes(tree);  // fully pruned, as tiles are
  return tree;
}

TEST(CliTiles, SummaryQueriesAndExport) {
  const std::string dir = freshDir("cli_tiles");
  const EvidentialOcTree whole = wall();
  saveMap(whole, dir + "/whole.ot");
  EvidentialOcTree consumed(whole);
  const WrittenTiles w = TiledMap::writeTiles(consumed, 12, dir + "/tiles");  // 3.2 m tiles
  writeTiledMapManifest(dir + "/tiles", {0.2, 12, whole.classNames(), "dempster",
                                         w.evidence_log_sum, w.evidence_points, w.tiles});
  const CliResult r = runCli("tiles " + dir + "/tiles --query 4.1,0.1,0.5 --query 500,0,0 " +
                             "--export " + dir + "/exported.ot");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("tiles:           " + std::to_string(w.tiles.size()) + " of depth 12 "
                          "(3.2 m edge)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(4.1, 0.1, 0.5): occupied, label " + whole.classNames()[1]),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(500, 0, 0): unknown, label none"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tiles read:      2\n"), std::string::npos) << r.output;
  EXPECT_TRUE(bytesOf(dir + "/exported.ot") == bytesOf(dir + "/whole.ot"));

  const CliResult bad = runCli("tiles " + dir);
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("is not a tiled map"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace evidential_octomap
