// Synthetic noisy predictions for data that ships only ground truth (the RELLIS-3D scan).
// Labelled "synthetic" in every output. The noise model, with a fixed seed:
//   1. region confusion: space is cut into cubes of `region_size` metres; each cube, with
//      probability `region_rate`, has all its points relabelled to one class (what a network
//      does when it confuses a whole patch);
//   2. point noise: each remaining point, with probability `point_rate`, gets a class drawn
//      uniformly from the other classes present in the scan's GT.
// Replacement classes are drawn from the classes present in the scan's GT (ignore class
// excluded). Ignore-class points keep their label unless a region flip hits them. Randomness is
// std::mt19937_64 (a standard-defined engine) and a SplitMix64 hash of the cube, so the result is
// the same on every platform.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace evidential_octomap::tools {

struct NoiseModel {
  double point_rate = 0.10;
  double region_rate = 0.05;
  double region_size = 1.0;  // [m]
  uint64_t seed = 42;
  std::string describe() const;
};

std::vector<int> syntheticPredictions(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<int>& gt, int num_classes,
                                      int ignore_class, const NoiseModel& model);

}  // namespace evidential_octomap::tools
