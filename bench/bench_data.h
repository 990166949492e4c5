// Bench-only helpers: the bundled SemanticKITTI scans in the world frame, derived evidence,
// timers and process memory. Nothing here is part of the library.
#pragma once

#include <octomap/Pointcloud.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace evidential_octomap {
struct ClassTable;
class Dataset;
}

namespace evbench {

using Clock = std::chrono::steady_clock;
inline double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// One scan: points already in the world frame (T_world_velo = inv(Tr) * P(i) * Tr), the sensor
// origin, and the class id of every point (predictions through the class table's learning map).
struct Scan {
  octomap::Pointcloud points_W;
  octomap::point3d origin_W;
  std::vector<int> classes;
  std::vector<float> xyz_S;      // N x 3, sensor frame (the learned model's features)
  std::vector<float> remission;  // N
};

// A SemanticKITTI-style folder (velodyne/, predictions/, poses.txt, calib.txt), read by the
// evaluation library's Dataset: scans loaded one at a time, so a long sequence never has to fit
// in memory. Throws std::runtime_error naming the file on any problem.
class KittiSequence {
 public:
  KittiSequence(const std::string& folder, const std::string& class_yaml);
  size_t size() const;
  int numClasses() const;
  Scan load(int i) const;

 private:
  std::shared_ptr<const evidential_octomap::ClassTable> classes_;  // the dataset keeps a pointer
  std::shared_ptr<const evidential_octomap::Dataset> dataset_;
};

// The scan indices of a revisit: 0..unique-1, then back and forth at the real poses
// (0..9, 8..0, 1..9, ... for 10 scans), `steps` of them.
std::vector<int> revisitOrder(int unique, int steps);

// Loads scans 0..count-1 of a SemanticKITTI-style folder (velodyne/, predictions/, poses.txt,
// calib.txt). Throws std::runtime_error naming the file on any problem.
std::vector<Scan> loadKittiScans(const std::string& folder, const std::string& class_yaml,
                                 int count, int* num_classes);

// "Derived" evidence: one-hot of the predicted class with magnitude `magnitude` (N x C).
std::vector<float> derivedEvidence(const std::vector<int>& classes, int num_classes,
                                   float magnitude = 20.0f);

// "Learned (cross-fitted)" evidence (N x C): the model file's folds not trained on the scan.
std::vector<float> learnedEvidence(const Scan& scan, const std::string& model_path,
                                   int num_classes);
// The model file next to a class table: <its directory>/learned/<dataset>.model.
std::string defaultLearnedModel(const std::string& class_yaml);

double median(std::vector<double> values);

// CPU time of the whole process (all threads) [ms]: robust to other load on the machine, unlike
// wall time. For a single-threaded call it equals the wall time on an idle core.
double processCpuMs();

// Peak resident set size of this process [MB] (getrusage ru_maxrss), and current RSS [MB].
double peakRssMb();
double currentRssMb();

}  // namespace evbench
