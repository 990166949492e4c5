#include "calibration_fit.h"

#include <cmath>
#include <functional>
#include <stdexcept>

namespace evidential_octomap::tools {
namespace {

struct Sample {
  std::vector<float> evidence;  // n x C
  std::vector<int> label;
};

Sample samplePoints(const std::vector<std::vector<float>>& evidence,
                    const std::vector<std::vector<int>>& labels, int C, int ignore_class,
                    size_t max_points) {
  size_t usable = 0;
  const auto usableAt = [&](size_t s, size_t i) {
    const int y = labels[s][i];
    if (y < 0 || y >= C || y == ignore_class) return false;
    for (int c = 0; c < C; ++c) {
      if (evidence[s][i * C + c] > 0.0f) return true;
    }
    return false;
  };
  for (size_t s = 0; s < labels.size(); ++s) {
    if (labels[s].empty()) continue;
    if (evidence.at(s).size() != labels[s].size() * size_t(C)) {
      throw std::runtime_error("calibration: evidence and labels of a scan differ in size");
    }
    for (size_t i = 0; i < labels[s].size(); ++i) usable += usableAt(s, i);
  }
  if (usable == 0) throw std::runtime_error("calibration: no labelled point with evidence");
  const size_t stride = (usable + max_points - 1) / max_points;
  Sample out;
  size_t k = 0;
  for (size_t s = 0; s < labels.size(); ++s) {
    for (size_t i = 0; i < labels[s].size(); ++i) {
      if (!usableAt(s, i) || k++ % stride != 0) continue;
      out.evidence.insert(out.evidence.end(), evidence[s].begin() + i * C,
                          evidence[s].begin() + (i + 1) * C);
      out.label.push_back(labels[s][i]);
    }
  }
  return out;
}

// Golden-section minimum of a unimodal f on [lo, hi].
double goldenMin(const std::function<double(double)>& f, double lo, double hi, int steps) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = lo, b = hi, x1 = b - r * (b - a), x2 = a + r * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < steps; ++i) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - r * (b - a), f1 = f(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + r * (b - a), f2 = f(x2);
    }
  }
  return (a + b) / 2.0;
}

// The mean NLL as a function of ln(scale) for one power: per point e_y^power and sum e^power.
class PowerTerms {
 public:
  PowerTerms(const Sample& s, int C, double power) : C_(C) {
    const size_t n = s.label.size();
    label_.resize(n);
    sum_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      double sum = 0.0;
      for (int c = 0; c < C; ++c) {
        const double e = s.evidence[i * C + c];
        sum += e > 0.0 ? std::pow(e, power) : 0.0;
      }
      const double ey = s.evidence[i * C + s.label[i]];
      label_[i] = ey > 0.0 ? std::pow(ey, power) : 0.0;
      sum_[i] = sum;
    }
  }
  double nll(double log_scale) const {
    const double scale = std::exp(log_scale);
    double total = 0.0;
    for (size_t i = 0; i < label_.size(); ++i) {
      total += std::log(scale * sum_[i] + C_) - std::log1p(scale * label_[i]);
    }
    return total / double(label_.size());
  }

 private:
  int C_;
  std::vector<double> label_, sum_;
};

}  // namespace

CalibrationFit fitInputCalibration(const std::vector<std::vector<float>>& evidence,
                                   const std::vector<std::vector<int>>& labels, int num_classes,
                                   int ignore_class, size_t max_points) {
  const Sample sample = samplePoints(evidence, labels, num_classes, ignore_class, max_points);
  const double lo = std::log(InputCalibration::kMinScale), hi = std::log(InputCalibration::kMaxScale);
  // Best ln(scale) and its NLL for a power.
  const auto bestForPower = [&](double power, double* log_scale) {
    const PowerTerms terms(sample, num_classes, power);
    *log_scale = goldenMin([&](double x) { return terms.nll(x); }, lo, hi, 60);
    return terms.nll(*log_scale);
  };
  // A coarse log grid of powers first (the NLL need not be unimodal in the power far from its
  // minimum), then golden-section between the grid neighbours of the best.
  const double pmin = std::log(InputCalibration::kMinPower), pmax = std::log(InputCalibration::kMaxPower);
  constexpr int kGrid = 24;
  int best_k = 0;
  double best_nll = INFINITY, ignored = 0.0;
  for (int k = 0; k <= kGrid; ++k) {
    const double nll = bestForPower(std::exp(pmin + (pmax - pmin) * k / kGrid), &ignored);
    if (nll < best_nll) best_nll = nll, best_k = k;
  }
  const double step = (pmax - pmin) / kGrid;
  const double log_power = goldenMin(
      [&](double x) { return bestForPower(std::exp(x), &ignored); },
      pmin + std::max(0, best_k - 1) * step, pmin + std::min(kGrid, best_k + 1) * step, 25);
  CalibrationFit fit;
  fit.points = sample.label.size();
  fit.calibration.power = std::exp(log_power);
  double log_scale = 0.0;
  fit.nll_after = bestForPower(fit.calibration.power, &log_scale);
  fit.calibration.scale = std::exp(log_scale);
  fit.nll_before = PowerTerms(sample, num_classes, 1.0).nll(0.0);
  return fit;
}

}  // namespace evidential_octomap::tools
