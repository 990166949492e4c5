#include "input_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "rng.h"

namespace evidential_octomap::generator {

namespace {
int bandOf(double r) {
  if (r < 10) return 0;
  if (r < 20) return 1;
  if (r < 30) return 2;
  if (r < 50) return 3;
  if (r < 80) return 4;
  return 5;
}
const char* kBandNames[InputMetrics::kRangeBands] = {"0-10 m",  "10-20 m", "20-30 m",
                                                     "30-50 m", "50-80 m", "80+ m"};
}  // namespace

void InputMetrics::Bins::add(double p, bool ok) {
  const int b = std::clamp(int(p * kBins), 0, kBins - 1);
  conf[b] += p;
  correct[b] += ok;
  ++count[b];
}

double InputMetrics::Bins::ece() const {
  size_t n = 0;
  double e = 0.0;
  for (int b = 0; b < kBins; ++b) {
    n += count[b];
    e += std::abs(conf[b] - correct[b]);
  }
  return n ? e / double(n) : 0.0;
}

double auroc(const std::vector<float>& score, const std::vector<uint8_t>& positive) {
  std::vector<size_t> order(score.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return score[a] < score[b] || (score[a] == score[b] && a < b);
  });
  double rank_sum = 0.0;
  size_t pos = 0;
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    while (j < order.size() && score[order[j]] == score[order[i]]) ++j;
    const double mid = 0.5 * double(i + j - 1) + 1.0;  // average rank of the tie group
    for (size_t k = i; k < j; ++k) {
      if (positive[order[k]]) rank_sum += mid, ++pos;
    }
    i = j;
  }
  const size_t neg = score.size() - pos;
  if (pos == 0 || neg == 0) return 0.5;
  return (rank_sum - double(pos) * (pos + 1) / 2.0) / (double(pos) * double(neg));
}

void InputMetrics::add(int scan, const std::vector<LidarPoint>& points, const NetworkOutput& net) {
  const int C = C_;
  for (size_t i = 0; i < points.size(); ++i) {
    const int g = net.gt[i];
    if (g <= 0) continue;  // void is ignored, as in the map's evaluation
    const bool ok = net.predicted[i] == g;
    ++points_;
    correct_ += ok;
    const int band = bandOf(points[i].range);
    ++band_points_[band];
    band_correct_[band] += ok;
    if (net.in_wrong_cell[i]) ++wrong_cell_points_, wrong_cell_correct_ += ok;
    const float* z = net.logits.data() + i * C;
    const float* e = net.evidence.data() + i * C;
    double m = z[0], S = C, sum = 0.0;
    for (int c = 0; c < C; ++c) m = std::max(m, double(z[c])), S += e[c];
    for (int c = 0; c < C; ++c) sum += std::exp(z[c] - m);
    const double maxp = 1.0 / sum;
    const int pred = net.predicted[i];
    softmax_.add(maxp, ok);
    dirichlet_.add((e[pred] + 1.0) / S, ok);
    const uint64_t h = hashOf(seed_, 99, uint64_t(scan), points[i].beam, points[i].column);
    if (unitOf(h) < keep_) {
      u_.push_back(float(C / S));
      maxp_.push_back(float(1.0 - maxp));
      wrong_.push_back(!ok);
    }
  }
}

double InputMetrics::aurocVacuity() const { return auroc(u_, wrong_); }
double InputMetrics::aurocSoftmax() const { return auroc(maxp_, wrong_); }

nlohmann::json InputMetrics::toJson() const {
  nlohmann::json j;
  j["synthetic"] = true;
  j["points"] = points_;
  j["accuracy"] = accuracy();
  j["auroc_vacuity"] = aurocVacuity();
  j["auroc_one_minus_max_softmax"] = aurocSoftmax();
  j["auroc_points"] = u_.size();
  j["ece_softmax"] = softmax_.ece();
  j["ece_dirichlet_mean"] = dirichlet_.ece();
  j["wrong_cell_points"] = wrong_cell_points_;
  j["wrong_cell_accuracy"] =
      wrong_cell_points_ ? double(wrong_cell_correct_) / wrong_cell_points_ : 0.0;
  for (int b = 0; b < kRangeBands; ++b) {
    j["range_bands"].push_back(
        {{"band", kBandNames[b]},
         {"points", band_points_[b]},
         {"accuracy", band_points_[b] ? double(band_correct_[b]) / band_points_[b] : 0.0}});
  }
  for (const auto& [name, bins] : {std::pair<const char*, const Bins*>{"softmax", &softmax_},
                                   {"dirichlet_mean", &dirichlet_}}) {
    for (int b = 0; b < kBins; ++b) {
      const size_t n = bins->count[b];
      j["reliability"][name].push_back({{"lo", double(b) / kBins},
                                        {"hi", double(b + 1) / kBins},
                                        {"count", n},
                                        {"confidence", n ? bins->conf[b] / n : 0.0},
                                        {"accuracy", n ? bins->correct[b] / n : 0.0}});
    }
  }
  return j;
}

std::string InputMetrics::toMarkdown() const {
  std::ostringstream s;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "| points | accuracy | AUROC u=C/S | AUROC 1-max softmax | ECE softmax | "
                "ECE Dirichlet mean | accuracy in wrong cells |\n|---|---|---|---|---|---|---|\n"
                "| %zu | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f (%zu points) |\n",
                points_, accuracy(), aurocVacuity(), aurocSoftmax(), softmax_.ece(),
                dirichlet_.ece(),
                wrong_cell_points_ ? double(wrong_cell_correct_) / wrong_cell_points_ : 0.0,
                wrong_cell_points_);
  s << buf << "\nAccuracy by range:";
  for (int b = 0; b < kRangeBands; ++b) {
    if (!band_points_[b]) continue;
    std::snprintf(buf, sizeof(buf), " %s %.3f (%zu);", kBandNames[b],
                  double(band_correct_[b]) / band_points_[b], band_points_[b]);
    s << buf;
  }
  s << "\n";
  return s.str();
}

}  // namespace evidential_octomap::generator
