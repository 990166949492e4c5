// Per-point features of the learned evidence head on scenes whose answer is known by
// construction: a flat disc, a line, a pole on the ground, predicted neighbourhoods.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "evidential_octomap/evidence/point_features.h"

namespace evidential_octomap {
namespace {

constexpr int kC = 3;

struct Scene {
  std::vector<float> xyz, remission;
  std::vector<int> predicted;
  size_t add(float x, float y, float z, int label = 0, float r = 0.5f) {
    xyz.insert(xyz.end(), {x, y, z});
    remission.push_back(r);
    predicted.push_back(label);
    return predicted.size() - 1;
  }
  ScanInput input() const {
    return {xyz.data(), remission.data(), predicted.data(), predicted.size()};
  }
};

int column(const std::string& name) {
  const auto names = pointFeatureNames(kC);
  for (size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return int(k);
  ADD_FAILURE() << "no feature " << name;
  return 0;
}

float feature(const FeatureMatrix& f, size_t point, const std::string& name) {
  return f.row(point)[column(name)];
}

// A 2 m x 2 m ground grid at z = -1.7 with 5 cm spacing, centred on (5, 0).
Scene groundGrid(int label = 0) {
  Scene s;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) s.add(5.0f + 0.05f * i, 0.05f * j, -1.7f, label);
  return s;
}

TEST(PointFeatures, NamesMatchColumns) {
  Scene s = groundGrid();
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  EXPECT_EQ(f.cols, 13 + 2 * kC);
  EXPECT_EQ(size_t(f.cols), pointFeatureNames(kC).size());
  EXPECT_EQ(f.rows, s.predicted.size());
}

TEST(PointFeatures, FlatGroundIsPlanarHorizontalAndAtGroundHeight) {
  Scene s = groundGrid();
  const size_t centre = 20 * 41 + 20;
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  EXPECT_NEAR(feature(f, centre, "range"), std::sqrt(25.0f + 1.7f * 1.7f), 1e-5);
  EXPECT_NEAR(feature(f, centre, "z"), -1.7f, 1e-6);
  EXPECT_NEAR(feature(f, centre, "height_above_ground"), 0.0f, 1e-6);
  EXPECT_NEAR(feature(f, centre, "column_height"), 0.0f, 1e-6);
  // No spread off the plane (l3 = 0): linearity + planarity = (l1 - l3) / l1 = 1. (How the two
  // split depends on which 3 of the 8 points at 11.2 cm make the 16 nearest.)
  EXPECT_NEAR(feature(f, centre, "scattering"), 0.0f, 1e-4);
  EXPECT_NEAR(feature(f, centre, "linearity") + feature(f, centre, "planarity"), 1.0f, 1e-4);
  EXPECT_GT(feature(f, centre, "planarity"), 0.5f);
  EXPECT_NEAR(feature(f, centre, "verticality"), 1.0f, 1e-4);  // normal along z
  EXPECT_FLOAT_EQ(feature(f, centre, "knn_fill"), 1.0f);       // 16 neighbours within 1 m
  EXPECT_FLOAT_EQ(feature(f, centre, "remission"), 0.5f);
  // The 16 nearest on a 5 cm grid: itself, 4 at 5 cm, 4 at 7.07 cm, 4 at 10 cm, 3 of 8 at 11.2 cm.
  const double mean =
      (4 * 0.05 + 4 * 0.05 * std::sqrt(2.0) + 4 * 0.1 + 3 * 0.05 * std::sqrt(5.0)) / 15;
  EXPECT_NEAR(feature(f, centre, "knn_mean_dist"), mean, 1e-5);
}

TEST(PointFeatures, LineIsLinear) {
  Scene s;
  for (int i = 0; i < 60; ++i) s.add(3.0f + 0.05f * i, 1.0f, -1.0f);
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  EXPECT_GT(feature(f, 30, "linearity"), 0.99f);
  EXPECT_LT(feature(f, 30, "planarity"), 0.01f);
}

TEST(PointFeatures, PoleTopIsHighAboveTheGround) {
  Scene s = groundGrid();
  size_t top = 0;
  for (int k = 0; k <= 60; ++k) top = s.add(5.0f, 0.0f, -1.7f + 0.05f * k, 1);  // 3 m pole
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  EXPECT_NEAR(feature(f, top, "height_above_ground"), 3.0f, 1e-4);
  EXPECT_NEAR(feature(f, top, "column_height"), 3.0f, 1e-4);
  EXPECT_GT(feature(f, top - 30, "linearity"), 0.99f);  // mid-pole: a vertical line
}

TEST(PointFeatures, PredictionOneHotAndNeighbourVotes) {
  Scene s = groundGrid(2);  // every neighbour says class 2
  const size_t centre = 20 * 41 + 20;
  s.predicted[centre] = 1;  // the point itself says 1
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  EXPECT_FLOAT_EQ(feature(f, centre, "pred_1"), 1.0f);
  EXPECT_FLOAT_EQ(feature(f, centre, "pred_2"), 0.0f);
  EXPECT_FLOAT_EQ(feature(f, centre, "vote_2"), 1.0f);  // self excluded from the votes
  EXPECT_FLOAT_EQ(feature(f, centre, "vote_1"), 0.0f);
  // A neighbour at 5 cm sees the centre among its 15 voting neighbours.
  EXPECT_NEAR(feature(f, centre + 1, "vote_1"), 1.0f / 15.0f, 1e-6);
}

TEST(PointFeatures, NoReturnPointsGetZeroRowsAndAreNoNeighbours) {
  Scene s;
  const size_t a = s.add(0.0f, 0.0f, 0.0f, 1);
  const size_t b = s.add(0.1f, 0.0f, 0.0f, 2);
  const FeatureMatrix f = computePointFeatures(s.input(), kC);
  for (int k = 0; k < f.cols; ++k) EXPECT_EQ(f.row(a)[k], 0.0f);
  EXPECT_FLOAT_EQ(feature(f, b, "knn_fill"), 1.0f / 16.0f);  // itself only
  EXPECT_FLOAT_EQ(feature(f, b, "vote_1"), 0.0f);
}

TEST(PointFeatures, BadInputIsRejected) {
  Scene s = groundGrid();
  s.predicted[3] = kC;
  EXPECT_THROW(computePointFeatures(s.input(), kC), std::invalid_argument);
  ScanInput missing = s.input();
  missing.predicted = nullptr;
  EXPECT_THROW(computePointFeatures(missing, kC), std::invalid_argument);
}

TEST(ScanFingerprint, IdentifiesContentNotNoReturnPoints) {
  Scene s = groundGrid();
  const uint64_t base = scanFingerprint(s.input());
  Scene with_zero = s;
  with_zero.add(0.0f, 0.0f, 0.0f);
  EXPECT_EQ(scanFingerprint(with_zero.input()), base);
  Scene moved = s;
  moved.xyz[7] = std::nextafter(moved.xyz[7], 10.0f);  // one ulp
  EXPECT_NE(scanFingerprint(moved.input()), base);
  Scene brighter = s;
  brighter.remission[0] = 0.75f;
  EXPECT_NE(scanFingerprint(brighter.input()), base);
  // Empty input: FNV-1a's 64-bit offset basis.
  EXPECT_EQ(scanFingerprint(ScanInput{}), 0xcbf29ce484222325ull);
  EXPECT_EQ(fingerprintHex(0xcbf29ce484222325ull), "cbf29ce484222325");
}

}  // namespace
}  // namespace evidential_octomap
