// Calibration of evidence derived from hard labels: every point's uncertainty u = C / S is set to
// how often "such points" are wrong, so the adaptive kernel, the percentile threshold and the
// map's uncertainty see a meaningful u.
//   such points  the points of one bin of the raw opinion: raw u in 20 equal bins of [0, 1] times
//                the argmax share e_max / sum(e) in 10 equal bins (onehot: one bin; confusion:
//                about one bin per predicted class; knn-vote: one per vote pattern);
//   error rate   of the argmax of the raw evidence against GT (ignore class skipped), counted on
//                the mapping scans only: leave-one-scan-out for a mapped scan, all mapped scans
//                for a query-only scan, the scan itself when it is the only one; smoothed as
//                (errors + m r) / (points + m) towards the overall rate r, m = 50;
//   rescaling    e' = e * s with sum(e') = C (1/u - 1): class shares kept, u clamped to
//                [0.001, 0.999]. Points without evidence stay vacuous.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace evidential_octomap::tools {

class EvidenceCalibration {
 public:
  EvidenceCalibration(int num_classes, int ignore_class);
  // Counts errors per bin of one mapping scan (N x C raw evidence, N GT classes).
  void addScan(size_t scan_index, const std::vector<float>& evidence, const std::vector<int>& gt);
  // Rescales `evidence` (N x C) of scan `scan_index` with the rates of the other added scans
  // (all added scans when it is not one of them or the only one).
  void apply(size_t scan_index, std::vector<float>* evidence) const;
  // Calibrated u of a bin, fitted without `scan_index` (exposed for tests).
  double uncertaintyOfBin(size_t bin, size_t scan_index) const;
  size_t binOf(const float* evidence) const;
  bool inSample() const { return per_scan_.size() == 1; }

  static constexpr size_t kUncertaintyBins = 20, kShareBins = 10;
  static constexpr double kSmoothing = 50.0, kMinU = 0.001, kMaxU = 0.999;

 private:
  struct Counts {
    std::vector<double> errors, points;  // per bin
  };
  Counts countsWithout(size_t scan_index) const;
  int num_classes_, ignore_class_;
  std::vector<std::pair<size_t, Counts>> per_scan_;
};

}  // namespace evidential_octomap::tools
