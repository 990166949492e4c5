// Map and input metrics, one set for every row (the input and each rule), computed
// on the same queries and defined so anyone can recompute them:
//   queries     GT-labelled points (ignore class excluded) of the evaluated scans, world frame;
//   answer      what a row says at a query: the map's answer (EvidentialOcTree::query: the
//               voxel's own evidence, or in a map built with semantic_occupied_only, for a
//               known voxel without any, the support answer of the voxels with evidence around
//               it) or, for the input row, the point's own opinion; "no label" otherwise;
//   occupancy coverage  share of queries whose voxel is occupied (OctoMap's isNodeOccupied);
//   semantic coverage   share of queries the map answers (the paper's O.Acc);
//   mIoU, Acc   over ALL queries (no label = wrong) and over labelled queries; mIoU averages
//               IoU = TP / (TP + FP + FN) over the classes present in GT;
//   Brier       mean over all queries of sum_c (p^c - 1[c = gt])^2 of the projected class
//               probabilities (dempster b + u/C, sbki/ebs alpha/S, no label: uniform 1/C);
//   NLL         mean of -ln max(p^gt, 1e-6);
//   ECE         sum over 10 equal-width bins of max_c p^c of (n_bin / N) |acc_bin - conf_bin|
//               (a query without label has confidence 1/C and is wrong);
//   error detection, among labelled queries, for each uncertainty output (kUncertaintyOutputs):
//               AUROC of the output as a score for "the label is wrong" (ties count 1/2), and
//               AURC, the mean over k = 1..n of the error rate of the k most certain answers
//               (ties ordered at random, in expectation).
#pragma once

#include <octomap/octomap_types.h>

#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/subjective_logic.h"  // dissonance

namespace evidential_octomap {

// One evaluation query: a GT-labelled point in the world frame, with the input's prediction.
struct Query {
  octomap::point3d point_W;
  int gt = -1;         // ground-truth class
  int predicted = -1;  // the input's per-point class (-1: none)
};

// C x C counts, rows = GT, columns = predicted class, plus one "no label" column: a query
// whose prediction is -1 is wrong for its GT class and a false positive for no class.
class ConfusionMatrix {
 public:
  explicit ConfusionMatrix(int num_classes = 0);

  void add(int gt, int predicted, uint64_t count = 1);  // predicted -1 = no label
  void merge(const ConfusionMatrix& other);

  int numClasses() const { return num_classes_; }
  uint64_t at(int gt, int predicted) const;  // predicted -1 = the no-label column
  uint64_t total() const { return total_; }
  uint64_t correct() const;
  uint64_t gtCount(int c) const;    // row sum, no-label column included
  uint64_t predCount(int c) const;  // column sum
  bool presentInGt(int c) const { return gtCount(c) > 0; }

  // TP / (TP + FP + FN); NaN when the class appears neither in GT nor in the predictions.
  double iou(int c) const;
  // Mean IoU over the classes present in GT, `ignore_class` excluded. NaN when none is.
  double meanIou(int ignore_class = -1) const;
  // correct / total; NaN when empty.
  double accuracy() const;

 private:
  int num_classes_ = 0;
  std::vector<uint64_t> counts_;  // num_classes x (num_classes + 1), last column = no label
  uint64_t total_ = 0;
};

// Per-voxel uncertainty outputs, each evaluated for error detection:
//   u           the rule's uncertainty (dempster: vacuity mass; sbki/ebs: Dirichlet variance)
//   conflict    VoxelOpinion::conflict
//   1-max_p     one minus the largest projected probability
//   dissonance  subjective logic's dissonance of the belief masses (Josang 2018, 4.4.3)
//   error_probability  FusionRule::errorProbability: the calibration's error model where the map
//               has one, else 1-max_p
inline const std::vector<std::string> kUncertaintyOutputs{"u", "conflict", "1-max_p", "dissonance",
                                                          "error_probability"};

// What a row says at one query.
struct Answer {
  int label = -1;                  // -1: no label
  std::vector<float> probability;  // C projected probabilities; empty: uniform
  std::vector<float> uncertainty;  // kUncertaintyOutputs, when labelled
};

// What one query contributed, kept for resampling (paired_bootstrap.h): gt -1 = not counted
// (ignore class or out of range), label -1 = no label, brier = the query's Brier term.
struct QueryOutcome {
  int16_t gt = -1, label = -1;
  float brier = 0.0f;
};

// The Brier term sum_c (p^c - 1[c = gt])^2 of one answer (no label or no p: uniform 1/C).
double brierScore(int gt, const Answer& answer, int num_classes);

// The answer of a voxel opinion read with `rule` (label -1: no label).
Answer answerOf(const VoxelOpinion& opinion, const FusionRule& rule);
// The answer of one point's evidence: its own subjective opinion (b = e/S, u = C/S, p = alpha/S),
// read exactly as a dempster voxel that fused only this point at k = 1.
Answer answerOfEvidence(const float* evidence, int num_classes);

// AUROC of `score` for `positive` (ties count 1/2); NaN without both kinds.
double auroc(const std::vector<float>& score, const std::vector<uint8_t>& positive);
// Area under the risk-coverage curve: answers sorted by ascending score, risk(k) = errors
// among the first k / k, averaged over k = 1..n; tied scores are taken in random order, in
// expectation. NaN when empty.
double aurc(const std::vector<float>& score, const std::vector<uint8_t>& wrong);

struct ReliabilityBin {  // one bin of max_c p^c
  double lower = 0.0, upper = 0.0;
  size_t count = 0;
  double mean_confidence = 0.0, accuracy = 0.0;
};

struct ErrorDetection {  // one uncertainty output among labelled queries
  std::string output;
  double auroc = 0.0, aurc = 0.0;
  // Error rate per tenth of the labelled queries sorted by ascending output (the curve).
  std::vector<double> error_rate_by_decile;
  std::vector<double> mean_output_by_decile;
};

struct QualityMetrics {
  size_t queries = 0, labelled = 0;
  ConfusionMatrix all;  // every query; no label = the no-label column
  ConfusionMatrix labelled_only;
  double miou_all = 0.0, acc_all = 0.0;
  double miou_labelled = 0.0, acc_labelled = 0.0;
  double brier = 0.0, nll = 0.0, ece = 0.0;  // over all queries
  double error_rate_labelled = 0.0;          // AURC of a random order, for reference
  std::vector<ReliabilityBin> reliability;
  std::vector<ErrorDetection> error_detection;  // kUncertaintyOutputs order
  const ErrorDetection* detection(const std::string& output) const;
};

// Collects answers query by query; finish() computes every metric above.
class QualityAccumulator {
 public:
  QualityAccumulator(int num_classes, int ignore_class);
  // Queries whose gt is the ignore class or outside [0, C) are skipped (not counted).
  void add(int gt, const Answer& answer);
  QualityMetrics finish() const;

 private:
  static constexpr int kBins = 10;
  int num_classes_, ignore_class_;
  QualityMetrics m_;
  double brier_sum_ = 0.0, nll_sum_ = 0.0;
  std::vector<ReliabilityBin> bins_;
  std::vector<uint8_t> wrong_;                   // per labelled query
  std::vector<std::vector<float>> uncertainty_;  // per output, per labelled query
};

struct MapMetrics {
  QualityMetrics quality;
  size_t occupied = 0;              // queries whose voxel is occupied
  double occupancy_coverage = 0.0;  // occupied / queries
  double semantic_coverage = 0.0;   // labelled / queries (paper O.Acc)
};

// `outcomes`, when given, receives one QueryOutcome per query (same order as `queries`).
MapMetrics evaluateMap(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                       int ignore_class, std::vector<QueryOutcome>* outcomes = nullptr);

// The input's per-point metrics on the same queries: `evidence` holds C values per query
// (same order), or is empty for hard predictions only (then p is one-hot on Query::predicted
// and every uncertainty output is 0).
QualityMetrics evaluateInput(const std::vector<Query>& queries, const std::vector<float>& evidence,
                             int num_classes, int ignore_class,
                             std::vector<QueryOutcome>* outcomes = nullptr);

// Occupied voxels (leaves at full depth; pruned leaves count every voxel they cover) that hold
// no ray end point of `endpoints`: what densification or a kernel adds as occupied.
size_t occupiedWithoutEndpoint(const EvidentialOcTree& tree,
                               const std::vector<octomap::OcTreeKey>& endpoints);

}  // namespace evidential_octomap
