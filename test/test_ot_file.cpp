// Files: .ot round trips (AbstractOcTree::read, saveMap/loadMap), .bt in plain OcTree,
// ColorOcTree export, exact merge, corrupt/truncated/foreign files and atomic saves.
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/octomap.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "synthetic_scene.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

namespace fs = std::filesystem;
using test::compareTrees;
using test::SyntheticScene;

using KeyTuple = std::tuple<int, int, int>;
KeyTuple tupleOf(const octomap::OcTreeKey& k) { return {k[0], k[1], k[2]}; }

// A fresh directory per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "evidential_ot_XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (fs::path(path_) / name).string(); }
  std::set<std::string> entries() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(path_)) out.insert(e.path().filename().string());
    return out;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

uint32_t bitsOf(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A map with non-default settings everywhere the file has to carry them.
std::unique_ptr<EvidentialOcTree> makeMap(const std::string& rule, int scans = 2,
                                          unsigned seed = 10, float shift = 0.0f) {
  SyntheticScene scene;
  SemanticConfig config;
  config.rule = rule;
  config.length_scale = 0.25;
  config.drop_percent = 15.0;
  config.max_range = 30.0;
  config.sbki_prior = 0.002f;
  config.kernel_creates_leaves = true;
  auto tree = std::make_unique<EvidentialOcTree>(0.2, scene.num_classes, config);
  tree->setClassNames({"ground", "box", "other"});
  tree->setProbHit(0.75);
  tree->setClampingThresMax(0.95);
  for (int i = 0; i < scans; ++i) {
    const auto scan = scene.scan(octomap::point3d(0.05f + shift + 0.4f * i, 0.1f, 1.7f), seed + i);
    tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  }
  return tree;
}

std::unique_ptr<EvidentialOcTree> smallMap() {
  auto tree = std::make_unique<EvidentialOcTree>(0.2, 2);
  octomap::Pointcloud points;
  points.push_back(1.1f, 0.1f, 0.1f);
  points.push_back(1.1f, 0.3f, 0.1f);
  tree->insertSemanticScan(points, {4.0f, 0.5f, 0.5f, 3.0f}, octomap::point3d(0.1f, 0.1f, 0.1f));
  return tree;
}

// --- round trips
// ----------------------------------------------------------------------------------

TEST(OtFile, RoundTripThroughAbstractOcTreeReadIsBitExact) {
  TempDir dir;
  for (const std::string& rule : kFusionRuleNames) {
    const auto tree = makeMap(rule);
    ASSERT_GT(tree->numSemanticNodes(), 0u);
    const std::string path = dir.file(rule + ".ot");
    ASSERT_TRUE(tree->write(path));
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
    ASSERT_NE(any, nullptr) << rule;
    EXPECT_EQ(any->getTreeType(), "EvidentialOcTree");
    auto* read_back = dynamic_cast<EvidentialOcTree*>(any.get());
    ASSERT_NE(read_back, nullptr) << rule;
    EXPECT_TRUE(read_back->readError().empty()) << read_back->readError();
    EXPECT_TRUE(compareTrees(*tree, *read_back)) << rule;
  }
}

// The ground classes and their support are part of the map: read back by OctoMap's reader, a
// map goes on mapping (and answers queries) as the one written.
TEST(OtFile, GroundClassesAndTheirSupportRoundTrip) {
  TempDir dir;
  auto tree = makeMap("dempster");
  SemanticConfig config = tree->config();
  config.ground_vertical_support = 0.4;
  tree->setConfig(config);
  const std::vector<bool> ground{true, false, true};
  ASSERT_EQ(tree->numClasses(), int(ground.size()));
  tree->setGroundClasses(ground);
  const std::string path = dir.file("ground.ot");
  ASSERT_TRUE(tree->write(path));
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
  auto* read_back = dynamic_cast<EvidentialOcTree*>(any.get());
  ASSERT_NE(read_back, nullptr);
  EXPECT_EQ(read_back->groundClasses(), ground);
  EXPECT_EQ(read_back->config().ground_vertical_support, 0.4);
  EXPECT_TRUE(compareTrees(*tree, *read_back));
}

TEST(OtFile, StreamRoundTripIsBitExact) {
  const auto tree = makeMap("dempster");
  std::stringstream s;
  ASSERT_TRUE(tree->write(s));
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(s));
  auto* read_back = dynamic_cast<EvidentialOcTree*>(any.get());
  ASSERT_NE(read_back, nullptr);
  EXPECT_TRUE(compareTrees(*tree, *read_back));
}

TEST(OtFile, SaveMapLoadMapRoundTripIsBitExact) {
  TempDir dir;
  for (const std::string& rule : kFusionRuleNames) {
    const auto tree = makeMap(rule);
    const std::string path = dir.file("map_" + rule + ".ot");
    saveMap(*tree, path);
    const auto loaded = loadMap(path);
    ASSERT_NE(loaded, nullptr);
    EXPECT_TRUE(compareTrees(*tree, *loaded)) << rule;
    // Saving the loaded map again gives the same bytes.
    const std::string again = dir.file("again_" + rule + ".ot");
    saveMap(*loaded, again);
    EXPECT_EQ(readBytes(path), readBytes(again)) << rule;
  }
}

TEST(OtFile, EmptyAndSingleClassMapsRoundTrip) {
  TempDir dir;
  EvidentialOcTree empty(0.1, 5);
  saveMap(empty, dir.file("empty.ot"));
  const auto loaded = loadMap(dir.file("empty.ot"));
  EXPECT_TRUE(compareTrees(empty, *loaded));
  EXPECT_EQ(loaded->numClasses(), 5);

  EvidentialOcTree one(0.5, 1);
  octomap::Pointcloud points;
  points.push_back(2.25f, 0.25f, 0.25f);
  one.insertSemanticScan(points, {7.0f}, octomap::point3d(0.25f, 0.25f, 0.25f));
  saveMap(one, dir.file("one.ot"));
  EXPECT_TRUE(compareTrees(one, *loadMap(dir.file("one.ot"))));
}

TEST(OtFile, ManyClassesAndOddNamesRoundTrip) {
  TempDir dir;
  EvidentialOcTree tree(0.2, 255);
  std::vector<std::string> names;
  for (int c = 0; c < 255; ++c) names.push_back("class " + std::to_string(c));
  names[0] = "";
  names[1] = "two words\nand a newline";
  names[2] =
      "\xc3\xbc"
      "nic\xc3\xb6"
      "de";
  names[3] = std::string(300, 'x');
  tree.setClassNames(names);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 50; ++i) {
    points.push_back(1.1f, -2.5f + 0.1f * i, 0.1f);
    for (int c = 0; c < 255; ++c) evidence.push_back(c == (i * 7) % 255 ? 9.0f : 0.01f * (c % 5));
  }
  tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f));
  saveMap(tree, dir.file("c255.ot"));
  const auto loaded = loadMap(dir.file("c255.ot"));
  EXPECT_TRUE(compareTrees(tree, *loaded));
  EXPECT_EQ(loaded->classNames()[1], names[1]);
}

// Format 3 stores a payload for leaves only, each in the shorter of its two forms. The size of
// the node records is recomputed here from the tree: 4 B log-odds + 1 B child mask per node,
// and per leaf a tag byte plus min(4 C dense, 5 B per class whose bits differ from the prior).
// Format 5: a node's log-odds as a 1-byte index into the table of the map's distinct values
// (2 bytes beyond 256 values), its child mask, and a leaf's payload in the shorter of the dense
// and the sparse form; inner nodes carry no payload.
TEST(OtFile, Format5CodesLogOddsByTableAndStoresLeafPayloadsInTheShorterForm) {
  for (const std::string& rule : kFusionRuleNames) {
    const auto tree = makeMap(rule);
    const int c = tree->numClasses();
    const float prior = tree->rule().prior();
    size_t nodes = 0, payload_bytes = 0, inner_with_semantics = 0;
    std::set<uint32_t> distinct;
    for (auto it = tree->begin_tree(); it != tree->end_tree(); ++it) {
      ++nodes;
      distinct.insert(bitsOf(it->getValue()));
      if (!it.isLeaf()) {
        inner_with_semantics += it->hasSemantics() ? 1 : 0;
        continue;
      }
      payload_bytes += 1;
      if (const std::vector<float> p = tree->payload(&*it); !p.empty()) {
        size_t differing = 0;
        for (int k = 0; k < c; ++k) differing += test::sameBits(p[k], prior) ? 0 : 1;
        const size_t sparse = 5 * differing;
        payload_bytes += sparse < 4u * c ? sparse : 4u * c;
      }
    }
    ASSERT_GT(inner_with_semantics, 10u) << rule;
    ASSERT_LE(distinct.size(), 256u) << rule;
    const size_t expected = nodes * (1 + 1) + 4 * distinct.size() + payload_bytes;
    std::ostringstream full, empty;
    tree->writeData(full);
    EvidentialOcTree blank(tree->getResolution(), c, tree->config());
    blank.setClassNames(tree->classNames());
    blank.writeData(empty);  // an empty table
    EXPECT_EQ(full.str().size() - empty.str().size(), expected) << rule;
  }
}

// Beyond 256 distinct log-odds the index takes 2 bytes, beyond 65536 the value itself (f32);
// each map reads back bit for bit.
TEST(OtFile, LogOddsIndexWidthFollowsTheNumberOfDistinctValues) {
  EvidentialOcTree blank(0.1, 2);
  std::ostringstream empty;
  blank.writeData(empty);  // width 1, an empty table
  for (const uint32_t leaves : {200u, 5000u, 70000u}) {
    EvidentialOcTree tree(0.1, 2);
    for (uint32_t i = 0; i < leaves; ++i) {  // a distinct value per leaf
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(32768 + i % 256),
                                   static_cast<octomap::key_type>(32768 + i / 256), 32768);
      tree.setNodeValue(key, -2.0f + 4.0f * float(i) / float(leaves));
    }
    std::stringstream data;
    tree.writeData(data);
    EvidentialOcTree loaded(0.1, 2);
    ASSERT_TRUE(loaded.readData(data)) << leaves;
    EXPECT_TRUE(compareTrees(tree, loaded)) << leaves;
    std::set<uint32_t> distinct;
    size_t inner = 0;
    for (auto it = tree.begin_tree(); it != tree.end_tree(); ++it) {
      distinct.insert(bitsOf(it->getValue()));
      inner += it.isLeaf() ? 0 : 1;
    }
    const size_t width = distinct.size() <= 256 ? 1 : distinct.size() <= 65536 ? 2 : 4;
    // Nodes: log-odds and child mask, leaves a payload tag; the table 4 B a value (and the
    // empty map's u32 table length, which width 4 leaves out).
    const size_t coded = tree.size() * (width + 1) + (tree.size() - inner) +
                         (width < 4 ? 4 * distinct.size() : 0);
    EXPECT_EQ(data.str().size() + (width < 4 ? 0 : 4) - empty.str().size(), coded) << leaves;
  }
}

TEST(OtFile, Format1FilesOfTheOldLibraryStillLoadLeafForLeaf) {
  for (const std::string rule : {"dempster", "sbki"}) {
    const std::string fixtures = std::string(EVIDENTIAL_OCTOMAP_SOURCE_DIR) + "/test/fixtures/";
    const auto tree = loadMap(fixtures + "ot_v1_" + rule + ".ot");
    ASSERT_EQ(tree->config().rule, rule);
    std::ifstream dump(fixtures + "ot_v1_" + rule + ".leaves.txt");
    std::string line;
    std::getline(dump, line);  // comment
    size_t leaves = 0, semantic = 0;
    for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it, ++leaves) {
      ASSERT_TRUE(std::getline(dump, line)) << "more leaves than the dump";
      std::istringstream fields(line);
      unsigned k0, k1, k2, depth, value_bits;
      fields >> k0 >> k1 >> k2 >> depth >> value_bits;
      EXPECT_EQ(octomap::OcTreeKey(k0, k1, k2), it.getKey());
      EXPECT_EQ(depth, it.getDepth());
      float value;
      std::memcpy(&value, &value_bits, 4);
      EXPECT_TRUE(test::sameBits(value, it->getLogOdds()));
      std::vector<float> payload;
      for (unsigned bits; fields >> bits;) {
        payload.push_back(0.0f);
        std::memcpy(&payload.back(), &bits, 4);
      }
      const std::vector<float> p = tree->payload(&*it);
      ASSERT_EQ(p.empty(), payload.empty());
      if (p.empty()) continue;
      ++semantic;
      for (int c = 0; c < tree->numClasses(); ++c) EXPECT_TRUE(test::sameBits(p[c], payload[c]));
    }
    EXPECT_FALSE(std::getline(dump, line)) << "fewer leaves than the dump";
    EXPECT_EQ(tree->numSemanticNodes(), semantic);
    EXPECT_GT(semantic, 50u);
    // Saved again, it is a format-3 file that reads back equal.
    std::stringstream again;
    tree->write(again);
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(again));
    auto* reread = dynamic_cast<EvidentialOcTree*>(read.get());
    ASSERT_NE(reread, nullptr);
    EXPECT_TRUE(compareTrees(*tree, *reread));
  }
}

TEST(OtFile, InsertingAfterLoadContinuesLikeTheOriginal) {
  TempDir dir;
  const auto tree = makeMap("dempster", 1);
  saveMap(*tree, dir.file("m.ot"));
  const auto loaded = loadMap(dir.file("m.ot"));
  SyntheticScene scene;
  const auto scan = scene.scan(octomap::point3d(1.05f, 0.1f, 1.7f), 77);
  tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  loaded->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  EXPECT_TRUE(compareTrees(*tree, *loaded));
}

std::set<KeyTuple> occupiedLeafKeys(octomap::OcTree& tree) {
  tree.expand();
  std::set<KeyTuple> out;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (tree.isNodeOccupied(*it)) out.insert(tupleOf(it.getKey()));
  }
  return out;
}

std::set<KeyTuple> occupiedLeafKeys(EvidentialOcTree& tree) {
  tree.expand();
  std::set<KeyTuple> out;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (tree.isNodeOccupied(*it)) out.insert(tupleOf(it.getKey()));
  }
  return out;
}

TEST(BtFile, LoadsInPlainOcTreeWithTheSameOccupiedLeaves) {
  TempDir dir;
  auto tree = makeMap("dempster");
  const std::string path = dir.file("map.bt");
  saveBinaryOccupancy(*tree, path);
  octomap::OcTree plain(0.1);
  ASSERT_TRUE(plain.readBinary(path));
  EXPECT_DOUBLE_EQ(plain.getResolution(), tree->getResolution());
  const auto expected = occupiedLeafKeys(*tree);
  ASSERT_GT(expected.size(), 100u);
  EXPECT_TRUE(occupiedLeafKeys(plain) == expected);
}

TEST(BtFile, LoadMapRefusesABtFileNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("map.bt");
  saveBinaryOccupancy(*makeMap("dempster", 1), path);
  try {
    loadMap(path);
    FAIL() << "a .bt file was loaded as an EvidentialOcTree";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(BtFile, LoadsIntoAnOccupancyOnlyMapToMapOn) {
  TempDir dir;
  auto tree = makeMap("dempster");
  const std::string path = dir.file("map.bt");
  saveBinaryOccupancy(*tree, path);
  SemanticConfig config;
  auto loaded = loadBinaryOccupancy(path, 5, config);
  EXPECT_DOUBLE_EQ(loaded->getResolution(), tree->getResolution());
  EXPECT_EQ(loaded->numClasses(), 5);
  EXPECT_EQ(loaded->numSemanticNodes(), 0u);
  const auto expected = occupiedLeafKeys(*tree);
  ASSERT_GT(expected.size(), 100u);
  EXPECT_TRUE(occupiedLeafKeys(*loaded) == expected);
  // A semantic scan on top of it works as on any map.
  SyntheticScene scene;
  const auto scan = scene.scan(octomap::point3d(0.05f, 0.1f, 1.7f), 3);
  std::vector<float> evidence;
  for (size_t i = 0; i < scan.points_W.size(); ++i)
    for (int c = 0; c < 5; ++c) evidence.push_back(c == 1 ? 5.f : 0.f);
  loaded->insertSemanticScan(scan.points_W, evidence, scan.origin_W);
  EXPECT_GT(loaded->numSemanticNodes(), 0u);
}

TEST(BtFile, LoadBinaryOccupancyRefusesAnOtNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("map.ot");
  saveMap(*makeMap("dempster", 1), path);
  try {
    loadBinaryOccupancy(path, 3, SemanticConfig());
    FAIL() << "an .ot file was read as a .bt";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(BtFile, HeaderNamesThePlainOcTreeForStockTools) {
  TempDir dir;
  const std::string path = dir.file("map.bt");
  saveBinaryOccupancy(*makeMap("dempster", 1), path);
  const std::string bytes = readBytes(path);
  EXPECT_EQ(bytes.rfind("# Octomap OcTree binary file\n", 0), 0u);
  EXPECT_NE(bytes.find("\nid OcTree\n"), std::string::npos);
  EXPECT_EQ(bytes.find("EvidentialOcTree"), std::string::npos) << "stock tools echo this id";
}

// --- ColorOcTree export
// ----------------------------------------------------------------------------

ClassTable threeClasses() {
  ClassTable table;
  table.dataset = "synthetic";
  table.names = {"ground", "box", "other"};
  table.colors = {{200, 10, 10}, {10, 200, 10}, {10, 10, 200}};
  return table;
}

// --- stock OctoMap tools (Debian's octomap-tools), where installed
// ------------------------------------------------------------------

bool haveTool(const std::string& name) {
  return std::system(("command -v " + name + " >/dev/null 2>&1").c_str()) == 0;
}

// Runs `command` in a shell; returns its exit code and what it printed (stdout and stderr).
std::pair<int, std::string> runTool(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return {-1, "popen failed"};
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) out.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(StockTools, ConvertOctreeReadsOurBtAsAPlainOcTree) {
  if (!haveTool("convert_octree")) GTEST_SKIP() << "convert_octree missing (Debian: octomap-tools)";
  TempDir dir;
  auto tree = makeMap("dempster");
  const std::string bt = dir.file("map.bt"), ot = dir.file("converted.ot");
  saveBinaryOccupancy(*tree, bt);
  const auto [code, out] = runTool("convert_octree " + bt + " " + ot);
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("Reading binary octree type OcTree"), std::string::npos) << out;
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(ot));
  auto* plain = dynamic_cast<octomap::OcTree*>(any.get());
  ASSERT_NE(plain, nullptr) << out;
  const auto expected = occupiedLeafKeys(*tree);
  ASSERT_GT(expected.size(), 100u);
  EXPECT_TRUE(occupiedLeafKeys(*plain) == expected);
}

// The ColorOcTree export is the file for stock viewers and converters: convert_octree turns it
// into a .bt with our occupancy.
TEST(StockTools, ConvertOctreeReadsTheColorExport) {
  if (!haveTool("convert_octree")) GTEST_SKIP() << "convert_octree missing (Debian: octomap-tools)";
  TempDir dir;
  auto tree = makeMap("dempster");
  const auto color = toColorOcTree(*tree, threeClasses(), ColorMode::kClass);
  const std::string ot = dir.file("color.ot"), bt = dir.file("color.bt");
  ASSERT_TRUE(color->write(ot));
  const auto [code, out] = runTool("convert_octree " + ot + " " + bt);
  ASSERT_EQ(code, 0) << out;
  EXPECT_NE(out.find("Reading octree type ColorOcTree"), std::string::npos) << out;
  EXPECT_EQ(out.find("legacy"), std::string::npos) << out;
  octomap::OcTree plain(0.1);
  ASSERT_TRUE(plain.readBinary(bt));
  EXPECT_TRUE(occupiedLeafKeys(plain) == occupiedLeafKeys(*tree));
}

// convert_octree reads a file whose tree type it does not know as a headerless legacy ColorOcTree
// from byte 0. On our .ot that parse descends about one level per 9 bytes and never closes, so
// it reaches the end of the file ("Error reading from file", exit 1) or overflows its stack on a
// large map (SIGSEGV): never a converted file, whatever the rule, size or class count.
TEST(StockTools, ConvertOctreeWritesNothingFromOurOt) {
  if (!haveTool("convert_octree")) GTEST_SKIP() << "convert_octree missing (Debian: octomap-tools)";
  TempDir dir;
  std::vector<std::unique_ptr<EvidentialOcTree>> maps;
  maps.push_back(smallMap());
  maps.push_back(makeMap("dempster", 1));
  maps.push_back(makeMap("sbki", 2, 4));
  maps.push_back(makeMap("ebs", 4, 7));
  for (size_t i = 0; i < maps.size(); ++i) {
    const std::string ot = dir.file("map" + std::to_string(i) + ".ot");
    const std::string out = dir.file("converted" + std::to_string(i) + ".bt");
    ASSERT_TRUE(maps[i]->write(ot));
    // No core file from the crash in the test's working directory.
    const auto [code, printed] = runTool("ulimit -c 0; convert_octree " + ot + " " + out);
    EXPECT_NE(code, 0) << "map " << i << ": " << printed;
    EXPECT_FALSE(fs::exists(out)) << "map " << i << ": " << printed;
  }
}

// Our .ot, .bt and ColorOcTree export opened the way octovis opens a file, by a program linked
// only with the stock OctoMap library (test/stock_octomap_open.cpp; octovis itself needs a
// display and answers a refusal with a dialog): our .ot is refused, never drawn wrongly; the two
// exports open as their stock types with our occupied voxels.
TEST(StockTools, OctovisWayOfOpeningRefusesOurOtAndOpensTheExports) {
  TempDir dir;
  auto tree = makeMap("dempster");
  const std::string ot = dir.file("map.ot"), bt = dir.file("map.bt"), color = dir.file("color.ot");
  ASSERT_TRUE(tree->write(ot));
  saveBinaryOccupancy(*tree, bt);
  ASSERT_TRUE(toColorOcTree(*tree, threeClasses(), ColorMode::kClass)->write(color));
  const std::string open = STOCK_OCTOMAP_OPEN;
  const size_t occupied = occupiedLeafKeys(*tree).size();
  ASSERT_GT(occupied, 100u);

  const auto [ot_code, ot_out] = runTool(open + " " + ot);
  EXPECT_EQ(ot_code, 1) << ot_out;
  EXPECT_NE(ot_out.find("refused"), std::string::npos) << ot_out;

  for (const auto& [path, type] : {std::pair{bt, "OcTree"}, std::pair{color, "ColorOcTree"}}) {
    const auto [code, out] = runTool(open + " " + path);
    ASSERT_EQ(code, 0) << out;
    // OctoMap's own progress lines come first; the program's answer is the last line.
    const size_t last_line = out.find_last_of('\n', out.size() - 2);
    std::istringstream fields(out.substr(last_line == std::string::npos ? 0 : last_line + 1));
    std::string read_type;
    size_t leaves = 0, read_occupied = 0;
    fields >> read_type >> leaves >> read_occupied;
    EXPECT_EQ(read_type, type) << out;
    EXPECT_EQ(read_occupied, occupied) << path;
  }
}

// edit_octree takes .bt files only: it refuses our .ot without writing anything and rewrites
// our .bt with the same occupied voxels.
TEST(StockTools, EditOctreeRefusesOurOtAndRewritesOurBt) {
  if (!haveTool("edit_octree")) GTEST_SKIP() << "edit_octree missing (Debian: octomap-tools)";
  TempDir dir;
  auto tree = makeMap("dempster");
  const std::string ot = dir.file("map.ot"), bt = dir.file("map.bt");
  ASSERT_TRUE(tree->write(ot));
  saveBinaryOccupancy(*tree, bt);

  const std::string from_ot = dir.file("from_ot.bt");
  const auto [ot_code, ot_out] = runTool("edit_octree -o " + from_ot + " " + ot);
  EXPECT_NE(ot_code, 0) << ot_out;
  EXPECT_FALSE(fs::exists(from_ot)) << ot_out;

  const std::string from_bt = dir.file("from_bt.bt");
  const auto [bt_code, bt_out] = runTool("edit_octree -o " + from_bt + " " + bt);
  ASSERT_EQ(bt_code, 0) << bt_out;
  octomap::OcTree plain(0.1);
  ASSERT_TRUE(plain.readBinary(from_bt)) << bt_out;
  EXPECT_TRUE(occupiedLeafKeys(plain) == occupiedLeafKeys(*tree));
}

TEST(ColorExport, ClassColoursSurviveAbstractOcTreeRead) {
  TempDir dir;
  const auto tree = makeMap("dempster");
  const ClassTable table = threeClasses();
  const auto color = toColorOcTree(*tree, table, ColorMode::kClass);
  ASSERT_NE(color, nullptr);
  const std::string path = dir.file("color.ot");
  ASSERT_TRUE(color->write(path));
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(path));
  auto* read_back = dynamic_cast<octomap::ColorOcTree*>(any.get());
  ASSERT_NE(read_back, nullptr);
  EXPECT_EQ(read_back->getTreeType(), "ColorOcTree");
  size_t checked = 0, grey = 0;
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    const octomap::ColorOcTreeNode* node = read_back->search(it.getKey(), it.getDepth());
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(read_back->isNodeOccupied(node), tree->isNodeOccupied(*it));
    const octomap::ColorOcTreeNode::Color c = node->getColor();
    const VoxelOpinion v = tree->opinion(&*it);
    if (tree->isNodeOccupied(*it) && it->hasSemantics() && v.label >= 0) {
      const auto& expected = table.colors[v.label];
      ASSERT_EQ(c.r, expected[0]);
      ASSERT_EQ(c.g, expected[1]);
      ASSERT_EQ(c.b, expected[2]);
      ++checked;
    } else if (!it->hasSemantics()) {
      EXPECT_TRUE(c.r == c.g && c.g == c.b) << "leaf without evidence is not grey";
      ++grey;
    }
  }
  EXPECT_GT(checked, 100u);
  EXPECT_GT(grey, 0u);
}

// Each leaf's colour is uncertaintyColor of the value the mode names, computed here from the
// leaf's opinion: P(label wrong) = 1 - max p over [0, 1 - 1/C], or the vacuity u over [0, 1].
static void expectColoursOf(ColorMode mode,
                            const std::function<double(const VoxelOpinion&)>& value) {
  const auto tree = makeMap("dempster");
  const auto color = toColorOcTree(*tree, threeClasses(), mode);
  size_t checked = 0;
  std::set<std::tuple<int, int, int>> distinct;
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    if (!it->hasSemantics()) continue;
    const auto c = color->search(it.getKey(), it.getDepth())->getColor();
    const ClassTable::Rgb expected = uncertaintyColor(value(tree->opinion(&*it)));
    ASSERT_EQ(c.r, expected[0]);
    ASSERT_EQ(c.g, expected[1]);
    ASSERT_EQ(c.b, expected[2]);
    distinct.insert({c.r, c.g, c.b});
    ++checked;
  }
  EXPECT_GT(checked, 100u);
  EXPECT_GT(distinct.size(), 3u);  // the map is not one colour
}

TEST(ColorExport, UncertaintyColoursShowTheProbabilityThatTheLabelIsWrong) {
  // Certain is blue-ish, uncertain red-ish.
  const ClassTable::Rgb certain = uncertaintyColor(0.0), uncertain = uncertaintyColor(1.0);
  EXPECT_GT(certain[2], certain[0]);
  EXPECT_GT(uncertain[0], uncertain[2]);
  expectColoursOf(ColorMode::kUncertainty, [](const VoxelOpinion& o) {
    const float u = o.uncertainty, c = float(o.belief.size());
    if (o.label < 0) return 1.0f / (1.0f - 1.0f / c);  // no label: none is right
    const float max_p = *std::max_element(o.belief.begin(), o.belief.end()) + u / c;
    return (1.0f - max_p) / (1.0f - 1.0f / c);
  });
}

TEST(ColorExport, VacuityColoursShowU) {
  expectColoursOf(ColorMode::kVacuity, [](const VoxelOpinion& o) { return o.uncertainty; });
}

TEST(ColorExport, ModesAreNamedOnce) {
  EXPECT_EQ(colorModeFromName("class"), ColorMode::kClass);
  EXPECT_EQ(colorModeFromName("uncertainty"), ColorMode::kUncertainty);
  EXPECT_EQ(colorModeFromName("vacuity"), ColorMode::kVacuity);
  EXPECT_THROW(colorModeFromName("rainbow"), std::invalid_argument);
}

TEST(ColorExport, ClassTableOfWrongSizeThrows) {
  const auto tree = makeMap("dempster", 1);
  ClassTable two = threeClasses();
  two.names.pop_back();
  two.colors.pop_back();
  EXPECT_THROW(toColorOcTree(*tree, two, ColorMode::kClass), std::invalid_argument);
}

// --- merge
// -----------------------------------------------------------------------------------------

TEST(Merge, IsSymmetricForEveryRule) {
  for (const std::string& rule : kFusionRuleNames) {
    const auto a = makeMap(rule, 1, 10, 0.0f);
    const auto b = makeMap(rule, 1, 20, 1.3f);  // overlapping, not identical
    EvidentialOcTree ab(*a), ba(*b);
    ab.merge(*b);
    ba.merge(*a);
    EXPECT_TRUE(compareTrees(ab, ba)) << rule;
    EXPECT_GT(ab.numSemanticNodes(), a->numSemanticNodes()) << rule;
  }
}

TEST(Merge, DempsterPayloadsAddAtSharedVoxels) {
  const auto a = makeMap("dempster", 1, 10, 0.0f);
  const auto b = makeMap("dempster", 1, 20, 1.3f);
  EvidentialOcTree ab(*a);
  ab.merge(*b);
  size_t shared = 0;
  for (auto it = ab.begin_leafs(); it != ab.end_leafs(); ++it) {
    if (it.getDepth() != ab.getTreeDepth()) continue;
    const std::vector<float> pa = a->payload(a->search(it.getKey()));
    const std::vector<float> pb = b->payload(b->search(it.getKey()));
    const std::vector<float> pab = ab.payload(&*it);
    if (pa.empty() || pb.empty()) continue;
    ASSERT_FALSE(pab.empty());
    for (int c = 0; c < ab.numClasses(); ++c) EXPECT_FLOAT_EQ(pab[c], pa[c] + pb[c]);
    ++shared;
  }
  EXPECT_GT(shared, 50u);
}

TEST(Merge, WithAnEmptyMapIsIdentity) {
  for (const std::string& rule : kFusionRuleNames) {
    const auto a = makeMap(rule);
    EvidentialOcTree empty(0.2, a->numClasses(), a->config());
    empty.setClassNames(a->classNames());
    empty.setProbHit(a->getProbHit());
    empty.setClampingThresMax(a->getClampingThresMax());
    EvidentialOcTree a_copy(*a);
    a_copy.merge(empty);
    EXPECT_TRUE(compareTrees(a_copy, *a)) << rule << ": a + empty";
    empty.merge(*a);
    EXPECT_TRUE(compareTrees(empty, *a)) << rule << ": empty + a";
  }
}

TEST(Merge, WithItselfDoublesTheEvidence) {
  // a.merge(a) must either refuse or behave like merging an independent copy of a.
  const auto a = makeMap("dempster", 1);
  EvidentialOcTree expected(*a), self(*a);
  const EvidentialOcTree copy(*a);
  expected.merge(copy);
  try {
    self.merge(self);
  } catch (const std::exception&) {
    EXPECT_TRUE(compareTrees(self, *a)) << "a refused self-merge changed the map";
    return;
  }
  EXPECT_TRUE(compareTrees(self, expected));
}

// Scans from three origins: later scans' kernels reach voxels only earlier scans observed.
std::vector<test::SyntheticScan> walkingScans() {
  const test::SyntheticScene scene;
  return {scene.scan(octomap::point3d(0.05f, 0.1f, 1.7f), 1),
          scene.scan(octomap::point3d(1.05f, 0.9f, 1.7f), 2),
          scene.scan(octomap::point3d(2.05f, -0.7f, 1.7f), 3)};
}

// Largest |belief difference| of `b` from `a` over a's leaves; labels must agree.
float maxBeliefDifference(const EvidentialOcTree& a, const EvidentialOcTree& b, int* label_diffs) {
  float worst = 0.0f;
  *label_diffs = 0;
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    const VoxelOpinion x = a.opinion(&*it), y = b.query(it.getKey());
    *label_diffs += x.label != y.label;
    for (size_t c = 0; c < x.belief.size(); ++c) {
      worst = std::max(worst, std::fabs(x.belief[c] - y.belief[c]));
    }
  }
  return worst;
}

TEST(Merge, InOrderWithUnobservedEvidenceEqualsTheSequentialMap) {
  const auto scans = walkingScans();
  EvidentialOcTree sequential(0.2, 3);
  for (const auto& s : scans) sequential.insertSemanticScan(s.points_W, s.evidence, s.origin_W);
  // Chunk A = scan 0, chunk B = scans 1-2, each with the evidence it could not place.
  EvidentialOcTree a(0.2, 3), a_unobserved(0.2, 3), b(0.2, 3), b_unobserved(0.2, 3);
  a.insertSemanticScan(scans[0].points_W, scans[0].evidence, scans[0].origin_W, &a_unobserved);
  for (size_t i = 1; i < 3; ++i) {
    b.insertSemanticScan(scans[i].points_W, scans[i].evidence, scans[i].origin_W, &b_unobserved);
  }
  EXPECT_GT(b_unobserved.numSemanticNodes(), 0u);
  int label_diffs = 0;
  EvidentialOcTree plain(a);
  plain.merge(b);  // without the unobserved evidence: B's evidence for A's voxels is lost
  EXPECT_GT(maxBeliefDifference(sequential, plain, &label_diffs), 1e-3f);

  EvidentialOcTree rest(0.2, 3);
  a.addEvidence(b_unobserved, &rest);
  a.merge(b);
  a_unobserved.merge(rest);
  EXPECT_LT(maxBeliefDifference(sequential, a, &label_diffs), 1e-5f);
  EXPECT_EQ(label_diffs, 0);
  EXPECT_EQ(a.getNumLeafNodes(), sequential.getNumLeafNodes());
  EXPECT_EQ(a.numSemanticNodes(), sequential.numSemanticNodes());
}

TEST(Merge, UnobservedEvidenceIsEmptyWhenTheKernelCreatesLeaves) {
  SemanticConfig config;
  config.kernel_creates_leaves = true;
  EvidentialOcTree map(0.2, 3, config), unobserved(0.2, 3, config);
  const auto s = walkingScans()[1];
  map.insertSemanticScan(s.points_W, s.evidence, s.origin_W, &unobserved);
  EXPECT_EQ(unobserved.numSemanticNodes(), 0u);
  EvidentialOcTree wrong_c(0.2, 4);
  EXPECT_THROW(map.insertSemanticScan(s.points_W, s.evidence, s.origin_W, &wrong_c),
               std::invalid_argument);
  EXPECT_THROW(map.addEvidence(wrong_c, nullptr), std::invalid_argument);
}

TEST(Merge, UnclampedChunksEqualTheSequentialMapClampedAtTheEnd) {
  // Repeated scans drive log-odds past both clamping bounds, where clamping order matters.
  const auto walk = walkingScans();
  const std::vector<const test::SyntheticScan*> scans{&walk[0], &walk[0], &walk[0], &walk[0],
                                                      &walk[0], &walk[0], &walk[1], &walk[1],
                                                      &walk[2], &walk[2]};
  const float unbounded = std::numeric_limits<float>::max();
  auto build = [&](size_t first, size_t last) {
    auto map = std::make_unique<EvidentialOcTree>(0.2, 3);
    map->setClampingThresLog(-unbounded, unbounded);
    for (size_t i = first; i < last; ++i) {
      map->insertSemanticScan(scans[i]->points_W, scans[i]->evidence, scans[i]->origin_W);
    }
    return map;
  };
  const EvidentialOcTree defaults(0.2, 3);
  const auto clampAsOctoMap = [&](EvidentialOcTree* map) {
    map->setClampingThresMin(defaults.getClampingThresMin());
    map->setClampingThresMax(defaults.getClampingThresMax());
    map->clampOccupancy();
  };
  const auto sequential = build(0, scans.size());
  clampAsOctoMap(sequential.get());
  auto merged = build(0, 6);
  merged->merge(*build(6, scans.size()));
  clampAsOctoMap(merged.get());
  EvidentialOcTree clamped_each_scan(0.2, 3);  // OctoMap's own order of clamping differs
  for (const auto* scan : scans) {
    clamped_each_scan.insertSemanticScan(scan->points_W, scan->evidence, scan->origin_W);
  }
  size_t differ = 0;
  for (auto it = clamped_each_scan.begin_leafs(); it != clamped_each_scan.end_leafs(); ++it) {
    differ += std::fabs(merged->search(it.getKey())->getLogOdds() - it->getLogOdds()) > 1e-3f;
  }
  EXPECT_GT(differ, 100u);
  size_t at_bounds = 0;
  for (auto it = sequential->begin_leafs(); it != sequential->end_leafs(); ++it) {
    const EvidentialOcTreeNode* other = merged->search(it.getKey());
    ASSERT_NE(other, nullptr);
    EXPECT_NEAR(other->getLogOdds(), it->getLogOdds(), 1e-4f);
    at_bounds += it->getLogOdds() >= sequential->getClampingThresMaxLog() ||
                 it->getLogOdds() <= sequential->getClampingThresMinLog();
  }
  EXPECT_GT(at_bounds, 100u);
  EXPECT_THROW(merged->setClampingThresLog(1.0f, 2.0f), std::invalid_argument);
}

TEST(Merge, MismatchedMapsThrowAndChangeNothing) {
  const auto a = makeMap("dempster", 1);
  const EvidentialOcTree before(*a);
  SemanticConfig ebs = a->config();
  ebs.rule = "ebs";
  EvidentialOcTree other_c(0.2, 4), other_res(0.1, 3), other_rule(0.2, 3, ebs);
  octomap::Pointcloud p;
  p.push_back(1.1f, 0.1f, 0.1f);
  other_c.insertSemanticScan(p, {1, 2, 3, 4}, octomap::point3d(0.1f, 0.1f, 0.1f));
  other_res.insertSemanticScan(p, {1, 2, 3}, octomap::point3d(0.1f, 0.1f, 0.1f));
  other_rule.insertSemanticScan(p, {1, 2, 3}, octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_ANY_THROW(a->merge(other_c));
  EXPECT_ANY_THROW(a->merge(other_res));
  EXPECT_ANY_THROW(a->merge(other_rule));
  EXPECT_TRUE(compareTrees(*a, before));
}

// --- corrupt, truncated and foreign files
// ------------------------------------------------------------

TEST(CorruptFile, TruncationAtAnyOffsetThrows) {
  TempDir dir;
  const auto tree = smallMap();
  const std::string good = dir.file("good.ot");
  saveMap(*tree, good);
  const std::string bytes = readBytes(good);
  ASSERT_GT(bytes.size(), 100u);
  const std::string cut = dir.file("cut.ot");
  size_t tried = 0;
  for (size_t length = 0; length < bytes.size(); length += (length < 64 ? 1 : 7)) {
    writeBytes(cut, bytes.substr(0, length));
    EXPECT_THROW(loadMap(cut), std::runtime_error)
        << "truncated to " << length << " of " << bytes.size();
    ++tried;
  }
  // The last byte too.
  writeBytes(cut, bytes.substr(0, bytes.size() - 1));
  EXPECT_THROW(loadMap(cut), std::runtime_error);
  EXPECT_GT(tried, 20u);
}

TEST(CorruptFile, TruncatedDataViaAbstractOcTreeReadIsNotAGoodTree) {
  // Through OctoMap's own reader a truncated file must not look like a complete tree.
  const auto tree = makeMap("dempster", 1);
  std::stringstream full;
  tree->write(full);
  const std::string bytes = full.str();
  std::istringstream cut(bytes.substr(0, bytes.size() * 2 / 3));
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(cut));
  if (any) {
    auto* t = dynamic_cast<EvidentialOcTree*>(any.get());
    ASSERT_NE(t, nullptr);
    EXPECT_FALSE(t->readError().empty());
    EXPECT_EQ(t->size(), 0u);  // a failed read leaves the tree empty
  }
}

// A loaded tree is well-formed when every node can be read back sensibly. Returns what is
// wrong with it, or an empty string.
std::string wellFormedProblem(const EvidentialOcTree& tree) {
  if (tree.numClasses() < 1 || tree.numClasses() > 255) return "class count out of range";
  size_t nodes = 0, semantic = 0;
  for (auto it = tree.begin_tree(); it != tree.end_tree(); ++it) {
    ++nodes;
    if (!std::isfinite(it->getLogOdds())) return "non-finite log-odds";
    if (!it->hasSemantics()) continue;
    if (it.isLeaf()) ++semantic;  // inner nodes name a leaf's payload
    if (tree.payload(&*it).empty()) return "semantic node without payload";
    const VoxelOpinion v = tree.opinion(&*it);
    if (v.label < -1 || v.label >= tree.numClasses()) return "label out of range";
    if (!std::isfinite(v.uncertainty) || v.uncertainty < 0.0f) return "bad uncertainty";
    if (tree.rule().uncertaintyIsMass() && v.uncertainty > 1.0f) return "uncertainty mass > 1";
    for (float b : v.belief) {
      if (!std::isfinite(b)) return "non-finite belief";
      if (b < 0.0f) return "negative belief " + std::to_string(b);
      if (b > 1.0f) return "belief > 1: " + std::to_string(b);
    }
  }
  if (nodes != tree.size()) return "node count differs from size()";
  if (semantic != tree.numSemanticNodes()) return "semantic leaf count differs";
  return "";
}

TEST(CorruptFile, RandomByteFlipsThrowOrGiveAWellFormedTree) {
  TempDir dir;
  for (const std::string& rule : kFusionRuleNames) {
    SemanticConfig config;
    config.rule = rule;
    EvidentialOcTree tree(0.2, 3, config);
    octomap::Pointcloud points;
    std::vector<float> evidence;
    for (int i = 0; i < 6; ++i) {
      points.push_back(1.1f, -0.5f + 0.2f * i, 0.1f);
      evidence.insert(evidence.end(), {float(i), 2.0f, 0.5f});
    }
    tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.5f));
    const std::string good = dir.file("good.ot");
    saveMap(tree, good);
    const std::string bytes = readBytes(good);
    const size_t data_start = bytes.find("data\n");
    ASSERT_NE(data_start, std::string::npos);
    const std::string flipped_path = dir.file("flipped.ot");
    std::mt19937 rng(5);
    size_t threw = 0, loaded = 0, garbage = 0;
    std::string first_problem;
    const int kTrials = 400;
    for (int trial = 0; trial < kTrials; ++trial) {
      std::string bad = bytes;
      std::uniform_int_distribution<size_t> where(data_start + 5, bytes.size() - 1);
      const int flips = 1 + trial % 3;
      for (int f = 0; f < flips; ++f) {
        bad[where(rng)] ^= static_cast<char>(1u << std::uniform_int_distribution<int>(0, 7)(rng));
      }
      writeBytes(flipped_path, bad);
      try {
        const auto t = loadMap(flipped_path);
        ASSERT_NE(t, nullptr);
        const std::string problem = wellFormedProblem(*t);
        if (problem.empty()) {
          ++loaded;
        } else {
          ++garbage;
          if (first_problem.empty())
            first_problem = "trial " + std::to_string(trial) + ": " + problem;
        }
      } catch (const std::runtime_error&) {
        ++threw;
      }
    }
    EXPECT_GT(threw, 0u) << rule;
    EXPECT_EQ(garbage, 0u) << rule << ": " << garbage << " of " << kTrials
                           << " corrupted files loaded as ill-formed "
                           << "maps (first: " << first_problem << ")";
    RecordProperty("byte_flips_loaded_" + rule, std::to_string(loaded));
  }
}

TEST(ForeignFile, ColorOcTreeFileThrowsNamingItsType) {
  TempDir dir;
  octomap::ColorOcTree color(0.2);
  color.updateNode(octomap::point3d(1, 1, 1), true)->setColor(1, 2, 3);
  const std::string path = dir.file("color.ot");
  ASSERT_TRUE(color.write(path));
  try {
    loadMap(path);
    FAIL() << "a ColorOcTree was loaded as an EvidentialOcTree";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("ColorOcTree"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  octomap::OcTree plain(0.2);
  plain.updateNode(octomap::point3d(1, 1, 1), true);
  const std::string plain_path = dir.file("plain.ot");
  ASSERT_TRUE(plain.write(plain_path));
  EXPECT_THROW(loadMap(plain_path), std::runtime_error);
}

TEST(ForeignFile, NonOctomapFileThrowsNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("notes.ot");
  writeBytes(path, "this is not an octree\n\x01\x02\x03 just text\n");
  try {
    loadMap(path);
    FAIL() << "a text file was loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  const std::string empty = dir.file("empty.ot");
  writeBytes(empty, "");
  EXPECT_THROW(loadMap(empty), std::runtime_error);
}

TEST(ForeignFile, MissingPathThrowsNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("nowhere/map.ot");
  try {
    loadMap(path);
    FAIL() << "a missing file was loaded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(ForeignFile, WrongFileTypeIdThrows) {
  // Our data section under a ColorOcTree id: the ColorOcTree reader must not accept it silently
  // as a map of ours, and loadMap must refuse it.
  TempDir dir;
  const auto tree = smallMap();
  std::stringstream s;
  tree->write(s);
  std::string bytes = s.str();
  const size_t id = bytes.find("id EvidentialOcTree");
  ASSERT_NE(id, std::string::npos);
  bytes.replace(id, std::string("id EvidentialOcTree").size(), "id ColorOcTree");
  const std::string path = dir.file("relabelled.ot");
  writeBytes(path, bytes);
  EXPECT_THROW(loadMap(path), std::runtime_error);
}

// --- atomic saves
// ----------------------------------------------------------------------------------

TEST(AtomicSave, SuccessfulSaveLeavesOnlyTheTarget) {
  TempDir dir;
  saveMap(*smallMap(), dir.file("map.ot"));
  saveMap(*makeMap("dempster", 1), dir.file("map.ot"));  // overwrite
  saveBinaryOccupancy(*smallMap(), dir.file("map.bt"));
  EXPECT_EQ(dir.entries(), (std::set<std::string>{"map.ot", "map.bt"}));
}

TEST(AtomicSave, TemporaryOfAKilledWriterIsRemovedByTheNextSave) {
  TempDir dir;
  // A pid that no longer exists: a child that has exited and been reaped.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);
  const std::string stale = "map.ot.tmp." + std::to_string(child);
  const std::string live = "map.ot.tmp." + std::to_string(::getppid());  // a running process
  std::ofstream(dir.file(stale)) << "torn";
  std::ofstream(dir.file(live)) << "in progress";
  saveMap(*smallMap(), dir.file("map.ot"));
  EXPECT_EQ(dir.entries(), (std::set<std::string>{"map.ot", live}));
}

TEST(AtomicSave, MissingDirectoryThrowsAndLeavesNoTempFile) {
  TempDir dir;
  const std::string path = dir.file("no_such_dir/map.ot");
  try {
    saveMap(*smallMap(), path);
    FAIL() << "saving into a missing directory succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dir.entries().empty());
  EXPECT_THROW(saveBinaryOccupancy(*smallMap(), path), std::runtime_error);
  EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicSave, FailedSaveLeavesThePreviousFileIntact) {
  TempDir dir;
  const std::string path = dir.file("map.ot");
  const auto small = smallMap();
  saveMap(*small, path);
  const std::string previous = readBytes(path);
  const auto big = makeMap("dempster", 2);
  {
    std::stringstream s;
    big->write(s);
    ASSERT_GT(s.str().size(), previous.size() + 8192)
        << "the new map must be larger than the limit";
  }
  // A file-size limit makes the write fail part-way, as a full disk would (works for root too).
  struct rlimit old_limit;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit limit = old_limit;
  limit.rlim_cur = previous.size() + 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limit), 0);
  bool threw = false;
  std::string message;
  try {
    saveMap(*big, path);
  } catch (const std::runtime_error& e) {
    threw = true;
    message = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(threw) << "a save that could not be written completely did not throw";
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_EQ(readBytes(path), previous) << "the previous file was damaged";
  EXPECT_EQ(dir.entries(), (std::set<std::string>{"map.ot"})) << "temporary file left behind";
  EXPECT_TRUE(compareTrees(*loadMap(path), *small));
}

}  // namespace
}  // namespace evidential_octomap
