// Where per-point evidence comes from. A network trained with EDL gives it directly (files);
// data that ships only hard labels needs it derived, and every output says which was used.
//   file       evidence/ or alpha/ files of the dataset (real network output)
//   onehot     e = E * onehot(prediction)                       (derived from hard labels)
//   knn-vote   votes of the k nearest same-scan neighbours within radius r:
//              e^c = E * n_c^2 / (k * n)   (n neighbours found incl. the point, n_c voting c),
//              i.e. E * (n/k) * (n_c/n)^2: full and unanimous neighbourhoods give E,
//              sparse ones (n < k) and mixed ones (class borders) give less, so u rises there.
//   confusion  e^c = E * P(p|p) * P(c|p), p the prediction, P(gt = c | pred = p) estimated on
//              *other* scans only (leave-one-scan-out) and smoothed towards the global accuracy;
//              u is constant per predicted class and larger for the less precise classes.
//   learned    a small evidential MLP on per-point geometry and the hard predictions
//              (include/evidential_octomap/evidence/learned_evidence.h), CROSS-FITTED: each scan's
//              evidence comes from the model fold(s) not trained on it. Labelled "learned
//              (cross-fitted)", never "derived".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evidence/learned_evidence.h"

namespace evidential_octomap {

enum class EvidenceSource { kFile, kOneHot, kKnnVote, kConfusion, kLearned };

struct EvidenceOptions {
  EvidenceSource source = EvidenceSource::kOneHot;
  float magnitude = kEvidenceMagnitude;  // E (the scale before calibration)
  int knn_k = 8;
  double knn_radius = 0.5;   // [m]
  std::string learned_model;  // model file of kLearned ("": defaultLearnedModel)
  InputConversion conversion;  // kFile: how logits/ and probabilities/ files become evidence
  std::string logit_transform_name = "softmax";  // CLI spelling of conversion.logit_transform
  std::string files;           // kFile: Dataset::describeEvidenceFiles(), for the captions
  // Derived sources only: rescale every point's evidence so that its u is the error rate of
  // such points on the mapping scans (evidence_calibration.h).
  bool calibrate = true;
};

EvidenceSource evidenceSourceFromName(const std::string& name);  // throws std::invalid_argument
std::string evidenceSourceName(EvidenceSource source);
bool derivedFromHardLabels(EvidenceSource source);
// The kind of evidence for captions: "derived", "learned (cross-fitted)" or "network evidence".
std::string evidenceKind(EvidenceSource source);
// <directory of the class table>/learned/<table's dataset>.model, e.g.
// config/learned/semantickitti.model beside config/classes_semantickitti.yaml.
std::string defaultLearnedModel(const std::string& classes_path, const ClassTable& classes);
// One line for captions and reports, e.g. "onehot, E=20 (derived from hard labels)".
std::string describeEvidence(const EvidenceOptions& options);
// Label of the input row of the metric tables, e.g. "input evidence (onehot), per point".
std::string inputDescription(const EvidenceOptions& options);

// Per-class confusion counts of each scan, so that the evidence of scan i can be estimated from
// the other scans of a calibration set only.
class ConfusionModel {
 public:
  explicit ConfusionModel(int num_classes, int ignore_class);
  // Counts (gt, predicted) of one scan; GT points of the ignore class are skipped.
  void addScan(size_t scan_index, const std::vector<int>& gt, const std::vector<int>& predicted);
  // P(gt = c | pred = p) from every added scan except `exclude_scan`, C x C row = p.
  // Smoothed: (n_pc + m * prior_pc) / (n_p + m), prior = global accuracy on the diagonal, the
  // rest spread evenly, m = 10 pseudo-points.
  std::vector<double> conditional(size_t exclude_scan) const;
  size_t numScans() const { return per_scan_.size(); }

 private:
  int num_classes_;
  int ignore_class_;
  std::vector<std::pair<size_t, std::vector<uint64_t>>> per_scan_;  // C x C, row = predicted
};

// N x C evidence of `scan` from `options`. For kConfusion, `model` must hold scans other than
// `scan_index`; for kLearned, `learned` is the loaded model. Throws std::runtime_error when the
// needed input (predictions, files, a fold that did not see the scan) is missing.
std::vector<float> deriveEvidence(const Scan& scan, size_t scan_index,
                                  const EvidenceOptions& options, int num_classes,
                                  const ConfusionModel* model,
                                  const LearnedEvidenceModel* learned = nullptr);

// The scan as the learned model's input (borrows the scan's arrays).
ScanInput scanInput(const Scan& scan);

std::vector<float> oneHotEvidence(const std::vector<int>& predicted, int num_classes,
                                  float magnitude);
// The k nearest within `radius` by NeighbourGrid (evidential_octomap/evidence/neighbour_grid.h).
std::vector<float> knnVoteEvidence(const std::vector<Eigen::Vector3f>& points,
                                   const std::vector<int>& predicted, int num_classes, int k,
                                   double radius, float magnitude);
std::vector<float> confusionEvidence(const std::vector<int>& predicted,
                                     const std::vector<double>& conditional, int num_classes,
                                     float magnitude);

}  // namespace evidential_octomap
