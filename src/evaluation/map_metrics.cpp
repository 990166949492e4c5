// What a map or the input answers at each query (metrics.h), and the evaluation loops.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_set>

#include "evidential_octomap/evaluation/metrics.h"
#include "evidential_octomap/safe_key.h"

namespace evidential_octomap {

Answer answerOf(const VoxelOpinion& o, const FusionRule& rule) {
  Answer a;
  a.label = o.label;
  if (o.label < 0) return a;
  a.probability = rule.probabilities(o);
  // Dissonance of the subjective-logic belief masses; the Dirichlet rules have none apart from
  // their expected probabilities, read as a dogmatic opinion.
  VoxelOpinion readout = o;
  readout.error_probability = -1.0f;  // 1 - max p of the read-out itself
  a.uncertainty = {o.uncertainty, o.conflict, rule.errorProbability(readout),
                   float(dissonance(o.belief)), rule.errorProbability(o)};
  return a;
}

Answer answerOfEvidence(const float* evidence, int num_classes) {
  static const auto kDempster = FusionRule::create(FusionRuleType::kDempster);
  // L^c = ln(1 + e^c / C) is the payload of a voxel that fused this point alone at k = 1.
  std::vector<float> payload(num_classes);
  for (int c = 0; c < num_classes; ++c)
    payload[c] = float(std::log1p(double(evidence[c]) / num_classes));
  // A point without any evidence is vacuous: no label (uniform p), like an empty voxel.
  return answerOf(kDempster->readout(payload.data(), num_classes), *kDempster);
}

namespace {
// Records one query's outcome when the caller asked for them (uncounted queries keep gt -1).
void record(std::vector<QueryOutcome>* outcomes, size_t i, int gt, const Answer& a,
            int num_classes) {
  if (outcomes == nullptr) return;
  QueryOutcome& out = (*outcomes)[i];
  out.gt = int16_t(gt);
  out.label = int16_t(a.label >= 0 && a.label < num_classes ? a.label : -1);
  out.brier = float(brierScore(gt, a, num_classes));
}
}  // namespace

MapMetrics evaluateMap(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                       int ignore_class, std::vector<QueryOutcome>* outcomes) {
  const int num_classes = tree.numClasses();
  MapMetrics m;
  QualityAccumulator acc(num_classes, ignore_class);
  if (outcomes != nullptr) outcomes->assign(queries.size(), QueryOutcome());
  for (size_t i = 0; i < queries.size(); ++i) {
    const Query& q = queries[i];
    if (q.gt < 0 || q.gt >= num_classes || q.gt == ignore_class) continue;
    octomap::OcTreeKey key;
    const bool inside = safeCoordToKey(tree, q.point_W, &key);
    const EvidentialOcTreeNode* node = inside ? tree.search(key) : nullptr;
    if (node != nullptr && tree.isNodeOccupied(node)) ++m.occupied;
    float values[EvidentialOcTree::kMaxClasses];
    const bool labelled = inside && tree.answerPayload(key, values);
    const Answer a =
        labelled ? answerOf(tree.rule().readout(values, num_classes), tree.rule()) : Answer();
    acc.add(q.gt, a);
    record(outcomes, i, q.gt, a, num_classes);
  }
  m.quality = acc.finish();
  const double n = double(m.quality.queries);
  m.occupancy_coverage = n > 0 ? double(m.occupied) / n : std::nan("");
  m.semantic_coverage = n > 0 ? double(m.quality.labelled) / n : std::nan("");
  return m;
}

QualityMetrics evaluateInput(const std::vector<Query>& queries, const std::vector<float>& evidence,
                             int num_classes, int ignore_class,
                             std::vector<QueryOutcome>* outcomes) {
  QualityAccumulator acc(num_classes, ignore_class);
  const bool has_evidence = evidence.size() == queries.size() * size_t(num_classes);
  if (outcomes != nullptr) outcomes->assign(queries.size(), QueryOutcome());
  for (size_t i = 0; i < queries.size(); ++i) {
    const Query& q = queries[i];
    Answer a;
    if (has_evidence) {
      a = answerOfEvidence(&evidence[i * num_classes], num_classes);
    } else if (q.predicted >= 0 && q.predicted < num_classes) {
      a.label = q.predicted;  // a hard label: one-hot p, no uncertainty
      a.probability.assign(num_classes, 0.0f);
      a.probability[q.predicted] = 1.0f;
      a.uncertainty.assign(kUncertaintyOutputs.size(), 0.0f);
    }
    acc.add(q.gt, a);
    const bool counted = q.gt >= 0 && q.gt < num_classes && q.gt != ignore_class;
    if (counted) record(outcomes, i, q.gt, a, num_classes);
  }
  return acc.finish();
}

size_t occupiedWithoutEndpoint(const EvidentialOcTree& tree,
                               const std::vector<octomap::OcTreeKey>& endpoints) {
  const std::unordered_set<octomap::OcTreeKey, octomap::OcTreeKey::KeyHash> ends(endpoints.begin(),
                                                                                 endpoints.end());
  const unsigned max_depth = tree.getTreeDepth();
  size_t count = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    // A pruned leaf of depth d covers 2^(max_depth - d) voxels per axis from its first key.
    const int side = 1 << (max_depth - it.getDepth());
    const octomap::OcTreeKey first = it.getIndexKey();
    for (int x = 0; x < side; ++x)
      for (int y = 0; y < side; ++y)
        for (int z = 0; z < side; ++z) {
          const octomap::OcTreeKey key(first[0] + x, first[1] + y, first[2] + z);
          count += ends.count(key) == 0;
        }
  }
  return count;
}

}  // namespace evidential_octomap
