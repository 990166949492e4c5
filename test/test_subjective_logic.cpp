// Subjective-logic opinions and the belief-space reduced Dempster rule (docs/design.md), checked
// against a long-double O(C^2) reference over thousands of random masses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "evidential_octomap/subjective_logic.h"
#include "random_masses.h"
#include "reference_dempster.h"

namespace evidential_octomap {
namespace {

using test::RandomMasses;
using test::RefOpinion;

const std::vector<int> kClassCounts{1, 2, 3, 20, 255};
constexpr int kTrials = 2000;

RefOpinion toRef(const Opinion& o) {
  RefOpinion r;
  for (double b : o.belief) r.belief.push_back(b);
  r.uncertainty = o.uncertainty;
  return r;
}

// Largest absolute difference over beliefs and uncertainty.
long double maxDiff(const Opinion& a, const RefOpinion& b) {
  EXPECT_EQ(a.belief.size(), b.belief.size());
  long double d = std::fabs(a.uncertainty - b.uncertainty);
  for (size_t c = 0; c < std::min(a.belief.size(), b.belief.size()); ++c) {
    d = std::max(d, std::fabs(a.belief[c] - b.belief[c]));
  }
  return d;
}

double maxDiff(const Opinion& a, const Opinion& b) {
  return static_cast<double>(maxDiff(a, toRef(b)));
}

double massSum(const Opinion& o) {
  double s = o.uncertainty;
  for (double b : o.belief) s += b;
  return s;
}

bool allFinite(const Opinion& o) {
  if (!std::isfinite(o.uncertainty)) return false;
  for (double b : o.belief) {
    if (!std::isfinite(b)) return false;
  }
  return true;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

TEST(DempsterRule, MatchesLongDoubleReference) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(1000 + num_classes);
    long double worst = 0.0L;
    for (int t = 0; t < kTrials; ++t) {
      const Opinion a = rnd.opinion(num_classes);
      const Opinion b = rnd.opinion(num_classes);
      const Opinion got = dempsterCombine(a, b);
      RefOpinion expected;
      ASSERT_TRUE(test::refCombine(toRef(a), toRef(b), &expected));
      worst = std::max(worst, maxDiff(got, expected));
    }
    EXPECT_LE(worst, 1e-9L) << "C = " << num_classes;
  }
}

TEST(DempsterRule, IsCommutative) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(2000 + num_classes);
    for (int t = 0; t < kTrials; ++t) {
      const Opinion a = rnd.opinion(num_classes);
      const Opinion b = rnd.opinion(num_classes);
      ASSERT_LE(maxDiff(dempsterCombine(a, b), dempsterCombine(b, a)), 1e-12)
          << "C = " << num_classes << ", trial " << t;
    }
  }
}

TEST(DempsterRule, IsAssociative) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(3000 + num_classes);
    for (int t = 0; t < kTrials; ++t) {
      const Opinion a = rnd.opinion(num_classes);
      const Opinion b = rnd.opinion(num_classes);
      const Opinion c = rnd.opinion(num_classes);
      const Opinion left = dempsterCombine(dempsterCombine(a, b), c);
      const Opinion right = dempsterCombine(a, dempsterCombine(b, c));
      ASSERT_LE(maxDiff(left, right), 1e-9) << "C = " << num_classes << ", trial " << t;
      const RefOpinion expected = test::refCombine(test::refCombine(toRef(a), toRef(b)), toRef(c));
      ASSERT_LE(maxDiff(left, expected), 1e-9L) << "C = " << num_classes << ", trial " << t;
    }
  }
}

TEST(DempsterRule, VacuousMassIsIdentity) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(4000 + num_classes);
    const Opinion vacuous = Opinion::vacuous(num_classes);
    ASSERT_EQ(vacuous.numClasses(), num_classes);
    ASSERT_EQ(vacuous.uncertainty, 1.0);
    for (int t = 0; t < kTrials; ++t) {
      const Opinion a = rnd.opinion(num_classes);
      // Exact in real arithmetic; allow rounding over a sum of C terms (C * 2^-53 < 1e-13).
      EXPECT_LE(maxDiff(dempsterCombine(a, vacuous), a), 1e-13);
      EXPECT_LE(maxDiff(dempsterCombine(vacuous, a), a), 1e-13);
    }
  }
}

TEST(DempsterRule, MassesSumToOne) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(5000 + num_classes);
    Opinion running = Opinion::vacuous(num_classes);
    for (int t = 0; t < kTrials; ++t) {
      const Opinion a = rnd.opinion(num_classes);
      const Opinion b = rnd.opinion(num_classes);
      const Opinion ab = dempsterCombine(a, b);
      ASSERT_NEAR(massSum(ab), 1.0, 1e-12) << "C = " << num_classes << ", trial " << t;
      for (double x : ab.belief) ASSERT_GE(x, 0.0);
      ASSERT_GE(ab.uncertainty, 0.0);
      ASSERT_LE(ab.uncertainty, 1.0);
      // A long chain stays normalised too.
      if (t < 200) {
        running = dempsterCombine(running, a);
        ASSERT_NEAR(massSum(running), 1.0, 1e-9) << "C = " << num_classes << ", chain " << t;
      }
    }
  }
}

TEST(DempsterRule, TotalConflictGivesNoNaN) {
  // Two dogmatic opinions on different classes: 1 - conflict is exactly 0.
  Opinion a = Opinion::vacuous(3), b = Opinion::vacuous(3);
  a.belief = {1.0, 0.0, 0.0};
  a.uncertainty = 0.0;
  b.belief = {0.0, 1.0, 0.0};
  b.uncertainty = 0.0;
  const Opinion ab = dempsterCombine(a, b);
  ASSERT_EQ(ab.numClasses(), 3);
  EXPECT_TRUE(allFinite(ab));
  // The header documents the vacuous opinion as the result under total conflict.
  EXPECT_EQ(ab.uncertainty, 1.0);
  for (double x : ab.belief) EXPECT_EQ(x, 0.0);

  // Split dogmatic masses with no common class are also in total conflict.
  Opinion c = Opinion::vacuous(4), d = Opinion::vacuous(4);
  c.belief = {0.5, 0.5, 0.0, 0.0};
  c.uncertainty = 0.0;
  d.belief = {0.0, 0.0, 0.25, 0.75};
  d.uncertainty = 0.0;
  EXPECT_TRUE(allFinite(dempsterCombine(c, d)));
  EXPECT_TRUE(allFinite(dempsterCombine(d, c)));
}

TEST(DempsterRule, NearTotalConflictStaysFiniteAndNormalised) {
  for (double eps : {1e-3, 1e-6, 1e-9, 1e-12}) {
    Opinion a = Opinion::vacuous(2), b = Opinion::vacuous(2);
    a.belief = {1.0 - eps, 0.0};
    a.uncertainty = eps;
    b.belief = {0.0, 1.0 - eps};
    b.uncertainty = eps;
    const Opinion ab = dempsterCombine(a, b);
    ASSERT_TRUE(allFinite(ab)) << "eps = " << eps;
    EXPECT_NEAR(massSum(ab), 1.0, 1e-6) << "eps = " << eps;
    // Symmetric conflict: the two classes stay equal.
    EXPECT_NEAR(ab.belief[0], ab.belief[1], 1e-9) << "eps = " << eps;
  }
}

TEST(DempsterRule, SingleClassHasNoConflict) {
  // With C = 1 there is no pair i != j: beliefs combine like independent evidence.
  Opinion a = Opinion::vacuous(1), b = Opinion::vacuous(1);
  a.belief = {0.5};
  a.uncertainty = 0.5;
  b.belief = {0.75};
  b.uncertainty = 0.25;
  const Opinion ab = dempsterCombine(a, b);
  // b = 0.5*0.75 + 0.5*0.25 + 0.75*0.5 = 0.875, u = 0.125, conflict 0 (worked by hand).
  EXPECT_NEAR(ab.belief[0], 0.875, 1e-15);
  EXPECT_NEAR(ab.uncertainty, 0.125, 1e-15);
}

TEST(DempsterRule, HandWorkedTwoClassExample) {
  // b1 = (0.6, 0.1), u1 = 0.3; b2 = (0.2, 0.5), u2 = 0.3.
  // conflict = 0.6*0.5 + 0.1*0.2 = 0.32, 1 - conflict = 0.68
  // b^0 = (0.12 + 0.18 + 0.06) / 0.68 = 0.36 / 0.68, b^1 = (0.05 + 0.03 + 0.15) / 0.68
  // u = 0.09 / 0.68
  Opinion a = Opinion::vacuous(2), b = Opinion::vacuous(2);
  a.belief = {0.6, 0.1};
  a.uncertainty = 0.3;
  b.belief = {0.2, 0.5};
  b.uncertainty = 0.3;
  const Opinion ab = dempsterCombine(a, b);
  EXPECT_NEAR(ab.belief[0], 0.36 / 0.68, 1e-14);
  EXPECT_NEAR(ab.belief[1], 0.23 / 0.68, 1e-14);
  EXPECT_NEAR(ab.uncertainty, 0.09 / 0.68, 1e-14);
  EXPECT_EQ(ab.argmax(), 0);
}

TEST(Opinion, ArgmaxOfVacuousIsMinusOne) {
  EXPECT_EQ(Opinion::vacuous(5).argmax(), -1);
  Opinion o = Opinion::vacuous(5);
  o.belief[3] = 0.2;
  o.belief[1] = 0.1;
  o.uncertainty = 0.7;
  EXPECT_EQ(o.argmax(), 3);
}

TEST(OpinionFromEvidence, MatchesHandComputedValues) {
  // e = (2, 0, 1): alpha = (3, 1, 2), S = 6, b = (1/3, 0, 1/6), u = 3/6.
  const float e[3] = {2.0f, 0.0f, 1.0f};
  const Opinion o = opinionFromEvidence(e, 3);
  ASSERT_EQ(o.numClasses(), 3);
  EXPECT_NEAR(o.belief[0], 1.0 / 3.0, 1e-15);
  EXPECT_EQ(o.belief[1], 0.0);
  EXPECT_NEAR(o.belief[2], 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(o.uncertainty, 0.5, 1e-15);
  EXPECT_EQ(o.argmax(), 0);
}

TEST(OpinionFromEvidence, ZeroEvidenceIsVacuous) {
  const std::vector<float> e(20, 0.0f);
  const Opinion o = opinionFromEvidence(e.data(), 20);
  EXPECT_EQ(o.uncertainty, 1.0);
  for (double b : o.belief) EXPECT_EQ(b, 0.0);
  EXPECT_EQ(o.argmax(), -1);
}

TEST(OpinionFromEvidence, RandomEvidenceIsNormalisedAndMatchesReference) {
  for (int num_classes : kClassCounts) {
    RandomMasses rnd(6000 + num_classes);
    for (int t = 0; t < 500; ++t) {
      const std::vector<float> e = rnd.evidence(num_classes, 1000.0);
      const Opinion o = opinionFromEvidence(e.data(), num_classes);
      ASSERT_NEAR(massSum(o), 1.0, 1e-12);
      ASSERT_LE(maxDiff(o, test::refFromEvidence(e)), 1e-12L);
    }
  }
}

TEST(OpinionFromEvidence, HugeEvidenceStaysFinite) {
  const float e[2] = {1e30f, 0.0f};
  const Opinion o = opinionFromEvidence(e, 2);
  EXPECT_TRUE(allFinite(o));
  EXPECT_GT(o.uncertainty, 0.0);
  EXPECT_NEAR(o.belief[0], 1.0, 1e-12);
}

TEST(EvidenceConversions, AlphaMinusOne) {
  const float alpha[4] = {1.0f, 3.5f, 1.0f, 11.0f};
  float e[4] = {-7, -7, -7, -7};
  evidenceFromAlpha(alpha, 4, e);
  EXPECT_EQ(e[0], 0.0f);
  EXPECT_EQ(e[1], 2.5f);
  EXPECT_EQ(e[2], 0.0f);
  EXPECT_EQ(e[3], 10.0f);
}

TEST(EvidenceConversions, LabelIsOneHot) {
  float e[5] = {-7, -7, -7, -7, -7};
  evidenceFromLabel(3, 5, 4.5f, e);
  for (int c = 0; c < 5; ++c) EXPECT_EQ(e[c], c == 3 ? 4.5f : 0.0f) << "class " << c;
  evidenceFromLabel(0, 5, 1.0f, e);
  EXPECT_EQ(e[0], 1.0f);
  EXPECT_EQ(e[3], 0.0f);
}

TEST(EvidenceConversions, OneHotProbabilityGivesTheLabelEvidence) {
  const float p[3] = {0.0f, 1.0f, 0.0f};
  float e[3], expected[3];
  EXPECT_EQ(evidenceFromProbabilities(p, 3, 20.0f, e), "");
  evidenceFromLabel(1, 3, 20.0f, expected);
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(e[c], expected[c]);
}

TEST(EvidenceConversions, UniformProbabilityIsVacuous) {
  const float p[4] = {0.25f, 0.25f, 0.25f, 0.25f};
  float e[4];
  EXPECT_EQ(evidenceFromProbabilities(p, 4, 20.0f, e), "");
  for (float v : e) EXPECT_NEAR(v, 0.0f, 1e-6);
}

TEST(EvidenceConversions, ProbabilityEvidenceIsConfidenceScaled) {
  // p = (0.6, 0.3, 0.1), C = 3: confidence (3 * 0.6 - 1) / 2 = 0.4, e = 20 * 0.4 * p.
  const float p[3] = {0.6f, 0.3f, 0.1f};
  float e[3];
  EXPECT_EQ(evidenceFromProbabilities(p, 3, 20.0f, e), "");
  EXPECT_NEAR(e[0], 4.8f, 1e-5);
  EXPECT_NEAR(e[1], 2.4f, 1e-5);
  EXPECT_NEAR(e[2], 0.8f, 1e-5);
  const float unnormalised[3] = {6.0f, 3.0f, 1.0f};  // normalised by the sum first
  EXPECT_EQ(evidenceFromProbabilities(unnormalised, 3, 20.0f, e), "");
  EXPECT_NEAR(e[0], 4.8f, 1e-5);
}

TEST(EvidenceConversions, BadProbabilitiesAreNamed) {
  float e[2];
  const float negative[2] = {-0.1f, 1.1f};
  EXPECT_NE(evidenceFromProbabilities(negative, 2, 20.0f, e).find("class 0"), std::string::npos);
  const float zero[2] = {0.0f, 0.0f};
  EXPECT_NE(evidenceFromProbabilities(zero, 2, 20.0f, e), "");
}

TEST(EvidenceConversions, LogitTransforms) {
  const float z[3] = {2.0f, 0.0f, -1.0f};
  float e[3];
  EXPECT_EQ(evidenceFromLogits(z, 3, LogitTransform::kExp, 20.0f, e), "");
  EXPECT_NEAR(e[0], std::exp(2.0), 1e-5);
  EXPECT_NEAR(e[2], std::exp(-1.0), 1e-6);
  EXPECT_EQ(evidenceFromLogits(z, 3, LogitTransform::kSoftplus, 20.0f, e), "");
  EXPECT_NEAR(e[0], std::log(1.0 + std::exp(2.0)), 1e-6);
  EXPECT_NEAR(e[1], std::log(2.0), 1e-6);
  // softmax: p = exp(z) / sum, then the probability conversion (computed here by hand).
  const double s = std::exp(2.0) + 1.0 + std::exp(-1.0);
  const double p0 = std::exp(2.0) / s, confidence = (3 * p0 - 1) / 2;
  EXPECT_EQ(evidenceFromLogits(z, 3, LogitTransform::kSoftmax, 20.0f, e), "");
  EXPECT_NEAR(e[0], 20.0 * p0 * confidence, 1e-5);
  EXPECT_NEAR(e[2], 20.0 * std::exp(-1.0) / s * confidence, 1e-5);
  const float huge[3] = {1000.0f, 0.0f, 0.0f};  // no overflow
  EXPECT_EQ(evidenceFromLogits(huge, 3, LogitTransform::kSoftmax, 20.0f, e), "");
  EXPECT_NEAR(e[0], 20.0f, 1e-4);
  EXPECT_EQ(evidenceFromLogits(huge, 3, LogitTransform::kExp, 20.0f, e), "");
  EXPECT_TRUE(std::isfinite(e[0]));
  const float nan[3] = {0.0f, std::nanf(""), 0.0f};
  EXPECT_NE(evidenceFromLogits(nan, 3, LogitTransform::kExp, 20.0f, e).find("class 1"),
            std::string::npos);
  EXPECT_EQ(logitTransformFromName("softplus"), LogitTransform::kSoftplus);
  EXPECT_THROW(logitTransformFromName("sigmoid"), std::invalid_argument);
}

TEST(CheckEvidence, ValidEvidenceGivesEmptyMessage) {
  const float e[4] = {0.0f, 1.5f, 1e20f, -0.0f};  // -0 is not negative
  EXPECT_EQ(checkEvidence(e, 4), "");
}

TEST(CheckEvidence, NaNIsNamedWithItsClass) {
  std::vector<float> e(10, 1.0f);
  e[7] = std::numeric_limits<float>::quiet_NaN();
  const std::string msg = checkEvidence(e.data(), 10);
  ASSERT_FALSE(msg.empty());
  EXPECT_NE(msg.find('7'), std::string::npos) << msg;
  EXPECT_NE(lower(msg).find("nan"), std::string::npos) << msg;
}

TEST(CheckEvidence, InfinityIsNamedWithItsClass) {
  std::vector<float> e(10, 1.0f);
  e[4] = std::numeric_limits<float>::infinity();
  const std::string msg = checkEvidence(e.data(), 10);
  ASSERT_FALSE(msg.empty());
  EXPECT_NE(msg.find('4'), std::string::npos) << msg;
  EXPECT_NE(lower(msg).find("inf"), std::string::npos) << msg;
}

TEST(CheckEvidence, NegativeValueIsNamedWithItsClass) {
  std::vector<float> e(10, 1.0f);
  e[6] = -3.25f;
  const std::string msg = checkEvidence(e.data(), 10);
  ASSERT_FALSE(msg.empty());
  EXPECT_NE(msg.find('6'), std::string::npos) << msg;
  EXPECT_NE(msg.find("-3.25"), std::string::npos) << msg;
}

}  // namespace
}  // namespace evidential_octomap
