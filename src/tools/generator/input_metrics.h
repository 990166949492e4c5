// Per-point metrics of the generated network outputs against the ground truth (void excluded),
// written into every dataset's README and network_metrics.json: accuracy, AUROC of the vacuity
// u = C / S and of 1 - max softmax for "prediction wrong", expected calibration errors, the
// reliability diagrams' bins, and accuracy per range band and inside the wrong cells.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lidar.h"
#include "network_model.h"

namespace evidential_octomap::generator {

class InputMetrics {
 public:
  static constexpr int kBins = 10;
  static constexpr int kRangeBands = 6;  // 0-10, 10-20, 20-30, 30-50, 50-80, 80+ m
  // keep_fraction: share of points kept for the AUROCs (deterministic, by a hash of the point).
  InputMetrics(int num_classes, double keep_fraction, uint64_t seed)
      : C_(num_classes), keep_(keep_fraction), seed_(seed) {}
  void add(int scan, const std::vector<LidarPoint>& points, const NetworkOutput& net);

  double accuracy() const { return points_ ? double(correct_) / points_ : 0.0; }
  double aurocVacuity() const;
  double aurocSoftmax() const;
  nlohmann::json toJson() const;
  std::string toMarkdown() const;

 private:
  struct Bins {
    double conf[kBins] = {}, correct[kBins] = {};
    size_t count[kBins] = {};
    void add(double p, bool ok);
    double ece() const;
  };
  int C_;
  double keep_;
  uint64_t seed_;
  size_t points_ = 0, correct_ = 0;
  size_t wrong_cell_points_ = 0, wrong_cell_correct_ = 0;
  size_t band_points_[kRangeBands] = {}, band_correct_[kRangeBands] = {};
  Bins softmax_, dirichlet_;
  std::vector<float> u_, maxp_;
  std::vector<uint8_t> wrong_;
};

// AUROC of `score` for the positives `positive` (ties count one half).
double auroc(const std::vector<float>& score, const std::vector<uint8_t>& positive);

}  // namespace evidential_octomap::generator
