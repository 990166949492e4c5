// The adaptive read-out cap of a dempster map (evidence_cap = -1, the default; docs/calibration.md):
// cap = 2.71 m^0.55, clamped to [1, 100], m the mean over the inserted points of a point's own
// sum_c log1p(e^c / C); 3 before any evidence. The constants are the documented formula, written
// out here rather than taken from the library, so a change to them fails this test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "synthetic_scene.h"

namespace evidential_octomap {
namespace {

double documentedCap(double m) { return std::min(100.0, std::max(1.0, 2.71 * std::pow(m, 0.55))); }

// A scan whose every point carries evidence `magnitude` for class 0 only, so every sampled point
// has the same statistic log1p(magnitude / C) and the sampling of points does not matter.
test::SyntheticScan uniformScan(const test::SyntheticScene& scene, float magnitude, unsigned seed) {
  test::SyntheticScan scan = scene.defaultScan(seed);
  const int C = scene.num_classes;
  for (size_t i = 0; i < scan.evidence.size(); ++i) {
    scan.evidence[i] = (i % C == 0) ? magnitude : 0.0f;
  }
  return scan;
}

void insert(EvidentialOcTree* tree, const test::SyntheticScan& scan) {
  tree->insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
}

TEST(AdaptiveCap, IsTheDefaultAndReadsWithThreeBeforeAnyEvidence) {
  EvidentialOcTree tree(0.2, 3);
  EXPECT_EQ(tree.config().evidence_cap, -1.0);
  EXPECT_EQ(tree.effectiveEvidenceCap(), 3.0);
}

TEST(AdaptiveCap, FollowsTheMeanLogEvidenceOfTheInsertedPoints) {
  test::SyntheticScene scene;
  const int C = scene.num_classes;
  EvidentialOcTree tree(0.2, C);
  insert(&tree, uniformScan(scene, 30.0f, 1));
  const double m1 = std::log1p(30.0 / C);
  EXPECT_NEAR(tree.meanPointLogEvidence(), m1, 1e-6);
  EXPECT_NEAR(tree.effectiveEvidenceCap(), documentedCap(m1), 1e-6);

  // A second scan of the same size with weaker evidence: m is the mean over both scans' points.
  insert(&tree, uniformScan(scene, 3.0f, 2));
  const double m2 = (m1 + std::log1p(3.0 / C)) / 2.0;
  EXPECT_NEAR(tree.meanPointLogEvidence(), m2, 1e-6);
  EXPECT_NEAR(tree.effectiveEvidenceCap(), documentedCap(m2), 1e-6);
  EXPECT_LT(tree.effectiveEvidenceCap(), documentedCap(m1));
}

TEST(AdaptiveCap, ScalingTheEvidenceUpRaisesTheCap) {
  // A network whose evidence is 10x larger earns a larger total per point, so it is read with a
  // larger cap: its voxels become more certain, but by less than 10x.
  test::SyntheticScene scene;
  EvidentialOcTree weak(0.2, scene.num_classes), strong(0.2, scene.num_classes);
  test::SyntheticScan scan = scene.defaultScan(3);
  insert(&weak, scan);
  for (float& e : scan.evidence) e *= 10.0f;
  insert(&strong, scan);
  EXPECT_GT(strong.effectiveEvidenceCap(), weak.effectiveEvidenceCap());
  EXPECT_LT(strong.effectiveEvidenceCap(), 10.0 * weak.effectiveEvidenceCap());
}

TEST(AdaptiveCap, IsClampedToOneForNearlyVacuousEvidence) {
  test::SyntheticScene scene;
  EvidentialOcTree tree(0.2, scene.num_classes);
  insert(&tree, uniformScan(scene, 0.01f, 1));  // m = log1p(0.01 / 3): 2.71 m^0.55 = 0.12
  EXPECT_EQ(tree.effectiveEvidenceCap(), 1.0);
}

TEST(AdaptiveCap, ReadsTheCappedOpinionOfTheStoredEvidence) {
  // The read-out of the adaptive map equals a fixed-cap read-out at the cap it reports.
  test::SyntheticScene scene;
  EvidentialOcTree tree(0.2, scene.num_classes);
  const test::SyntheticScan scan = scene.defaultScan(4);
  for (unsigned s = 0; s < 3; ++s) insert(&tree, scene.defaultScan(4 + s));
  const double cap = tree.effectiveEvidenceCap();
  ASSERT_GT(cap, 1.0);
  ASSERT_NE(cap, 3.0);
  SemanticConfig fixed = tree.config();
  fixed.evidence_cap = cap;
  EvidentialOcTree reread(tree);
  reread.setConfig(fixed);
  int compared = 0;
  for (size_t i = 0; i < scan.points_W.size(); i += 37) {
    const octomap::OcTreeKey key = tree.coordToKey(scan.points_W[i]);
    const VoxelOpinion a = tree.query(key), b = reread.query(key);
    ASSERT_EQ(a.label, b.label);
    EXPECT_NEAR(a.uncertainty, b.uncertainty, 1e-6);
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

TEST(AdaptiveCap, AFixedCapIgnoresTheStatistic) {
  test::SyntheticScene scene;
  EvidentialOcTree tree(0.2, scene.num_classes);
  SemanticConfig config = tree.config();
  config.evidence_cap = 5.0;
  tree.setConfig(config);
  insert(&tree, uniformScan(scene, 30.0f, 1));
  EXPECT_EQ(tree.effectiveEvidenceCap(), 5.0);
}

TEST(AdaptiveCap, AMergedMapReadsAsTheSequentialOne) {
  // Halves with different evidence scales: the merged statistic is the mean over all points.
  test::SyntheticScene scene;
  const int C = scene.num_classes;
  EvidentialOcTree sequential(0.2, C), first(0.2, C), second(0.2, C);
  test::SyntheticScan strong = scene.defaultScan(5);
  for (float& e : strong.evidence) e *= 8.0f;
  const test::SyntheticScan weak = scene.scan(octomap::point3d(1.05f, 0.3f, 1.7f), 6);
  insert(&sequential, strong);
  insert(&sequential, weak);
  insert(&first, strong);
  insert(&second, weak);
  first.merge(second);
  EXPECT_NEAR(first.meanPointLogEvidence(), sequential.meanPointLogEvidence(), 1e-9);
  EXPECT_NEAR(first.effectiveEvidenceCap(), sequential.effectiveEvidenceCap(), 1e-9);
  EXPECT_NE(first.effectiveEvidenceCap(), 3.0);
}

TEST(AdaptiveCap, ASavedMapLoadsWithItsStatisticAndGoesOnFromIt) {
  test::SyntheticScene scene;
  EvidentialOcTree all(0.2, scene.num_classes), part(0.2, scene.num_classes);
  const test::SyntheticScan a = uniformScan(scene, 30.0f, 1), b = uniformScan(scene, 2.0f, 2);
  insert(&all, a);
  insert(&all, b);
  insert(&part, a);
  const std::string path = testing::TempDir() + "adaptive_cap.ot";
  saveMap(part, path);
  std::unique_ptr<EvidentialOcTree> loaded = loadMap(path);
  std::remove(path.c_str());
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->config().evidence_cap, -1.0);
  EXPECT_NEAR(loaded->effectiveEvidenceCap(), part.effectiveEvidenceCap(), 1e-12);
  insert(loaded.get(), b);
  EXPECT_NEAR(loaded->meanPointLogEvidence(), all.meanPointLogEvidence(), 1e-9);
  EXPECT_NEAR(loaded->effectiveEvidenceCap(), all.effectiveEvidenceCap(), 1e-9);
}

}  // namespace
}  // namespace evidential_octomap
