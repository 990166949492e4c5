#include <gtest/gtest.h>

#include <numeric>

#include "evidential_octomap/evidence/evidence_sources.h"
#include "synthetic.h"

using namespace evidential_octomap;
using namespace evidential_octomap::tools;

namespace {
float sum(const std::vector<float>& e, size_t i, int C) {
  return std::accumulate(e.begin() + i * C, e.begin() + (i + 1) * C, 0.0f);
}
}  // namespace

TEST(OneHotEvidence, MagnitudeOnThePredictedClassOnly) {
  const auto e = oneHotEvidence({2, 0, -1}, 3, 20.0f);
  EXPECT_EQ(e, (std::vector<float>{0, 0, 20, 20, 0, 0, 0, 0, 0}));
}

TEST(KnnVoteEvidence, UnanimousFullNeighbourhoodGivesE) {
  // 9 points within 0.1 m, all class 1, k = 8: every point finds 8 neighbours (itself included).
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 9; ++i) pts.emplace_back(0.01f * i, 0.0f, 0.0f);
  const auto e = knnVoteEvidence(pts, std::vector<int>(9, 1), 3, 8, 0.5, 20.0f);
  for (size_t i = 0; i < 9; ++i) {
    EXPECT_FLOAT_EQ(e[i * 3 + 1], 20.0f);
    EXPECT_FLOAT_EQ(sum(e, i, 3), 20.0f);
  }
}

TEST(KnnVoteEvidence, IsolatedPointGetsEOverK) {
  const std::vector<Eigen::Vector3f> pts{{0, 0, 0}, {5, 5, 5}};
  const auto e = knnVoteEvidence(pts, {2, 1}, 3, 8, 0.5, 16.0f);
  EXPECT_FLOAT_EQ(e[2], 2.0f);  // 16 * 1 / (8 * 1)
  EXPECT_FLOAT_EQ(sum(e, 0, 3), 2.0f);
}

TEST(KnnVoteEvidence, ClassBorderGetsLessEvidenceThanTheInterior) {
  // A row of 16 points 5 cm apart: class 0 left, class 1 right, border in the middle.
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> labels;
  for (int i = 0; i < 16; ++i) {
    pts.emplace_back(0.05f * i, 0.0f, 0.0f);
    labels.push_back(i < 8 ? 0 : 1);
  }
  const auto e = knnVoteEvidence(pts, labels, 2, 4, 0.5, 20.0f);
  EXPECT_FLOAT_EQ(sum(e, 0, 2), 20.0f);  // interior: 4 neighbours, all class 0
  EXPECT_LT(sum(e, 7, 2), 15.0f);        // border: 2 + 2 votes -> 20 * 8 / 16 = 10
  EXPECT_GT(e[7 * 2 + 0], 0.0f);
  EXPECT_GT(e[7 * 2 + 1], 0.0f);
}

TEST(ConfusionEvidence, EstimatedOnOtherScansOnly) {
  ConfusionModel model(3, 0);
  // Scan 0: predictions of class 1 always right. Scan 1: predictions of 1 are class 2 half the time.
  model.addScan(0, std::vector<int>(100, 1), std::vector<int>(100, 1));
  std::vector<int> gt1(100, 1);
  for (int i = 0; i < 50; ++i) gt1[i] = 2;
  model.addScan(1, gt1, std::vector<int>(100, 1));
  const auto P_for_scan0 = model.conditional(0);  // from scan 1 only
  const auto P_for_scan1 = model.conditional(1);  // from scan 0 only
  EXPECT_NEAR(P_for_scan0[1 * 3 + 1], 0.5, 0.05);
  EXPECT_NEAR(P_for_scan0[1 * 3 + 2], 0.5, 0.05);
  EXPECT_GT(P_for_scan1[1 * 3 + 1], 0.9);
  // Evidence total = E * precision: the less precise prediction is more uncertain.
  const auto e0 = confusionEvidence({1}, P_for_scan0, 3, 20.0f);
  const auto e1 = confusionEvidence({1}, P_for_scan1, 3, 20.0f);
  EXPECT_LT(sum(e0, 0, 3), sum(e1, 0, 3));
  EXPECT_NEAR(sum(e1, 0, 3), 20.0f * P_for_scan1[4], 1e-4);
  // With a single scan there is no "other" scan to estimate on.
  ConfusionModel lonely(3, 0);
  lonely.addScan(0, {1}, {1});
  EXPECT_THROW(lonely.conditional(0), std::runtime_error);
}

TEST(SyntheticPredictions, DeterministicWithTheSeedAndNoisyAtTheDocumentedRate) {
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> gt;
  for (int i = 0; i < 20000; ++i) {
    pts.emplace_back(0.01f * (i % 200), 0.01f * (i / 200), 0.0f);
    gt.push_back(1 + i % 3);
  }
  NoiseModel noise;
  noise.region_rate = 0.0;  // point noise only: the flip rate must be point_rate
  const auto a = syntheticPredictions(pts, gt, 4, 0, noise);
  const auto b = syntheticPredictions(pts, gt, 4, 0, noise);
  EXPECT_EQ(a, b);
  size_t wrong = 0;
  for (size_t i = 0; i < gt.size(); ++i) {
    wrong += a[i] != gt[i];
    EXPECT_NE(a[i], 0);  // never the ignore class
  }
  EXPECT_NEAR(double(wrong) / gt.size(), noise.point_rate, 0.01);
  noise.seed = 7;
  EXPECT_NE(syntheticPredictions(pts, gt, 4, 0, noise), a);
}

TEST(EvidenceSourceNames, RoundTripAndDerivedFlag) {
  for (const char* n : {"file", "onehot", "knn-vote", "confusion"}) {
    EXPECT_EQ(evidenceSourceName(evidenceSourceFromName(n)), n);
  }
  EXPECT_THROW(evidenceSourceFromName("softmax"), std::invalid_argument);
  EXPECT_FALSE(derivedFromHardLabels(EvidenceSource::kFile));
  EXPECT_TRUE(derivedFromHardLabels(EvidenceSource::kKnnVote));
  EvidenceOptions o;
  o.source = EvidenceSource::kOneHot;
  EXPECT_NE(describeEvidence(o).find("derived from hard labels"), std::string::npos);
}
