// The map's error probability P(label wrong) of a dempster voxel, fitted by `evidential_octomap
// calibrate` on labelled scans (docs/calibration.md) and read with the calibration file.
//
// A logistic model over everything the voxel holds, all read from its C floats of fused
// log-evidence L (fusion_rule.h) and the opinion the rule reads from them:
//   error_readout       logit of 1 - max p of the read-out (capped) opinion
//   vacuity             ln u of the read-out opinion
//   dissonance          of the read-out belief masses
//   conflict            VoxelOpinion::conflict (the share of L Dempster's rule discarded)
//   dirichlet_variance  ln of the label's Dirichlet variance with alpha^c = e^(L^c), the same
//                       fused evidence read as S-BKI reads its counts (uncapped)
//   evidence_mass       ln(1 + sum L)
//   label_share         L^label / sum L
// Terms: the intercept, each feature, hinges max(0, feature - knot) at knots the fit places at
// quantiles of its rows (a monotone read-out need not be what the data say), and one offset per
// label (networks err more on some classes). The tree stores no count of points per voxel, so
// evidence_mass stands for how much was fused.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/fusion_rule.h"

namespace evidential_octomap {

class ErrorModel {
 public:
  static constexpr int kNumFeatures = 7;
  using Features = std::array<double, kNumFeatures>;
  static const std::array<const char*, kNumFeatures>& featureNames();

  // The features of a labelled voxel: its payload (C floats of L) and the rule's read-out of it.
  static Features features(const float* payload, const VoxelOpinion& opinion, int num_classes);

  // One term: "intercept", a feature name, "<feature>><knot>" (a hinge) or "label=<c>".
  // Throws std::invalid_argument naming the term when it is none of these.
  ErrorModel(const std::vector<std::string>& terms, const std::vector<double>& weights);
  ErrorModel() = default;

  double probability(const Features& x, int label) const;
  double probability(const float* payload, const VoxelOpinion& opinion, int num_classes) const {
    return probability(features(payload, opinion, num_classes), opinion.label);
  }
  std::vector<std::string> terms() const;
  const std::vector<double>& weights() const { return weights_; }
  bool empty() const { return weights_.empty(); }

  struct Term {
    enum Kind { kIntercept, kFeature, kHinge, kLabel } kind = kIntercept;
    int index = 0;      // feature or label
    double knot = 0.0;  // hinges
  };

 private:
  static Term parse(const std::string& text);
  static double value(const Term& t, const Features& x, int label);
  friend class ErrorModelFit;
  std::vector<Term> terms_;
  std::vector<double> weights_;
};

// Rows for the fit: features, label, whether the label is wrong and a group (the spatial block,
// for cross-validation).
struct ErrorRow {
  ErrorModel::Features x{};
  int label = -1;
  bool wrong = false;
  uint32_t fold = 0;
};

struct ErrorModelFitResult {
  ErrorModel model;                 // fitted on every row
  std::vector<double> out_of_fold;  // each row's probability from the fit without its fold
  double penalty = 0.0;             // the L2 penalty the folds chose
};

// Fits the model: hinges at the quartiles of each feature, L2-penalised logistic regression by
// Newton's method (standardised terms), the penalty chosen by the out-of-fold log loss over
// `folds` folds of rows (ErrorRow::fold % folds). At most `max_rows` rows are used (an even
// subsample, deterministic). Throws std::runtime_error without both right and wrong labels.
ErrorModelFitResult fitErrorModel(const std::vector<ErrorRow>& rows, int num_classes,
                                  int folds = 5, size_t max_rows = 300000);

}  // namespace evidential_octomap
