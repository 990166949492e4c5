#include "bench_data.h"

#include <evidential_octomap/class_table.h>
#include <evidential_octomap/evaluation/dataset.h>
#include <evidential_octomap/evidence/evidence_sources.h>
#include <evidential_octomap/evidence/learned_evidence.h>
#include <evidential_octomap/subjective_logic.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>

namespace evbench {

KittiSequence::KittiSequence(const std::string& folder, const std::string& class_yaml)
    : classes_(std::make_shared<const evidential_octomap::ClassTable>(
          evidential_octomap::ClassTable::load(class_yaml))),
      dataset_(std::make_shared<const evidential_octomap::Dataset>(
          evidential_octomap::Dataset::open(folder, *classes_))) {
  if (!dataset_->hasPredictions()) throw std::runtime_error(folder + " has no predictions/");
}

size_t KittiSequence::size() const { return dataset_->size(); }

int KittiSequence::numClasses() const { return classes_->numClasses(); }

Scan KittiSequence::load(int i) const {
  if (i < 0 || size_t(i) >= size()) {
    throw std::runtime_error("the sequence has no scan " + std::to_string(i));
  }
  const evidential_octomap::Scan read = dataset_->load(size_t(i));
  Scan scan;
  scan.points_W = read.pointsW();
  const Eigen::Vector3d origin = read.originW();
  scan.origin_W = octomap::point3d(float(origin.x()), float(origin.y()), float(origin.z()));
  scan.classes = read.predicted;
  scan.remission = read.remission;
  scan.xyz_S.reserve(3 * read.size());
  for (const Eigen::Vector3f& p : read.points_S) {
    scan.xyz_S.insert(scan.xyz_S.end(), {p.x(), p.y(), p.z()});
  }
  return scan;
}

std::vector<Scan> loadKittiScans(const std::string& folder, const std::string& class_yaml,
                                 int count, int* num_classes) {
  const KittiSequence sequence(folder, class_yaml);
  *num_classes = sequence.numClasses();
  if (size_t(count) > sequence.size())
    throw std::runtime_error("poses.txt has fewer lines than scans");
  std::vector<Scan> scans;
  for (int i = 0; i < count; ++i) scans.push_back(sequence.load(i));
  return scans;
}

std::vector<int> revisitOrder(int unique, int steps) {
  // 0..n-1, n-2..0, 1..n-1, n-2..0, ...: forth and back, never the same scan twice in a row.
  std::vector<int> order;
  int i = 0, direction = 1;
  while (int(order.size()) < steps) {
    order.push_back(i);
    if (unique < 2) continue;
    if (i + direction < 0 || i + direction >= unique) direction = -direction;
    i += direction;
  }
  return order;
}

std::vector<float> derivedEvidence(const std::vector<int>& classes, int num_classes,
                                   float magnitude) {
  std::vector<float> evidence(classes.size() * size_t(num_classes));
  for (size_t i = 0; i < classes.size(); ++i) {
    evidential_octomap::evidenceFromLabel(classes[i], num_classes, magnitude,
                                          &evidence[i * num_classes]);
  }
  return evidence;
}

std::vector<float> learnedEvidence(const Scan& scan, const std::string& model_path,
                                   int num_classes) {
  static std::string loaded_path;
  static evidential_octomap::LearnedEvidenceModel model;
  if (loaded_path != model_path) {
    model = evidential_octomap::LearnedEvidenceModel::load(model_path);
    loaded_path = model_path;
  }
  if (model.numClasses() != num_classes) {
    throw std::runtime_error(model_path + " has " + std::to_string(model.numClasses()) +
                             " classes, the class table " + std::to_string(num_classes));
  }
  evidential_octomap::ScanInput in;
  in.xyz = scan.xyz_S.data();
  in.remission = scan.remission.data();
  in.predicted = scan.classes.data();
  in.num_points = scan.classes.size();
  return model.evidence(in);
}

std::string defaultLearnedModel(const std::string& class_yaml) {
  return evidential_octomap::defaultLearnedModel(class_yaml,
                                                 evidential_octomap::ClassTable::load(class_yaml));
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // KiB on Linux
}

double currentRssMb() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return pages_resident * 4096.0 / (1024.0 * 1024.0);
}

}  // namespace evbench
