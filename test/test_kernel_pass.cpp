// The kernel loop's precomputed kernel (kernel_pass.h): the table's error against the closed
// form, and a whole scan's map against a direct evaluation written out here (every point, every
// voxel of its support, sparseKernel and distanceToCube called as docs/design.md states them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/sparse_kernel.h"
#include "fast_log1p.h"
#include "fusion_contributions.h"
#include "kernel_pass.h"
#include "random_masses.h"
#include "semantic_points.h"
#include "subtree_source.h"
#include "synthetic_scene.h"

namespace evidential_octomap {
namespace {

TEST(KernelTable, StaysWithinItsStatedErrorOfTheClosedForm) {
  for (double sigma0 : {1.0, 0.7, 2.5}) {
    const KernelTable table(sigma0);
    double worst = 0.0;
    for (int i = 0; i <= 2000000; ++i) {
      const double r = i / 2000000.0 * 1.01;  // past the support too
      worst = std::max(worst, std::fabs(table(r * r) - sparseKernel(r, 1.0, sigma0)));
    }
    EXPECT_LE(worst, KernelTable::kMaxError * sigma0) << "sigma0 " << sigma0;
    RecordProperty("worst_error_sigma0_" + std::to_string(sigma0), std::to_string(worst));
  }
}

using KeyTuple = std::tuple<int, int, int>;

// Each rule's increment as fusion_rule.h states it, with libm's log1p.
void contributeDirectly(FusionRuleType rule, const PointOpinion& o, double k, int num_classes,
                        double* row) {
  if (rule == FusionRuleType::kSbki) {
    if (o.argmax >= 0) row[o.argmax] += k;
    return;
  }
  for (int c = 0; c < num_classes; ++c) {
    const double e = o.evidence[c];
    if (rule == FusionRuleType::kEbs) {
      row[c] += k / o.strength * (e + 1.0);
    } else if (e > 0.0) {
      const double kc = std::min(k, 1.0);  // the extended belief's k
      row[c] += std::log1p(kc * e / (o.strength * (1.0 - kc) + kc * num_classes));
    }
  }
}

// What the map should hold after one scan into an empty map: per voxel, the rule's increments
// summed over every point and every voxel within the support, with the kernel evaluated
// directly; `bound` gets, per voxel and class, the sum over those contributions of the table's
// error times the largest derivative of the rule's increment with respect to k.
std::map<KeyTuple, std::vector<double>> directEvaluation(
    const EvidentialOcTree& tree, const test::SyntheticScan& scan, const SemanticConfig& config,
    std::map<KeyTuple, std::vector<double>>* bound) {
  const int num_classes = tree.numClasses();
  const FusionRule& rule = tree.rule();
  const double resolution = tree.getResolution(), half = resolution / 2.0;
  const double epsilon = KernelTable::kMaxError * config.sigma0;
  std::map<KeyTuple, std::vector<double>> rows;
  // other_class_weight: how many of the scan's points of each class (argmax) each voxel has,
  // and the classes it holds (two of its points, or one and one in a neighbouring voxel).
  std::map<KeyTuple, std::map<int, int>> classes_hit;
  for (size_t i = 0; i < scan.points_W.size(); ++i) {
    const float* e = &scan.evidence[i * num_classes];
    const int argmax = int(std::max_element(e, e + num_classes) - e);
    if (e[argmax] <= 0.0f) continue;
    const octomap::OcTreeKey key = tree.coordToKey(scan.points_W.getPoint(i));
    ++classes_hit[KeyTuple{key[0], key[1], key[2]}][argmax];
  }
  std::map<KeyTuple, std::set<int>> classes_held;
  for (const auto& [voxel, counts] : classes_hit) {
    for (const auto& [c, count] : counts) {
      bool beside = false;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto n = classes_hit.find(KeyTuple{
                std::get<0>(voxel) + dx, std::get<1>(voxel) + dy, std::get<2>(voxel) + dz});
            beside |= (dx || dy || dz) && n != classes_hit.end() && n->second.count(c);
          }
      if (count >= 2 || beside) classes_held[voxel].insert(c);
    }
  }
  for (size_t i = 0; i < scan.points_W.size(); ++i) {
    const octomap::point3d& p = scan.points_W.getPoint(i);
    PointOpinion o;
    o.evidence = &scan.evidence[i * num_classes];
    o.strength = num_classes;
    float best = 0.0f;
    for (int c = 0; c < num_classes; ++c) {
      o.strength += o.evidence[c];
      if (o.evidence[c] > best) {
        best = o.evidence[c];
        o.argmax = c;
      }
    }
    o.uncertainty = num_classes / o.strength;
    const float length = static_cast<float>(
        rule.usesUncertaintyKernel() ? adaptiveLength(config.length_scale, config.beta,
                                                      config.effectiveGamma(), o.uncertainty)
                                     : config.length_scale);
    const octomap::OcTreeKey centre = tree.coordToKey(p);
    const int n = static_cast<int>(std::ceil(length / resolution)) + 2;
    for (int dx = -n; dx <= n; ++dx)
      for (int dy = -n; dy <= n; ++dy)
        for (int dz = -n; dz <= n; ++dz) {
          const octomap::OcTreeKey voxel(centre[0] + dx, centre[1] + dy, centre[2] + dz);
          const octomap::point3d d = p - tree.keyToCoord(voxel);
          // Per axis the gap to the voxel's cube (or centre); z's divided by vertical_support.
          double gap[3];
          for (int a = 0; a < 3; ++a) {
            gap[a] = config.kernel_distance == "voxel" ? std::max(std::fabs(d(a)) - half, 0.0)
                                                       : std::fabs(d(a));
          }
          gap[2] /= config.vertical_support;
          const double distance =
              std::sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2]);
          double k = sparseKernel(distance, length, config.sigma0);
          const bool near_edge = distance >= length * 0.999 && distance < length * 1.001;
          if (k <= 0.0 && !near_edge) continue;
          const KeyTuple key{voxel[0], voxel[1], voxel[2]};
          const auto held = classes_held.find(key);
          if (o.argmax >= 0 && held != classes_held.end() &&
              !classes_hit.at(key).count(o.argmax)) {
            if (config.other_class_weight <= 0.0) continue;  // holds other classes only
            k *= config.other_class_weight;
          }
          auto& row = rows[key];
          auto& b = (*bound)[key];
          row.resize(num_classes, 0.0);
          b.resize(num_classes, 0.0);
          if (k > 0.0) contributeDirectly(rule.type(), o, k, num_classes, row.data());
          // Largest d(increment)/dk: dempster log1p(e k / (S - k (S - C))) has at most
          // e S / C^2; sbki k on the argmax has 1; ebs k (e + 1) / S has (e + 1) / S.
          for (int c = 0; c < num_classes; ++c) {
            const double e = o.evidence[c];
            const double slope = rule.name() == "dempster"
                                     ? e * o.strength / (num_classes * num_classes)
                                 : rule.name() == "sbki" ? (c == o.argmax ? 1.0 : 0.0)
                                                         : (e + 1.0) / o.strength;
            b[c] += slope * epsilon;
          }
        }
  }
  return rows;
}

// Every leaf of `tree` (one scan into an empty map) against directEvaluation, within its bound
// and float rounding; returns the leaves with a payload.
size_t expectWithinDirectEvaluation(EvidentialOcTree* tree, const test::SyntheticScan& scan,
                                    const SemanticConfig& config, const std::string& what) {
  std::map<KeyTuple, std::vector<double>> bound;
  const auto expected = directEvaluation(*tree, scan, config, &bound);
  tree->expand();  // every leaf at full depth
  const float prior = tree->rule().prior();
  const int num_classes = tree->numClasses();
  size_t compared = 0, with_evidence = 0;
  for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it) {
    const KeyTuple key{it.getKey()[0], it.getKey()[1], it.getKey()[2]};
    const std::vector<float> payload = tree->payload(&*it);
    const auto row = expected.find(key);
    for (int c = 0; c < num_classes; ++c) {
      const double want = row == expected.end() ? prior : float(prior + row->second[c]);
      const double got = payload.empty() ? prior : payload[c];
      const double slack = (row == expected.end() ? 0.0 : bound.at(key)[c]) +
                           2.0 * FLT_EPSILON * std::fabs(want) + 1e-30;
      EXPECT_LE(std::fabs(got - want), slack)
          << what << " voxel " << it.getKey()[0] << " " << it.getKey()[1] << " "
          << it.getKey()[2] << " class " << c;
      if (std::fabs(got - want) > slack) return with_evidence;  // one voxel's report is enough
    }
    ++compared;
    with_evidence += payload.empty() ? 0 : 1;
  }
  EXPECT_GT(compared, with_evidence) << what;
  return with_evidence;
}

TEST(KernelPass, MapStaysWithinTheTableErrorOfDirectEvaluation) {
  test::SyntheticScene scene;
  const test::SyntheticScan scan = scene.defaultScan();
  for (const std::string& rule : kFusionRuleNames) {
    for (const std::string distance :
         {"voxel", "centre", "voxel, class-aware", "voxel, other classes half",
          "voxel, vertical", "centre, vertical"}) {
      SemanticConfig config;
      config.rule = rule;
      config.kernel_distance = distance.substr(0, distance.find(','));
      if (distance.find("class-aware") != std::string::npos) config.other_class_weight = 0.0;
      if (distance.find("half") != std::string::npos) config.other_class_weight = 0.5;
      if (distance.find("vertical") != std::string::npos) config.vertical_support = 0.4;
      config.ds_multiplier = 0.0;            // every point, as the direct evaluation
      config.uncertainty_threshold = false;  // likewise
      config.length_scale = 0.45;            // supports of several voxels
      config.threads = 2;
      EvidentialOcTree tree(0.2, scene.num_classes, config);
      tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
      const size_t with_evidence =
          expectWithinDirectEvaluation(&tree, scan, config, rule + " " + distance);
      EXPECT_GT(with_evidence, 500u) << rule << " " << distance;
    }
  }
}

// A pole of a few points (class kPole) standing on a dense ground (class kGround).
constexpr int kPoleClasses = 3, kGround = 0, kPole = 1;
void poleOnGround(octomap::Pointcloud* points, std::vector<float>* evidence) {
  auto add = [&](float x, float y, float z, int label) {
    points->push_back(x, y, z);
    for (int c = 0; c < kPoleClasses; ++c) evidence->push_back(c == label ? 20.0f : 0.0f);
  };
  for (float x = -1.0f; x <= 1.0f; x += 0.04f)
    for (float y = -1.0f; y <= 1.0f; y += 0.04f) add(x, y, 0.02f, kGround);
  for (float z = 0.1f; z <= 1.2f; z += 0.1f) add(0.05f, 0.05f, z, kPole);
}

// The label of the pole's voxel just above the ground's, once the pole on its ground is mapped
// with `config` (the count cap off: it would keep a 2x2x2 block's first points only) and the
// `ground` classes; the pole's upper voxels and the ground's plane keep their class whatever
// the support.
int lowPoleLabel(SemanticConfig config, const std::vector<bool>& ground = {}) {
  octomap::Pointcloud points;
  std::vector<float> evidence;
  poleOnGround(&points, &evidence);
  config.ds_multiplier = 0.0;
  config.threads = 2;
  EvidentialOcTree tree(0.2, kPoleClasses, config);
  tree.setGroundClasses(ground);
  tree.insertSemanticScan(points, evidence, octomap::point3d(3.0f, 0.0f, 1.5f));
  EXPECT_EQ(tree.query(octomap::point3d(0.05f, 0.05f, 0.9f)).label, kPole);
  EXPECT_EQ(tree.query(octomap::point3d(0.45f, 0.05f, 0.02f)).label, kGround);
  return tree.query(octomap::point3d(0.05f, 0.05f, 0.25f)).label;
}

// When the ground's points stay out of the voxels the pole's points hold, the pole's voxels
// near the ground keep the pole's class; at full weight the ground's many points outvote it.
TEST(KernelPass, ClassAwareSupportKeepsAThinObjectsClass) {
  for (double weight : {1.0, 0.0}) {
    SemanticConfig config;
    config.other_class_weight = weight;
    const int low_pole = lowPoleLabel(config);
    EXPECT_EQ(low_pole == kPole, weight < 1.0) << "other_class_weight " << weight << ": label "
                                               << low_pole;
  }
}

// A class one point alone shows (a network's noise) does not keep its neighbours' evidence out
// of its voxel; two points of it in neighbouring voxels (a thin object) do.
TEST(KernelPass, ALonePointDoesNotHoldItsVoxelAgainstItsNeighbours) {
  for (const std::vector<float>& heights : {std::vector<float>{0.3f}, {0.3f, 0.5f}}) {
    octomap::Pointcloud points;
    std::vector<float> evidence;
    auto add = [&](float x, float y, float z, int label) {
      points.push_back(x, y, z);
      for (int c = 0; c < kPoleClasses; ++c) evidence.push_back(c == label ? 20.0f : 0.0f);
    };
    for (float x = -1.0f; x <= 1.0f; x += 0.04f)
      for (float y = -1.0f; y <= 1.0f; y += 0.04f) add(x, y, 0.02f, kGround);
    for (float z : heights) add(0.05f, 0.05f, z, kPole);
    SemanticConfig config;
    config.other_class_weight = 0.0;
    config.ds_multiplier = 0.0;
    config.threads = 2;
    EvidentialOcTree tree(0.2, kPoleClasses, config);
    tree.insertSemanticScan(points, evidence, octomap::point3d(3.0f, 0.0f, 1.5f));
    const int label = tree.query(octomap::point3d(0.05f, 0.05f, 0.3f)).label;
    EXPECT_EQ(label, heights.size() == 1 ? kGround : kPole) << heights.size() << " pole points";
  }
}

// With a support a quarter as tall as wide the ground's points no longer reach the pole's voxels
// above the ground's own.
TEST(KernelPass, FlatterSupportKeepsGroundEvidenceOffAnUprightObject) {
  for (double vertical : {1.0, 0.25}) {
    SemanticConfig config;
    config.vertical_support = vertical;
    const int low_pole = lowPoleLabel(config);
    EXPECT_EQ(low_pole == kPole, vertical < 1.0) << "vertical_support " << vertical << ": label "
                                                 << low_pole;
  }
}

// The flatter support goes to the points of the ground classes only: marking the ground as a
// ground class keeps its evidence off the pole as a flatter support for every point does;
// marking no class, or only the pole, leaves the ground's ball, which outvotes the pole.
TEST(KernelPass, GroundClassesGetTheGroundSupport) {
  std::vector<bool> ground_only(kPoleClasses, false), pole_only(kPoleClasses, false);
  ground_only[kGround] = true;
  pole_only[kPole] = true;
  SemanticConfig config;
  config.ground_vertical_support = 1.0 / 3.0;
  for (const auto& ground : {std::vector<bool>(), ground_only, pole_only}) {
    const bool ground_is_flat = !ground.empty() && ground[kGround];
    const int low_pole = lowPoleLabel(config, ground);
    EXPECT_EQ(low_pole == kPole, ground_is_flat) << "ground flat " << ground_is_flat << ": label "
                                                 << low_pole;
  }
}

TEST(KernelPass, GroundFlagsMustBeOnePerClass) {
  EvidentialOcTree tree(0.2, 3, SemanticConfig());
  EXPECT_THROW(tree.setGroundClasses({true, false}), std::invalid_argument);
  EXPECT_NO_THROW(tree.setGroundClasses({}));
}

TEST(FastLog1p, StaysWithinItsStatedErrorOfLibm) {
  EXPECT_EQ(fastLog1p(0.0), 0.0);
  double worst = 0.0;
  auto check = [&](double x) {
    const double want = std::log1p(x);
    const double error = std::fabs(fastLog1p(x) - want) / want;
    worst = std::max(worst, error);
    ASSERT_LE(error, kFastLog1pMaxError) << "x = " << x;
  };
  for (double x = 1e-300; x < 1e300; x *= 1.0001) check(x);  // every binade, 23 k per decade
  check(std::numeric_limits<double>::denorm_min());
  check(std::numeric_limits<double>::max());
  test::RandomMasses rnd(7);
  for (int i = 0; i < 1000000; ++i) check(rnd.uniform(0.0, 3.0));  // the kernel's usual range
  std::ostringstream text;
  text << worst;
  RecordProperty("worst_relative_error", text.str());
}

// 10^5 Dempster fusions of random points at random k into one payload, through the rule (fast
// log1p) and through libm's log1p written out: the stored floats stay within float rounding.
TEST(FastLog1p, StoredDempsterEvidenceStaysWithinFloatRoundingOfLibm) {
  const int num_classes = 20;
  const auto rule = FusionRule::create(FusionRuleType::kDempster);
  std::vector<float> fast(num_classes, 0.0f), libm(num_classes, 0.0f);
  test::RandomMasses rnd(11);
  int differing_steps = 0;
  for (int n = 0; n < 100000; ++n) {
    std::vector<float> e(num_classes);
    for (float& x : e) x = rnd.uniform(0.0, 1.0) < 0.3 ? float(rnd.uniform(0.0, 30.0)) : 0.0f;
    PointOpinion o;
    o.evidence = e.data();
    o.strength = num_classes;
    for (float x : e) o.strength += x;
    const double k = rnd.uniform(0.0, 1.0);
    std::vector<double> by_rule(num_classes, 0.0), by_libm(num_classes, 0.0);
    rule->contribute(o, k, num_classes, by_rule.data());
    contributeDirectly(FusionRuleType::kDempster, o, k, num_classes, by_libm.data());
    // One step from the same payload: at most one float rounding apart.
    std::vector<float> step_fast = libm, step_libm = libm;
    rule->add(step_fast.data(), by_rule.data(), num_classes);
    rule->add(step_libm.data(), by_libm.data(), num_classes);
    for (int c = 0; c < num_classes; ++c) {
      ASSERT_LE(std::fabs(step_fast[c] - step_libm[c]), std::fabs(step_libm[c]) * FLT_EPSILON)
          << "fusion " << n << " class " << c;
      differing_steps += step_fast[c] != step_libm[c];
    }
    rule->add(fast.data(), by_rule.data(), num_classes);
    rule->add(libm.data(), by_libm.data(), num_classes);
  }
  // The whole sequence: within a few float roundings (the bound of sum L = 1024 is reached, so
  // the proportional scaling is exercised too).
  double total = 0.0;
  for (int c = 0; c < num_classes; ++c) {
    total += libm[c];
    EXPECT_LE(std::fabs(fast[c] - libm[c]), 8.0 * FLT_EPSILON * std::fabs(libm[c])) << c;
  }
  EXPECT_NEAR(total, kMaxStoredLogEvidence, 1e-3);
  RecordProperty("steps_one_rounding_apart", std::to_string(differing_steps));
}

// A row of the kernel loop accumulates many contributions as a running product: it must give
// the sum of libm's log1p of each, also when the product passes what a double holds (huge
// evidence: folded into the log on the way).
TEST(DempsterContribution, RowOfManyContributionsEqualsTheSumOfLog1p) {
  const int num_classes = 5;
  test::RandomMasses rnd(3);
  for (double magnitude : {0.01, 20.0, 1e6, 3e38}) {
    std::vector<double> row(DempsterContribution::kRowWidth * num_classes, 0.0);
    std::vector<double> direct(num_classes, 0.0);
    for (int n = 0; n < 2000; ++n) {
      std::vector<float> e(num_classes, 0.0f);
      e[n % num_classes] = float(rnd.uniform(0.0, magnitude));  // sparse ...
      if (n % 3 == 0) {
        for (float& x : e) x = float(rnd.uniform(0.0, magnitude / 1e3));  // ... and dense
      }
      PointOpinion o;
      o.evidence = e.data();
      o.strength = num_classes;
      for (float x : e) o.strength += x;
      const double k = rnd.uniform(0.0, 1.2);
      DempsterContribution(o, num_classes)(k, row.data());
      contributeDirectly(FusionRuleType::kDempster, o, k, num_classes, direct.data());
    }
    DempsterContribution::finish(row.data(), num_classes);
    for (int c = 0; c < num_classes; ++c) {
      ASSERT_TRUE(std::isfinite(row[c])) << magnitude;
      EXPECT_NEAR(row[c], direct[c], 1e-12 * direct[c])
          << "magnitude " << magnitude << " class " << c;
    }
  }
}

// A one-hot point's increment tabulated over s = r^2 (OneHotTable) stays within KernelTable's
// bound carried through the increment: e S / C^2 times kMaxError sigma0 (for sigma0 <= 1, where
// the tables are used).
TEST(OneHotTable, StaysWithinItsStatedErrorOfTheClosedForm) {
  const int num_classes = 20;
  for (double sigma0 : {0.3, 0.7, 1.0})
    for (float evidence : {0.01f, 20.0f, 1000.0f, 3e38f})
      for (double weight : {1.0, 0.75}) {
        const OneHotTable table(sigma0, evidence, num_classes, weight);
        const double strength = double(num_classes) + evidence;
        double worst = 0.0;
        for (int i = 0; i <= 200000; ++i) {
          const double r = i / 200000.0 * 1.01;  // past the support too
          const double k = std::min(weight * sparseKernel(r, 1.0, sigma0), 1.0);
          const double want =
              std::log1p(evidence * k / (strength * (1.0 - k) + k * num_classes));
          worst = std::max(worst, std::fabs(table(r * r) - want));
        }
        const double bound =
            evidence * strength / (num_classes * num_classes) * KernelTable::kMaxError * sigma0;
        EXPECT_LE(worst, bound) << sigma0 << " " << evidence << " " << weight;
      }
}

// Scan 0 of the bundled SemanticKITTI scans in the sensor frame, one-hot evidence x 20 of its
// predicted classes.
struct RealScan {
  ClassTable classes;
  RawPoints raw;
  std::vector<octomap::point3d> positions;
  std::vector<float> evidence;
};

RealScan loadRealScan() {
  const std::string root = std::string(EVIDENTIAL_OCTOMAP_SOURCE_DIR) + "/";
  const std::string folder = root + "data/semantickitti_08_first10/";
  RealScan scan;
  scan.classes = ClassTable::load(root + "config/classes_semantickitti.yaml");
  std::ifstream points(folder + "velodyne/000000.bin", std::ios::binary);
  std::ifstream labels(folder + "predictions/000000.label", std::ios::binary);
  float xyzr[4];
  uint32_t label = 0;
  const int num_classes = scan.classes.numClasses();
  while (points.read(reinterpret_cast<char*>(xyzr), sizeof xyzr) &&
         labels.read(reinterpret_cast<char*>(&label), sizeof label)) {
    scan.positions.emplace_back(xyzr[0], xyzr[1], xyzr[2]);
    const size_t at = scan.evidence.size();
    scan.evidence.resize(at + num_classes, 0.0f);
    scan.evidence[at + scan.classes.classOfRaw(label)] = 20.0f;
  }
  for (size_t i = 0; i < scan.positions.size(); ++i) {
    scan.raw.positions.push_back(scan.positions[i]);
    scan.raw.evidence.push_back(&scan.evidence[i * num_classes]);
  }
  return scan;
}

// The finished rows of one subtree, per local voxel, the points scattered as the map does:
// one-hot points in groups, with their tables; the others (every point when their tables are
// taken away: the general loop, the reference) one by one.
std::map<uint32_t, std::vector<double>> subtreeRows(const KernelPass& kernel,
                                                    const std::vector<KernelPoint>& points,
                                                    const SemanticPoints& semantic,
                                                    const octomap::OcTreeKey& base,
                                                    int num_classes) {
  KernelRows rows;
  rows.index.assign(size_t(1) << (3 * kSubtreeLevels), KernelRows::kNone);
  for (const KernelPoint& p : points) kernel.markClasses(p, base, &rows);
  KernelPass::holdClasses(&rows);
  KernelMember group[KernelPass::kMaxGroup];
  for (size_t j = 0; j < points.size();) {
    int n = 0;
    do {
      group[n++] = {&points[j], &semantic.positions[j]};
      ++j;
    } while (n < KernelPass::kMaxGroup && j < points.size() &&
             KernelPass::sameGroup(points[j - n], points[j]));
    kernel.scatter(group, n, base, &rows);
  }
  kernel.flushOneHot(&rows);
  KernelPass::clearClasses(&rows);
  kernel.finishRows(&rows);
  std::map<uint32_t, std::vector<double>> out;
  for (size_t r = 0; r < rows.touched.size(); ++r) {
    out[rows.touched[r]].assign(&rows.rows[r * num_classes], &rows.rows[(r + 1) * num_classes]);
  }
  return out;
}

// How many points' supports (s < 1 a hair wide, as the loop's intervals) reach each local voxel
// of the subtree at `base`: the contributions its row sums.
std::vector<int> contributionsPerVoxel(const EvidentialOcTree& tree,
                                       const std::vector<KernelPoint>& points,
                                       const SemanticPoints& semantic,
                                       const octomap::OcTreeKey& base) {
  const int size = 1 << kSubtreeLevels;
  const double half = tree.getResolution() / 2.0;
  std::vector<int> count(size_t(size) * size * size, 0);
  for (size_t j = 0; j < points.size(); ++j) {
    const KernelPoint& p = points[j];
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(int(p.key[a]) - p.reach[a], int(base[a])) - int(base[a]);
      hi[a] = std::min(int(p.key[a]) + p.reach[a], int(base[a]) + size - 1) - int(base[a]);
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const int local[3] = {x, y, z};
          double s = 0.0;
          for (int a = 0; a < 3; ++a) {
            const double centre = tree.keyToCoord(octomap::key_type(base[a] + local[a]));
            const double gap = std::max(std::fabs(semantic.positions[j](a) - centre) - half, 0.0);
            s += gap * gap * (a == 2 ? p.inv_length2_z : p.inv_length2);
          }
          if (s < 1.0 + 1e-6) ++count[(size_t(z) * size + y) * size + x];
        }
  }
  return count;
}

// The one-hot road (tables, groups) against the general per-point loop on a real scan, library
// defaults (count-cap cells, class-aware weights, ground supports), every voxel of the
// supports: the same voxels get rows, and each row's log-evidence differs by at most both
// tables' error per contribution (e S / C^2 kMaxError sigma0 each, KernelTable's carried
// through the increment) times its contributions, plus rounding.
TEST(KernelPass, OneHotRoadStaysWithinTheTableErrorOfTheGeneralLoopOnARealScan) {
  RealScan scan = loadRealScan();
  const int num_classes = scan.classes.numClasses();
  SemanticConfig config;
  config.threads = 2;
  EvidentialOcTree tree(0.2, num_classes, config);
  tree.setGroundClasses(scan.classes.ground);
  KernelPass kernel(config, tree);
  const PointSelection how = PointSelection::of(config, num_classes, config.effectiveThreshold(),
                                                tree.getResolution());
  SemanticScratch scratch;
  SemanticPoints semantic;
  InsertStats stats;
  selectSemanticPoints(scan.raw, how, 2, &scratch, &semantic, &stats);
  std::vector<KernelPoint> points;
  kernel.preparePoints(semantic, 2, &points);
  ASSERT_GT(points.size(), 30000u);
  std::vector<KernelPoint> general = points;
  // Every third point on the general loop, between the groups: one-hot sums into the rows those
  // points made, 2 C wide, and a running product finished on top of them.
  std::vector<KernelPoint> mixed = points;
  size_t one_hot = 0, grouped = 0;
  for (size_t j = 0; j < points.size(); ++j) {
    one_hot += points[j].table >= 0 ? 1 : 0;
    grouped += j > 0 && KernelPass::sameGroup(points[j - 1], points[j]) ? 1 : 0;
    general[j].table = -1;
    if (j % 3 == 0) mixed[j].table = -1;
  }
  EXPECT_EQ(one_hot, points.size());      // derived evidence: every point one-hot, one value
  EXPECT_GT(grouped, points.size() / 3);  // groups are common
  const double per_contribution =
      20.0 * (20.0 + num_classes) / (num_classes * num_classes) * KernelTable::kMaxError *
      config.sigma0;
  // The subtrees below the sensor and beside them: the ground and the objects near it.
  size_t voxels = 0;
  double worst = 0.0, worst_relative = 0.0;
  const octomap::OcTreeKey sensor = tree.coordToKey(0.0, 0.0, 0.0);
  const int size = 1 << kSubtreeLevels;
  for (int dx = -1; dx <= 0; ++dx)
    for (int dy = -1; dy <= 0; ++dy) {
      const octomap::OcTreeKey base(
          static_cast<octomap::key_type>((sensor[0] / size + dx) * size),
          static_cast<octomap::key_type>((sensor[1] / size + dy) * size),
          static_cast<octomap::key_type>((sensor[2] / size - 1) * size));
      const auto reference = subtreeRows(kernel, general, semantic, base, num_classes);
      const std::vector<int> contributions = contributionsPerVoxel(tree, points, semantic, base);
      for (const auto* road : {&points, &mixed}) {
        const auto fast = subtreeRows(kernel, *road, semantic, base, num_classes);
        const char* what = road == &points ? "one-hot" : "mixed";
        ASSERT_EQ(fast.size(), reference.size()) << what;
        for (const auto& [local, row] : reference) {
          const auto other = fast.find(local);
          ASSERT_NE(other, fast.end()) << what << " voxel " << local;
          const double bound = 2.0 * per_contribution * contributions[local];
          for (int c = 0; c < num_classes; ++c) {
            const double difference = std::fabs(other->second[c] - row[c]);
            worst = std::max(worst, difference);
            if (row[c] > 1e-3) worst_relative = std::max(worst_relative, difference / row[c]);
            ASSERT_LE(difference, bound + 1e-12 * row[c])
                << what << " voxel " << local << " class " << c;
          }
        }
      }
      voxels += reference.size();
    }
  EXPECT_GT(voxels, 50000u);
  std::ostringstream text;
  text << worst << " (relative " << worst_relative << ")";
  RecordProperty("worst_difference", text.str());
  RecordProperty("points_grouped_with_the_previous",
                 std::to_string(grouped) + " of " + std::to_string(points.size()));
}

// A subtree's one-hot groups wait for flushOneHot, which needs the class-aware marks that
// clearClasses resets: clearing them first, or scattering into the next subtree, is an error.
TEST(KernelPass, OneHotGroupsMustBeFlushedBeforeTheClassesAreCleared) {
  const RealScan scan = loadRealScan();
  SemanticConfig config;
  EvidentialOcTree tree(0.2, scan.classes.numClasses(), config);
  KernelPass kernel(config, tree);
  SemanticPoints semantic;
  semantic.positions = scan.raw.positions;
  semantic.evidence = scan.raw.evidence;
  std::vector<KernelPoint> points;
  kernel.preparePoints(semantic, 2, &points);
  ASSERT_GE(points[0].table, 0);
  KernelRows rows;
  rows.index.assign(size_t(1) << (3 * kSubtreeLevels), KernelRows::kNone);
  const int size = 1 << kSubtreeLevels;
  const octomap::OcTreeKey base(
      static_cast<octomap::key_type>(points[0].key[0] / size * size),
      static_cast<octomap::key_type>(points[0].key[1] / size * size),
      static_cast<octomap::key_type>(points[0].key[2] / size * size));
  const KernelMember member{&points[0], &semantic.positions[0]};
  kernel.markClasses(points[0], base, &rows);
  KernelPass::holdClasses(&rows);
  kernel.scatter(&member, 1, base, &rows);
  const octomap::OcTreeKey next(static_cast<octomap::key_type>(base[0] + size), base[1], base[2]);
  EXPECT_THROW(kernel.scatter(&member, 1, next, &rows), std::logic_error);
  EXPECT_THROW(KernelPass::clearClasses(&rows), std::logic_error);
  kernel.flushOneHot(&rows);
  EXPECT_NO_THROW(KernelPass::clearClasses(&rows));
  kernel.finishRows(&rows);
  EXPECT_GT(rows.touched.size(), 0u);
  EXPECT_EQ(rows.rows.size(), rows.touched.size() * scan.classes.numClasses());
}

// The map of a real scan's points ahead of the sensor (scan 0, one-hot evidence x 20: every
// point takes the one-hot road, in groups, class by class, into C-wide rows) against the direct
// evaluation above: every leaf within the one-hot table's error per contribution (KernelTable's
// carried through the increment, e S / C^2 kMaxError sigma0: directEvaluation's bound) and
// float rounding. Library defaults (class-aware weights, cube distance, adaptive length) on the
// points the default down-sampling keeps, in its order, inserted without down-sampling again
// (the direct evaluation takes every point it is given), and no ground classes (it knows one
// vertical support).
TEST(KernelPass, OneHotRoadStaysWithinTheTableErrorOfDirectEvaluationOnARealScan) {
  const RealScan real = loadRealScan();
  const int num_classes = real.classes.numClasses();
  RawPoints ahead;  // in a box ahead of the sensor: the ground, a car, the kerb
  for (size_t i = 0; i < real.positions.size(); ++i) {
    const octomap::point3d& p = real.positions[i];
    if (p.x() < 4.0f || p.x() > 16.0f || std::fabs(p.y()) > 6.0f) continue;
    ahead.positions.push_back(p);
    ahead.evidence.push_back(real.raw.evidence[i]);
  }
  SemanticConfig config;
  config.threads = 2;
  EvidentialOcTree tree(0.2, num_classes, config);
  SemanticScratch scratch;
  SemanticPoints kept;
  InsertStats stats;
  selectSemanticPoints(ahead, PointSelection::of(config, num_classes, config.effectiveThreshold(),
                                                 tree.getResolution()),
                       2, &scratch, &kept, &stats);
  test::SyntheticScan scan;
  for (size_t i = 0; i < kept.positions.size(); ++i) {
    scan.points_W.push_back(kept.positions[i]);
    scan.evidence.insert(scan.evidence.end(), kept.evidence[i], kept.evidence[i] + num_classes);
  }
  ASSERT_GT(scan.points_W.size(), 2000u);
  // Every point one-hot with a table (the road under test), in groups, of several classes.
  {
    KernelPass kernel(config, tree);
    std::vector<KernelPoint> points;
    kernel.preparePoints(kept, 2, &points);
    std::set<int> classes;
    size_t grouped = 0;
    for (size_t j = 0; j < points.size(); ++j) {
      ASSERT_GE(points[j].table, 0);
      classes.insert(points[j].opinion.argmax);
      grouped += j > 0 && KernelPass::sameGroup(points[j - 1], points[j]) ? 1 : 0;
    }
    EXPECT_GE(classes.size(), 3u);
    EXPECT_GT(grouped, points.size() / 3);
  }
  config.ds_multiplier = 0.0;  // the points above, every one
  config.uncertainty_threshold = false;
  EvidentialOcTree map(0.2, num_classes, config);
  map.insertSemanticScan(scan.points_W, scan.evidence, octomap::point3d(0, 0, 0));
  const size_t with_evidence = expectWithinDirectEvaluation(&map, scan, config, "real scan");
  EXPECT_GT(with_evidence, 5000u);
  RecordProperty("points", std::to_string(scan.points_W.size()));
  RecordProperty("leaves_with_evidence", std::to_string(with_evidence));
}

// KernelPoint::reach bounds the voxels a point's loop visits: every voxel within its support
// (the kernel's distance, sparse_kernel.h, from the float position the map keeps to the voxel
// as keyToCoord places it, below the support length) must lie within it, for supports just
// under and at whole numbers of voxels, far from the origin (float rounding), both distances.
TEST(KernelPass, ReachHoldsEveryVoxelWithinTheSupport) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> within(-0.5, 0.5);
  for (const char* distance : {"voxel", "centre"}) {
    for (double length : {0.2 - 1e-6, 0.2, 0.3, 0.4 - 1e-6, 0.5}) {
      for (double vertical : {1.0, 0.5}) {
        SemanticConfig config;
        config.rule = "sbki";  // the support length is length_scale itself
        config.length_scale = length;
        config.kernel_distance = distance;
        config.vertical_support = vertical;
        EvidentialOcTree tree(0.2, 3, config);
        KernelPass kernel(config, tree);
        SemanticPoints semantic;
        const float evidence[3] = {5.0f, 0.0f, 0.0f};
        for (int i = 0; i < 2000; ++i) {
          const octomap::OcTreeKey key(32768 + 250 + i % 7, 32768 - 240, 32768 + 3);
          const octomap::point3d centre = tree.keyToCoord(key);
          semantic.positions.emplace_back(centre.x() + float(0.2 * within(random)),
                                          centre.y() + float(0.2 * within(random)),
                                          centre.z() + float(0.2 * within(random)));
          semantic.evidence.push_back(evidence);
        }
        std::vector<KernelPoint> points;
        kernel.preparePoints(semantic, 1, &points);
        const double half = std::string(distance) == "voxel" ? 0.1 : 0.0;
        size_t at_the_edge = 0;  // voxels inside the support at an offset of +-reach
        for (size_t j = 0; j < points.size(); ++j) {
          const KernelPoint& p = points[j];
          const octomap::point3d& at = semantic.positions[j];
          for (int dx = -p.reach[0] - 2; dx <= p.reach[0] + 2; ++dx)
            for (int dy = -2; dy <= 2; ++dy)
              for (int dz = -p.reach[2] - 2; dz <= p.reach[2] + 2; ++dz) {
                const octomap::point3d c = tree.keyToCoord(octomap::OcTreeKey(
                    p.key[0] + dx, p.key[1] + dy, p.key[2] + dz));
                const double d = kernelDistance(at.x() - c.x(), at.y() - c.y(), at.z() - c.z(),
                                                half, vertical);
                if (!(d < length)) continue;
                ASSERT_LE(std::abs(dx), p.reach[0]) << distance << " L " << length;
                ASSERT_LE(std::abs(dy), p.reach[1]) << distance << " L " << length;
                ASSERT_LE(std::abs(dz), p.reach[2]) << distance << " L " << length;
                at_the_edge += std::abs(dx) == p.reach[0] ? 1 : 0;
              }
        }
        // Not wider than needed, but where the margin for rounding adds a voxel: a support
        // of a whole number of voxels (plus the own voxel's half or whole), or just under it.
        const double across = length / 0.2 + (half > 0.0 ? 1.0 : 0.5);
        const double fraction = across - std::floor(across);
        if (fraction > 0.0 && fraction < 0.99)
          EXPECT_GT(at_the_edge, 0u) << distance << " L " << length << ": reach wider than needed";
      }
    }
  }
}

}  // namespace
}  // namespace evidential_octomap
