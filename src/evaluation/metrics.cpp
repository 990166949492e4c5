// Metric definitions (metrics.h): confusion matrix, error-detection rankings, and the
// accumulator that turns per-query answers into the metric set.
#include "evidential_octomap/evaluation/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace evidential_octomap {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMinProbability = 1e-6;  // NLL clip
}  // namespace

double brierScore(int gt, const Answer& a, int num_classes) {
  const bool labelled = a.label >= 0 && a.label < num_classes;
  if (!labelled || a.probability.empty()) {
    const double uniform = 1.0 / num_classes;
    return (1.0 - uniform) * (1.0 - uniform) + (num_classes - 1) * uniform * uniform;
  }
  double brier = 0.0;
  for (int c = 0; c < num_classes; ++c) {
    const double p = a.probability[c];
    brier += (p - (c == gt)) * (p - (c == gt));
  }
  return brier;
}

// --- ConfusionMatrix ----------------------------------------------------------------------

ConfusionMatrix::ConfusionMatrix(int num_classes) : num_classes_(num_classes) {
  if (num_classes < 0) throw std::invalid_argument("ConfusionMatrix: negative class count");
  counts_.assign(size_t(num_classes) * size_t(num_classes + 1), 0);
}

void ConfusionMatrix::add(int gt, int predicted, uint64_t count) {
  if (gt < 0 || gt >= num_classes_) {
    throw std::out_of_range("ConfusionMatrix::add: gt class " + std::to_string(gt) +
                            " outside [0, " + std::to_string(num_classes_) + ")");
  }
  if (predicted < -1 || predicted >= num_classes_) {
    throw std::out_of_range("ConfusionMatrix::add: predicted class " + std::to_string(predicted) +
                            " outside [-1, " + std::to_string(num_classes_) + ")");
  }
  const int col = predicted < 0 ? num_classes_ : predicted;
  counts_[size_t(gt) * size_t(num_classes_ + 1) + size_t(col)] += count;
  total_ += count;
}

void ConfusionMatrix::merge(const ConfusionMatrix& other) {
  if (other.num_classes_ != num_classes_) {
    throw std::invalid_argument("ConfusionMatrix::merge: class counts differ");
  }
  for (size_t i = 0; i < counts_.size(); ++i) counts_[i] += other.counts_[i];
  total_ += other.total_;
}

uint64_t ConfusionMatrix::at(int gt, int predicted) const {
  const int col = predicted < 0 ? num_classes_ : predicted;
  return counts_[size_t(gt) * size_t(num_classes_ + 1) + size_t(col)];
}

uint64_t ConfusionMatrix::correct() const {
  uint64_t sum = 0;
  for (int c = 0; c < num_classes_; ++c) sum += at(c, c);
  return sum;
}

uint64_t ConfusionMatrix::gtCount(int c) const {
  uint64_t sum = 0;
  for (int p = -1; p < num_classes_; ++p) sum += at(c, p);
  return sum;
}

uint64_t ConfusionMatrix::predCount(int c) const {
  uint64_t sum = 0;
  for (int g = 0; g < num_classes_; ++g) sum += at(g, c);
  return sum;
}

double ConfusionMatrix::iou(int c) const {
  const uint64_t tp = at(c, c);
  const uint64_t fn = gtCount(c) - tp;
  const uint64_t fp = predCount(c) - tp;
  const uint64_t denom = tp + fn + fp;
  return denom == 0 ? kNaN : double(tp) / double(denom);
}

double ConfusionMatrix::meanIou(int ignore_class) const {
  double sum = 0.0;
  int n = 0;
  for (int c = 0; c < num_classes_; ++c) {
    if (c == ignore_class || !presentInGt(c)) continue;
    sum += iou(c);
    ++n;
  }
  return n == 0 ? kNaN : sum / n;
}

double ConfusionMatrix::accuracy() const {
  return total_ == 0 ? kNaN : double(correct()) / double(total_);
}

// --- error-detection rankings --------------------------------------------------------------

namespace {
// Indices sorted by ascending score, and the [begin, end) runs of equal scores.
std::vector<uint32_t> sortedOrder(const std::vector<float>& score) {
  std::vector<uint32_t> order(score.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return score[a] < score[b]; });
  return order;
}
}  // namespace

double auroc(const std::vector<float>& score, const std::vector<uint8_t>& positive) {
  const std::vector<uint32_t> order = sortedOrder(score);
  // Mann-Whitney U: sum of the (tie-averaged) ranks of the positives.
  double rank_sum = 0.0;
  size_t positives = 0;
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    size_t group_positives = 0;
    while (j < order.size() && score[order[j]] == score[order[i]])
      group_positives += positive[order[j++]];
    rank_sum += double(group_positives) * (double(i + 1) + double(j)) / 2.0;
    positives += group_positives;
    i = j;
  }
  const size_t negatives = order.size() - positives;
  if (positives == 0 || negatives == 0) return kNaN;
  const double u = rank_sum - double(positives) * double(positives + 1) / 2.0;
  return u / (double(positives) * double(negatives));
}

double aurc(const std::vector<float>& score, const std::vector<uint8_t>& wrong) {
  const std::vector<uint32_t> order = sortedOrder(score);
  if (order.empty()) return kNaN;
  double sum = 0.0, errors_before = 0.0;
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    double group_errors = 0.0;
    while (j < order.size() && score[order[j]] == score[order[i]])
      group_errors += wrong[order[j++]];
    // In a random order of the tied group, t of its m answers hold t/m of its errors on average.
    const double m = double(j - i);
    for (size_t k = i; k < j; ++k) {
      const double t = double(k - i + 1);
      sum += (errors_before + group_errors * t / m) / double(k + 1);
    }
    errors_before += group_errors;
    i = j;
  }
  return sum / double(order.size());
}

// --- QualityAccumulator -------------------------------------------------------------------

const ErrorDetection* QualityMetrics::detection(const std::string& output) const {
  for (const ErrorDetection& d : error_detection) {
    if (d.output == output) return &d;
  }
  return nullptr;
}

QualityAccumulator::QualityAccumulator(int num_classes, int ignore_class)
    : num_classes_(num_classes),
      ignore_class_(ignore_class),
      bins_(kBins),
      uncertainty_(kUncertaintyOutputs.size()) {
  m_.all = ConfusionMatrix(num_classes);
  m_.labelled_only = ConfusionMatrix(num_classes);
  for (int b = 0; b < kBins; ++b) {
    bins_[b].lower = double(b) / kBins;
    bins_[b].upper = double(b + 1) / kBins;
  }
}

void QualityAccumulator::add(int gt, const Answer& a) {
  if (gt < 0 || gt >= num_classes_ || gt == ignore_class_) return;
  ++m_.queries;
  const int label = (a.label >= 0 && a.label < num_classes_) ? a.label : -1;
  m_.all.add(gt, label);
  // Projected probabilities (uniform without an answer): Brier, NLL, confidence.
  const double uniform = 1.0 / num_classes_;
  double confidence = uniform, p_gt = uniform;
  if (label >= 0 && !a.probability.empty()) {
    confidence = *std::max_element(a.probability.begin(), a.probability.end());
    p_gt = a.probability[gt];
  }
  brier_sum_ += brierScore(gt, a, num_classes_);
  nll_sum_ -= std::log(std::max(p_gt, kMinProbability));
  const bool correct = label == gt;
  ReliabilityBin& bin = bins_[std::min(kBins - 1, int(confidence * kBins))];
  ++bin.count;
  bin.mean_confidence += confidence;
  bin.accuracy += correct;
  if (label < 0) return;
  ++m_.labelled;
  m_.labelled_only.add(gt, label);
  wrong_.push_back(!correct);
  for (size_t o = 0; o < uncertainty_.size(); ++o) {
    uncertainty_[o].push_back(o < a.uncertainty.size() ? a.uncertainty[o] : 0.0f);
  }
}

QualityMetrics QualityAccumulator::finish() const {
  QualityMetrics m = m_;
  const double n = double(m.queries);
  m.miou_all = m.all.meanIou(ignore_class_);
  m.acc_all = m.all.accuracy();
  m.miou_labelled = m.labelled_only.meanIou(ignore_class_);
  m.acc_labelled = m.labelled_only.accuracy();
  m.brier = m.queries ? brier_sum_ / n : kNaN;
  m.nll = m.queries ? nll_sum_ / n : kNaN;
  m.reliability = bins_;
  m.ece = 0.0;
  for (ReliabilityBin& b : m.reliability) {
    if (b.count == 0) continue;
    b.mean_confidence /= double(b.count);
    b.accuracy /= double(b.count);
    m.ece += double(b.count) / n * std::fabs(b.accuracy - b.mean_confidence);
  }
  if (!m.queries) m.ece = kNaN;
  const size_t errors = std::accumulate(wrong_.begin(), wrong_.end(), size_t(0));
  m.error_rate_labelled = m.labelled ? double(errors) / double(m.labelled) : kNaN;
  for (size_t o = 0; o < kUncertaintyOutputs.size(); ++o) {
    ErrorDetection d;
    d.output = kUncertaintyOutputs[o];
    d.auroc = auroc(uncertainty_[o], wrong_);
    d.aurc = aurc(uncertainty_[o], wrong_);
    const std::vector<uint32_t> order = sortedOrder(uncertainty_[o]);
    for (int b = 0; b < kBins && !order.empty(); ++b) {
      const size_t lo = order.size() * b / kBins, hi = order.size() * (b + 1) / kBins;
      double e = 0.0, s = 0.0;
      for (size_t i = lo; i < hi; ++i) {
        e += wrong_[order[i]];
        s += uncertainty_[o][order[i]];
      }
      d.error_rate_by_decile.push_back(hi > lo ? e / double(hi - lo) : kNaN);
      d.mean_output_by_decile.push_back(hi > lo ? s / double(hi - lo) : kNaN);
    }
    m.error_detection.push_back(std::move(d));
  }
  return m;
}

}  // namespace evidential_octomap
