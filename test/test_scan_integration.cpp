// Scan integration on a SYNTHETIC scene with known ground truth (synthetic_scene.h): occupancy by
// ray casting, semantics by the adaptive kernel, bad inputs, key-range edges, the percentile
// threshold, leaf creation, and the three fusion rules through one integrator.
#include <gtest/gtest.h>
#include <octomap/octomap.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "synthetic_scene.h"
#include "tree_compare.h"

namespace evidential_octomap {
namespace {

using test::compareTrees;
using test::SyntheticScan;
using test::SyntheticScene;

using KeyTuple = std::tuple<int, int, int>;
KeyTuple tupleOf(const octomap::OcTreeKey& k) { return {k[0], k[1], k[2]}; }

// Majority true label of the points in each endpoint voxel.
std::map<KeyTuple, int> groundTruthVoxels(const octomap::OcTree& keys_from,
                                          const SyntheticScan& scan, int num_classes) {
  std::map<KeyTuple, std::vector<int>> votes;
  for (size_t i = 0; i < scan.points_W.size(); ++i) {
    auto& v = votes[tupleOf(keys_from.coordToKey(scan.points_W.getPoint(i)))];
    v.resize(num_classes, 0);
    ++v[scan.labels[i]];
  }
  std::map<KeyTuple, int> truth;
  for (const auto& [key, v] : votes) {
    truth[key] = int(std::max_element(v.begin(), v.end()) - v.begin());
  }
  return truth;
}

octomap::OcTreeKey keyOf(const KeyTuple& t) {
  return octomap::OcTreeKey(std::get<0>(t), std::get<1>(t), std::get<2>(t));
}

// Occupancy and semantic state that a user can observe at a key.
struct Observation {
  bool known = false;
  bool occupied = false;
  int label = -1;
  std::vector<float> belief;
  float uncertainty = 1.0f;
  bool operator==(const Observation& o) const {
    return known == o.known && occupied == o.occupied && label == o.label && belief == o.belief &&
           uncertainty == o.uncertainty;
  }
};

Observation observe(const EvidentialOcTree& tree, const octomap::OcTreeKey& key) {
  Observation o;
  const EvidentialOcTreeNode* node = tree.search(key);
  o.known = node != nullptr;
  if (node) o.occupied = tree.isNodeOccupied(node);
  const VoxelOpinion v = tree.query(key);
  o.label = v.label;
  o.belief = v.belief;
  o.uncertainty = v.uncertainty;
  return o;
}

class SyntheticSceneTest : public ::testing::Test {
 protected:
  SyntheticScene scene;
  SyntheticScan scan = scene.defaultScan();
  octomap::OcTree key_helper{0.2};  // only for coordToKey at the same resolution
};

TEST_F(SyntheticSceneTest, SceneHasBothClasses) {
  // Guards the fixture itself: rays hit both the ground and the box.
  const auto ground = std::count(scan.labels.begin(), scan.labels.end(), SyntheticScene::kGround);
  const auto box = std::count(scan.labels.begin(), scan.labels.end(), SyntheticScene::kBox);
  EXPECT_GT(ground, 1000);
  EXPECT_GT(box, 100);
  RecordProperty("synthetic_points", std::to_string(scan.points_W.size()));
}

TEST_F(SyntheticSceneTest, EndpointVoxelsAreOccupied) {
  EvidentialOcTree tree(0.2, scene.num_classes);
  const InsertStats stats = tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  EXPECT_EQ(stats.points_in, scan.points_W.size());
  EXPECT_EQ(stats.points_skipped, 0u);
  EXPECT_GT(stats.voxels_updated, 0u);
  const auto truth = groundTruthVoxels(key_helper, scan, scene.num_classes);
  size_t occupied = 0;
  for (const auto& [key, label] : truth) {
    const EvidentialOcTreeNode* node = tree.search(keyOf(key));
    ASSERT_NE(node, nullptr);
    if (tree.isNodeOccupied(node)) ++occupied;
  }
  EXPECT_EQ(occupied, truth.size());
}

TEST_F(SyntheticSceneTest, VoxelsAlongRaysAreFree) {
  EvidentialOcTree tree(0.2, scene.num_classes);
  tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  const auto truth = groundTruthVoxels(key_helper, scan, scene.num_classes);
  size_t checked = 0;
  for (size_t i = 0; i < scan.points_W.size(); i += 7) {
    // Discretized insertion casts to the endpoint voxel's centre: sample that ray.
    const octomap::point3d end = tree.keyToCoord(tree.coordToKey(scan.points_W.getPoint(i)));
    for (double f : {0.25, 0.5, 0.75}) {
      const octomap::point3d p = scan.origin_W + (end - scan.origin_W) * float(f);
      if ((end - p).norm() < 0.5) continue;  // near the surface
      const octomap::OcTreeKey key = tree.coordToKey(p);
      if (truth.count(tupleOf(key))) continue;  // some other ray ends here
      const EvidentialOcTreeNode* node = tree.search(key);
      ASSERT_NE(node, nullptr) << "unknown voxel on ray " << i << " at " << p;
      EXPECT_FALSE(tree.isNodeOccupied(node)) << "occupied voxel on ray " << i << " at " << p;
      EXPECT_LT(node->getLogOdds(), 0.0f);
      ++checked;
    }
  }
  EXPECT_GT(checked, 500u);
}

TEST_F(SyntheticSceneTest, ArgmaxIsRightOnSurfaceVoxelsForEveryRule) {
  const auto truth = groundTruthVoxels(key_helper, scan, scene.num_classes);
  for (const std::string& rule : kFusionRuleNames) {
    SemanticConfig config;
    config.rule = rule;
    EvidentialOcTree tree(0.2, scene.num_classes, config);
    ASSERT_EQ(tree.rule().name(), rule);
    tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    size_t right = 0, per_class_total[2] = {0, 0}, per_class_right[2] = {0, 0};
    for (const auto& [key, label] : truth) {
      const VoxelOpinion v = tree.query(keyOf(key));
      ASSERT_EQ(v.belief.size(), size_t(scene.num_classes));
      ++per_class_total[label];
      if (v.label == label) {
        ++right;
        ++per_class_right[label];
      }
    }
    const double accuracy = double(right) / truth.size();
    RecordProperty("surface_accuracy_" + rule, std::to_string(accuracy));
    EXPECT_GE(accuracy, 0.95) << rule;
    // Both classes are recovered, not just the majority one.
    EXPECT_GE(double(per_class_right[1]) / per_class_total[1], 0.9) << rule;
    EXPECT_GE(double(per_class_right[0]) / per_class_total[0], 0.9) << rule;
  }
}

TEST(ScanIntegration, SceneInTheNegativeOctantIsMappedAlike) {
  // The same scene shifted by a whole number of voxels into negative coordinates.
  SyntheticScene scene;
  const octomap::point3d shift(-100.0f, -50.0f, -3.0f);
  const SyntheticScan here = scene.defaultScan();
  SyntheticScan there = here;
  there.origin_W = here.origin_W + shift;
  there.points_W = octomap::Pointcloud();
  for (size_t i = 0; i < here.points_W.size(); ++i)
    there.points_W.push_back(here.points_W.getPoint(i) + shift);
  SemanticConfig config;
  config.ds_multiplier = 0.0;  // a down-sampling grid need not align with the shift
  EvidentialOcTree a(0.2, scene.num_classes, config), b(0.2, scene.num_classes, config);
  a.insertSemanticScan(here.points_W, here.evidence, here.origin_W);
  b.insertSemanticScan(there.points_W, there.evidence, there.origin_W);
  // Pruned blocks are aligned to the key grid, so compare full-depth leaves. Float rounding
  // of shifted coordinates may move a ray across a voxel boundary here and there.
  a.expand();
  b.expand();
  EXPECT_NEAR(double(a.getNumLeafNodes()), double(b.getNumLeafNodes()), 0.01 * a.getNumLeafNodes());
  size_t same_label = 0, total = 0;
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    if (!it->hasSemantics()) continue;
    ++total;
    const VoxelOpinion va = a.opinion(&*it);
    const VoxelOpinion vb = b.query(it.getCoordinate() + shift);
    if (va.label == vb.label) ++same_label;
  }
  ASSERT_GT(total, 100u);
  EXPECT_GE(double(same_label) / total, 0.99);
}

TEST_F(SyntheticSceneTest, UncertaintyFallsWithRepeatedConsistentScans) {
  // Dempster's rule itself (no evidence cap on the read-out): every consistent scan lowers u.
  const auto truth = groundTruthVoxels(key_helper, scan, scene.num_classes);
  SemanticConfig uncapped;
  uncapped.evidence_cap = 0.0;
  EvidentialOcTree once(0.2, scene.num_classes, uncapped), five(0.2, scene.num_classes, uncapped);
  once.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  for (int i = 0; i < 5; ++i) five.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  size_t strictly_lower = 0, comparable = 0;
  for (const auto& [key, label] : truth) {
    const float u1 = once.query(keyOf(key)).uncertainty;
    const float u5 = five.query(keyOf(key)).uncertainty;
    ASSERT_LT(u1, 1.0f);
    ASSERT_LE(u5, u1);
    if (u1 > 1e-30f) {
      ++comparable;
      if (u5 < u1) ++strictly_lower;
    }
  }
  ASSERT_GT(comparable, truth.size() / 2);
  EXPECT_EQ(strictly_lower, comparable);
}

TEST_F(SyntheticSceneTest, EbsVarianceFallsWithRepeatedConsistentScans) {
  const auto truth = groundTruthVoxels(key_helper, scan, scene.num_classes);
  SemanticConfig config;
  config.rule = "ebs";
  EvidentialOcTree once(0.2, scene.num_classes, config), five(0.2, scene.num_classes, config);
  once.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  for (int i = 0; i < 5; ++i) five.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  // Dirichlet variance p(1-p)/(S+1): S grows with every scan while p stays near its value.
  double sum1 = 0, sum5 = 0;
  size_t lower = 0;
  for (const auto& [key, label] : truth) {
    const float u1 = once.query(keyOf(key)).uncertainty;
    const float u5 = five.query(keyOf(key)).uncertainty;
    sum1 += u1;
    sum5 += u5;
    if (u5 < u1) ++lower;
  }
  EXPECT_LT(sum5, sum1);
  EXPECT_GE(double(lower) / truth.size(), 0.95);
}

// --- bad inputs leave the map unchanged -----------------------------------------------------

class BadInputTest : public SyntheticSceneTest {
 protected:
  void SetUp() override {
    tree = std::make_unique<EvidentialOcTree>(0.2, scene.num_classes);
    tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    before = std::make_unique<EvidentialOcTree>(*tree);
    ASSERT_TRUE(compareTrees(*tree, *before));
    // A second scan from elsewhere that would change the map if it were applied.
    other = scene.scan(octomap::point3d(1.05f, -0.5f, 1.7f), 99);
  }
  void expectUnchanged() {
    EXPECT_TRUE(compareTrees(*tree, *before));
    const octomap::OcTreeKey key = tree->coordToKey(other.points_W.getPoint(0));
    EXPECT_TRUE(observe(*tree, key) == observe(*before, key));
  }
  std::unique_ptr<EvidentialOcTree> tree, before;
  SyntheticScan other;
};

TEST_F(BadInputTest, NaNEvidenceThrowsAndChangesNothing) {
  other.evidence[other.evidence.size() / 2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, other.evidence, other.origin_W),
               std::invalid_argument);
  expectUnchanged();
}

TEST_F(BadInputTest, InfiniteEvidenceThrowsAndChangesNothing) {
  other.evidence.back() = std::numeric_limits<float>::infinity();
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, other.evidence, other.origin_W),
               std::invalid_argument);
  expectUnchanged();
}

TEST_F(BadInputTest, NegativeEvidenceThrowsAndChangesNothing) {
  other.evidence[5] = -0.01f;
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, other.evidence, other.origin_W),
               std::invalid_argument);
  expectUnchanged();
}

TEST_F(BadInputTest, EvidenceOfWrongSizeThrowsAndChangesNothing) {
  std::vector<float> short_evidence(other.evidence.begin(), other.evidence.end() - 1);
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, short_evidence, other.origin_W),
               std::invalid_argument);
  std::vector<float> long_evidence = other.evidence;
  long_evidence.insert(long_evidence.end(), {1.0f, 1.0f, 1.0f});
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, long_evidence, other.origin_W),
               std::invalid_argument);
  // Evidence for C = 2 handed to a C = 3 map.
  std::vector<float> two_classes(other.points_W.size() * 2, 1.0f);
  EXPECT_THROW(tree->insertSemanticScan(other.points_W, two_classes, other.origin_W),
               std::invalid_argument);
  expectUnchanged();
}

TEST_F(BadInputTest, EmptyScanIsFineAndChangesNothing) {
  InsertStats stats;
  EXPECT_NO_THROW(stats = tree->insertSemanticScan(octomap::Pointcloud(), {}, other.origin_W));
  EXPECT_EQ(stats.points_in, 0u);
  EXPECT_EQ(stats.voxels_updated, 0u);
  expectUnchanged();
  EvidentialOcTree empty(0.2, 4);
  EXPECT_NO_THROW(empty.insertSemanticScan(octomap::Pointcloud(), {}, octomap::point3d(0, 0, 0)));
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_EQ(empty.numSemanticNodes(), 0u);
}

TEST(ScanIntegration, PointsOutsideKeyRangeAreSkippedAndCounted) {
  // At 0.2 m the key range covers about +-6553 m.
  EvidentialOcTree tree(0.2, 2);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  points.push_back(2.1f, 0.1f, 0.1f);
  evidence.insert(evidence.end(), {5.0f, 0.0f});
  points.push_back(1e5f, 0.0f, 0.0f);
  evidence.insert(evidence.end(), {5.0f, 0.0f});
  points.push_back(0.0f, -2e4f, 0.0f);
  evidence.insert(evidence.end(), {5.0f, 0.0f});
  points.push_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  evidence.insert(evidence.end(), {5.0f, 0.0f});
  points.push_back(0.0f, 0.0f, std::numeric_limits<float>::infinity());
  evidence.insert(evidence.end(), {5.0f, 0.0f});
  points.push_back(-1.9f, 0.3f, 0.1f);
  evidence.insert(evidence.end(), {0.0f, 5.0f});
  InsertStats stats;
  ASSERT_NO_THROW(
      stats = tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f)));
  EXPECT_EQ(stats.points_in, 6u);
  EXPECT_EQ(stats.points_skipped, 4u);
  // The two good points were inserted.
  EXPECT_TRUE(tree.isNodeOccupied(tree.search(octomap::point3d(2.1f, 0.1f, 0.1f))));
  EXPECT_EQ(tree.query(octomap::point3d(2.1f, 0.1f, 0.1f)).label, 0);
  EXPECT_TRUE(tree.isNodeOccupied(tree.search(octomap::point3d(-1.9f, 0.3f, 0.1f))));
  EXPECT_EQ(tree.query(octomap::point3d(-1.9f, 0.3f, 0.1f)).label, 1);
}

TEST(ScanIntegration, KernelDoesNotWrapAroundTheKeyRange) {
  // A point in the last voxel of the key range: its kernel support must not reach voxels on
  // the far side of the map through key wrap-around (key 65535 + 1 == 0).
  EvidentialOcTree tree(0.2, 2);
  const octomap::OcTreeKey edge(65535, 32768, 32768);
  const octomap::point3d p = tree.keyToCoord(edge);
  octomap::Pointcloud points;
  points.push_back(p);
  const std::vector<float> evidence{20.0f, 0.0f};  // certain point: long support (> 0.5 m)
  const octomap::point3d origin = p - octomap::point3d(2.0f, 0.0f, 0.0f);
  tree.insertSemanticScan(points, evidence, origin);
  ASSERT_EQ(tree.query(edge).label, 0);
  const double half_range = 32768 * 0.2;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!it->hasSemantics()) continue;
    EXPECT_GT(it.getX(), half_range - 10.0)
        << "semantic leaf at " << it.getCoordinate() << " far from the point at " << p;
  }
}

TEST(ScanIntegration, PoseOverloadEqualsWorldFrameInsertion) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  const octomap::pose6d T_W_S(2.0, -1.0, 0.5, 0.1, -0.05, 0.7);  // x y z roll pitch yaw
  // The scan's points relative to its origin, expressed in a sensor frame S.
  octomap::Pointcloud points_S;
  const octomap::pose6d T_S_W = T_W_S.inv();
  for (size_t i = 0; i < scan.points_W.size(); ++i) {
    points_S.push_back(T_S_W.transform(scan.points_W.getPoint(i)));
  }
  octomap::Pointcloud points_W;
  for (size_t i = 0; i < points_S.size(); ++i)
    points_W.push_back(T_W_S.transform(points_S.getPoint(i)));
  EvidentialOcTree by_pose(0.2, scene.num_classes), by_points(0.2, scene.num_classes);
  by_pose.insertSemanticScan(points_S, scan.evidence, T_W_S);
  by_points.insertSemanticScan(points_W, scan.evidence, T_W_S.trans());
  EXPECT_TRUE(compareTrees(by_pose, by_points));
  EXPECT_GT(by_pose.numSemanticNodes(), 0u);
}

// The integrator keeps its scratch buffers from scan to scan, but not what one dense scan grew
// them to once sparse scans follow; and what it keeps never changes the map: the same scans
// each through a fresh integrator (setConfig drops it) give the same map, bit for bit.
TEST(ScanIntegration, KeptScratchIsBoundedAndNeverChangesTheMap) {
  SyntheticScene dense, sparse;
  dense.azimuth_step_deg = dense.elevation_step_deg = 0.15;
  sparse.azimuth_step_deg = sparse.elevation_step_deg = 2.0;
  const SyntheticScan scans[] = {dense.defaultScan(1), sparse.defaultScan(2), dense.defaultScan(3),
                                 sparse.defaultScan(4)};
  SemanticConfig config;
  config.threads = 2;
  EvidentialOcTree kept(0.2, dense.num_classes, config), fresh(0.2, dense.num_classes, config);
  EXPECT_EQ(kept.scratchBytes(), 0u);
  std::vector<size_t> bytes;
  for (const SyntheticScan& scan : scans) {
    kept.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    fresh.setConfig(config);  // drops the integrator: this scan starts from empty scratch
    ASSERT_EQ(fresh.scratchBytes(), 0u);
    fresh.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    bytes.push_back(kept.scratchBytes());
  }
  ASSERT_GT(scans[0].points_W.size(), 40 * scans[1].points_W.size());
  EXPECT_GT(bytes[0], size_t(8) << 20);  // the dense scan needs its buffers
  // After a sparse scan only the fixed per-thread index (1 MiB + mask) and small buffers stay.
  EXPECT_LT(bytes[1], bytes[0] / 2);
  EXPECT_LT(bytes[3], bytes[2] / 2);
  EXPECT_TRUE(compareTrees(kept, fresh));
}

TEST(ScanIntegration, OneAndTwoThreadsGiveTheSameLabels) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  SemanticConfig one, two;
  one.threads = 1;
  two.threads = 2;
  EvidentialOcTree a(0.2, scene.num_classes, one), b(0.2, scene.num_classes, two);
  a.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  b.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.numSemanticNodes(), b.numSemanticNodes());
  // Summation order across threads may differ in the last bits; labels and occupancy may not.
  for (auto it = a.begin_leafs(); it != a.end_leafs(); ++it) {
    const EvidentialOcTreeNode* nb = b.search(it.getKey(), it.getDepth());
    ASSERT_NE(nb, nullptr);
    EXPECT_EQ(it->getLogOdds(), nb->getLogOdds());
    const VoxelOpinion va = a.opinion(&*it), vb = b.opinion(nb);
    EXPECT_NEAR(va.uncertainty, vb.uncertainty, 1e-5);
    for (int c = 0; c < scene.num_classes; ++c) EXPECT_NEAR(va.belief[c], vb.belief[c], 1e-5);
  }
}

// The kernel computes rows only for voxels the map keeps (existing leaves, pruned blocks whole,
// and this scan's ray voxels). With an `unobserved` map every row is computed and the map's
// share of them must be the same, bit for bit; the unobserved map shows rows were skipped.
TEST(ScanIntegration, RowsOnlyForKeptVoxelsGiveTheSameMapBitForBit) {
  SyntheticScene scene;
  SemanticConfig config;
  config.threads = 2;
  EvidentialOcTree masked(0.2, scene.num_classes, config),
      everywhere(0.2, scene.num_classes, config), unobserved(0.2, scene.num_classes, config);
  const octomap::point3d origins[] = {{0.05f, 0.1f, 1.7f},
                                      {0.05f, 0.1f, 1.7f},
                                      {0.05f, 0.1f, 1.7f},
                                      {1.05f, 0.9f, 1.7f},
                                      {-2.95f, -0.7f, 1.3f}};
  bool saw_pruned_block = false;
  for (unsigned i = 0; i < 5; ++i) {
    const SyntheticScan s = scene.scan(origins[i], i + 1);
    for (auto it = masked.begin_leafs(); it != masked.end_leafs(); ++it) {
      saw_pruned_block |= it.getDepth() < masked.getTreeDepth();
    }
    masked.insertSemanticScan(s.points_W, s.evidence, s.origin_W);
    everywhere.insertSemanticScan(s.points_W, s.evidence, s.origin_W, &unobserved);
  }
  EXPECT_TRUE(saw_pruned_block) << "the scene should exercise rows inside pruned blocks";
  EXPECT_GT(unobserved.numSemanticNodes(), 0u);
  EXPECT_GT(masked.numSemanticNodes(), 0u);
  EXPECT_TRUE(compareTrees(masked, everywhere));
}

// evidence_floor: the map equals the map of the same scan whose values below the floor were
// set to 0 before insertion, and differs from the map without the floor (the synthetic scene
// gives every class U(0, 0.6) of noise evidence, so a floor of 0.3 drops about half of them).
TEST(ScanIntegration, EvidenceFloorEqualsZeroingTheSmallValuesBeforeInsertion) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  const float floor = 0.3f;
  std::vector<float> zeroed = scan.evidence;
  size_t dropped = 0;
  for (float& e : zeroed) {
    if (e < floor) {
      dropped += e > 0.0f;
      e = 0.0f;
    }
  }
  ASSERT_GT(dropped, scan.evidence.size() / 4);
  SemanticConfig with_floor, without;
  with_floor.threads = without.threads = 1;
  with_floor.evidence_floor = floor;
  EvidentialOcTree floored(0.2, scene.num_classes, with_floor),
      zeroed_first(0.2, scene.num_classes, without), plain(0.2, scene.num_classes, without);
  floored.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  zeroed_first.insertSemanticScan(scan.points_W, zeroed, scan.origin_W);
  plain.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  EXPECT_TRUE(compareTrees(floored, zeroed_first));
  EXPECT_FALSE(compareTrees(floored, plain));
}

// semantic_occupied_only: into an empty map, exactly the end voxels get evidence, each the same
// evidence as in the default map (a voxel's rows do not depend on which other voxels get rows);
// a second scan adds evidence only to voxels occupied before it or holding its end points.
TEST(ScanIntegration, SemanticOccupiedOnlyGivesEvidenceToOccupiedAndEndVoxelsOnly) {
  SyntheticScene scene;
  SemanticConfig all, occupied;
  occupied.semantic_occupied_only = true;
  EvidentialOcTree a(0.2, scene.num_classes, all), b(0.2, scene.num_classes, occupied);
  const SyntheticScan first = scene.defaultScan(1);
  a.insertSemanticScan(first.points_W, first.evidence, first.origin_W);
  b.insertSemanticScan(first.points_W, first.evidence, first.origin_W);
  std::set<KeyTuple> ends;
  for (size_t i = 0; i < first.points_W.size(); ++i)
    ends.insert(tupleOf(b.coordToKey(first.points_W.getPoint(i))));
  std::set<KeyTuple> with_evidence;
  for (auto it = b.begin_leafs(); it != b.end_leafs(); ++it) {
    if (!it->hasSemantics()) continue;
    ASSERT_EQ(it.getDepth(), b.getTreeDepth());
    with_evidence.insert(tupleOf(it.getKey()));
    const std::vector<float> pa = a.payload(a.search(it.getKey()));
    const std::vector<float> pb = b.payload(&*it);
    ASSERT_FALSE(pa.empty());
    for (int c = 0; c < scene.num_classes; ++c) EXPECT_EQ(pa[c], pb[c]);
  }
  EXPECT_TRUE(with_evidence == ends)
      << with_evidence.size() << " voxels with evidence, " << ends.size() << " end voxels";
  EXPECT_GT(a.numSemanticNodes(), 2 * b.numSemanticNodes());  // free space near surfaces
  // Second scan from elsewhere: new evidence only where occupied before or an end voxel now.
  std::map<KeyTuple, std::vector<float>> before;
  std::set<KeyTuple> occupied_before;
  EvidentialOcTree expanded(b);  // pruned blocks as their voxels
  expanded.expand();
  for (auto it = expanded.begin_leafs(); it != expanded.end_leafs(); ++it) {
    if (expanded.isNodeOccupied(*it)) occupied_before.insert(tupleOf(it.getKey()));
    if (it->hasSemantics()) {
      before[tupleOf(it.getKey())] = expanded.payload(&*it);
    }
  }
  const SyntheticScan second = scene.scan(octomap::point3d(1.05f, 0.9f, 1.7f), 2);
  b.insertSemanticScan(second.points_W, second.evidence, second.origin_W);
  std::set<KeyTuple> second_ends;
  for (size_t i = 0; i < second.points_W.size(); ++i)
    second_ends.insert(tupleOf(b.coordToKey(second.points_W.getPoint(i))));
  b.expand();
  size_t changed = 0;
  for (auto it = b.begin_leafs(); it != b.end_leafs(); ++it) {
    if (!it->hasSemantics()) continue;
    const KeyTuple key = tupleOf(it.getKey());
    const std::vector<float> p = b.payload(&*it);
    const auto old = before.find(key);
    if (old != before.end() && p == old->second) continue;
    ++changed;
    EXPECT_TRUE(occupied_before.count(key) || second_ends.count(key));
  }
  EXPECT_GT(changed, 100u);
}

// --- leaf creation by the kernel --------------------------------------------------------------

std::set<KeyTuple> fullDepthLeafKeys(octomap::OcTree& tree) {
  tree.expand();
  std::set<KeyTuple> keys;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
    keys.insert(tupleOf(it.getKey()));
  return keys;
}

std::set<KeyTuple> fullDepthLeafKeys(EvidentialOcTree& tree) {
  tree.expand();
  std::set<KeyTuple> keys;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    EXPECT_EQ(it.getDepth(), tree.getTreeDepth());
    keys.insert(tupleOf(it.getKey()));
  }
  return keys;
}

TEST(KernelLeafCreation, OffTouchesOnlyRayCastLeaves) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  octomap::OcTree plain(0.2);
  plain.insertPointCloud(scan.points_W, scan.origin_W, -1.0, false, true);
  SemanticConfig config;
  config.kernel_creates_leaves = false;
  EvidentialOcTree tree(0.2, scene.num_classes, config);
  tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  EXPECT_GT(tree.numSemanticNodes(), 0u);
  const auto expected = fullDepthLeafKeys(plain);
  const auto got = fullDepthLeafKeys(tree);
  EXPECT_EQ(got.size(), expected.size());
  EXPECT_TRUE(got == expected) << "leaf sets differ from plain OcTree::insertPointCloud";
  // Same occupancy, voxel by voxel.
  size_t mismatches = 0;
  for (const auto& key : expected) {
    const octomap::OcTreeNode* a = plain.search(keyOf(key));
    const EvidentialOcTreeNode* b = tree.search(keyOf(key));
    if (!a || !b || a->getLogOdds() != b->getLogOdds()) ++mismatches;
  }
  EXPECT_EQ(mismatches, 0u);
}

TEST(KernelLeafCreation, OnAddsLeavesAroundSurfacesAtUnknownOccupancy) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  octomap::OcTree plain(0.2);
  plain.insertPointCloud(scan.points_W, scan.origin_W, -1.0, false, true);
  SemanticConfig config;
  config.kernel_creates_leaves = true;
  EvidentialOcTree tree(0.2, scene.num_classes, config);
  tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  const auto ray_cast = fullDepthLeafKeys(plain);
  const auto got = fullDepthLeafKeys(tree);
  EXPECT_TRUE(std::includes(got.begin(), got.end(), ray_cast.begin(), ray_cast.end()));
  EXPECT_GT(got.size(), ray_cast.size());
  for (const auto& key : got) {
    if (ray_cast.count(key)) continue;
    const EvidentialOcTreeNode* node = tree.search(keyOf(key));
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(node->getLogOdds(), 0.0f);  // created by the kernel: p = 0.5
    EXPECT_TRUE(node->hasSemantics());
  }
}

TEST(KernelLeafCreation, OccupancyEqualsPlainOcTreeOverSeveralScans) {
  // Kernel-created leaves start at log-odds 0, which is where OctoMap starts an unknown voxel,
  // so every voxel a plain OcTree knows has the same log-odds here, with or without creation.
  SyntheticScene scene;
  for (bool create : {false, true}) {
    octomap::OcTree plain(0.2);
    SemanticConfig config;
    config.kernel_creates_leaves = create;
    EvidentialOcTree tree(0.2, scene.num_classes, config);
    for (int i = 0; i < 4; ++i) {
      const SyntheticScan scan =
          scene.scan(octomap::point3d(0.05f + 0.6f * i, -0.3f + 0.2f * i, 1.7f), 40 + i);
      plain.insertPointCloud(scan.points_W, scan.origin_W, -1.0, false, true);
      tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    }
    const auto keys = fullDepthLeafKeys(plain);
    fullDepthLeafKeys(tree);  // expands
    size_t mismatches = 0;
    for (const auto& key : keys) {
      const EvidentialOcTreeNode* node = tree.search(keyOf(key));
      if (!node || node->getLogOdds() != plain.search(keyOf(key))->getLogOdds()) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0u) << "kernel_creates_leaves = " << create << " of " << keys.size();
  }
}

TEST(KernelLeafCreation, OccupancyEqualsPlainOcTreeWithoutDiscretizationAndWithMaxRange) {
  SyntheticScene scene;
  for (double max_range : {-1.0, 6.0}) {
    octomap::OcTree plain(0.2);
    SemanticConfig config;
    config.discretize = false;
    config.max_range = max_range;
    config.kernel_creates_leaves = false;
    EvidentialOcTree tree(0.2, scene.num_classes, config);
    for (int i = 0; i < 2; ++i) {
      const SyntheticScan scan = scene.scan(octomap::point3d(0.05f + 0.8f * i, 0.1f, 1.7f), 60 + i);
      plain.insertPointCloud(scan.points_W, scan.origin_W, max_range, false, false);
      tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    }
    const auto expected = fullDepthLeafKeys(plain);
    const auto got = fullDepthLeafKeys(tree);
    EXPECT_TRUE(got == expected) << "max_range " << max_range << ": " << got.size() << " leaves vs "
                                 << expected.size();
    size_t mismatches = 0;
    for (const auto& key : expected) {
      const EvidentialOcTreeNode* node = tree.search(keyOf(key));
      if (!node || node->getLogOdds() != plain.search(keyOf(key))->getLogOdds()) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0u) << "max_range " << max_range;
  }
}

TEST(KernelLeafCreation, VoxelsUpdatedCountsTheSemanticLeaves) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  EvidentialOcTree tree(0.2, scene.num_classes);
  const InsertStats stats = tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  tree.expand();
  size_t semantic_leaves = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
    semantic_leaves += it->hasSemantics();
  EXPECT_EQ(stats.voxels_updated, semantic_leaves);
}

// --- kernel settings as seen through the integrator ---------------------------------------------

// Evidence reaching the voxel `offset_cells` voxels above a single point at a voxel centre.
VoxelOpinion neighbourAfterOnePoint(const SemanticConfig& config,
                                    const std::vector<float>& evidence, int offset_cells) {
  // The neighbours are unknown space: let the kernel create them so its reach is visible.
  SemanticConfig densify = config;
  densify.kernel_creates_leaves = true;
  EvidentialOcTree tree(0.2, static_cast<int>(evidence.size()), densify);
  const octomap::OcTreeKey key = tree.coordToKey(octomap::point3d(0.1f, 0.1f, 0.1f));
  octomap::Pointcloud points;
  points.push_back(tree.keyToCoord(key));
  tree.insertSemanticScan(points, evidence, octomap::point3d(-2.9f, 0.1f, 0.1f));
  return tree.query(octomap::OcTreeKey(key[0], key[1], key[2] + offset_cells));
}

// With kernel_distance "voxel" (the default) the point, at its voxel's centre, is
// 0.2 n - 0.1 m from the cube n voxels above.
TEST(KernelSettings, UncertainPointsHaveShortSupportUnlessReferenceCompat) {
  // e = (0.2, 0, 0): u = 3 / 3.2. Adaptive: L = 0.3 e^{1 - 3 u} ~ 0.049 m, no neighbour.
  // reference_compat (gamma = 0): L = 0.3 e ~ 0.815 m: 0.5 m (3 above) in, 0.9 m (5 above) out.
  const std::vector<float> weak{0.2f, 0.0f, 0.0f};
  SemanticConfig adaptive, compat;
  adaptive.adaptive_length = true;
  adaptive.uncertainty_threshold = compat.uncertainty_threshold = false;
  adaptive.ds_multiplier = compat.ds_multiplier = 0.0;
  compat.reference_compat = true;
  EXPECT_EQ(compat.effectiveGamma(), 0.0);
  EXPECT_EQ(compat.effectiveDownsampling(), "count_cap");
  EXPECT_EQ(neighbourAfterOnePoint(adaptive, weak, 1).label, -1);
  EXPECT_EQ(neighbourAfterOnePoint(compat, weak, 3).label, 0);
  EXPECT_EQ(neighbourAfterOnePoint(compat, weak, 5).label, -1);
}

TEST(KernelSettings, NoAdaptiveLengthIsThePapersGammaZero) {
  // adaptive_length = false is the paper's gamma = 0: L = l beta e = 0.815 m for every point,
  // certain or not: 0.7 m (4 above) in, 0.9 m (5 above) out.
  SemanticConfig fixed;
  fixed.adaptive_length = false;
  fixed.uncertainty_threshold = false;
  fixed.ds_multiplier = 0.0;
  EXPECT_EQ(fixed.effectiveGamma(), 0.0);
  const std::vector<float> certain{50.0f, 0.0f, 0.0f}, weak{0.2f, 0.0f, 0.0f};
  EXPECT_EQ(neighbourAfterOnePoint(fixed, certain, 4).label, 0);
  EXPECT_EQ(neighbourAfterOnePoint(fixed, weak, 4).label, 0);
  EXPECT_EQ(neighbourAfterOnePoint(fixed, certain, 5).label, -1);
  // Adaptive: the certain point reaches 0.3 e^{1 - 9/53} ~ 0.688 m: 0.5 m in, 0.7 m out.
  SemanticConfig adaptive = fixed;
  adaptive.adaptive_length = true;
  EXPECT_EQ(neighbourAfterOnePoint(adaptive, certain, 3).label, 0);
  EXPECT_EQ(neighbourAfterOnePoint(adaptive, certain, 4).label, -1);
}

TEST(KernelSettings, SbkiUsesThePlainKernelOnTheArgmax) {
  // S-BKI: alpha[argmax] += k'(d, l, sigma0) with the fixed length l = 0.3 m.
  SemanticConfig sbki;
  sbki.rule = "sbki";
  sbki.ds_multiplier = 0.0;
  const std::vector<float> e{0.0f, 0.3f, 0.1f};  // uncertain, argmax 1
  const VoxelOpinion above = neighbourAfterOnePoint(sbki, e, 1);
  // d = 0.1 m to the cube above:
  // k'(0.1, 0.3, sigma0) = sigma0 [(2 + cos(2 pi / 3))/3 (2/3) + sin(2 pi / 3) / (2 pi)]
  const double pi = 3.14159265358979323846;
  const double k =
      sbki.sigma0 * ((2 + std::cos(2 * pi / 3)) / 3 * 2 / 3 + std::sin(2 * pi / 3) / (2 * pi));
  const double prior = sbki.sbki_prior;
  const double s = 3 * prior + k;
  EXPECT_EQ(above.label, 1);
  EXPECT_NEAR(above.belief[1], (prior + k) / s, 1e-5);
  EXPECT_NEAR(above.belief[0], prior / s, 1e-5);
}

TEST(KernelSettings, SbkiCountsScaleWithSigma0AboveOne) {
  // The kernel is not clamped for the Dirichlet rules: sigma0 = 3 adds 3 k' to the count.
  SemanticConfig sbki;
  sbki.rule = "sbki";
  sbki.ds_multiplier = 0.0;
  sbki.sigma0 = 3.0;
  const std::vector<float> e{0.0f, 0.3f, 0.1f};
  const VoxelOpinion above = neighbourAfterOnePoint(sbki, e, 1);
  const double pi = 3.14159265358979323846;
  const double k = 3.0 * ((2 + std::cos(2 * pi / 3)) / 3 * 2 / 3 + std::sin(2 * pi / 3) / (2 * pi));
  ASSERT_GT(k, 1.0);
  const double prior = sbki.sbki_prior;
  EXPECT_NEAR(above.belief[1], (prior + k) / (3 * prior + k), 1e-5);
}

TEST(KernelSettings, PointAlwaysReachesItsOwnVoxel) {
  // A weak point (u = 3 / 3.2, L ~ 0.049 m) near the corner of its voxel [0, 0.2]^3: 0.156 m
  // from the centre. Measured to the voxel's cube it is inside (d = 0, k = sigma0), so the voxel
  // holds the point's opinion discounted by sigma0; measured to the centre it gets nothing.
  const std::vector<float> weak{0.2f, 0.0f, 0.0f};
  octomap::Pointcloud points;
  points.push_back(0.01f, 0.01f, 0.01f);
  SemanticConfig voxel, centre;
  voxel.adaptive_length = centre.adaptive_length = true;  // the short support of a weak point
  voxel.ds_multiplier = centre.ds_multiplier = 0.0;
  voxel.uncertainty_threshold = centre.uncertainty_threshold = false;
  centre.kernel_distance = "centre";
  EvidentialOcTree by_voxel(0.2, 3, voxel), by_centre(0.2, 3, centre);
  by_voxel.insertSemanticScan(points, weak, octomap::point3d(-2.9f, 0.1f, 0.1f));
  by_centre.insertSemanticScan(points, weak, octomap::point3d(-2.9f, 0.1f, 0.1f));
  const VoxelOpinion own = by_voxel.query(octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_EQ(own.label, 0);
  EXPECT_NEAR(own.belief[0], voxel.sigma0 * 0.2 / 3.2, 1e-6);  // k b, b = e / S
  EXPECT_NEAR(own.uncertainty, 1.0 - voxel.sigma0 * (1.0 - 3.0 / 3.2), 1e-6);  // 1 - k (1 - u)
  EXPECT_EQ(by_centre.query(octomap::point3d(0.1f, 0.1f, 0.1f)).label, -1);
}

TEST(ScanIntegration, DownSamplingMergesPointsOfOneCell) {
  // ds_multiplier 5 at 0.2 m: a 0.04 m grid. Ten points inside one cell are one semantic point.
  SemanticConfig config;
  config.downsampling = "average";
  EvidentialOcTree tree(0.2, 2, config);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 10; ++i) {
    points.push_back(2.105f + 0.001f * i, 0.105f, 0.105f);
    evidence.insert(evidence.end(), {3.0f, 1.0f});
  }
  points.push_back(-2.1f, 0.1f, 0.1f);
  evidence.insert(evidence.end(), {1.0f, 3.0f});
  const InsertStats stats =
      tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_EQ(stats.semantic_points, 2u);
  EXPECT_EQ(tree.query(octomap::point3d(2.1f, 0.1f, 0.1f)).label, 0);
  EXPECT_EQ(tree.query(octomap::point3d(-2.1f, 0.1f, 0.1f)).label, 1);
  SemanticConfig none = config;
  none.ds_multiplier = 0.0;
  EvidentialOcTree all(0.2, 2, none);
  EXPECT_EQ(
      all.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f)).semantic_points,
      11u);
}

TEST(ScanIntegration, CountCapKeepsDsMultiplierPlusOnePointsPerBlock) {
  // count_cap, ds_multiplier 5: at most 6 points per block of 2 x 2 x 2 voxels (0.4 m at 0.2 m).
  // Ten points in the block [2.0, 2.4) x [0, 0.4) x [0, 0.4), three in the next block up.
  SemanticConfig config;
  config.downsampling = "count_cap";
  config.uncertainty_threshold = false;
  EvidentialOcTree tree(0.2, 2, config);
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (int i = 0; i < 10; ++i) {
    points.push_back(2.05f + 0.03f * i, 0.1f, 0.1f);
    evidence.insert(evidence.end(), {3.0f, 1.0f});
  }
  for (int i = 0; i < 3; ++i) {
    points.push_back(2.1f, 0.1f, 0.45f + 0.1f * i);
    evidence.insert(evidence.end(), {1.0f, 3.0f});
  }
  const InsertStats stats =
      tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_EQ(stats.semantic_points, 6u + 3u);
  // The first six of the row were kept: the voxel of the 7th to 10th (x in [2.2, 2.4)) holds
  // only kernel evidence from its neighbours, the voxel of the first ones their own.
  SemanticConfig average = config;
  average.downsampling = "average";
  average.ds_multiplier = 0.0;
  EvidentialOcTree all(0.2, 2, average);
  EXPECT_EQ(
      all.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f)).semantic_points,
      13u);
  // ds_multiplier <= 0 switches the cap off too.
  SemanticConfig off = config;
  off.ds_multiplier = 0.0;
  EvidentialOcTree uncapped(0.2, 2, off);
  EXPECT_EQ(uncapped.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f))
                .semantic_points,
            13u);
}

TEST(ScanIntegration, HugeEvidenceInOneCellStaysFiniteAndLoadable) {
  // Issue 16 item 1: two points with evidence 3e38 (finite floats) in one down-sampling cell.
  // A float sum overflows to inf, the voxel's payload becomes NaN, reads as "no label" and the
  // saved file cannot be loaded. Summed in double, the mean is 3e38 and the voxel is class 0.
  for (const std::string mode : {"average", "count_cap"}) {
    SemanticConfig config;
    config.downsampling = mode;
    config.uncertainty_threshold = false;
    EvidentialOcTree tree(0.2, 3, config);
    octomap::Pointcloud points;
    points.push_back(2.101f, 1.001f, 0.501f);
    points.push_back(2.102f, 1.002f, 0.502f);  // same 0.04 m cell
    const std::vector<float> evidence{3e38f, 0.0f, 0.0f, 3e38f, 0.0f, 0.0f};
    tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.5f));
    const EvidentialOcTreeNode* node = tree.search(octomap::point3d(2.1f, 1.0f, 0.5f));
    ASSERT_NE(node, nullptr);
    const std::vector<float> payload = tree.payload(node);
    ASSERT_FALSE(payload.empty()) << mode;
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(payload[c])) << mode << " class " << c;
    EXPECT_EQ(tree.query(octomap::point3d(2.1f, 1.0f, 0.5f)).label, 0) << mode;
    const std::string path =
        ::testing::TempDir() + "/huge_evidence_" + mode + "_" + std::to_string(::getpid()) + ".ot";
    saveMap(tree, path);
    const auto loaded = loadMap(path);
    EXPECT_EQ(loaded->query(octomap::point3d(2.1f, 1.0f, 0.5f)).label, 0) << mode;
    std::remove(path.c_str());
  }
}

TEST(ScanIntegration, InvalidOriginThrowsAndChangesNothing) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  EvidentialOcTree tree(0.2, scene.num_classes);
  tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
  const EvidentialOcTree before(tree);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(tree.insertSemanticScan(scan.points_W, scan.evidence, octomap::point3d(nan, 0, 0)),
               std::invalid_argument);
  EXPECT_THROW(tree.insertSemanticScan(scan.points_W, scan.evidence, octomap::point3d(1e6f, 0, 0)),
               std::invalid_argument);
  EXPECT_TRUE(compareTrees(tree, before));
  // Queries at non-finite points are answered, not crashed on.
  EXPECT_EQ(tree.query(octomap::point3d(nan, 0, 0)).label, -1);
}

// --- the percentile threshold -------------------------------------------------------------------

TEST(PercentileThreshold, DropsTheMostUncertainPsiPercent) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  const int num_classes = scene.num_classes;
  for (double psi : {10.0, 30.0}) {
    SemanticConfig config;
    config.uncertainty_threshold = true;
    config.ds_multiplier = 0.0;  // every point takes part in the semantic pass
    config.drop_percent = psi;
    EvidentialOcTree tree(0.2, num_classes, config);
    const InsertStats stats = tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    const size_t n = scan.points_W.size();
    // The threshold acts on the scan's points first; the kept ones take part in the kernel pass.
    ASSERT_EQ(stats.semantic_points + stats.points_dropped_uncertain, n);
    // u_i = C / (sum e + C), computed here from the evidence.
    std::vector<double> u(n);
    for (size_t i = 0; i < n; ++i) {
      double s = num_classes;
      for (int c = 0; c < num_classes; ++c) s += scan.evidence[i * num_classes + c];
      u[i] = num_classes / s;
    }
    const size_t above = std::count_if(
        u.begin(), u.end(), [&](double x) { return float(x) > stats.uncertainty_threshold; });
    const size_t expected = static_cast<size_t>(std::floor(n * psi / 100.0));
    // The fixture has no tie at the threshold, so exactly floor(n psi / 100) points go.
    std::vector<float> uf(u.begin(), u.end());
    std::sort(uf.begin(), uf.end());
    ASSERT_LT(uf[n - expected - 1], uf[n - expected]) << "tie at the percentile";
    EXPECT_EQ(stats.points_dropped_uncertain, expected) << "psi " << psi;
    // U_thr as reported: what lies above it is what was dropped.
    EXPECT_EQ(stats.points_dropped_uncertain, above) << "psi " << psi;
    // The threshold is the (100 - psi)-th percentile of u.
    std::vector<double> sorted = u;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_NEAR(stats.uncertainty_threshold, sorted[n - expected - 1], 1e-6) << "psi " << psi;
  }
}

TEST(PercentileThreshold, OffOrZeroOrSbkiDropsNothing) {
  SyntheticScene scene;
  const SyntheticScan scan = scene.defaultScan();
  SemanticConfig off, zero, sbki;
  off.uncertainty_threshold = false;
  zero.uncertainty_threshold = sbki.uncertainty_threshold = true;
  zero.drop_percent = 0.0;
  sbki.rule = "sbki";
  for (const SemanticConfig& config : {off, zero, sbki}) {
    EvidentialOcTree tree(0.2, scene.num_classes, config);
    const InsertStats stats = tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
    EXPECT_EQ(stats.points_dropped_uncertain, 0u) << config.rule << " " << config.drop_percent;
    EXPECT_GT(stats.voxels_updated, 0u);
  }
}

TEST(PercentileThreshold, DroppedPointsLeaveNoEvidence) {
  // Two far-apart points; the more uncertain one is dropped at psi = 50.
  SemanticConfig config;
  config.uncertainty_threshold = true;
  config.drop_percent = 50.0;
  config.ds_multiplier = 0.0;
  EvidentialOcTree tree(0.2, 2, config);
  octomap::Pointcloud points;
  points.push_back(2.1f, 0.1f, 0.1f);
  points.push_back(-2.1f, 0.1f, 0.1f);
  const std::vector<float> evidence{10.0f, 0.0f, 0.0f, 0.5f};
  const InsertStats stats =
      tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_EQ(stats.points_dropped_uncertain, 1u);
  EXPECT_EQ(tree.query(octomap::point3d(2.1f, 0.1f, 0.1f)).label, 0);
  EXPECT_EQ(tree.query(octomap::point3d(-2.1f, 0.1f, 0.1f)).label, -1);
  // Occupancy still comes from every point.
  EXPECT_TRUE(tree.isNodeOccupied(tree.search(octomap::point3d(-2.1f, 0.1f, 0.1f))));
}

// --- max range ---------------------------------------------------------------------------------

TEST(ScanIntegration, PointsBeyondMaxRangeGiveFreeSpaceOnly) {
  SemanticConfig config;
  config.max_range = 5.0;
  EvidentialOcTree tree(0.2, 2, config);
  octomap::Pointcloud points;
  points.push_back(3.1f, 0.1f, 0.1f);
  points.push_back(-9.9f, 0.1f, 0.1f);  // 10 m away
  const std::vector<float> evidence{10.0f, 0.0f, 0.0f, 10.0f};
  const InsertStats stats =
      tree.insertSemanticScan(points, evidence, octomap::point3d(0.1f, 0.1f, 0.1f));
  EXPECT_EQ(stats.points_beyond_range, 1u);
  EXPECT_EQ(tree.query(octomap::point3d(3.1f, 0.1f, 0.1f)).label, 0);
  const EvidentialOcTreeNode* far_end = tree.search(octomap::point3d(-9.9f, 0.1f, 0.1f));
  EXPECT_TRUE(far_end == nullptr || !tree.isNodeOccupied(far_end));
  EXPECT_EQ(tree.query(octomap::point3d(-9.9f, 0.1f, 0.1f)).label, -1);
  // Free up to the max range along that ray.
  const EvidentialOcTreeNode* on_ray = tree.search(octomap::point3d(-3.9f, 0.1f, 0.1f));
  ASSERT_NE(on_ray, nullptr);
  EXPECT_FALSE(tree.isNodeOccupied(on_ray));
}

}  // namespace
}  // namespace evidential_octomap
