// Per-point features of one LiDAR scan for the learned evidence head (learned_evidence.h).
// The only implementation: the training script reads them from `evidential_octomap features`,
// so training and inference cannot drift apart.
//
// Everything is scan-local, in the sensor frame (no world coordinates, so a model cannot learn
// where things are). Per point:
//   range, z                      distance to the sensor and height in the sensor frame [m]
//   height_above_ground           z minus the lowest z of the 3 x 3 ground cells (1 m) around it
//   column_height                 highest minus lowest z of those cells (object height)
//   remission                     the sensor's intensity (0 when the scan has none)
//   knn_fill, knn_mean_dist       neighbours found / k and their mean distance, for the k = 16
//                                 nearest within 1 m (sparse, far points have few)
//   linearity, planarity, scattering, verticality
//                                 eigenvalue features of the neighbourhood covariance
//                                 (l1 >= l2 >= l3): (l1-l2)/l1, (l2-l3)/l1, l3/l1, |normal_z|
//   knn_z_extent, z_minus_knn_mean
//   pred_<c>                      one-hot of the network's hard prediction (C values)
//   vote_<c>                      share of the neighbours (self excluded) predicted c (C values)
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace evidential_octomap {

// One scan as the network saw it (borrowed arrays; none is copied).
struct ScanInput {
  const float* xyz = nullptr;        // N x 3, sensor frame
  const float* remission = nullptr;  // N, or nullptr
  const int* predicted = nullptr;    // N classes in [0, C), or -1 for none
  size_t num_points = 0;
};

// Row-major N x F.
struct FeatureMatrix {
  size_t rows = 0;
  int cols = 0;
  std::vector<float> values;
  const float* row(size_t i) const { return values.data() + i * size_t(cols); }
};

// F = 13 + 2 C names, in column order.
std::vector<std::string> pointFeatureNames(int num_classes);

// Features of every point. Points at (0, 0, 0) (no return) get a row of zeros.
// Throws std::invalid_argument when xyz or predicted is missing, or a prediction is >= C.
FeatureMatrix computePointFeatures(const ScanInput& scan, int num_classes);

// FNV-1a 64 over the bits of x, y, z and remission of every point with a return: identifies a
// scan by content (not by file name), so a model can refuse the scans it was trained on.
uint64_t scanFingerprint(const ScanInput& scan);
std::string fingerprintHex(uint64_t fingerprint);  // 16 lower-case hex digits

}  // namespace evidential_octomap
