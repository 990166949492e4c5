// Sparse kernel of Melkumyan & Ramos, its adaptive length and the per-scan percentile threshold
// (docs/design.md). Expected values are worked out by hand in the comments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "evidential_octomap/sparse_kernel.h"

namespace evidential_octomap {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(SparseKernel, IsOneAtZeroDistance) {
  // d = 0: sigma0 [ (2 + cos 0)/3 * 1 + sin 0 / 2pi ] = sigma0.
  EXPECT_DOUBLE_EQ(sparseKernel(0.0, 0.3, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(sparseKernel(0.0, 2.0, 0.5), 0.5);
}

TEST(SparseKernel, MatchesClosedFormAtQuarterHalfAndThreeQuarters) {
  for (double length : {0.3, 1.0, 2.5}) {
    // d = L/4: (2 + cos(pi/2))/3 * 3/4 + sin(pi/2)/(2 pi) = 1/2 + 1/(2 pi)
    EXPECT_NEAR(sparseKernel(length / 4, length, 1.0), 0.5 + 1.0 / (2 * kPi), 1e-12);
    // d = L/2: (2 + cos(pi))/3 * 1/2 + sin(pi)/(2 pi) = 1/6
    EXPECT_NEAR(sparseKernel(length / 2, length, 1.0), 1.0 / 6.0, 1e-12);
    // d = 3L/4: (2 + cos(3pi/2))/3 * 1/4 + sin(3pi/2)/(2 pi) = 1/6 - 1/(2 pi)
    EXPECT_NEAR(sparseKernel(3 * length / 4, length, 1.0), 1.0 / 6.0 - 1.0 / (2 * kPi), 1e-12);
    // sigma0 scales the value linearly below the clamp: 0.5 * 1/6.
    EXPECT_NEAR(sparseKernel(length / 2, length, 0.5), 1.0 / 12.0, 1e-12);
  }
}

TEST(SparseKernel, ZeroAtAndBeyondSupport) {
  EXPECT_EQ(sparseKernel(0.3, 0.3, 1.0), 0.0);
  EXPECT_EQ(sparseKernel(0.3000001, 0.3, 1.0), 0.0);
  EXPECT_EQ(sparseKernel(10.0, 0.3, 1.0), 0.0);
  EXPECT_EQ(sparseKernel(1e9, 0.3, 5.0), 0.0);
  // Just inside the support the value is small and positive (the kernel is continuous at L:
  // near r = 1, k ~ (2 pi^2 / 9) (1 - r)^3 ... tends to 0).
  const double inside = sparseKernel(0.3 * (1 - 1e-3), 0.3, 1.0);
  EXPECT_GE(inside, 0.0);
  EXPECT_LT(inside, 1e-6);
}

TEST(SparseKernel, IsNotClampedSigma0ScalesIt) {
  // The clamp to [0, 1] belongs to the dempster rule's extended belief, not to the kernel that
  // sbki and ebs share: sigma0 = 2 gives 2 at d = 0 and 2/6 at d = L/2.
  EXPECT_EQ(sparseKernel(0.0, 0.3, 2.0), 2.0);
  EXPECT_NEAR(sparseKernel(0.15, 0.3, 2.0), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(sparseKernel(0.075, 0.3, 3.0), 3.0 * (0.5 + 1.0 / (2 * kPi)), 1e-12);
  for (double d = 0.0; d < 0.35; d += 0.001) {
    ASSERT_GE(sparseKernel(d, 0.3, 4.0), 0.0) << "d = " << d;
  }
}

TEST(DistanceToCube, ZeroInsideAndEuclideanOutside) {
  EXPECT_EQ(distanceToCube(0.0, 0.0, 0.0, 0.1), 0.0);
  EXPECT_EQ(distanceToCube(0.09, -0.1, 0.05, 0.1), 0.0);        // inside or on the faces
  EXPECT_NEAR(distanceToCube(0.3, 0.0, 0.0, 0.1), 0.2, 1e-12);  // beyond one face
  EXPECT_NEAR(distanceToCube(-0.2, 0.2, 0.0, 0.1), std::sqrt(0.02), 1e-12);  // beyond an edge
  EXPECT_NEAR(distanceToCube(0.2, 0.2, -0.2, 0.1), std::sqrt(0.03), 1e-12);  // beyond a corner
}

TEST(SparseKernel, DecreasesMonotonicallyInsideSupport) {
  double previous = sparseKernel(0.0, 1.0, 1.0);
  for (int i = 1; i <= 1000; ++i) {
    const double k = sparseKernel(i / 1000.0, 1.0, 1.0);
    ASSERT_LE(k, previous + 1e-15) << "d = " << i / 1000.0;
    previous = k;
  }
  EXPECT_EQ(previous, 0.0);
}

TEST(SparseKernel, DegenerateLengthGivesZero) {
  EXPECT_EQ(sparseKernel(0.1, 0.0, 1.0), 0.0);
  EXPECT_EQ(sparseKernel(0.1, -1.0, 1.0), 0.0);
}

TEST(AdaptiveLength, MatchesClosedForm) {
  // l beta e^{1 - gamma u}
  EXPECT_NEAR(adaptiveLength(0.3, 1.0, 3.0, 0.0), 0.3 * std::exp(1.0), 1e-12);
  EXPECT_NEAR(adaptiveLength(0.3, 1.0, 3.0, 1.0), 0.3 * std::exp(-2.0), 1e-12);
  EXPECT_NEAR(adaptiveLength(0.3, 1.0, 3.0, 1.0 / 3.0), 0.3, 1e-12);
  EXPECT_NEAR(adaptiveLength(0.5, 2.0, 1.0, 0.5), 1.0 * std::exp(0.5), 1e-12);
  // gamma = 0 (reference_compat): l beta e, whatever u is.
  EXPECT_NEAR(adaptiveLength(0.3, 1.0, 0.0, 0.9), 0.3 * std::exp(1.0), 1e-12);
}

TEST(AdaptiveLength, ShrinksAsUncertaintyGrows) {
  double previous = adaptiveLength(0.3, 1.0, 3.0, 0.0);
  for (int i = 1; i <= 100; ++i) {
    const double l = adaptiveLength(0.3, 1.0, 3.0, i / 100.0);
    ASSERT_LT(l, previous);
    previous = l;
  }
}

size_t countAbove(const std::vector<float>& values, double threshold) {
  return std::count_if(values.begin(), values.end(), [&](float v) { return v > threshold; });
}

TEST(UncertaintyThreshold, DropsExactlyPsiPercentOfDistinctValues) {
  std::vector<float> values(100);
  std::iota(values.begin(), values.end(), 0.0f);  // 0 .. 99
  std::shuffle(values.begin(), values.end(), std::mt19937(7));
  const double threshold = uncertaintyThreshold(values, 10.0);
  // Exactly 90, 91, ..., 99 lie above it; 89 is kept.
  EXPECT_EQ(countAbove(values, threshold), 10u);
  EXPECT_GE(threshold, 89.0);
  EXPECT_LT(threshold, 90.0);

  EXPECT_EQ(countAbove(values, uncertaintyThreshold(values, 25.0)), 25u);
  EXPECT_EQ(countAbove(values, uncertaintyThreshold(values, 50.0)), 50u);
  EXPECT_EQ(countAbove(values, uncertaintyThreshold(values, 1.0)), 1u);
}

TEST(UncertaintyThreshold, RandomUncertaintiesDropTheirPercentile) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t n : {10u, 1000u, 123457u}) {
    std::vector<float> values(n);
    for (float& v : values) v = u(rng);
    const double threshold = uncertaintyThreshold(values, 10.0);
    const size_t expected = n / 10;  // floor(10 % of n); values are distinct with probability ~1
    const size_t above = countAbove(values, threshold);
    EXPECT_GE(above + 1, expected) << "n = " << n;
    EXPECT_LE(above, expected + 1) << "n = " << n;
  }
}

TEST(UncertaintyThreshold, ZeroPercentKeepsEverything) {
  std::vector<float> values{0.1f, 0.9f, 1.0f, 0.5f, 0.0f};
  const double threshold = uncertaintyThreshold(values, 0.0);
  EXPECT_EQ(countAbove(values, threshold), 0u);
  EXPECT_EQ(countAbove(values, uncertaintyThreshold(values, -5.0)), 0u);
}

TEST(UncertaintyThreshold, EmptyInputKeepsEverything) {
  const double threshold = uncertaintyThreshold({}, 10.0);
  EXPECT_FALSE(std::isnan(threshold));
  EXPECT_GE(threshold, 1.0);  // any later u in [0, 1] would be kept
}

TEST(UncertaintyThreshold, DoesNotModifyTheCallersValues) {
  const std::vector<float> values{0.9f, 0.1f, 0.5f, 0.7f, 0.3f};
  std::vector<float> copy = values;
  uncertaintyThreshold(copy, 40.0);
  EXPECT_EQ(copy, values);
}

}  // namespace
}  // namespace evidential_octomap
