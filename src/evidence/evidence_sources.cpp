#include "evidential_octomap/evidence/evidence_sources.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "evidential_octomap/evidence/neighbour_grid.h"

namespace evidential_octomap {

namespace {
const std::vector<std::pair<EvidenceSource, std::string>> kSourceNames{
    {EvidenceSource::kFile, "file"},
    {EvidenceSource::kOneHot, "onehot"},
    {EvidenceSource::kKnnVote, "knn-vote"},
    {EvidenceSource::kConfusion, "confusion"},
    {EvidenceSource::kLearned, "learned"}};

void requirePredictions(const Scan& scan, const std::string& source) {
  if (scan.predicted.size() != scan.size()) {
    throw std::runtime_error("evidence source '" + source + "' needs predictions/ labels, scan " +
                             scan.name + " has none");
  }
}
}  // namespace

EvidenceSource evidenceSourceFromName(const std::string& name) {
  for (const auto& [source, n] : kSourceNames) {
    if (n == name) return source;
  }
  throw std::invalid_argument("unknown evidence source '" + name +
                              "' (valid: file, onehot, knn-vote, confusion, learned)");
}

std::string evidenceSourceName(EvidenceSource source) {
  for (const auto& [s, n] : kSourceNames) {
    if (s == source) return n;
  }
  return "?";
}

bool derivedFromHardLabels(EvidenceSource source) {
  return source != EvidenceSource::kFile && source != EvidenceSource::kLearned;
}

std::string evidenceKind(EvidenceSource source) {
  if (source == EvidenceSource::kLearned) return "learned (cross-fitted)";
  return derivedFromHardLabels(source) ? "derived" : "network evidence";
}

std::string defaultLearnedModel(const std::string& classes_path, const ClassTable& classes) {
  const std::filesystem::path dir = std::filesystem::path(classes_path).parent_path();
  return (dir / "learned" / (classes.dataset + ".model")).string();
}

ScanInput scanInput(const Scan& scan) {
  ScanInput in;
  in.xyz = scan.points_S.empty() ? nullptr : scan.points_S.front().data();
  in.remission = scan.remission.size() == scan.size() ? scan.remission.data() : nullptr;
  in.predicted = scan.predicted.size() == scan.size() ? scan.predicted.data() : nullptr;
  in.num_points = scan.size();
  return in;
}

std::string describeEvidence(const EvidenceOptions& o) {
  std::ostringstream s;
  s << evidenceSourceName(o.source);
  switch (o.source) {
    case EvidenceSource::kFile:
      s << " (per-point " << (o.files.empty() ? "evidence files" : o.files) << " of the dataset)";
      return s.str();
    case EvidenceSource::kOneHot:
      s << ", E=" << o.magnitude;
      break;
    case EvidenceSource::kKnnVote:
      s << ", E=" << o.magnitude << ", k=" << o.knn_k << ", r=" << o.knn_radius << " m";
      break;
    case EvidenceSource::kConfusion:
      s << ", E=" << o.magnitude << ", leave-one-scan-out";
      break;
    case EvidenceSource::kLearned:
      s << " (cross-fitted; model " << o.learned_model << ")";
      return s.str();
  }
  if (o.calibrate) s << ", calibrated (u = error rate of such points on the mapping scans)";
  s << " (derived from hard labels)";
  return s.str();
}

std::string inputDescription(const EvidenceOptions& o) {
  return "input evidence (" + evidenceSourceName(o.source) + "), per point";
}

// --- ConfusionModel ----------------------------------------------------------------------------

ConfusionModel::ConfusionModel(int num_classes, int ignore_class)
    : num_classes_(num_classes), ignore_class_(ignore_class) {}

void ConfusionModel::addScan(size_t scan_index, const std::vector<int>& gt,
                             const std::vector<int>& predicted) {
  if (gt.size() != predicted.size()) {
    throw std::invalid_argument("ConfusionModel::addScan: gt and predictions differ in size");
  }
  std::vector<uint64_t> counts(size_t(num_classes_) * num_classes_, 0);
  for (size_t i = 0; i < gt.size(); ++i) {
    if (gt[i] < 0 || gt[i] == ignore_class_ || predicted[i] < 0) continue;
    ++counts[size_t(predicted[i]) * num_classes_ + gt[i]];
  }
  per_scan_.emplace_back(scan_index, std::move(counts));
}

std::vector<double> ConfusionModel::conditional(size_t exclude_scan) const {
  const int C = num_classes_;
  std::vector<double> n(size_t(C) * C, 0.0);
  size_t used = 0;
  for (const auto& [index, counts] : per_scan_) {
    if (index == exclude_scan) continue;
    ++used;
    for (size_t k = 0; k < counts.size(); ++k) n[k] += double(counts[k]);
  }
  if (used == 0) {
    throw std::runtime_error(
        "confusion evidence needs GT and predictions of at least one scan other than the one "
        "being mapped");
  }
  double total = 0.0, diag = 0.0;
  for (int p = 0; p < C; ++p) {
    for (int c = 0; c < C; ++c) {
      total += n[size_t(p) * C + c];
      if (p == c) diag += n[size_t(p) * C + c];
    }
  }
  const double acc = total > 0 ? diag / total : 1.0 / C;
  const double m = 10.0;
  std::vector<double> P(size_t(C) * C);
  for (int p = 0; p < C; ++p) {
    double row = 0.0;
    for (int c = 0; c < C; ++c) row += n[size_t(p) * C + c];
    for (int c = 0; c < C; ++c) {
      const double prior = c == p ? acc : (C > 1 ? (1.0 - acc) / (C - 1) : 0.0);
      P[size_t(p) * C + c] = (n[size_t(p) * C + c] + m * prior) / (row + m);
    }
  }
  return P;
}

// --- derivations -------------------------------------------------------------------------------

std::vector<float> oneHotEvidence(const std::vector<int>& predicted, int num_classes,
                                  float magnitude) {
  std::vector<float> e(predicted.size() * size_t(num_classes), 0.0f);
  for (size_t i = 0; i < predicted.size(); ++i) {
    if (predicted[i] >= 0 && predicted[i] < num_classes) {
      e[i * num_classes + predicted[i]] = magnitude;
    }
  }
  return e;
}

std::vector<float> knnVoteEvidence(const std::vector<Eigen::Vector3f>& points,
                                   const std::vector<int>& predicted, int num_classes, int k,
                                   double radius, float magnitude) {
  if (points.size() != predicted.size()) {
    throw std::invalid_argument("knnVoteEvidence: points and predictions differ in size");
  }
  if (k < 1 || radius <= 0.0) throw std::invalid_argument("knnVoteEvidence: k >= 1, radius > 0");
  const size_t N = points.size();
  const NeighbourGrid grid(N ? points.front().data() : nullptr, N, float(radius));
  std::vector<float> evidence(N * size_t(num_classes), 0.0f);
  std::vector<std::pair<float, uint32_t>> candidates;
  std::vector<int> votes(num_classes, 0);
  for (size_t i = 0; i < N; ++i) {
    grid.nearest(i, k, &candidates);
    const int n = int(candidates.size());  // >= 1: the point itself
    std::fill(votes.begin(), votes.end(), 0);
    for (const auto& cand : candidates) {
      const int c = predicted[cand.second];
      if (c >= 0 && c < num_classes) ++votes[c];
    }
    for (int cls = 0; cls < num_classes; ++cls) {
      if (votes[cls] == 0) continue;
      evidence[i * num_classes + cls] =
          magnitude * float(votes[cls]) * float(votes[cls]) / (float(k) * float(n));
    }
  }
  return evidence;
}

std::vector<float> confusionEvidence(const std::vector<int>& predicted,
                                     const std::vector<double>& P, int num_classes,
                                     float magnitude) {
  const int C = num_classes;
  std::vector<float> e(predicted.size() * size_t(C), 0.0f);
  for (size_t i = 0; i < predicted.size(); ++i) {
    const int p = predicted[i];
    if (p < 0 || p >= C) continue;
    const double precision = P[size_t(p) * C + p];
    for (int c = 0; c < C; ++c) {
      e[i * C + c] = float(magnitude * precision * P[size_t(p) * C + c]);
    }
  }
  return e;
}

std::vector<float> deriveEvidence(const Scan& scan, size_t scan_index,
                                  const EvidenceOptions& options, int num_classes,
                                  const ConfusionModel* model,
                                  const LearnedEvidenceModel* learned) {
  switch (options.source) {
    case EvidenceSource::kFile:
      if (scan.evidence.size() != scan.size() * size_t(num_classes)) {
        throw std::runtime_error("evidence source 'file' needs evidence/ or alpha/ files, scan " +
                                 scan.name + " has none");
      }
      return scan.evidence;
    case EvidenceSource::kOneHot:
      requirePredictions(scan, "onehot");
      return oneHotEvidence(scan.predicted, num_classes, options.magnitude);
    case EvidenceSource::kKnnVote:
      requirePredictions(scan, "knn-vote");
      return knnVoteEvidence(scan.points_S, scan.predicted, num_classes, options.knn_k,
                             options.knn_radius, options.magnitude);
    case EvidenceSource::kConfusion:
      requirePredictions(scan, "confusion");
      if (model == nullptr) throw std::runtime_error("confusion evidence needs a ConfusionModel");
      return confusionEvidence(scan.predicted, model->conditional(scan_index), num_classes,
                               options.magnitude);
    case EvidenceSource::kLearned:
      requirePredictions(scan, "learned");
      if (learned == nullptr) throw std::runtime_error("learned evidence needs a loaded model");
      if (learned->numClasses() != num_classes) {
        throw std::runtime_error(learned->path() + " has " + std::to_string(learned->numClasses()) +
                                 " classes, the class table " + std::to_string(num_classes));
      }
      try {
        return learned->evidence(scanInput(scan));
      } catch (const std::runtime_error& e) {
        throw std::runtime_error("scan " + scan.name + ": " + e.what());
      }
  }
  return {};
}

}  // namespace evidential_octomap
