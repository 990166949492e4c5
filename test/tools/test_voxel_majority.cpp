// The voxel-majority reference rows of compare (voxel_majority.h) on hand-made scans: each
// query's voxel is labelled by the majority of the mapped points' labels in it, worked out in
// the comments.
#include <gtest/gtest.h>

#include "voxel_majority.h"

using namespace evidential_octomap;
using namespace evidential_octomap::tools;

namespace {
constexpr double kResolution = 0.2;
constexpr int kClasses = 4;  // class 0 is the ignore class

// A scan at the identity pose; each point's GT and prediction given.
Scan makeScan(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& gt,
              const std::vector<int>& predicted) {
  Scan s;
  s.points_S = points;
  s.gt = gt;
  s.predicted = predicted;
  return s;
}

Query queryAt(float x, float y, float z, int gt) {
  Query q;
  q.point_W = octomap::point3d(x, y, z);
  q.gt = gt;
  q.predicted = 3;  // replaced by the row's answer
  return q;
}
}  // namespace

TEST(VoxelMajority, MajorityOfTheMappedPointsInTheQuerysVoxel) {
  // Voxel A = [0, 0.2)^3: predictions 1, 2, 2 (scan 0) and 1 (scan 1): tie 2-2 -> class 1, the
  // lower index; GT 1, 1, 3, 3 -> tie -> 1. Voxel B = [0.2, 0.4) x [0, 0.2)^2: predictions 3
  // and 0 (ignore class, not counted) -> 3; GT 0, 0 -> no counted GT point -> no label.
  // Voxel C (x in [1, 1.2)): scan 2 only, which is not mapped -> no label.
  const std::vector<Scan> scans = {
      makeScan({{0.05f, 0.05f, 0.05f},
                {0.1f, 0.1f, 0.1f},
                {0.15f, 0.05f, 0.1f},
                {0.25f, 0.1f, 0.1f},
                {0.3f, 0.1f, 0.1f}},
               {1, 1, 3, 0, 0}, {1, 2, 2, 3, 0}),
      makeScan({{0.19f, 0.19f, 0.19f}}, {3}, {1}),
      makeScan({{1.1f, 0.1f, 0.1f}}, {2}, {2}),
  };
  const std::vector<Query> queries = {queryAt(0.01f, 0.02f, 0.03f, 2),
                                      queryAt(0.39f, 0.1f, 0.1f, 3), queryAt(1.1f, 0.1f, 0.1f, 2)};
  const std::vector<size_t> mapped = {0, 1};
  const std::vector<Query> pred = voxelMajorityAnswers(scans, mapped, queries, kResolution,
                                                       kClasses, 0, MajorityOf::kPredictions);
  ASSERT_EQ(pred.size(), 3u);
  EXPECT_EQ(pred[0].predicted, 1);
  EXPECT_EQ(pred[1].predicted, 3);
  EXPECT_EQ(pred[2].predicted, -1);
  EXPECT_EQ(pred[1].gt, 3);  // everything but the answer is kept
  const std::vector<Query> gt = voxelMajorityAnswers(scans, mapped, queries, kResolution, kClasses,
                                                     0, MajorityOf::kGroundTruth);
  EXPECT_EQ(gt[0].predicted, 1);
  EXPECT_EQ(gt[1].predicted, -1);
  EXPECT_EQ(gt[2].predicted, -1);
  // Mapping scan 2 as well labels voxel C.
  EXPECT_EQ(voxelMajorityAnswers(scans, {0, 1, 2}, queries, kResolution, kClasses, 0,
                                 MajorityOf::kPredictions)[2]
                .predicted,
            2);
}

TEST(VoxelMajority, LabelsOfAnEvidenceSourceAreTheArgmaxOfEachPointsEvidence) {
  // Three points in voxel A = [0, 0.2)^3 whose predictions say 1, 1, 2 but whose evidence says
  // 2 (0.5 < 3), 2 and 1: by the evidence's labels A is class 2, by the predictions class 1.
  // A fourth point (voxel B) has no evidence at all: label -1, not counted -> B has no label.
  // Ties go to the lowest class: evidence (0, 4, 4, 0) is class 1.
  const std::vector<Scan> scans = {makeScan(
      {{0.05f, 0.05f, 0.05f}, {0.1f, 0.1f, 0.1f}, {0.15f, 0.1f, 0.1f}, {0.3f, 0.1f, 0.1f}},
      {2, 2, 2, 1}, {1, 1, 2, 1})};
  const std::vector<std::vector<float>> evidence = {
      {0, 0.5f, 3, 0, /**/ 0, 0, 1, 0, /**/ 0, 2, 0, 0, /**/ 0, 0, 0, 0}};
  const std::vector<std::vector<int>> labels = evidenceLabels(evidence, kClasses);
  ASSERT_EQ(labels.size(), 1u);
  EXPECT_EQ(labels[0], (std::vector<int>{2, 2, 1, -1}));
  EXPECT_EQ(evidenceLabels({{0, 4, 4, 0}}, kClasses)[0], std::vector<int>{1});
  const std::vector<Query> queries = {queryAt(0.01f, 0.02f, 0.03f, 2),
                                      queryAt(0.3f, 0.1f, 0.1f, 1)};
  const std::vector<Query> by_evidence =
      voxelMajorityAnswers(scans, labels, {0}, queries, kResolution, kClasses, 0);
  EXPECT_EQ(by_evidence[0].predicted, 2);
  EXPECT_EQ(by_evidence[1].predicted, -1);
  const std::vector<Query> by_predictions =
      voxelMajorityAnswers(scans, {0}, queries, kResolution, kClasses, 0, MajorityOf::kPredictions);
  EXPECT_EQ(by_predictions[0].predicted, 1);
  EXPECT_EQ(by_predictions[1].predicted, 1);
}

TEST(NeighbourhoodOracle, GtWhenAnyPredictionWithinTheSupportHasIt) {
  // Mapped predictions: voxel (0,0,0) class 1 twice; voxel 3 voxels away in x (gap 0.4 m)
  // class 2 once. Query in voxel (0,0,0) with GT 2: with support 0.5 m class 2 is within
  // reach -> right (2); with support 0.3 m only class 1 is -> wrong, answered 1. A query whose
  // neighbourhood holds no mapped point has no label.
  const std::vector<Scan> scans = {makeScan(
      {{0.1f, 0.1f, 0.1f}, {0.12f, 0.1f, 0.1f}, {0.7f, 0.1f, 0.1f}}, {1, 1, 2}, {1, 1, 2})};
  const std::vector<Query> queries = {queryAt(0.05f, 0.05f, 0.05f, 2),
                                      queryAt(5.0f, 5.0f, 5.0f, 1)};
  const auto wide = neighbourhoodOracleAnswers(scans, {0}, queries, kResolution, 0.5, kClasses, 0);
  EXPECT_EQ(wide[0].predicted, 2);
  EXPECT_EQ(wide[1].predicted, -1);
  const auto narrow =
      neighbourhoodOracleAnswers(scans, {0}, queries, kResolution, 0.3, kClasses, 0);
  EXPECT_EQ(narrow[0].predicted, 1);
}
