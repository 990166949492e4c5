// The three fusion rules behind FusionRule. The dempster rule stores evidence-space sums
// (docs/design.md, "Fusion"); these tests check it against sequential belief-space
// combination of the extended beliefs, in both orders, at the rule, tree and integrator level,
// and over 10^6 fusions into one voxel beside a naive float belief-space rule that fails.
#include <gtest/gtest.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/fusion_rule.h"
#include "evidential_octomap/subjective_logic.h"
#include "random_masses.h"
#include "reference_dempster.h"

namespace evidential_octomap {
namespace {

using test::RandomMasses;
using test::RefOpinion;

constexpr double kPi = 3.14159265358979323846;

PointOpinion pointOpinion(const std::vector<float>& e) {
  PointOpinion p;
  p.evidence = e.data();
  const int num_classes = static_cast<int>(e.size());
  p.strength = num_classes;
  float best = 0.0f;
  for (int c = 0; c < num_classes; ++c) {
    p.strength += e[c];
    if (e[c] > best) {
      best = e[c];
      p.argmax = c;
    }
  }
  p.uncertainty = num_classes / p.strength;
  return p;
}

// Applies one point to a payload the way the map does: increments first, then the rule's add.
void fuse(const FusionRule& rule, const std::vector<float>& e, double k, float* payload) {
  const int num_classes = static_cast<int>(e.size());
  std::vector<double> increments(num_classes, 0.0);
  rule.contribute(pointOpinion(e), k, num_classes, increments.data());
  rule.add(payload, increments.data(), num_classes);
}

// Dempster's rule read without the evidence cap: what the belief-space cross-checks compare.
SemanticConfig uncappedDempster() {
  SemanticConfig config;
  config.evidence_cap = 0.0;
  return config;
}

// Extended belief of a point at kernel value k, in the library's belief-space type.
Opinion extended(const std::vector<float>& e, double k) {
  Opinion o = opinionFromEvidence(e.data(), static_cast<int>(e.size()));
  for (double& b : o.belief) b *= k;
  o.uncertainty = 1.0 - k * (1.0 - o.uncertainty);
  return o;
}

double maxDiff(const VoxelOpinion& v, const Opinion& o) {
  double d = std::fabs(v.uncertainty - o.uncertainty);
  for (size_t c = 0; c < o.belief.size(); ++c)
    d = std::max(d, std::fabs(v.belief[c] - o.belief[c]));
  return d;
}

double maxDiff(const VoxelOpinion& v, const RefOpinion& o) {
  double d = std::fabs(double(v.uncertainty - o.uncertainty));
  for (size_t c = 0; c < o.belief.size(); ++c) {
    d = std::max(d, std::fabs(double(v.belief[c] - o.belief[c])));
  }
  return d;
}

int argmaxOf(const RefOpinion& o) {
  int best = -1;
  long double value = 0.0L;
  for (size_t c = 0; c < o.belief.size(); ++c) {
    if (o.belief[c] > value) {
      value = o.belief[c];
      best = static_cast<int>(c);
    }
  }
  return best;
}

// Closed form of the sparse kernel, written out here so the test does not use the code under test.
double kernelClosedForm(double d, double length, double sigma0) {
  if (d >= length) return 0.0;
  const double r = d / length;
  const double k =
      sigma0 * ((2 + std::cos(2 * kPi * r)) / 3 * (1 - r) + std::sin(2 * kPi * r) / (2 * kPi));
  return std::min(1.0, std::max(0.0, k));
}

// --- rule level -----------------------------------------------------------------------------

TEST(DempsterRule, EvidenceSpaceAgreesWithBeliefSpaceInBothOrders) {
  const auto rule = FusionRule::create("dempster");
  for (int num_classes : {1, 2, 3, 20}) {
    RandomMasses rnd(100 + num_classes);
    double worst = 0.0;
    for (int trial = 0; trial < 500; ++trial) {
      const int n = rnd.integer(1, 6);
      std::vector<std::vector<float>> evidence;
      std::vector<double> kernel;
      for (int i = 0; i < n; ++i) {
        evidence.push_back(rnd.evidence(num_classes, 3.0));
        const int kind = rnd.integer(0, 3);
        kernel.push_back(kind == 0 ? 1.0 : kind == 1 ? 0.0 : rnd.uniform(0.0, 1.0));
      }
      std::vector<float> payload(num_classes, rule->prior());
      for (int i = 0; i < n; ++i) fuse(*rule, evidence[i], kernel[i], payload.data());
      const VoxelOpinion voxel = rule->readout(payload.data(), num_classes);

      Opinion forward = Opinion::vacuous(num_classes), backward = Opinion::vacuous(num_classes);
      for (int i = 0; i < n; ++i)
        forward = dempsterCombine(forward, extended(evidence[i], kernel[i]));
      for (int i = n - 1; i >= 0; --i) {
        backward = dempsterCombine(backward, extended(evidence[i], kernel[i]));
      }
      ASSERT_EQ(voxel.belief.size(), size_t(num_classes));
      const double d = std::max(maxDiff(voxel, forward), maxDiff(voxel, backward));
      ASSERT_LE(d, 1e-6) << "C = " << num_classes << ", trial " << trial << ", n = " << n;
      worst = std::max(worst, d);
      if (forward.argmax() >= 0 && voxel.label >= 0) {
        // Beliefs may tie within float precision; the label must carry (one of) the largest.
        EXPECT_NEAR(voxel.belief[voxel.label], forward.belief[forward.argmax()], 1e-6);
      }
    }
    RecordProperty("worst_diff_C" + std::to_string(num_classes), std::to_string(worst));
  }
}

// The projection the Brier score, the ECE and the error probability use, by hand.
TEST(FusionRules, ErrorProbabilityIsOneMinusTheLargestProjectedProbability) {
  VoxelOpinion o;
  o.label = 0;
  o.belief = {0.5f, 0.2f, 0.1f};
  o.uncertainty = 0.2f;  // dempster: p = b + u / 3
  const auto dempster = FusionRule::create(FusionRuleType::kDempster);
  const std::vector<float> p = dempster->probabilities(o);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR(p[1], 0.2 + 0.2 / 3, 1e-6);
  EXPECT_NEAR(dempster->errorProbability(o), 1.0 - (0.5 + 0.2 / 3), 1e-6);
  const auto sbki = FusionRule::create(FusionRuleType::kSbki);  // belief: alpha / S itself
  EXPECT_NEAR(sbki->errorProbability(o), 0.5, 1e-6);
  EXPECT_EQ(dempster->errorProbability(VoxelOpinion()), 1.0f);  // no label: none is right
  o.label = -1;
  EXPECT_EQ(dempster->errorProbability(o), 1.0f);
}

TEST(DempsterRule, ContributionMatchesHandComputation) {
  const auto rule = FusionRule::create("dempster");
  EXPECT_EQ(rule->prior(), 0.0f);  // L = 0: the vacuous opinion
  // e = (2, 0), C = 2, S = 4: b = (0.5, 0), u = 0.5. At k = 1: log1p(b/u) = (ln 2, 0).
  std::vector<float> e{2.0f, 0.0f};
  std::vector<double> inc(2, 0.0);
  rule->contribute(pointOpinion(e), 1.0, 2, inc.data());
  EXPECT_NEAR(inc[0], std::log(2.0), 1e-12);
  EXPECT_EQ(inc[1], 0.0);
  // At k = 0.5: b~ = (0.25, 0), u~ = 1 - 0.5 * 0.5 = 0.75, log1p(1/3). Increments accumulate.
  rule->contribute(pointOpinion(e), 0.5, 2, inc.data());
  EXPECT_NEAR(inc[0], std::log(2.0) + std::log1p(1.0 / 3.0), 1e-12);
  // k = 0 contributes nothing.
  rule->contribute(pointOpinion(e), 0.0, 2, inc.data());
  EXPECT_NEAR(inc[0], std::log(2.0) + std::log1p(1.0 / 3.0), 1e-12);
}

TEST(DempsterRule, KernelAboveOneIsClampedToTheFullOpinion) {
  // sigma0 > 1 can give k > 1; the extended belief k b is an opinion only for k <= 1, so the
  // rule uses k = 1: e = (2, 0), C = 2 gives log1p(b/u) = ln 2 at k = 1, 2 and 7.
  const auto rule = FusionRule::create("dempster");
  std::vector<float> e{2.0f, 0.0f};
  for (double k : {1.0, 2.0, 7.0}) {
    std::vector<double> inc(2, 0.0);
    rule->contribute(pointOpinion(e), k, 2, inc.data());
    EXPECT_NEAR(inc[0], std::log(2.0), 1e-12) << "k = " << k;
    EXPECT_EQ(inc[1], 0.0);
  }
}

TEST(DempsterRule, ConflictOfHandComputedPayloads) {
  const auto rule = FusionRule::create("dempster");
  // One class only: -ln u = ln(e^2) = 2 = sum L, no conflict.
  const std::vector<float> one{2.0f, 0.0f, 0.0f};
  EXPECT_NEAR(rule->readout(one.data(), 3).conflict, 0.0, 1e-6);
  // L = (1, 1): 1/u = 2e - 1, conflict = 1 - ln(2e - 1) / 2.
  const std::vector<float> two{1.0f, 1.0f};
  EXPECT_NEAR(rule->readout(two.data(), 2).conflict, 1.0 - std::log(2 * std::exp(1.0) - 1) / 2,
              1e-6);
  // Vacuous: no evidence, no conflict.
  const std::vector<float> none{0.0f, 0.0f};
  EXPECT_EQ(rule->readout(none.data(), 2).conflict, 0.0f);
}

TEST(DempsterRule, ConflictIsTheAccumulatedDempsterConflictOfOneHotInputs) {
  // Sequential belief-space fusion in long double: the normaliser of each step is
  // 1 - delta = 1 - sum_{i != j} b1^i b2^j (reference_dempster.h). The map's conflict times the
  // log-evidence brought in must equal -sum ln(1 - delta).
  const int num_classes = 3;
  RandomMasses rnd(41);
  const auto rule = FusionRule::create("dempster");
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> payload(num_classes, 0.0f);
    test::RefOpinion fused = test::refVacuous(num_classes);
    long double lost = 0.0L;
    for (int i = 0; i < 12; ++i) {
      std::vector<float> e(num_classes, 0.0f);
      e[size_t(rnd.uniform(0.0, 1.0) < 0.7 ? 0 : 1 + (i % 2))] = float(rnd.uniform(0.5, 10.0));
      const double k = rnd.uniform(0.2, 1.0);
      fuse(*rule, e, k, payload.data());
      const test::RefOpinion m = test::refExtend(test::refFromEvidence(e), k);
      long double delta = 0.0L;
      for (int a = 0; a < num_classes; ++a)
        for (int b = 0; b < num_classes; ++b)
          if (a != b) delta += fused.belief[a] * m.belief[b];
      lost -= std::log(1.0L - delta);
      fused = test::refCombine(fused, m);
    }
    double total = 0.0;
    for (float l : payload) total += l;
    const VoxelOpinion voxel = rule->readout(payload.data(), num_classes);
    EXPECT_NEAR(voxel.conflict * total, double(lost), 1e-4 * total) << "trial " << trial;
  }
}

TEST(DirichletRules, ConflictIsTheShareOfCountsOffTheLabel) {
  for (const std::string name : {"sbki", "ebs"}) {
    const auto rule = FusionRule::create(name);
    const float prior = rule->prior();
    // Added counts (3, 1, 0): label 0, conflict 1 / 4.
    const std::vector<float> alpha{prior + 3.0f, prior + 1.0f, prior};
    const VoxelOpinion v = rule->readout(alpha.data(), 3);
    EXPECT_EQ(v.label, 0) << name;
    EXPECT_NEAR(v.conflict, 0.25, 1e-6) << name;
    const std::vector<float> untouched(3, prior);
    EXPECT_EQ(rule->readout(untouched.data(), 3).conflict, 0.0f) << name;
  }
}

TEST(DempsterRule, ReadoutOfHandComputedPayload) {
  const auto rule = FusionRule::create("dempster");
  // L = (ln 3, ln 2, 0): u = 1 / (3 + 2 + 1 - 3 + 1) = 1/4, b = (2/4, 1/4, 0).
  const float payload[3] = {float(std::log(3.0)), float(std::log(2.0)), 0.0f};
  const VoxelOpinion v = rule->readout(payload, 3);
  EXPECT_EQ(v.label, 0);
  EXPECT_NEAR(v.uncertainty, 0.25, 1e-6);
  ASSERT_EQ(v.belief.size(), 3u);
  EXPECT_NEAR(v.belief[0], 0.5, 1e-6);
  EXPECT_NEAR(v.belief[1], 0.25, 1e-6);
  EXPECT_NEAR(v.belief[2], 0.0, 1e-7);
  // The prior payload reads as the vacuous opinion with no label.
  const float vacuous[3] = {0.0f, 0.0f, 0.0f};
  const VoxelOpinion none = rule->readout(vacuous, 3);
  EXPECT_EQ(none.label, -1);
  EXPECT_EQ(none.uncertainty, 1.0f);
}

TEST(DempsterRule, ReadoutOfHugePayloadDoesNotOverflow) {
  const auto rule = FusionRule::create("dempster");
  // e^1e6 overflows any float or double: the read-out must subtract the max (log-sum-exp).
  const float payload[3] = {1e6f, 1e6f - 1.0f, 10.0f};
  const VoxelOpinion v = rule->readout(payload, 3);
  ASSERT_TRUE(std::isfinite(v.uncertainty));
  for (float b : v.belief) ASSERT_TRUE(std::isfinite(b));
  EXPECT_EQ(v.label, 0);
  // b0 / b1 = (e^L0 - 1) / (e^L1 - 1) = e (to double precision), u ~ 0.
  EXPECT_NEAR(v.belief[0], std::exp(1.0) / (1 + std::exp(1.0)), 1e-6);
  EXPECT_NEAR(v.belief[1], 1.0 / (1 + std::exp(1.0)), 1e-6);
  EXPECT_NEAR(v.belief[0] + v.belief[1] + v.belief[2] + v.uncertainty, 1.0, 1e-6);
}

// --- tree level: payloads in the map, read through EvidentialOcTree::query ------------------

TEST(DempsterRule, MapPayloadAgreesWithBeliefSpaceInBothOrders) {
  for (int num_classes : {2, 7, 20}) {
    RandomMasses rnd(200 + num_classes);
    EvidentialOcTree tree(0.2, num_classes, uncappedDempster());
    const octomap::OcTreeKey key = tree.coordToKey(octomap::point3d(1.0f, 2.0f, 0.5f));
    EvidentialOcTreeNode* node = detail::TreeEditing::leafForUpdate(tree, key, true);
    ASSERT_NE(node, nullptr);
    EXPECT_TRUE(tree.payload(node).empty());
    std::vector<float> payload(num_classes, tree.rule().prior());

    std::vector<std::vector<float>> evidence;
    std::vector<double> kernel;
    for (int i = 0; i < 8; ++i) {
      evidence.push_back(rnd.evidence(num_classes, 3.0));
      kernel.push_back(i % 2 ? 1.0 : rnd.uniform(0.0, 1.0));
      fuse(tree.rule(), evidence.back(), kernel.back(), payload.data());
    }
    detail::TreeEditing::setPayload(tree, node, payload.data());
    detail::TreeEditing::updateInnerNodes(tree);
    node = tree.search(key);
    ASSERT_NE(node, nullptr);
    ASSERT_TRUE(node->hasSemantics());
    const VoxelOpinion voxel = tree.query(key);
    Opinion forward = Opinion::vacuous(num_classes), backward = Opinion::vacuous(num_classes);
    for (size_t i = 0; i < evidence.size(); ++i) {
      forward = dempsterCombine(forward, extended(evidence[i], kernel[i]));
      const size_t j = evidence.size() - 1 - i;
      backward = dempsterCombine(backward, extended(evidence[j], kernel[j]));
    }
    EXPECT_LE(maxDiff(voxel, forward), 1e-6) << "C = " << num_classes;
    EXPECT_LE(maxDiff(voxel, backward), 1e-6) << "C = " << num_classes;
    EXPECT_EQ(voxel.label, forward.argmax());
    // Point and key queries agree.
    const VoxelOpinion by_point = tree.query(tree.keyToCoord(key));
    EXPECT_EQ(by_point.label, voxel.label);
    EXPECT_EQ(by_point.belief, voxel.belief);
  }
}

// --- integrator level: single-point scans, kernel value sigma0 at the voxel centre ----------

TEST(DempsterRule, IntegratedScansAgreeWithBeliefSpaceInBothOrders) {
  const int num_classes = 4;
  RandomMasses rnd(300);
  SemanticConfig config = uncappedDempster();
  config.adaptive_length = true;         // the expected supports below are adaptive
  config.uncertainty_threshold = false;  // one point per scan: nothing to drop
  config.ds_multiplier = 0.0;            // keep the point exactly where it is
  config.kernel_creates_leaves = true;   // the voxel above is unknown space
  EvidentialOcTree probe(0.2, num_classes, config);
  const octomap::OcTreeKey key = probe.coordToKey(octomap::point3d(0.1f, 0.1f, 0.1f));
  const octomap::point3d centre = probe.keyToCoord(key);
  const octomap::OcTreeKey above_key(key[0], key[1], key[2] + 1);
  const octomap::point3d above = probe.keyToCoord(above_key);  // 0.2 m above, off the ray
  ASSERT_NEAR((above - centre).norm(), 0.2, 1e-6);
  // kernel_distance "voxel": from the point (the own voxel's centre) to the cube above is half
  // a voxel; "centre": the 0.2 m between the centres.
  const double d_above = config.kernel_distance == "voxel" ? 0.1 : 0.2;

  std::vector<std::vector<float>> evidence;
  for (int i = 0; i < 6; ++i) evidence.push_back(rnd.evidence(num_classes, 3.0));
  // One nearly certain point so that the neighbour above lies inside its support:
  // u = 4 / (40 + 4) -> L = 0.3 e^{1 - 3/11} > 0.2.
  evidence.push_back({40.0f, 0.0f, 0.0f, 0.0f});

  auto build = [&](bool reverse) {
    auto tree = std::make_unique<EvidentialOcTree>(0.2, num_classes, config);
    for (size_t n = 0; n < evidence.size(); ++n) {
      const size_t i = reverse ? evidence.size() - 1 - n : n;
      octomap::Pointcloud scan;
      scan.push_back(centre);
      const InsertStats stats =
          tree->insertSemanticScan(scan, evidence[i], octomap::point3d(-3.0f, 0.1f, 0.1f));
      EXPECT_EQ(stats.points_in, 1u);
      EXPECT_EQ(stats.points_skipped, 0u);
      EXPECT_EQ(stats.points_dropped_uncertain, 0u);
    }
    return tree;
  };
  const auto forward_tree = build(false);
  const auto backward_tree = build(true);

  Opinion expected = Opinion::vacuous(num_classes), expected_above = Opinion::vacuous(num_classes);
  for (const auto& e : evidence) {
    // The own voxel gets the kernel's value at d = 0, sigma0 (the point's reliability).
    expected = dempsterCombine(expected, extended(e, config.sigma0));
    const double u = opinionFromEvidence(e.data(), num_classes).uncertainty;
    const double support = 0.3 * 1.0 * std::exp(1.0 - 3.0 * u);  // l beta e^{1 - gamma u}
    expected_above = dempsterCombine(
        expected_above, extended(e, kernelClosedForm(d_above, support, config.sigma0)));
  }
  ASSERT_LT(expected_above.uncertainty, 1.0);  // the neighbour did receive evidence
  for (const auto* tree : {forward_tree.get(), backward_tree.get()}) {
    const VoxelOpinion voxel = tree->query(key);
    EXPECT_LE(maxDiff(voxel, expected), 1e-6);
    EXPECT_EQ(voxel.label, expected.argmax());
    EXPECT_TRUE(tree->isNodeOccupied(tree->search(key)));
    const VoxelOpinion neighbour = tree->query(above_key);
    EXPECT_LE(maxDiff(neighbour, expected_above), 1e-6);
  }
}

// --- 10^6 fusions into one voxel, beside a naive float belief-space rule --------------------

struct NaiveFloatOpinion {
  std::vector<float> belief;
  float uncertainty = 1.0f;
};

// The belief-space rule as one would write it first: floats, O(C) conflict, no rescaling.
NaiveFloatOpinion naiveCombine(const NaiveFloatOpinion& m1, const std::vector<float>& e) {
  const int num_classes = static_cast<int>(e.size());
  float strength = static_cast<float>(num_classes);
  for (float x : e) strength += x;
  NaiveFloatOpinion m2;
  for (float x : e) m2.belief.push_back(x / strength);
  m2.uncertainty = num_classes / strength;
  float sum1 = 0, sum2 = 0, agree = 0;
  for (int c = 0; c < num_classes; ++c) {
    sum1 += m1.belief[c];
    sum2 += m2.belief[c];
    agree += m1.belief[c] * m2.belief[c];
  }
  const float norm = 1.0f - (sum1 * sum2 - agree);
  NaiveFloatOpinion out;
  for (int c = 0; c < num_classes; ++c) {
    out.belief.push_back((m1.belief[c] * m2.belief[c] + m1.belief[c] * m2.uncertainty +
                          m2.belief[c] * m1.uncertainty) /
                         norm);
  }
  out.uncertainty = m1.uncertainty * m2.uncertainty / norm;
  return out;
}

// --- float absorption: the map's float payload against the rule in long double

// One voxel updated the way the map updates it (rule.add of a scan's increments), beside the
// long-double reference of the same rule (bounded storage, capped read-out).
struct BoundedVoxel {
  std::unique_ptr<FusionRule> rule;
  std::vector<float> payload;
  test::RefBoundedEvidence reference;
  BoundedVoxel(int num_classes, double cap)
      : rule(FusionRule::create(FusionRuleType::kDempster, 0.001f, cap)),
        payload(num_classes, 0.0f),
        reference(num_classes, kMaxStoredLogEvidence, cap) {}
  void add(const std::vector<double>& increments) {
    rule->add(payload.data(), increments.data(), static_cast<int>(payload.size()));
    reference.add(std::vector<long double>(increments.begin(), increments.end()));
  }
  VoxelOpinion opinion() const { return rule->readout(payload.data(), int(payload.size())); }
};

TEST(FloatAbsorption, TieBrokenBySmallIncrementsAtTheBound) {
  // Both classes fill the voxel to the bound (L = 512 each), then 1000 scans add 0.005 to class
  // 1 only. Unbounded floats at L ~ 2^18 lost every one of them (label 0 at b = 0.5 / 0.5); the
  // rule as defined ends at L1 - L0 ~ 4.99, b1 ~ 0.9932 uncapped.
  for (double cap : {0.0, 3.0}) {
    BoundedVoxel voxel(2, cap);
    for (int i = 0; i < 20000; ++i) voxel.add({1.0, 1.0});
    for (int i = 0; i < 1000; ++i) voxel.add({0.0, 0.005});
    const RefOpinion expected = voxel.reference.opinion();
    const VoxelOpinion got = voxel.opinion();
    ASSERT_EQ(argmaxOf(expected), 1);
    EXPECT_EQ(got.label, 1) << "cap " << cap;
    EXPECT_LE(maxDiff(got, expected), 2e-4) << "cap " << cap;
    if (cap == 0.0) {
      EXPECT_NEAR(got.belief[1], 0.9932, 1e-3);
    }
  }
}

TEST(FloatAbsorption, DominantClassIsOvertakenWhenTheReferenceIsOvertaken) {
  // Class 0 saturates the voxel; then scans favouring class 1 arrive. The label must flip at the
  // very scan the long-double rule flips, and the beliefs follow it throughout.
  for (double cap : {0.0, 3.0}) {
    BoundedVoxel voxel(3, cap);
    for (int i = 0; i < 5000; ++i) voxel.add({2.0, 0.01, 0.0});
    int flipped_at = -1, reference_flipped_at = -1;
    double worst = 0.0;
    for (int i = 0; i < 2000; ++i) {
      voxel.add({0.05, 1.0, 0.0});
      const VoxelOpinion got = voxel.opinion();
      const RefOpinion expected = voxel.reference.opinion();
      if (flipped_at < 0 && got.label == 1) flipped_at = i;
      if (reference_flipped_at < 0 && argmaxOf(expected) == 1) reference_flipped_at = i;
      worst = std::max(worst, maxDiff(got, expected));
    }
    ASSERT_GE(reference_flipped_at, 0);
    EXPECT_EQ(flipped_at, reference_flipped_at) << "cap " << cap;
    EXPECT_LE(worst, 2e-4) << "cap " << cap;
  }
}

TEST(FloatAbsorption, MillionFusionsIntoOneVoxelFollowTheRule) {
  // 10^6 point contributions (k in [0.5, 1]) into one map voxel, read through the tree; class 2
  // dominates noisily. Checked against the long-double rule at every power of ten.
  const int num_classes = 4;
  const int kFusions = 1000000;
  const int kTrue = 2;
  RandomMasses rnd(400);
  EvidentialOcTree tree(0.2, num_classes);  // the default read-out cap
  const octomap::OcTreeKey key = tree.coordToKey(octomap::point3d(0.0f, 0.0f, 0.0f));
  EvidentialOcTreeNode* leaf = detail::TreeEditing::leafForUpdate(tree, key, true);
  std::vector<float> payload(num_classes, tree.rule().prior());
  test::RefBoundedEvidence reference(num_classes, kMaxStoredLogEvidence,
                                     tree.effectiveEvidenceCap());
  const auto uncapped = FusionRule::create(FusionRuleType::kDempster);
  int next_check = 1;
  for (int n = 1; n <= kFusions; ++n) {
    std::vector<float> e(num_classes);
    for (float& x : e) x = static_cast<float>(rnd.uniform(0.0, 1.0));
    e[kTrue] += static_cast<float>(rnd.uniform(1.0, 3.0));
    const double k = rnd.uniform(0.5, 1.0);
    std::vector<double> increments(num_classes, 0.0);
    tree.rule().contribute(pointOpinion(e), k, num_classes, increments.data());
    tree.rule().add(payload.data(), increments.data(), num_classes);
    detail::TreeEditing::setPayload(tree, leaf, payload.data());
    reference.add(std::vector<long double>(increments.begin(), increments.end()));
    if (n == next_check || n == kFusions) {
      next_check *= 10;
      const VoxelOpinion v = tree.query(key);
      double sum = v.uncertainty;
      for (float b : v.belief) sum += b;
      EXPECT_NEAR(sum, 1.0, 1e-6) << "after " << n << " fusions";
      EXPECT_LE(maxDiff(v, reference.opinion()), 1e-5) << "after " << n << " fusions";
      if (n >= 10) {
        EXPECT_EQ(v.label, kTrue) << "after " << n << " fusions";
      }
      double stored = 0.0;
      for (int c = 0; c < num_classes; ++c) stored += payload[c];
      EXPECT_LE(stored, kMaxStoredLogEvidence * (1 + 1e-6));
    }
  }
  // Read without the cap, the saturated voxel is as certain as floats can say: u ~ e^-1024 = 0.
  const VoxelOpinion raw = uncapped->readout(tree.payload(leaf).data(), num_classes);
  EXPECT_EQ(raw.label, kTrue);
  EXPECT_NEAR(raw.belief[kTrue], 1.0, 1e-6);
}

TEST(EvidenceCap, ReadsTheOpinionOfTheCappedLogEvidence) {
  // L = (6, 3, 0), cap 3: read as L = (2, 1, 0): u = 1 / (e^2 + e + 1 - 3 + 1),
  // b = (e^2 - 1, e - 1, 0) u. The label and the conflict are those of the uncapped payload.
  const auto capped = FusionRule::create(FusionRuleType::kDempster, 0.001f, 3.0);
  const auto raw = FusionRule::create(FusionRuleType::kDempster);
  const float payload[3] = {6.0f, 3.0f, 0.0f};
  const VoxelOpinion v = capped->readout(payload, 3);
  const double e = std::exp(1.0), u = 1.0 / (e * e + e - 1);
  EXPECT_EQ(v.label, 0);
  EXPECT_NEAR(v.uncertainty, u, 1e-6);
  EXPECT_NEAR(v.belief[0], (e * e - 1) * u, 1e-6);
  EXPECT_NEAR(v.belief[1], (e - 1) * u, 1e-6);
  EXPECT_EQ(v.conflict, raw->readout(payload, 3).conflict);
  // Below the cap nothing changes.
  const float small[3] = {1.0f, 0.5f, 0.0f};
  EXPECT_EQ(capped->readout(small, 3).belief, raw->readout(small, 3).belief);
}

TEST(DempsterRule, NaiveFloatBeliefRuleFailsWhereEvidenceSpaceDoesNot) {
  // 200 fusions of (4, 1) evidence, then 400 of (1, 4) evidence (C = 2, k = 1).
  // Exactly: L = (200 ln 3 + 400 ln 1.5, 200 ln 1.5 + 400 ln 3), so class 1 wins by e^{200 ln 2}.
  const int num_classes = 2;
  const std::vector<float> for0{4.0f, 1.0f}, for1{1.0f, 4.0f};
  const auto rule = FusionRule::create("dempster");
  std::vector<float> payload(num_classes, rule->prior());
  test::RefEvidenceSum reference(num_classes);
  NaiveFloatOpinion naive;
  naive.belief.assign(num_classes, 0.0f);
  RefOpinion exact = test::refVacuous(num_classes);  // sequential long-double belief space

  for (int i = 0; i < 200; ++i) {
    fuse(*rule, for0, 1.0, payload.data());
    reference.add(test::refFromEvidence(for0));
    exact = test::refCombine(exact, test::refFromEvidence(for0));
    naive = naiveCombine(naive, for0);
  }
  // The naive float rule has lost its uncertainty and the minority class altogether.
  EXPECT_EQ(naive.uncertainty, 0.0f);
  EXPECT_EQ(naive.belief[1], 0.0f);
  EXPECT_GT(exact.uncertainty, 0.0L);
  EXPECT_GT(exact.belief[1], 0.0L);

  for (int i = 0; i < 400; ++i) {
    fuse(*rule, for1, 1.0, payload.data());
    reference.add(test::refFromEvidence(for1));
    exact = test::refCombine(exact, test::refFromEvidence(for1));
    naive = naiveCombine(naive, for1);
  }
  const RefOpinion expected = reference.opinion();
  ASSERT_EQ(argmaxOf(expected), 1);
  ASSERT_EQ(argmaxOf(exact), 1);  // the two references agree
  // The naive rule can never change its mind again; the evidence-space map does.
  const float naive_sum = naive.belief[0] + naive.belief[1] + naive.uncertainty;
  const bool naive_right = naive.belief[1] > naive.belief[0] && std::fabs(naive_sum - 1.0f) < 1e-3f;
  EXPECT_FALSE(naive_right) << "naive float rule recovered: b = (" << naive.belief[0] << ", "
                            << naive.belief[1] << "), u = " << naive.uncertainty;
  const VoxelOpinion voxel = rule->readout(payload.data(), num_classes);
  EXPECT_EQ(voxel.label, 1);
  EXPECT_LE(maxDiff(voxel, expected), 1e-6);
}

// --- sbki and ebs read-outs against hand computations ----------------------------------------

TEST(SbkiRule, CountsKernelWeightedOneHotVotes) {
  const auto rule = FusionRule::create("sbki", 0.001f);
  EXPECT_EQ(rule->name(), "sbki");
  EXPECT_EQ(rule->prior(), 0.001f);
  EXPECT_FALSE(rule->usesUncertaintyKernel());
  EXPECT_FALSE(rule->uncertaintyIsMass());
  std::vector<float> payload(3, rule->prior());
  fuse(*rule, {0.0f, 1.0f, 5.0f}, 1.0, payload.data());   // argmax 2, k = 1
  fuse(*rule, {0.2f, 0.0f, 9.0f}, 0.25, payload.data());  // argmax 2, k = 0.25
  fuse(*rule, {3.0f, 1.0f, 0.0f}, 0.5, payload.data());   // argmax 0, k = 0.5
  // alpha = (0.501, 0.001, 1.251), S = 1.753
  EXPECT_NEAR(payload[0], 0.501, 1e-6);
  EXPECT_NEAR(payload[1], 0.001, 1e-6);
  EXPECT_NEAR(payload[2], 1.251, 1e-6);
  const VoxelOpinion v = rule->readout(payload.data(), 3);
  const double s = 1.753, p = 1.251 / s;
  EXPECT_EQ(v.label, 2);
  EXPECT_NEAR(v.belief[0], 0.501 / s, 1e-6);
  EXPECT_NEAR(v.belief[2], p, 1e-6);
  EXPECT_NEAR(v.uncertainty, p * (1 - p) / (s + 1), 1e-6);  // Dirichlet variance
}

TEST(SbkiRule, PriorOnlyVoxelHasNoLabel) {
  const auto rule = FusionRule::create("sbki", 0.5f);
  EXPECT_EQ(rule->prior(), 0.5f);
  const std::vector<float> payload(4, 0.5f);
  EXPECT_EQ(rule->readout(payload.data(), 4).label, -1);
}

TEST(EbsRule, AddsKernelWeightedExpectedProbabilities) {
  const auto rule = FusionRule::create("ebs");
  EXPECT_EQ(rule->name(), "ebs");
  EXPECT_EQ(rule->prior(), 1.0f);
  EXPECT_TRUE(rule->usesUncertaintyKernel());
  EXPECT_FALSE(rule->uncertaintyIsMass());
  std::vector<float> payload(3, rule->prior());
  // e = (3, 0, 1): alpha = (4, 1, 2), S = 7; k = 0.5 adds (2/7, 1/14, 1/7).
  fuse(*rule, {3.0f, 0.0f, 1.0f}, 0.5, payload.data());
  EXPECT_NEAR(payload[0], 1 + 2.0 / 7, 1e-6);
  EXPECT_NEAR(payload[1], 1 + 1.0 / 14, 1e-6);
  EXPECT_NEAR(payload[2], 1 + 1.0 / 7, 1e-6);
  const VoxelOpinion v = rule->readout(payload.data(), 3);
  const double s = 3.5, p = (9.0 / 7) / s;  // alpha sum = 3 + 0.5
  EXPECT_EQ(v.label, 0);
  EXPECT_NEAR(v.belief[0], p, 1e-6);
  EXPECT_NEAR(v.belief[1], (15.0 / 14) / s, 1e-6);
  EXPECT_NEAR(v.uncertainty, p * (1 - p) / (s + 1), 1e-6);
  const std::vector<float> prior_only(3, 1.0f);
  EXPECT_EQ(rule->readout(prior_only.data(), 3).label, -1);
}

TEST(FusionRuleFactory, CreatesEveryRuleByName) {
  for (size_t i = 0; i < kFusionRuleNames.size(); ++i) {
    const auto rule = FusionRule::create(kFusionRuleNames[i]);
    ASSERT_NE(rule, nullptr);
    EXPECT_EQ(rule->name(), kFusionRuleNames[i]);
    EXPECT_EQ(static_cast<size_t>(rule->type()), i);
    EXPECT_EQ(fusionRuleFromName(kFusionRuleNames[i]), rule->type());
  }
  EXPECT_EQ(FusionRule::create(FusionRuleType::kDempster)->name(), "dempster");
  EXPECT_TRUE(FusionRule::create("dempster")->uncertaintyIsMass());
  EXPECT_TRUE(FusionRule::create("dempster")->usesUncertaintyKernel());
}

TEST(FusionRuleFactory, UnknownNameThrowsListingValidNames) {
  try {
    FusionRule::create("nope");
    FAIL() << "no exception for an unknown rule";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("nope"), std::string::npos) << msg;
    for (const auto& name : kFusionRuleNames) EXPECT_NE(msg.find(name), std::string::npos) << msg;
  }
  EXPECT_THROW(fusionRuleFromName("Dempster"), std::invalid_argument);  // names are exact
  EXPECT_THROW(fusionRuleFromName(""), std::invalid_argument);
}

}  // namespace
}  // namespace evidential_octomap
