// Calibration of a network's evidence before it reaches the map: e' = scale * e^power per value.
//
// An evidential network's evidence has a scale nobody tells the map (EDL nets are often
// under-confident, softmax-derived evidence over-confident) and a sharpness that may be off too.
// `scale` corrects the first and `power` the second (for e = exp(z) it is temperature scaling of
// the logits, z' = power * z + ln scale). Both are fitted by `evidential_octomap calibrate`
// (src/tools/calibration_fit.h): on a user's labelled scans, or without labels on the agreement
// of each point's prediction with the other scans' predictions of its voxel. The identity
// (scale 1, power 1) changes nothing.
#pragma once

#include <cstddef>
#include <string>

namespace evidential_octomap {

struct InputCalibration {
  double scale = 1.0;
  double power = 1.0;
  // What the constants were fitted against: "gt" (labelled scans), "consensus" (label-free) or
  // "" (identity, not fitted), and on which data; both only describe, nothing reads them.
  std::string labels;
  std::string fitted_on;

  bool isIdentity() const { return scale == 1.0 && power == 1.0; }
  // "" when usable, else the value and its allowed range.
  std::string problem() const;
  // Rewrites `n` rows of `num_classes` evidence values in place.
  void apply(float* evidence, size_t n, int num_classes) const;
  // One line for captions, e.g. "e' = 3.1 e^1.25 (consensus, label-free)".
  std::string describe() const;

  // A small YAML file (scale, power, labels, fitted_on). load() throws std::runtime_error naming
  // the file and the problem; save() writes atomically (io.h) and throws on failure.
  static InputCalibration load(const std::string& path);
  void save(const std::string& path) const;

  static constexpr double kMinScale = 1e-6, kMaxScale = 1e6, kMinPower = 0.05, kMaxPower = 5.0;
};

}  // namespace evidential_octomap
