// Fits InputCalibration (evidential_octomap/input_calibration.h) to labelled points: the scale
// and power that minimise the mean negative log-likelihood of each point's projected
// probability of its label, p_y = (e'_y + 1) / (sum_c e'_c + C) with e' = scale * e^power,
// i.e. temperature scaling of the subjective opinion. The labels are GT (a user's validation
// scans) or cross-scan consensus (consensus_labels.h, no labels needed).
#pragma once

#include <vector>

#include "evidential_octomap/input_calibration.h"

namespace evidential_octomap::tools {

struct CalibrationFit {
  InputCalibration calibration;
  size_t points = 0;          // points the fit used (labelled, with evidence; subsampled)
  double nll_before = 0.0;    // mean NLL of the identity
  double nll_after = 0.0;     // mean NLL of the fitted calibration
};

// `evidence[s]` (N_s x C) and `labels[s]` (N_s, -1 or `ignore_class` = skipped) per scan; scans
// with empty labels are skipped. At most `max_points` points, taken at an even stride so the
// fit is deterministic. Throws std::runtime_error when no point is usable.
CalibrationFit fitInputCalibration(const std::vector<std::vector<float>>& evidence,
                                   const std::vector<std::vector<int>>& labels, int num_classes,
                                   int ignore_class, size_t max_points = 200000);

}  // namespace evidential_octomap::tools
