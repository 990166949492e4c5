// The metric definitions of metrics.h, each pinned by a hand-made case worked out in the
// comments or by a brute-force recomputation in this file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/evaluation/metrics.h"

using namespace evidential_octomap;

namespace {
// An occupied (or free) leaf at `p` with the given payload (C floats), in a tree of C classes.
void setVoxel(EvidentialOcTree& tree, const octomap::point3d& p, bool occupied,
              const std::vector<float>& payload) {
  const octomap::OcTreeKey key = tree.coordToKey(p);
  tree.updateNode(key, occupied);
  if (payload.empty()) return;
  EvidentialOcTreeNode* node = detail::TreeEditing::leafForUpdate(tree, key, false);
  ASSERT_NE(node, nullptr);
  std::vector<float> values(tree.numClasses(), tree.rule().prior());
  std::copy(payload.begin(), payload.end(), values.begin());
  detail::TreeEditing::setPayload(tree, node, values.data());
}

const ErrorDetection& detectionOf(const QualityMetrics& q, const std::string& output) {
  const ErrorDetection* d = q.detection(output);
  EXPECT_NE(d, nullptr) << output;
  return *d;
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

// C = 3, class 0 ignored. Payload L = (0, ln 3, 0): e^L = (1, 3, 1), 1/u = 5 - 3 + 1 = 3, so
// u = 1/3, b = (e^L - 1) u = (0, 2/3, 0), p = b + u/3 = (1/9, 7/9, 1/9), label 1.
class HandMadeMap : public ::testing::Test {
 protected:
  EvidentialOcTree tree{0.5, 3};
  const float l3 = std::log(3.0f);
  const octomap::point3d a{0.25f, 0.25f, 0.25f}, b{1.25f, 0.25f, 0.25f}, f{2.25f, 0.25f, 0.25f},
      g{6.25f, 0.25f, 0.25f}, unknown{9.f, 9.f, 9.f};  // g: beyond every support of f
  std::vector<Query> queries;
  void SetUp() override {
    setVoxel(tree, a, true, {0.0f, l3, 0.0f});   // occupied, says 1
    setVoxel(tree, b, true, {0.0f, 0.0f, l3});   // occupied, says 2
    setVoxel(tree, f, false, {0.0f, l3, 0.0f});  // free, but holds evidence: says 1
    setVoxel(tree, g, true, {});                 // occupied without evidence
    queries = {{a, 1, 1}, {b, 1, 2}, {f, 1, 1}, {g, 2, 2}, {unknown, 2, 2}, {a, 0, 0}};
  }
};

TEST_F(HandMadeMap, CoverageMiouAndAccuracyOverAllAndLabelledQueries) {
  const MapMetrics m = evaluateMap(tree, queries, 0);
  const QualityMetrics& q = m.quality;
  EXPECT_EQ(q.queries, 5u);   // the ignore-class query is not counted
  EXPECT_EQ(m.occupied, 3u);  // a, b, g
  EXPECT_EQ(q.labelled, 3u);  // a, b, f
  EXPECT_DOUBLE_EQ(m.occupancy_coverage, 0.6);
  EXPECT_DOUBLE_EQ(m.semantic_coverage, 0.6);
  // All queries: gt 1 -> 1, 2, 1; gt 2 -> none, none. IoU1 = 2/3, IoU2 = 0/(0+2+1) = 0.
  EXPECT_NEAR(q.miou_all, (2.0 / 3.0 + 0.0) / 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(q.acc_all, 2.0 / 5.0);
  // Labelled: gt 1 -> 1, 2, 1: IoU1 = 2/3; class 2 is not in the labelled GT.
  EXPECT_NEAR(q.miou_labelled, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.acc_labelled, 2.0 / 3.0, 1e-12);
}

TEST_F(HandMadeMap, BrierNllAndEceOfProjectedProbabilities) {
  const QualityMetrics q = evaluateMap(tree, queries, 0).quality;
  // a, f (gt 1): (1/9)^2 + (2/9)^2 + (1/9)^2 = 6/81; b (gt 1, p = (1/9, 1/9, 7/9)): 114/81;
  // g and unknown, uniform: (2/3)^2 + 2 (1/3)^2 = 54/81. Mean over 5: 234/405.
  EXPECT_NEAR(q.brier, 234.0 / 405.0, 1e-6);
  EXPECT_NEAR(q.nll, (-2 * std::log(7.0 / 9.0) - std::log(1.0 / 9.0) - 2 * std::log(1.0 / 3.0)) / 5,
              1e-6);
  // Confidences 7/9 (a right, b wrong, f right) and 1/3 (two wrong): bins 7 and 3.
  // ECE = 3/5 |2/3 - 7/9| + 2/5 |0 - 1/3| = 1/15 + 2/15.
  EXPECT_NEAR(q.ece, 0.2, 1e-6);
  EXPECT_EQ(q.reliability[7].count, 3u);
  EXPECT_NEAR(q.reliability[7].accuracy, 2.0 / 3.0, 1e-12);
  EXPECT_EQ(q.reliability[3].count, 2u);
}

TEST_F(HandMadeMap, ErrorDetectionWithAllUncertaintiesTied) {
  const QualityMetrics q = evaluateMap(tree, queries, 0).quality;
  // Every labelled voxel has u = 1/3 and one class only (conflict 0): a tie is chance, and the
  // risk at every coverage is the error rate 1/3.
  EXPECT_NEAR(q.error_rate_labelled, 1.0 / 3.0, 1e-12);
  for (const std::string& output : kUncertaintyOutputs) {
    EXPECT_DOUBLE_EQ(detectionOf(q, output).auroc, 0.5) << output;
    EXPECT_NEAR(detectionOf(q, output).aurc, 1.0 / 3.0, 1e-12) << output;
  }
}

TEST(ErrorDetection, AurocEqualsPairCountingAndAurcEqualsTheMeanOverTieOrders) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + int(rng() % 8);
    std::vector<float> score(n);
    std::vector<uint8_t> wrong(n);
    for (int i = 0; i < n; ++i) {
      score[i] = float(rng() % 4) / 4.0f;  // few levels: many ties
      wrong[i] = rng() % 3 == 0;
    }
    // AUROC: P(score of a wrong answer > score of a right one) + 1/2 P(equal), over all pairs.
    double pairs = 0.0, favourable = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (wrong[i] && !wrong[j]) {
          pairs += 1.0;
          favourable += score[i] > score[j] ? 1.0 : (score[i] == score[j] ? 0.5 : 0.0);
        }
    const double expected_auroc = pairs > 0 ? favourable / pairs : NAN;
    const double got_auroc = auroc(score, wrong);
    if (std::isnan(expected_auroc)) {
      EXPECT_TRUE(std::isnan(got_auroc));
    } else {
      EXPECT_NEAR(got_auroc, expected_auroc, 1e-12);
    }
    // AURC: average over every order of the answers that sorts the scores ascending.
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    double total = 0.0;
    int orders = 0;
    do {
      bool sorted = true;
      for (int i = 1; i < n; ++i) sorted = sorted && score[order[i - 1]] <= score[order[i]];
      if (!sorted) continue;
      double risk_sum = 0.0, errors = 0.0;
      for (int k = 0; k < n; ++k) {
        errors += wrong[order[k]];
        risk_sum += errors / (k + 1);
      }
      total += risk_sum / n;
      ++orders;
    } while (std::next_permutation(order.begin(), order.end()));
    EXPECT_NEAR(aurc(score, wrong), total / orders, 1e-12) << "trial " << trial;
  }
}

TEST(ErrorDetection, PerfectAndInvertedRankings) {
  const std::vector<float> score{0.1f, 0.2f, 0.8f, 0.9f};
  const std::vector<uint8_t> wrong{0, 0, 1, 1};
  EXPECT_DOUBLE_EQ(auroc(score, wrong), 1.0);
  EXPECT_DOUBLE_EQ(auroc(score, {1, 1, 0, 0}), 0.0);
  // Perfect: risks 0, 0, 1/3, 2/4 -> AURC = (1/3 + 1/2) / 4.
  EXPECT_NEAR(aurc(score, wrong), (1.0 / 3.0 + 0.5) / 4.0, 1e-12);
  EXPECT_TRUE(std::isnan(auroc(score, {0, 0, 0, 0})));
}

TEST(Dissonance, HandComputedBalances) {
  // Bal(a, b) = 1 - |a - b| / (a + b). Equal masses: dissonance = sum of them.
  EXPECT_NEAR(dissonance({0.4f, 0.4f, 0.0f}), 0.8, 1e-6);
  // (0.6, 0.2): Bal = 0.5; 0.6 * 0.5 + 0.2 * 0.5 = 0.4.
  EXPECT_NEAR(dissonance({0.6f, 0.2f}), 0.4, 1e-6);
  EXPECT_EQ(dissonance({0.7f, 0.0f, 0.0f}), 0.0);
  EXPECT_EQ(dissonance({0.0f, 0.0f}), 0.0);
}

TEST(InputMetrics, EvidenceGivesTheSubjectiveOpinionOfThePoint) {
  // e = (0, 2, 0), C = 3: S = 5, b = (0, 2/5, 0), u = 3/5, p = alpha / S = (1/5, 3/5, 1/5).
  const std::vector<float> e{0.0f, 2.0f, 0.0f};
  const Answer a = answerOfEvidence(e.data(), 3);
  EXPECT_EQ(a.label, 1);
  EXPECT_NEAR(a.probability[0], 0.2, 1e-6);
  EXPECT_NEAR(a.probability[1], 0.6, 1e-6);
  EXPECT_NEAR(a.uncertainty[0], 0.6, 1e-6);  // u
  EXPECT_NEAR(a.uncertainty[2], 0.4, 1e-6);  // 1 - max p
  // Two queries, one right and one wrong: Brier (6/25 + (1/5)^2 + (3/5)^2 + (4/5)^2) / 2.
  const octomap::point3d p(0, 0, 0);
  const std::vector<Query> q{{p, 1, 1}, {p, 2, 1}};
  const std::vector<float> evidence{0, 2, 0, 0, 2, 0};
  const QualityMetrics m = evaluateInput(q, evidence, 3, -1);
  EXPECT_NEAR(m.brier, (6.0 / 25.0 + 26.0 / 25.0) / 2.0, 1e-6);
  EXPECT_DOUBLE_EQ(m.acc_all, 0.5);
  // A point without evidence has no label.
  const std::vector<float> none(3, 0.0f);
  EXPECT_EQ(answerOfEvidence(none.data(), 3).label, -1);
}

TEST(InputMetrics, HardPredictionsAreOneHotAndCountMissingOnesAsWrong) {
  const octomap::point3d p(0, 0, 0);
  const std::vector<Query> q{{p, 1, 1}, {p, 1, 2}, {p, 2, 2}, {p, 2, -1}, {p, 0, 1}};
  const QualityMetrics m = evaluateInput(q, {}, 3, 0);
  EXPECT_EQ(m.queries, 4u);
  EXPECT_DOUBLE_EQ(m.acc_all, 0.5);
  // IoU1 = 1 / (1 + 1 + 0); IoU2 = 1 / (1 + 1 + 1)
  EXPECT_DOUBLE_EQ(m.miou_all, (0.5 + 1.0 / 3.0) / 2.0);
  // Brier: right 0, wrong 2, right 0, no label 2/3.
  EXPECT_NEAR(m.brier, (2.0 + 2.0 / 3.0) / 4.0, 1e-12);
}

TEST(MapMetrics, SbkiProbabilitiesAreAlphaOverS) {
  SemanticConfig config;
  config.rule = "sbki";
  EvidentialOcTree tree(0.5, 3, config);
  const octomap::point3d a(0.25f, 0.25f, 0.25f);
  setVoxel(tree, a, true, {1.0f, 3.0f, 0.0f});  // alpha / S = (1/4, 3/4, 0)
  const QualityMetrics q = evaluateMap(tree, {{a, 1, 1}}, -1).quality;
  EXPECT_NEAR(q.brier, 1.0 / 16 + 1.0 / 16, 1e-6);
  EXPECT_NEAR(q.nll, -std::log(0.75), 1e-6);
}

TEST(OccupiedWithoutEndpoint, CountsOccupiedVoxelsOutsideTheEndpointSet) {
  EvidentialOcTree tree(0.5, 2);
  const octomap::point3d a(0.25f, 0.25f, 0.25f), b(1.25f, 0.25f, 0.25f), c(2.25f, 0.25f, 0.25f);
  tree.updateNode(a, true);
  tree.updateNode(b, true);
  tree.updateNode(c, false);
  EXPECT_EQ(occupiedWithoutEndpoint(tree, {tree.coordToKey(a)}), 1u);
  EXPECT_EQ(occupiedWithoutEndpoint(tree, {tree.coordToKey(a), tree.coordToKey(b)}), 0u);
  // A pruned block of 8 occupied voxels counts as 8 voxels.
  EvidentialOcTree block(0.5, 2);
  for (float x : {4.25f, 4.75f})
    for (float y : {0.25f, 0.75f})
      for (float z : {0.25f, 0.75f}) block.updateNode(octomap::point3d(x, y, z), true);
  block.prune();
  EXPECT_LT(block.getNumLeafNodes(), 8u);
  EXPECT_EQ(
      occupiedWithoutEndpoint(block, {block.coordToKey(octomap::point3d(4.25f, 0.25f, 0.25f))}),
      7u);
}
