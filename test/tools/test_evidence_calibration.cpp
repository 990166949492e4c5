// Calibration of derived evidence (evidence_calibration.h): u becomes the error rate of such
// points on the other mapping scans; checked on hand-made scans.
#include <gtest/gtest.h>

#include <numeric>

#include "evidence_calibration.h"
#include "evidential_octomap/evidence/evidence_sources.h"

using namespace evidential_octomap;
using namespace evidential_octomap::tools;

namespace {
double uOf(const std::vector<float>& e, size_t i, int C) {
  const double sum = std::accumulate(e.begin() + i * C, e.begin() + (i + 1) * C, 0.0);
  return C / (sum + C);
}
}  // namespace

TEST(EvidenceCalibration, OneHotUIsTheErrorRateOfTheOtherScans) {
  // C = 3, class 0 ignored. Scan 0: 100 predictions of 1, all right. Scan 1: 100 predictions of
  // 1, 40 of them wrong (GT 2). One-hot evidence puts every point in one bin.
  const int C = 3;
  const std::vector<int> pred(100, 1), right(100, 1);
  std::vector<int> gt1(100, 1);
  for (int i = 0; i < 40; ++i) gt1[i] = 2;
  const auto e = oneHotEvidence(pred, C, 20.0f);
  EvidenceCalibration cal(C, 0);
  cal.addScan(0, e, right);
  cal.addScan(1, e, gt1);
  // Scan 0 is calibrated on scan 1 alone: u = 0.4 (the bin holds every point, so the smoothing
  // towards the overall rate changes nothing). Scan 1 on scan 0: u = 0, clamped to 0.001.
  auto e0 = e, e1 = e;
  cal.apply(0, &e0);
  cal.apply(1, &e1);
  EXPECT_NEAR(uOf(e0, 0, C), 0.4, 1e-6);
  EXPECT_NEAR(uOf(e1, 0, C), EvidenceCalibration::kMinU, 1e-6);
  // The class shares are kept: still one-hot on the prediction.
  EXPECT_EQ(e0[0], 0.0f);
  EXPECT_GT(e0[1], 0.0f);
  EXPECT_EQ(e0[2], 0.0f);
  // A scan that was not added (a held-out query scan) uses every added scan: 40 / 200.
  auto e_query = e;
  cal.apply(7, &e_query);
  EXPECT_NEAR(uOf(e_query, 0, C), 0.2, 1e-6);
}

TEST(EvidenceCalibration, BinsSeparateConfidentFromUnsurePoints) {
  // Two kinds of points in one scan pair: unanimous (share 1) ones are right, split ones
  // (share 0.5) are wrong half the time. Each kind gets its own u; smoothing pulls a bin of n
  // points towards the overall rate with weight 50 / (n + 50).
  const int C = 3;
  std::vector<float> e;
  std::vector<int> gt;
  for (int i = 0; i < 200; ++i) {
    const bool split = i % 2 == 1;
    const std::vector<float> row =
        split ? std::vector<float>{0, 10, 10} : std::vector<float>{0, 20, 0};
    e.insert(e.end(), row.begin(), row.end());
    gt.push_back(split ? (i % 4 == 1 ? 1 : 2) : 1);
  }
  EvidenceCalibration cal(C, 0);
  cal.addScan(0, e, gt);
  cal.addScan(1, e, gt);
  auto calibrated = e;
  cal.apply(0, &calibrated);
  // Counts of scan 1: unanimous 100 points, 0 wrong; split 100 points, 50 wrong (argmax = class
  // 1, the first maximum); overall 50 / 200.
  const double overall = 0.25;
  EXPECT_NEAR(uOf(calibrated, 0, C), (0 + 50 * overall) / (100 + 50), 1e-6);
  EXPECT_NEAR(uOf(calibrated, 1, C), (50 + 50 * overall) / (100 + 50), 1e-6);
  EXPECT_TRUE(cal.binOf(&e[0]) != cal.binOf(&e[3]));
}

TEST(EvidenceCalibration, SingleScanIsCalibratedInSampleAndVacuousPointsStay) {
  const int C = 2;
  const std::vector<float> e{5, 0, 0, 0, 5, 0};  // the middle point has no evidence
  EvidenceCalibration cal(C, -1);
  cal.addScan(0, e, {0, 1, 1});  // point 0 right, point 2 wrong (argmax 0, GT 1)
  EXPECT_TRUE(cal.inSample());
  auto calibrated = e;
  cal.apply(0, &calibrated);
  EXPECT_EQ(calibrated[2], 0.0f);
  EXPECT_EQ(calibrated[3], 0.0f);
  EXPECT_NEAR(uOf(calibrated, 0, C), 0.5, 1e-6);  // 1 error in 2 points of the one bin
}
