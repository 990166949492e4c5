#include <gtest/gtest.h>

#include <cmath>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/metrics.h"

using namespace evidential_octomap;

namespace {
// An occupied (or free) leaf at `p` with the given payload (C floats), in a tree of C classes.
void setVoxel(EvidentialOcTree& tree, const octomap::point3d& p, bool occupied,
              const std::vector<float>& payload) {
  const octomap::OcTreeKey key = tree.coordToKey(p);
  tree.updateNode(key, occupied);
  if (payload.empty()) return;
  EvidentialOcTreeNode* node = tree.leafForUpdate(key, false);
  ASSERT_NE(node, nullptr);
  float* slot = tree.payloadForUpdate(node);
  for (size_t c = 0; c < payload.size(); ++c) slot[c] = payload[c];
}
}  // namespace

TEST(ConfusionMatrix, IouAccuracyAndMeanOverClassesPresentInGt) {
  ConfusionMatrix m(4);
  // class 1: 3 right, 1 called 2; class 2: 1 right, 1 without label; class 3 never in GT but
  // predicted once for a class-1 point; class 0 is the ignore class.
  m.add(1, 1, 3);
  m.add(1, 2);
  m.add(1, 3);
  m.add(2, 2);
  m.add(2, -1);
  m.add(0, 0, 5);
  EXPECT_EQ(m.total(), 12u);
  EXPECT_EQ(m.at(2, -1), 1u);
  // IoU1 = 3 / (3 + 2 + 0); IoU2 = 1 / (1 + 1 + 1); IoU3 = 0 / (0 + 0 + 1).
  EXPECT_DOUBLE_EQ(m.iou(1), 3.0 / 5.0);
  EXPECT_DOUBLE_EQ(m.iou(2), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(m.iou(3), 0.0);
  EXPECT_FALSE(m.presentInGt(3));
  EXPECT_DOUBLE_EQ(m.meanIou(0), (3.0 / 5.0 + 1.0 / 3.0) / 2.0);  // 0 ignored, 3 absent
  EXPECT_DOUBLE_EQ(m.accuracy(), (3.0 + 1.0 + 5.0) / 12.0);
  EXPECT_TRUE(std::isnan(ConfusionMatrix(2).meanIou()));
}

TEST(MapMetrics, HandMadeDempsterMapHasKnownOAccIouAccAndBrier) {
  // C = 3, class 0 ignored. Payload L = (0, ln 3, 0): e^L = (1, 3, 1), so
  // u = 1 / (1 + 3 + 1 - 3 + 1) = 1/3 and the label is 1.
  EvidentialOcTree tree(0.5, 3);
  const float l3 = std::log(3.0f);
  const octomap::point3d a(0.25f, 0.25f, 0.25f), b(1.25f, 0.25f, 0.25f), f(2.25f, 0.25f, 0.25f);
  setVoxel(tree, a, true, {0.0f, l3, 0.0f});   // says 1, u = 1/3
  setVoxel(tree, b, true, {0.0f, 0.0f, l3});   // says 2, u = 1/3
  setVoxel(tree, f, false, {});                // free
  ASSERT_EQ(tree.opinion(tree.search(a)).label, 1);
  ASSERT_NEAR(tree.opinion(tree.search(a)).uncertainty, 1.0 / 3.0, 1e-6);

  std::vector<Query> q{{a, 1, 1},                                       // covered, right
                       {b, 1, 2},                                       // covered, wrong
                       {f, 1, 1},                                       // free: uncovered
                       {octomap::point3d(9.f, 9.f, 9.f), 2, 2},         // unknown: uncovered
                       {a, 0, 0}};                                      // ignore class: skipped
  const MapMetrics m = evaluateMap(tree, q, 0);
  EXPECT_EQ(m.queries, 4u);
  EXPECT_EQ(m.covered, 2u);
  EXPECT_DOUBLE_EQ(m.occupied_accuracy, 0.5);
  EXPECT_DOUBLE_EQ(m.accuracy, 0.5);
  // Covered: gt 1 -> 1, gt 1 -> 2. IoU1 = 1/2; class 2 absent from covered GT: mIoU = 1/2.
  EXPECT_DOUBLE_EQ(m.confusion.iou(1), 0.5);
  EXPECT_DOUBLE_EQ(m.miou, 0.5);
  // All queries: class 1: TP 1, FN 2 (wrong + uncovered), FP 0 -> 1/3; class 2: 0 -> mIoU 1/6.
  EXPECT_NEAR(m.miou_all, (1.0 / 3.0 + 0.0) / 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.accuracy_all, 0.25);
  // BS = ((1/3 - 0)^2 + (1/3 - 1)^2) / 2 = 5/18; dempster u is a mass: no scaling.
  EXPECT_FALSE(m.scale.scaled);
  EXPECT_NEAR(m.brier, 5.0 / 18.0, 1e-6);
  EXPECT_NEAR(m.mean_u_correct, 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(m.mean_u_wrong, 1.0 / 3.0, 1e-6);
}

TEST(MapMetrics, OccupiedVoxelWithoutEvidenceIsWrongWithFullUncertainty) {
  EvidentialOcTree tree(0.5, 3);
  const octomap::point3d a(0.25f, 0.25f, 0.25f);
  setVoxel(tree, a, true, {});
  const MapMetrics m = evaluateMap(tree, {{a, 1, 1}}, 0);
  EXPECT_EQ(m.covered, 1u);
  EXPECT_DOUBLE_EQ(m.accuracy, 0.0);
  EXPECT_EQ(m.confusion.at(1, -1), 1u);
  EXPECT_DOUBLE_EQ(m.brier, 0.0);  // u_bar = 1 and wrong: (1 - 1)^2
}

TEST(MapMetrics, SbkiUncertaintyIsMinMaxScaledOverTheMap) {
  SemanticConfig config;
  config.rule = "sbki";
  EvidentialOcTree tree(0.5, 3, config);
  ASSERT_FALSE(tree.rule().uncertaintyIsMass());
  const octomap::point3d a(0.25f, 0.25f, 0.25f), b(1.25f, 0.25f, 0.25f);
  setVoxel(tree, a, true, {0.001f, 50.0f, 0.001f});  // confident class 1: smallest variance
  setVoxel(tree, b, true, {0.001f, 2.0f, 1.0f});     // unsure class 1: largest variance
  const double ua = tree.opinion(tree.search(a)).uncertainty;
  const double ub = tree.opinion(tree.search(b)).uncertainty;
  ASSERT_LT(ua, ub);
  const UncertaintyScale s = uncertaintyScale(tree);
  EXPECT_TRUE(s.scaled);
  EXPECT_DOUBLE_EQ(s.min, ua);
  EXPECT_DOUBLE_EQ(s.max, ub);
  // a right with u_bar 0, b wrong with u_bar 1: BS = 0; swap the GT and BS = 1.
  EXPECT_DOUBLE_EQ(evaluateMap(tree, {{a, 1, 1}, {b, 2, 2}}, 0).brier, 0.0);
  EXPECT_DOUBLE_EQ(evaluateMap(tree, {{a, 2, 2}, {b, 1, 1}}, 0).brier, 1.0);
}

TEST(PredictionMetrics, PerPointIouOnTheSameQueries) {
  const octomap::point3d p(0, 0, 0);
  const std::vector<Query> q{{p, 1, 1}, {p, 1, 2}, {p, 2, 2}, {p, 2, -1}, {p, 0, 1}};
  const PredictionMetrics m = evaluatePredictions(q, 3, 0);
  EXPECT_EQ(m.queries, 4u);
  EXPECT_DOUBLE_EQ(m.accuracy, 0.5);
  // IoU1 = 1 / (1 + 1 + 0) ; IoU2 = 1 / (1 + 1 + 1)
  EXPECT_DOUBLE_EQ(m.miou, (0.5 + 1.0 / 3.0) / 2.0);
}
