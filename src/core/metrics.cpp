#include "evidential_octomap/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

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

// --- uncertainty scaling ------------------------------------------------------------------

double UncertaintyScale::apply(double u) const {
  double t = u;
  if (scaled) t = max > min ? (u - min) / (max - min) : 0.0;
  return std::min(1.0, std::max(0.0, t));
}

std::string UncertaintyScale::describe() const {
  if (!scaled) return "uncertainty is a mass in [0,1], used as is";
  std::ostringstream s;
  s << "min-max scaled over the map's semantic leaves (min " << min << ", max " << max << ")";
  return s.str();
}

UncertaintyScale uncertaintyScale(const EvidentialOcTree& tree) {
  UncertaintyScale scale;
  if (tree.rule().uncertaintyIsMass()) return scale;
  scale.scaled = true;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!it->hasSemantics()) continue;
    const double u = tree.opinion(&*it).uncertainty;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  if (lo > hi) {  // no semantic leaf at all
    lo = 0.0;
    hi = 1.0;
  }
  scale.min = lo;
  scale.max = hi;
  return scale;
}

// --- evaluation ---------------------------------------------------------------------------

MapMetrics evaluateMap(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                       int ignore_class) {
  const int C = tree.numClasses();
  MapMetrics m;
  m.confusion = ConfusionMatrix(C);
  m.confusion_all = ConfusionMatrix(C);
  m.scale = uncertaintyScale(tree);

  double brier_sum = 0.0, u_correct = 0.0, u_wrong = 0.0;
  size_t n_correct = 0, n_wrong = 0;
  for (const Query& q : queries) {
    if (q.gt < 0 || q.gt >= C || q.gt == ignore_class) continue;
    ++m.queries;
    const EvidentialOcTreeNode* node = tree.search(q.point_W);
    if (node == nullptr || !tree.isNodeOccupied(node)) {
      m.confusion_all.add(q.gt, -1);
      continue;
    }
    ++m.covered;
    int label = -1;
    double u_bar = 1.0;
    if (node->hasSemantics()) {
      const VoxelOpinion op = tree.opinion(node);
      label = (op.label >= 0 && op.label < C) ? op.label : -1;
      u_bar = label >= 0 ? m.scale.apply(op.uncertainty) : 1.0;
    }
    m.confusion.add(q.gt, label);
    m.confusion_all.add(q.gt, label);
    const bool wrong = label != q.gt;
    const double d = u_bar - (wrong ? 1.0 : 0.0);
    brier_sum += d * d;
    if (wrong) {
      u_wrong += u_bar;
      ++n_wrong;
    } else {
      u_correct += u_bar;
      ++n_correct;
    }
  }
  m.occupied_accuracy = m.queries ? double(m.covered) / double(m.queries) : kNaN;
  m.miou = m.confusion.meanIou(ignore_class);
  m.accuracy = m.confusion.accuracy();
  m.miou_all = m.confusion_all.meanIou(ignore_class);
  m.accuracy_all = m.confusion_all.accuracy();
  m.brier = m.covered ? brier_sum / double(m.covered) : kNaN;
  m.mean_u_correct = n_correct ? u_correct / double(n_correct) : kNaN;
  m.mean_u_wrong = n_wrong ? u_wrong / double(n_wrong) : kNaN;
  return m;
}

PredictionMetrics evaluatePredictions(const std::vector<Query>& queries, int num_classes,
                                      int ignore_class) {
  PredictionMetrics m;
  m.confusion = ConfusionMatrix(num_classes);
  for (const Query& q : queries) {
    if (q.gt < 0 || q.gt >= num_classes || q.gt == ignore_class) continue;
    ++m.queries;
    const int p = (q.predicted >= 0 && q.predicted < num_classes) ? q.predicted : -1;
    m.confusion.add(q.gt, p);
  }
  m.miou = m.confusion.meanIou(ignore_class);
  m.accuracy = m.confusion.accuracy();
  return m;
}

}  // namespace evidential_octomap
