// The one parameter validation (SemanticConfig::problem, SensorModel::problem and the tree's
// parameterProblem): a property test over the parameter space that every map the library
// writes, it loads again, with the same parameters; and the kernel-support bound that keeps a
// scan affordable.
#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// One file per process, so that ctest -j runs of this binary never share it; in /dev/shm when
// there is one, where saveMap's fsyncs cost nothing (thousands of saves run here).
std::string tempPath(const std::string& name) {
  const std::string dir = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm/" : ::testing::TempDir();
  return dir + "evidential_params_" + std::to_string(::getpid()) + "_" + name;
}

// A small map with evidence in a few leaves, so the file holds payloads and inner nodes.
void addScan(EvidentialOcTree* tree) {
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 6; ++i) {
    points.push_back(0.4f * i, 0.2f, -0.3f);
    for (int c = 0; c < tree->numClasses(); ++c) evidence.push_back(c == i % 2 ? 7.f : 0.5f);
  }
  tree->insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.5f));
}

// saveMap either refuses (std::runtime_error) or writes a file loadMap accepts, with the same
// bytes when written again. Returns whether it saved.
bool savedAndLoadsBack(const EvidentialOcTree& tree, const std::string& path,
                       const std::string& what) {
  try {
    saveMap(tree, path);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << what << ": " << e.what();
    return false;
  }
  std::unique_ptr<EvidentialOcTree> loaded;
  try {
    loaded = loadMap(path);
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": saved, but the file does not load: " << e.what();
    return true;
  }
  std::ostringstream a, b;
  tree.write(a);
  loaded->write(b);
  EXPECT_TRUE(a.str() == b.str()) << what << ": the loaded map differs";
  return true;
}

TEST(ParameterSpace, EverySensorModelTheTreeAcceptsIsSavedAndLoaded) {
  const std::string path = tempPath("sensor.ot");
  const std::vector<double> hits{0.3, 0.5, 0.5001, 0.7, 0.999, 0.9995, 1.0, kNaN};
  const std::vector<double> misses{0.0, 0.0005, 0.001, 0.4, 0.5, 0.6, kNaN};
  const std::vector<double> clamps{0.0, 0.001, 0.12, 0.3, 0.5, 0.7, 0.97, 0.999, 1.0};
  const std::vector<double> thresholds{0.0, 0.5, 1.0};
  size_t accepted = 0, refused = 0;
  EvidentialOcTree tree(0.2, 2);  // one tree: constructing 8000 costs more than the checks
  addScan(&tree);
  for (double hit : hits)
    for (double miss : misses)
      for (double lo : clamps)
        for (double hi : clamps)
          for (double threshold : thresholds) {
            const SensorModel model{hit, miss, lo, hi, threshold};
            std::ostringstream what;
            what << "hit " << hit << " miss " << miss << " clamp " << lo << ".." << hi
                 << " threshold " << threshold;
            const SensorModel before = tree.sensorModel();
            try {
              tree.setSensorModel(model);
            } catch (const std::invalid_argument& e) {
              ++refused;
              EXPECT_FALSE(model.problem().empty()) << what.str();
              const SensorModel now = tree.sensorModel();
              EXPECT_TRUE(now.hit == before.hit && now.miss == before.miss &&
                          now.clamp_min == before.clamp_min && now.clamp_max == before.clamp_max)
                  << what.str() << ": refused, but the tree changed";
              continue;
            }
            ++accepted;
            EXPECT_TRUE(model.problem().empty()) << what.str();
            // What the tree reports back (through its float log-odds) is accepted again.
            EXPECT_NO_THROW(tree.setSensorModel(tree.sensorModel())) << what.str();
            EXPECT_TRUE(savedAndLoadsBack(tree, path, what.str())) << what.str() << " refused";
          }
  std::remove(path.c_str());
  std::cout << "[sensor models] " << accepted << " accepted (saved and loaded back), " << refused
            << " refused\n";
  // Both sides of the property were exercised.
  EXPECT_GT(accepted, 100u);
  EXPECT_GT(refused, 1000u);
}

// OctoMap's own setters are not checked (they are not virtual), so the writer is: a map set to
// hit = 1 (log-odds +inf) through them is refused by saveMap instead of written unloadable.
TEST(ParameterSpace, MapsSetThroughOctoMapSettersAreRefusedOrLoad) {
  const std::string path = tempPath("octomap_setters.ot");
  struct Case {
    const char* what;
    void (*set)(EvidentialOcTree*);
  };
  const Case cases[] = {
      {"hit 1", [](EvidentialOcTree* t) { t->setProbHit(1.0); }},
      {"miss 0", [](EvidentialOcTree* t) { t->setProbMiss(0.0); }},
      {"clamp min 0", [](EvidentialOcTree* t) { t->setClampingThresMin(0.0); }},
      {"clamp max 1", [](EvidentialOcTree* t) { t->setClampingThresMax(1.0); }},
      {"clamps inverted",
       [](EvidentialOcTree* t) {
         t->setClampingThresMin(0.9);
         t->setClampingThresMax(0.2);
       }},
      {"hit below 0.5", [](EvidentialOcTree* t) { t->setProbHit(0.3); }},
      {"resolution 0", [](EvidentialOcTree* t) { t->setResolution(0.0); }},
  };
  for (const Case& c : cases) {
    EvidentialOcTree tree(0.2, 3);
    addScan(&tree);
    c.set(&tree);
    EXPECT_FALSE(tree.parameterProblem().empty()) << c.what;
    EXPECT_FALSE(savedAndLoadsBack(tree, path, c.what)) << c.what << ": written";
    // Through the plain stream writer too: no data section, and the stream fails (OctoMap's
    // AbstractOcTree::write returns true whatever happened).
    std::ostringstream out;
    tree.write(out);
    EXPECT_TRUE(out.fail()) << c.what;
    EXPECT_EQ(out.str().find("EVEM"), std::string::npos) << c.what;
  }
  std::remove(path.c_str());
}

// --- refused by the insert that would use them --------------------------------------------------

// Every leaf (key, log-odds, payload): what an insert that is refused must not change. (The map
// cannot be written to compare bytes: its parameters are what the writer refuses.)
struct LeafState {
  octomap::OcTreeKey key;
  float log_odds;
  std::vector<float> payload;
  bool operator==(const LeafState& o) const {
    return key == o.key && log_odds == o.log_odds && payload == o.payload;
  }
};
std::vector<LeafState> leafStates(const EvidentialOcTree& tree) {
  std::vector<LeafState> leaves;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    leaves.push_back({it.getKey(), it->getLogOdds(), tree.payload(&*it)});
  }
  return leaves;
}

struct UnsavableValue {
  const char* name;
  void (*set)(EvidentialOcTree*);
};
void PrintTo(const UnsavableValue& v, std::ostream* os) { *os << v.name; }

class InsertCheck : public ::testing::TestWithParam<UnsavableValue> {};

// A value set through OctoMap's own (unchecked) setters that saveMap would refuse is refused by
// the next insert, with the reason saveMap gives, and the map is left as it was; once the value
// is put right, the same scan inserts and the map saves.
TEST_P(InsertCheck, UnsavableValueIsRefusedByTheNextInsertWithSaveMapsReason) {
  const std::string path = tempPath(std::string("insert_check_") + GetParam().name + ".ot");
  EvidentialOcTree tree(0.2, 3);
  addScan(&tree);
  const SensorModel good = tree.sensorModel();
  const std::vector<LeafState> before = leafStates(tree);
  ASSERT_GT(before.size(), 0u);
  GetParam().set(&tree);

  std::string save_message;
  try {
    saveMap(tree, path);
  } catch (const std::runtime_error& e) {
    save_message = e.what();
  }
  ASSERT_FALSE(save_message.empty()) << "saveMap accepted " << GetParam().name;
  std::string insert_message;
  try {
    addScan(&tree);
  } catch (const std::invalid_argument& e) {
    insert_message = e.what();
  }
  ASSERT_FALSE(insert_message.empty()) << "the insert accepted " << GetParam().name;
  EXPECT_EQ(save_message, "cannot save " + path + ": " + insert_message);
  EXPECT_EQ(insert_message, tree.parameterProblem());
  EXPECT_TRUE(leafStates(tree) == before) << "a refused insert changed the map";
  // The other overload (sensor frame and pose) is refused alike.
  octomap::Pointcloud points;
  points.push_back(1.0f, 0.0f, 0.0f);
  EXPECT_THROW(tree.insertSemanticScan(points, std::vector<float>{1.f, 0.f, 0.f},
                                       octomap::pose6d(0, 0, 0, 0, 0, 0)),
               std::invalid_argument);
  EXPECT_TRUE(leafStates(tree) == before);

  tree.setResolution(0.2);
  tree.setSensorModel(good);
  EXPECT_NO_THROW(addScan(&tree));
  EXPECT_NO_THROW(saveMap(tree, path));
  std::remove(path.c_str());
}

constexpr double kNaNValue = std::numeric_limits<double>::quiet_NaN();
INSTANTIATE_TEST_SUITE_P(
    OctoMapSetters, InsertCheck,
    ::testing::Values(
        UnsavableValue{"hit_1", [](EvidentialOcTree* t) { t->setProbHit(1.0); }},
        UnsavableValue{"hit_NaN", [](EvidentialOcTree* t) { t->setProbHit(kNaNValue); }},
        UnsavableValue{"hit_below_half", [](EvidentialOcTree* t) { t->setProbHit(0.3); }},
        UnsavableValue{"miss_0", [](EvidentialOcTree* t) { t->setProbMiss(0.0); }},
        UnsavableValue{"miss_NaN", [](EvidentialOcTree* t) { t->setProbMiss(kNaNValue); }},
        UnsavableValue{"miss_above_half", [](EvidentialOcTree* t) { t->setProbMiss(0.6); }},
        UnsavableValue{"clamp_min_0", [](EvidentialOcTree* t) { t->setClampingThresMin(0.0); }},
        UnsavableValue{"clamp_max_1", [](EvidentialOcTree* t) { t->setClampingThresMax(1.0); }},
        UnsavableValue{"clamp_min_NaN",
                       [](EvidentialOcTree* t) { t->setClampingThresMin(kNaNValue); }},
        UnsavableValue{"clamp_max_NaN",
                       [](EvidentialOcTree* t) { t->setClampingThresMax(kNaNValue); }},
        UnsavableValue{"clamps_inverted",
                       [](EvidentialOcTree* t) {
                         t->setClampingThresMin(0.4);
                         t->setClampingThresMax(0.3);
                       }},
        UnsavableValue{"occupancy_threshold_1",
                       [](EvidentialOcTree* t) { t->setOccupancyThres(1.0); }},
        UnsavableValue{"occupancy_threshold_NaN",
                       [](EvidentialOcTree* t) { t->setOccupancyThres(kNaNValue); }},
        UnsavableValue{"resolution_0", [](EvidentialOcTree* t) { t->setResolution(0.0); }},
        UnsavableValue{"resolution_NaN",
                       [](EvidentialOcTree* t) { t->setResolution(kNaNValue); }}),
    [](const ::testing::TestParamInfo<UnsavableValue>& info) { return info.param.name; });

// Unbounded clamping set through setClampingThresLog (chunk maps merged and clamped later) is
// what that setter is for: inserts go on; a bound then changed through OctoMap's setter is checked.
TEST(InsertCheck, UnboundedChunkClampsMapButAnOctoMapClampOfZeroIsRefused) {
  EvidentialOcTree tree(0.2, 3);
  const float unbounded = std::numeric_limits<float>::max();
  tree.setClampingThresLog(-unbounded, unbounded);
  EXPECT_FALSE(tree.parameterProblem().empty());  // not savable until clamped
  EXPECT_EQ(tree.insertProblem(), "");
  EXPECT_NO_THROW(addScan(&tree));
  tree.setClampingThresMin(0.0);
  EXPECT_THROW(addScan(&tree), std::invalid_argument);
  tree.setProbHit(1.0);
  tree.setClampingThresLog(-unbounded, unbounded);
  EXPECT_THROW(addScan(&tree), std::invalid_argument);  // hit is still checked
}

// Each value valid most of the time, so that both accepted and refused configs are common.
SemanticConfig randomConfig(std::mt19937& rng) {
  auto pick = [&rng](const std::vector<double>& valid, const std::vector<double>& invalid) {
    const std::vector<double>& from = rng() % 100 < 85 ? valid : invalid;
    return from[std::uniform_int_distribution<size_t>(0, from.size() - 1)(rng)];
  };
  SemanticConfig c;
  c.rule = std::vector<std::string>{"dempster", "sbki", "ebs", "dempster", "nope"}[rng() % 5];
  c.length_scale = pick({1e-9, 0.05, 0.3, 5.0, 1e300}, {-1.0, 0.0, kInf, kNaN});
  c.beta = pick({0.5, 1.0, 10.0, 1e300}, {-1.0, 0.0, kInf, kNaN});
  c.gamma = pick({-5.0, 0.0, 3.0, 20.0}, {kInf, -kInf, kNaN});
  c.sigma0 = pick({0.5, 1.0, 3.0}, {-1.0, 0.0, kInf, kNaN});
  c.drop_percent = pick({0.0, 10.0, 99.9}, {-1.0, 100.0, kNaN});
  c.ds_multiplier = pick({-kInf, -1.0, 0.0, 5.0, 1000.0}, {1001.0, kInf, kNaN});
  c.max_range = pick({-1.0, 50.0, kInf}, {kNaN});
  c.sbki_prior = static_cast<float>(pick({0.001, 1.0}, {-1.0, 0.0, kInf, kNaN}));
  c.threads = rng() % 100 < 85 ? int(rng() % 3) : std::vector<int>{-1, 5000}[rng() % 2];
  c.adaptive_length = rng() % 2;
  c.uncertainty_threshold = rng() % 2;
  c.reference_compat = rng() % 2;
  c.kernel_creates_leaves = rng() % 2;
  c.discretize = rng() % 2;
  return c;
}

TEST(ParameterSpace, EverySemanticConfigTheTreeAcceptsIsSavedAndLoaded) {
  const std::string path = tempPath("semantic.ot");
  std::mt19937 rng(20261124);
  size_t accepted = 0, refused = 0, inserted = 0, refused_scans = 0;
  EvidentialOcTree tree(0.2, 3);
  for (int trial = 0; trial < 1500; ++trial) {
    const SemanticConfig config = randomConfig(rng);
    std::ostringstream what;
    what << "trial " << trial << ":\n";
    config.print(what);
    // One tree, cleared and reconfigured (constructing 1500 costs more than the checks); the
    // constructor applies the same setConfig.
    tree.clear();
    try {
      tree.setConfig(config);
    } catch (const std::invalid_argument&) {
      ++refused;
      EXPECT_FALSE(config.problem().empty()) << what.str();
      if (refused < 20) {
        EXPECT_THROW(EvidentialOcTree(0.2, 3, config), std::invalid_argument);
      }
      continue;
    }
    ++accepted;
    EXPECT_TRUE(config.problem().empty()) << what.str();
    // A scan goes in when the kernel is affordable, and is refused before any change if not
    // (for the first accepted configs only: each scan has a fixed cost of some 50 ms).
    if (accepted > 40) {
      // saved and loaded empty below
    } else if (config.supportProblem(0.2).empty()) {
      EXPECT_NO_THROW(addScan(&tree)) << what.str();
      ++inserted;
    } else {
      EXPECT_THROW(addScan(&tree), std::invalid_argument) << what.str();
      ++refused_scans;
      EXPECT_EQ(tree.size(), 0u) << what.str();
    }
    EXPECT_TRUE(savedAndLoadsBack(tree, path, what.str())) << what.str() << " refused";
  }
  std::remove(path.c_str());
  std::cout << "[semantic configs] " << accepted << " accepted (saved and loaded back; " << inserted
            << " took a scan, " << refused_scans << " scans refused for their kernel), " << refused
            << " refused\n";
  EXPECT_GT(accepted, 200u);
  EXPECT_GT(inserted, 5u);
  EXPECT_GT(refused_scans, 5u);
  EXPECT_GT(refused, 500u);
}

TEST(ParameterSpace, EvidenceFloorMustBeFiniteAndNonNegative) {
  for (double good : {0.0, 1e-3, 0.01, 5.0, 1e300}) {
    SemanticConfig c;
    c.evidence_floor = good;
    EXPECT_EQ(c.problem(), "") << good;
    EXPECT_NO_THROW(EvidentialOcTree(0.2, 3, c)) << good;
  }
  for (double bad : {-1e-9, -1.0, kInf, -kInf, kNaN}) {
    SemanticConfig c;
    c.evidence_floor = bad;
    EXPECT_NE(c.problem().find("evidence_floor"), std::string::npos) << bad;
    EXPECT_THROW(EvidentialOcTree(0.2, 3, c), std::invalid_argument) << bad;
  }
}

TEST(ParameterSpace, EveryResolutionIsSavedAndLoadedExactlyOrRefused) {
  const std::string path = tempPath("resolution.ot");
  for (double res : {1e-7, 1e-6, 0.05, 0.123456789, 1.0 / 3.0, 1e6, 2e6}) {
    SemanticConfig config;
    config.length_scale = res;  // a kernel of a few leaves at every resolution
    EvidentialOcTree tree(res, 2, config);
    const bool valid =
        res >= EvidentialOcTree::kMinResolution && res <= EvidentialOcTree::kMaxResolution;
    EXPECT_EQ(tree.parameterProblem().empty(), valid) << res;
    EXPECT_EQ(savedAndLoadsBack(tree, path, "resolution " + std::to_string(res)), valid) << res;
  }
  std::remove(path.c_str());
}

// --- the kernel bound -----------------------------------------------------------------------

TEST(KernelBound, SupportIsBoundedInLeaves) {
  SemanticConfig config;  // l = 0.3 m, beta 1 -> up to 0.3 e = 0.815 m
  config.adaptive_length = true;  // the paper's gamma 3: the same bound, u -> 0
  EXPECT_NEAR(config.maxSupportLength(), 0.3 * std::exp(1.0), 1e-12);
  EXPECT_EQ(config.supportProblem(0.2), "");
  EXPECT_EQ(config.supportProblem(0.3 * std::exp(1.0) / SemanticConfig::kMaxSupportLeaves), "");
  EXPECT_NE(config.supportProblem(0.05), "");  // 16.3 leaves
  config.gamma = -2.0;                         // support grows with u: largest at u = 1
  EXPECT_NEAR(config.maxSupportLength(), 0.3 * std::exp(3.0), 1e-12);
  config.reference_compat = true;  // gamma 0 is used
  EXPECT_NEAR(config.maxSupportLength(), 0.3 * std::exp(1.0), 1e-12);
}

// l = 5 m, beta = 10 at 0.2 m: a support of 680 leaves took 180 s and 3.3 GB for 16 points in
// the node, and died with std::bad_alloc with large evidence. The scan is refused instead, with
// the parameters to change, and the map is left as it was.
TEST(KernelBound, AnUnaffordableKernelIsRefusedBeforeTheMapChanges) {
  EvidentialOcTree tree(0.2, 20);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 16; ++i) {
    points.push_back(2.f + 0.1f * i, 1.f, 0.f);
    for (int c = 0; c < 20; ++c) evidence.push_back(c == 3 ? 1000.f : 0.f);
  }
  tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
  SemanticConfig huge;
  huge.length_scale = 5.0;
  huge.beta = 10.0;
  ASSERT_EQ(huge.problem(), "");  // a valid map setting ...
  tree.setConfig(huge);
  std::ostringstream before;
  tree.write(before);
  try {
    tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
    FAIL() << "an unaffordable kernel was run";
  } catch (const std::invalid_argument& e) {  // ... that no scan may use
    EXPECT_NE(std::string(e.what()).find("length_scale"), std::string::npos) << e.what();
  }
  std::ostringstream after;
  tree.write(after);
  EXPECT_TRUE(before.str() == after.str()) << "the refused scan changed the map";
}

}  // namespace
}  // namespace evidential_octomap
