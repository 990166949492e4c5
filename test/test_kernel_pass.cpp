// The kernel loop's precomputed kernel (kernel_pass.h): the table's error against the closed
// form, and a whole scan's map against a direct evaluation written out here (every point, every
// voxel of its support, sparseKernel and distanceToCube called as DESIGN §1 states them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/kernel.h"
#include "kernel_pass.h"
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
          const double distance = config.kernel_distance == "voxel"
                                      ? distanceToCube(d.x(), d.y(), d.z(), half)
                                      : std::sqrt(double(d.x()) * d.x() + double(d.y()) * d.y() +
                                                  double(d.z()) * d.z());
          const double k = sparseKernel(distance, length, config.sigma0);
          const bool near_edge = distance >= length * 0.999 && distance < length * 1.001;
          if (k <= 0.0 && !near_edge) continue;
          const KeyTuple key{voxel[0], voxel[1], voxel[2]};
          auto& row = rows[key];
          auto& b = (*bound)[key];
          row.resize(num_classes, 0.0);
          b.resize(num_classes, 0.0);
          if (k > 0.0) rule.contribute(o, k, num_classes, row.data());
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

TEST(KernelPass, MapStaysWithinTheTableErrorOfDirectEvaluation) {
  test::SyntheticScene scene;
  const test::SyntheticScan scan = scene.defaultScan();
  for (const std::string& rule : kFusionRuleNames) {
    for (const std::string distance : {"voxel", "centre"}) {
      SemanticConfig config;
      config.rule = rule;
      config.kernel_distance = distance;
      config.ds_multiplier = 0.0;            // every point, as the direct evaluation
      config.uncertainty_threshold = false;  // likewise
      config.length_scale = 0.45;            // supports of several voxels
      config.threads = 2;
      EvidentialOcTree tree(0.2, scene.num_classes, config);
      tree.insertSemanticScan(scan.points_W, scan.evidence, scan.origin_W);
      std::map<KeyTuple, std::vector<double>> bound;
      const auto expected = directEvaluation(tree, scan, config, &bound);
      tree.expand();  // every leaf at full depth
      const float prior = tree.rule().prior();
      size_t compared = 0, with_evidence = 0;
      for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
        const KeyTuple key{it.getKey()[0], it.getKey()[1], it.getKey()[2]};
        const float* payload = tree.payload(&*it);
        const auto row = expected.find(key);
        for (int c = 0; c < scene.num_classes; ++c) {
          const double want = row == expected.end() ? prior : float(prior + row->second[c]);
          const double got = payload ? payload[c] : prior;
          const double slack = (row == expected.end() ? 0.0 : bound.at(key)[c]) +
                               2.0 * FLT_EPSILON * std::fabs(want) + 1e-30;
          ASSERT_LE(std::fabs(got - want), slack)
              << rule << " " << distance << " voxel " << it.getKey()[0] << " " << it.getKey()[1]
              << " " << it.getKey()[2] << " class " << c;
        }
        ++compared;
        with_evidence += payload ? 1 : 0;
      }
      EXPECT_GT(with_evidence, 500u) << rule << " " << distance;
      EXPECT_GT(compared, with_evidence);
    }
  }
}

}  // namespace
}  // namespace evidential_octomap
