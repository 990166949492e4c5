// Queries off the surface (query_support.cpp): in a map that keeps evidence on the surface
// (semantic_occupied_only), a known voxel without evidence answers from the voxels with
// evidence within a point's full support; the expected values are computed here from the
// kernel formula and the documented weighting, on a map built voxel by voxel.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/sparse_kernel.h"

namespace evidential_octomap {
namespace {

constexpr double kRes = 0.2;
constexpr int kClasses = 3;
const octomap::OcTreeKey kCentre(32768, 32768, 32768);

octomap::OcTreeKey offset(int dx, int dy, int dz) {
  return octomap::OcTreeKey(kCentre[0] + dx, kCentre[1] + dy, kCentre[2] + dz);
}

// A known voxel (occupancy untouched: log-odds 0), with `values` as its payload when given.
void addVoxel(EvidentialOcTree& tree, const octomap::OcTreeKey& key,
              const std::vector<float>& values = {}) {
  EvidentialOcTreeNode* leaf = detail::TreeEditing::leafForUpdate(tree, key, true);
  ASSERT_NE(leaf, nullptr);
  if (!values.empty()) detail::TreeEditing::setPayload(tree, leaf, values.data());
}

SemanticConfig surfaceOnly() {
  SemanticConfig c;
  c.semantic_occupied_only = true;
  return c;
}

// The default support of a point without uncertainty: l * beta * e (semantic_config.h).
double supportLength() {
  const SemanticConfig c;
  return c.length_scale * c.beta * std::exp(1.0);
}

// The kernel's shape at distance d from a point without uncertainty (sigma0 is already in
// the stored evidence, so the answer weighs by the shape alone).
double kernelAt(double d) { return sparseKernel(d, supportLength(), 1.0); }

void expectOpinionOf(const EvidentialOcTree& tree, const VoxelOpinion& got,
                     const std::vector<float>& payload) {
  const VoxelOpinion want = tree.rule().readout(payload.data(), kClasses);
  ASSERT_EQ(got.label, want.label);
  ASSERT_EQ(got.belief.size(), want.belief.size());
  for (int c = 0; c < kClasses; ++c) EXPECT_NEAR(got.belief[c], want.belief[c], 1e-6) << c;
  EXPECT_NEAR(got.uncertainty, want.uncertainty, 1e-6);
}

class QuerySupport : public ::testing::Test {
 protected:
  QuerySupport() : tree(kRes, kClasses, surfaceOnly()) {
    addVoxel(tree, offset(1, 0, 0), near_values);   // next to the query voxel
    addVoxel(tree, offset(0, 0, -2), far_values);   // two voxels below it
    addVoxel(tree, kCentre);                        // the query voxel: known, no evidence
    addVoxel(tree, offset(10, 0, 0));               // known, beyond every support
    detail::TreeEditing::updateInnerNodes(tree);
  }
  EvidentialOcTree tree;
  const std::vector<float> near_values{2.0f, 0.0f, 0.0f};
  const std::vector<float> far_values{0.0f, 3.0f, 0.0f};
};

TEST_F(QuerySupport, KnownVoxelWithoutEvidenceAnswersTheDiscountedKernelMeanOfItsNeighbours) {
  // Distances from the query voxel's centre to the neighbours' cubes: 0.1 m and 0.3 m.
  const double k_near = kernelAt(0.1);
  const double k_far = kernelAt(0.3);
  ASSERT_GT(k_far, 0.0);
  ASSERT_GT(k_near, k_far);
  std::vector<float> expected(kClasses);
  for (int c = 0; c < kClasses; ++c)
    expected[c] = float(k_near * (k_near * near_values[c] + k_far * far_values[c]) /
                        (k_near + k_far));
  float got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  for (int c = 0; c < kClasses; ++c) EXPECT_NEAR(got[c], expected[c], 1e-5) << c;
  expectOpinionOf(tree, tree.query(tree.keyToCoord(kCentre)), expected);
  EXPECT_EQ(tree.query(tree.keyToCoord(kCentre)).label, 0);  // the nearer voxel's class
}

TEST_F(QuerySupport, AFreeVoxelAnswersNoMovableClassWhileMovableClearingIsOn) {
  // Class 0 (the near neighbour's) moves. Rays found the query voxel empty: with movable
  // clearing on (the default) its answer holds the neighbours' other classes only, weighted as
  // before; an occupied voxel, or a map that does not clear movers, still answers class 0.
  tree.setMovableClasses({true, false, false});
  const double k_near = kernelAt(0.1), k_far = kernelAt(0.3);
  const float prior = tree.rule().prior();
  float got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  EXPECT_EQ(tree.answer(kCentre).label, 0);  // log-odds 0: occupied
  tree.updateNode(kCentre, false);
  ASSERT_FALSE(tree.isNodeOccupied(tree.search(kCentre)));
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  EXPECT_EQ(got[0], prior);
  EXPECT_NEAR(got[1], prior + k_near * k_far * (far_values[1] - prior) / (k_near + k_far), 1e-5);
  EXPECT_EQ(tree.answer(kCentre).label, 1);
  SemanticConfig keeps_movers = surfaceOnly();
  keeps_movers.movable_clearing_observations = 0;
  tree.setConfig(keeps_movers);
  EXPECT_EQ(tree.answer(kCentre).label, 0);
}

// In the default map a free voxel holds evidence of its own, some spread there by the kernel of
// an object beside it. A movable class of it is answered while an occupied voxel within the
// support answers that class (the object is there); once that voxel is free (the object left)
// it is not, and the voxel's other classes answer as they were stored.
TEST(FreeVoxelEvidence, AMovableClassIsAnsweredOnlyBesideASurfaceOfIt) {
  EvidentialOcTree tree(kRes, kClasses, SemanticConfig());
  tree.setMovableClasses({true, false, false});
  const std::vector<float> own{2.0f, 1.0f, 0.0f};
  addVoxel(tree, kCentre, own);
  addVoxel(tree, offset(1, 0, 0), {3.0f, 0.0f, 0.0f});   // the mover's surface beside it
  addVoxel(tree, offset(10, 0, 0), {3.0f, 0.0f, 0.0f});  // one beyond every support
  detail::TreeEditing::updateInnerNodes(tree);
  tree.updateNode(kCentre, false);
  ASSERT_FALSE(tree.isNodeOccupied(tree.search(kCentre)));
  ASSERT_TRUE(tree.isNodeOccupied(tree.search(offset(1, 0, 0))));
  float got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  for (int c = 0; c < kClasses; ++c) EXPECT_EQ(got[c], own[c]) << c;
  EXPECT_EQ(tree.answer(kCentre).label, 0);

  tree.updateNode(offset(1, 0, 0), false);  // the mover has left
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  EXPECT_EQ(got[0], tree.rule().prior());
  EXPECT_EQ(got[1], own[1]);
  EXPECT_EQ(tree.answer(kCentre).label, 1);
  // A static class stays, and so does a movable one in a map that does not clear movers.
  tree.setMovableClasses({false, false, false});
  EXPECT_EQ(tree.answer(kCentre).label, 0);
  tree.setMovableClasses({true, false, false});
  SemanticConfig keeps_movers;
  keeps_movers.movable_clearing_observations = 0;
  tree.setConfig(keeps_movers);
  EXPECT_EQ(tree.answer(kCentre).label, 0);
}

// An occupied voxel is the surface: it answers its own movable class whatever is beside it.
TEST(FreeVoxelEvidence, AnOccupiedVoxelKeepsItsMovableClass) {
  EvidentialOcTree tree(kRes, kClasses, SemanticConfig());
  tree.setMovableClasses({true, false, false});
  addVoxel(tree, kCentre, {2.0f, 1.0f, 0.0f});
  detail::TreeEditing::updateInnerNodes(tree);
  ASSERT_TRUE(tree.isNodeOccupied(tree.search(kCentre)));
  EXPECT_EQ(tree.answer(kCentre).label, 0);
}

TEST_F(QuerySupport, TheAnswerDoesNotDiscountAPointsReliabilityTwice) {
  // The same stored evidence answers the same whatever sigma0 the map was made with: sigma0
  // discounted each point where it was fused.
  float reference[kClasses], got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, reference));
  for (double sigma0 : {0.3, 0.7, 1.0}) {
    SemanticConfig config = surfaceOnly();
    config.sigma0 = sigma0;
    tree.setConfig(config);
    ASSERT_TRUE(tree.answerPayload(kCentre, got));
    for (int c = 0; c < kClasses; ++c) EXPECT_EQ(got[c], reference[c]) << sigma0 << " " << c;
  }
}

TEST_F(QuerySupport, AFlatterSupportReachesLessFarUp) {
  // vertical_support 0.25: the voxel two below is 0.3 m / 0.25 = 1.2 m away for the kernel,
  // beyond the support; the one beside it stays 0.1 m away and answers alone.
  SemanticConfig config = surfaceOnly();
  config.vertical_support = 0.25;
  tree.setConfig(config);
  ASSERT_GT(0.3 / 0.25, supportLength());
  const double k_near = kernelAt(0.1);
  std::vector<float> expected(kClasses);
  for (int c = 0; c < kClasses; ++c) expected[c] = float(k_near * near_values[c]);
  float got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  for (int c = 0; c < kClasses; ++c) EXPECT_NEAR(got[c], expected[c], 1e-5) << c;
}

TEST_F(QuerySupport, AGroundNeighbourReachesAsFarUpAsItsPoints) {
  // ground_vertical_support 0.25 for class 1 (the voxel two below): it no longer reaches the
  // query voxel, and the one beside it answers alone; with class 0 (the one beside) ground
  // instead, nothing changes, since it lies level with the query voxel.
  SemanticConfig config = surfaceOnly();
  config.ground_vertical_support = 0.25;
  tree.setConfig(config);
  float ball[kClasses], got[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, ball));
  tree.setGroundClasses({false, true, false});
  const double k_near = kernelAt(0.1);
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  for (int c = 0; c < kClasses; ++c) EXPECT_NEAR(got[c], k_near * near_values[c], 1e-5) << c;
  tree.setGroundClasses({true, false, false});
  ASSERT_TRUE(tree.answerPayload(kCentre, got));
  for (int c = 0; c < kClasses; ++c) EXPECT_EQ(got[c], ball[c]) << c;
  EXPECT_NE(ball[1], 0.0f) << "the voxel below reaches the query voxel with a ball";
}

TEST_F(QuerySupport, VoxelWithEvidenceAnswersItsOwnOnly) {
  expectOpinionOf(tree, tree.query(tree.keyToCoord(offset(1, 0, 0))), near_values);
  expectOpinionOf(tree, tree.query(tree.keyToCoord(offset(0, 0, -2))), far_values);
}

TEST_F(QuerySupport, UnknownSpaceAndVoxelsBeyondTheSupportHaveNoAnswer) {
  float values[kClasses];
  EXPECT_FALSE(tree.answerPayload(offset(0, 1, 0), values));  // unknown, next to evidence
  EXPECT_EQ(tree.query(tree.keyToCoord(offset(0, 1, 0))).label, -1);
  EXPECT_FALSE(tree.answerPayload(offset(10, 0, 0), values));  // known, 1.7 m from evidence
  EXPECT_EQ(tree.query(tree.keyToCoord(offset(10, 0, 0))).label, -1);
  EXPECT_EQ(tree.query(octomap::point3d(NAN, 0, 0)).label, -1);
}

TEST_F(QuerySupport, TheNodesOwnOpinionStaysWithoutTheSupportAnswer) {
  // opinion(node) and query(key, depth) read what the voxel stores: nothing here.
  EXPECT_EQ(tree.opinion(tree.search(kCentre)).label, -1);
  EXPECT_EQ(tree.query(kCentre).label, -1);
}

TEST_F(QuerySupport, AMapWithEvidenceOffTheSurfaceAnswersOnlyWhatAVoxelHolds) {
  // The default map keeps evidence in free space near surfaces itself: a voxel without any
  // (beyond every support, or cleared) has no answer there.
  tree.setConfig(SemanticConfig());
  float values[kClasses];
  EXPECT_FALSE(tree.answerPayload(kCentre, values));
  EXPECT_EQ(tree.query(tree.keyToCoord(kCentre)).label, -1);
  expectOpinionOf(tree, tree.query(tree.keyToCoord(offset(1, 0, 0))), near_values);
}

TEST_F(QuerySupport, ASavedMapAnswersFreeSpaceAfterLoadingAsBefore) {
  // The .ot file says the map keeps its evidence on the surface; OctoMap's generic reader
  // gives back a map that answers the known voxel without evidence as the saved one did.
  float before[kClasses], after[kClasses];
  ASSERT_TRUE(tree.answerPayload(kCentre, before));
  std::stringstream file;
  ASSERT_TRUE(tree.write(file));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(file));
  const auto* loaded = dynamic_cast<const EvidentialOcTree*>(read.get());
  ASSERT_NE(loaded, nullptr);
  EXPECT_TRUE(loaded->config().semantic_occupied_only);
  ASSERT_TRUE(loaded->answerPayload(kCentre, after));
  for (int c = 0; c < kClasses; ++c) EXPECT_EQ(after[c], before[c]) << c;
}

TEST(QuerySupportMerge, AnswersOfAMergedMapAreThoseOfItsSummedEvidence) {
  // The answer is read from the stored sums, so merging maps and then querying equals querying
  // one map holding the summed evidence.
  EvidentialOcTree a(kRes, kClasses, surfaceOnly()), b(kRes, kClasses, surfaceOnly()),
      sum(kRes, kClasses, surfaceOnly());
  addVoxel(a, offset(1, 0, 0), {1.0f, 0.5f, 0.0f});
  addVoxel(b, offset(1, 0, 0), {0.0f, 1.0f, 0.0f});
  addVoxel(b, offset(-1, 0, 0), {0.0f, 0.0f, 2.0f});
  addVoxel(sum, offset(1, 0, 0), {1.0f, 1.5f, 0.0f});
  addVoxel(sum, offset(-1, 0, 0), {0.0f, 0.0f, 2.0f});
  for (EvidentialOcTree* t : {&a, &b, &sum}) {
    addVoxel(*t, kCentre);
    detail::TreeEditing::updateInnerNodes(*t);
  }
  a.merge(b);
  float merged[kClasses], summed[kClasses];
  ASSERT_TRUE(a.answerPayload(kCentre, merged));
  ASSERT_TRUE(sum.answerPayload(kCentre, summed));
  for (int c = 0; c < kClasses; ++c) EXPECT_FLOAT_EQ(merged[c], summed[c]) << c;
}

}  // namespace
}  // namespace evidential_octomap
