// OctoMap's occupancy sensor model as one value, and the one check of it shared by the tree's
// setter, its file reader and writer, the ROS node's parameters and its dynamic_reconfigure
// ranges: a model inside these ranges has finite log-odds and is not inverted, so every map
// written with it loads again.
#pragma once

#include <string>

namespace evidential_octomap {

struct SensorModel {
  double hit = 0.0;        // P(occupied | hit)
  double miss = 0.0;       // P(occupied | miss)
  double clamp_min = 0.0;  // clamping thresholds of the occupancy probability
  double clamp_max = 0.0;
  double occupancy_threshold = 0.0;  // P above which a voxel counts as occupied

  // Closed ranges (dynamic_reconfigure uses them as its slider bounds). Probabilities stay in
  // [0.001, 0.999] (|log-odds| <= 6.9); a hit never lowers occupancy, a miss never raises it,
  // and clamping never turns a voxel free by rays into an occupied one or the reverse
  // (clamp_min <= 0.5 <= clamp_max; a mutated file with clamps 0.5 + 1e-43 .. 0.5 + 2e-38
  // loaded with every observed voxel occupied).
  static constexpr double kMinProbability = 0.001;
  static constexpr double kMaxProbability = 0.999;
  static constexpr double kMinHit = 0.5, kMaxHit = kMaxProbability;
  static constexpr double kMinMiss = kMinProbability, kMaxMiss = 0.5;
  static constexpr double kMinClampMin = kMinProbability, kMaxClampMin = 0.5;
  static constexpr double kMinClampMax = 0.5, kMaxClampMax = kMaxProbability;

  // "" when the model is usable, else the first value out of range (and clamp_min < clamp_max).
  std::string problem() const;
  // The same check on log-odds as stored in a tree or a file (float, as OctoMap stores them;
  // comparisons are made in float so a value written from an accepted model is accepted).
  static std::string problemOfLogOdds(float hit_log, float miss_log, float clamp_min_log,
                                      float clamp_max_log, float threshold_log);
};

}  // namespace evidential_octomap
