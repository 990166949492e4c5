#include "evidence_calibration.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace evidential_octomap::tools {

namespace {
constexpr size_t kBins = EvidenceCalibration::kUncertaintyBins * EvidenceCalibration::kShareBins;
}  // namespace

EvidenceCalibration::EvidenceCalibration(int num_classes, int ignore_class)
    : num_classes_(num_classes), ignore_class_(ignore_class) {}

size_t EvidenceCalibration::binOf(const float* e) const {
  double sum = 0.0, best = 0.0;
  for (int c = 0; c < num_classes_; ++c) {
    sum += e[c];
    best = std::max(best, double(e[c]));
  }
  const double u = num_classes_ / (sum + num_classes_);
  const double share = sum > 0.0 ? best / sum : 0.0;
  const size_t ub = std::min(kUncertaintyBins - 1, size_t(u * kUncertaintyBins));
  const size_t sb = std::min(kShareBins - 1, size_t(share * kShareBins));
  return ub * kShareBins + sb;
}

void EvidenceCalibration::addScan(size_t scan_index, const std::vector<float>& evidence,
                                  const std::vector<int>& gt) {
  if (evidence.size() != gt.size() * size_t(num_classes_)) {
    throw std::invalid_argument("EvidenceCalibration::addScan: evidence and GT differ in size");
  }
  Counts counts{std::vector<double>(kBins, 0.0), std::vector<double>(kBins, 0.0)};
  for (size_t i = 0; i < gt.size(); ++i) {
    if (gt[i] < 0 || gt[i] == ignore_class_) continue;
    const float* e = &evidence[i * num_classes_];
    const int argmax = int(std::max_element(e, e + num_classes_) - e);
    if (!(e[argmax] > 0.0f)) continue;  // vacuous points are left alone
    const size_t bin = binOf(e);
    counts.points[bin] += 1.0;
    counts.errors[bin] += argmax != gt[i];
  }
  per_scan_.emplace_back(scan_index, std::move(counts));
}

EvidenceCalibration::Counts EvidenceCalibration::countsWithout(size_t scan_index) const {
  Counts total{std::vector<double>(kBins, 0.0), std::vector<double>(kBins, 0.0)};
  for (const auto& [index, counts] : per_scan_) {
    if (index == scan_index && per_scan_.size() > 1) continue;
    for (size_t b = 0; b < kBins; ++b) {
      total.errors[b] += counts.errors[b];
      total.points[b] += counts.points[b];
    }
  }
  return total;
}

double EvidenceCalibration::uncertaintyOfBin(size_t bin, size_t scan_index) const {
  if (per_scan_.empty())
    throw std::runtime_error("evidence calibration needs a mapping scan with GT");
  const Counts c = countsWithout(scan_index);
  double errors = 0.0, points = 0.0;
  for (size_t b = 0; b < kBins; ++b) {
    errors += c.errors[b];
    points += c.points[b];
  }
  const double overall = points > 0.0 ? errors / points : 0.5;
  const double rate = (c.errors[bin] + kSmoothing * overall) / (c.points[bin] + kSmoothing);
  return std::clamp(rate, kMinU, kMaxU);
}

void EvidenceCalibration::apply(size_t scan_index, std::vector<float>* evidence) const {
  std::vector<double> u_of_bin(kBins);
  for (size_t b = 0; b < kBins; ++b) u_of_bin[b] = uncertaintyOfBin(b, scan_index);
  const size_t n = evidence->size() / num_classes_;
  for (size_t i = 0; i < n; ++i) {
    float* e = &(*evidence)[i * num_classes_];
    double sum = 0.0;
    for (int c = 0; c < num_classes_; ++c) sum += e[c];
    if (!(sum > 0.0)) continue;
    const double target = num_classes_ * (1.0 / u_of_bin[binOf(e)] - 1.0);  // sum(e') for u
    const double scale = target / sum;
    for (int c = 0; c < num_classes_; ++c) e[c] = float(e[c] * scale);
  }
}

}  // namespace evidential_octomap::tools
