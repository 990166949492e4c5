// Learned evidence: a small evidential MLP (Sensoy et al. 2018 loss, trained by
// docs/experiments/drivers/learned_evidence/train.py) that turns the per-point features of
// point_features.h into a C-vector of evidence e >= 0 (softplus output), so data that ships only a
// network's hard predictions gets evidence whose uncertainty follows real error structure.
//
// A model file holds one or more *folds*, each trained on some scans (stored by content
// fingerprint). A scan's evidence comes only from the folds that were NOT trained on it
// (cross-fitting: no point's evidence from a model that saw its labels); with several such
// folds their evidence is averaged. Text format, written by the training script:
//   evidential_octomap_learned_evidence 1
//   classes <C>
//   features <F> <name_1> .. <name_F>      (must equal pointFeatureNames(C))
//   description <one line>
//   folds <K>
//   fold <name> trained_on <n> <hex fingerprint> x n
//   normalise <F means> <F stds>
//   layers <L>
//   dense <in> <out> <relu|softplus> <out x in weights, row-major> <out biases>   (x L)
//   end
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "evidential_octomap/evidence/point_features.h"

namespace evidential_octomap {

// A feed-forward net: x -> (x - mean) / std -> dense layers.
struct EvidentialMlp {
  enum class Activation { kRelu, kSoftplus };
  struct Dense {
    int in = 0, out = 0;
    Activation activation = Activation::kRelu;
    std::vector<float> weight;  // out x in, row-major
    std::vector<float> bias;    // out
  };
  std::vector<float> mean, stddev;  // F each
  std::vector<Dense> layers;

  int inputs() const { return int(mean.size()); }
  int outputs() const { return layers.empty() ? 0 : layers.back().out; }
  // N x outputs() for an N x inputs() matrix (OpenMP over rows).
  std::vector<float> forward(const FeatureMatrix& features) const;
};

class LearnedEvidenceModel {
 public:
  struct Fold {
    std::string name;
    std::vector<uint64_t> trained_on;  // scan fingerprints
    EvidentialMlp mlp;
  };

  // Throws std::runtime_error naming the file and what is wrong (format, sizes, values, or
  // feature names that differ from this build's pointFeatureNames).
  static LearnedEvidenceModel load(const std::string& path);

  int numClasses() const { return num_classes_; }
  const std::string& path() const { return path_; }
  const std::string& description() const { return description_; }
  const std::vector<Fold>& folds() const { return folds_; }

  // Folds that were not trained on the scan with this fingerprint.
  std::vector<size_t> heldOutFolds(uint64_t fingerprint) const;

  // N x C evidence of a scan: mean of its held-out folds (listed in `folds_used` when given).
  // Throws std::runtime_error when every fold was trained on this scan. Points without a
  // return (0, 0, 0) get zero evidence.
  std::vector<float> evidence(const ScanInput& scan,
                              std::vector<size_t>* folds_used = nullptr) const;

 private:
  int num_classes_ = 0;
  std::string path_, description_;
  std::vector<Fold> folds_;
};

}  // namespace evidential_octomap
