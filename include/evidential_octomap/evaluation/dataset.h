// Readers for the offline tool: SemanticKITTI-layout sequences and single pose-less scans.
//
// SemanticKITTI layout (a directory):
//   velodyne/<stem>.bin       float32 N x 4 (x, y, z, remission), sensor (Velodyne) frame
//   labels/<stem>.label       uint32 N, ground truth; lower 16 bits = raw class id (optional)
//   predictions/<stem>.label  uint32 N, a network's hard predictions (optional)
//   evidence/<stem>.{bin,npy} float32 N x C per-point evidence e >= 0 (optional), or
//   alpha/<stem>.{bin,npy}    float32 N x C Dirichlet parameters alpha = e + 1 (optional), or
//   logits/<stem>.{bin,npy}   float32 N x C a network's logits (optional), or
//   probabilities/<stem>.{bin,npy}  float32 N x C class probabilities (optional);
//                             logits and probabilities become evidence as InputConversion says
//                             (subjective_logic.h: evidenceFromLogits / evidenceFromProbabilities)
//   poses.txt, calib.txt      KITTI: left-camera poses P(i) and the Velodyne->camera Tr;
//                             the Velodyne pose is T_W_S(i) = inv(Tr) * P(i) * Tr.
// Single scan (RELLIS-3D example): a directory holding <stem>.bin (+ <stem>.label), or the .bin
// path itself; no pose is shipped, so T_W_S = identity.
// In both layouts points with x = y = z = 0 (no return) are dropped, with their labels.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <octomap/Pointcloud.h>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {

struct Scan {
  std::string name;                 // file stem, e.g. "000000"
  std::vector<Eigen::Vector3f> points_S;
  std::vector<float> remission;     // per point, the .bin's fourth column
  std::vector<int> gt;              // class per point (empty: no labels)
  std::vector<int> predicted;       // class per point (empty: no predictions)
  std::vector<float> evidence;      // N x C row-major (empty: no evidence files)
  Eigen::Matrix4d T_W_S = Eigen::Matrix4d::Identity();
  size_t dropped_no_return = 0;     // all-zero points removed on load

  size_t size() const { return points_S.size(); }
  Eigen::Vector3d originW() const { return T_W_S.block<3, 1>(0, 3); }
  octomap::Pointcloud pointsW() const;
  Eigen::Vector3f pointW(size_t i) const;
};

// How logits/ and probabilities/ files become evidence.
struct InputConversion {
  LogitTransform logit_transform = LogitTransform::kSoftmax;
  float probability_magnitude = kEvidenceMagnitude;  // E of the confidence-scaled conversion
};

class Dataset {
 public:
  enum class Layout { kSemanticKitti, kSingleScan };

  // `classes` must outlive the Dataset (it is kept by pointer).
  // Throws std::runtime_error naming the path when the layout is not recognised or a
  // required file is missing or malformed.
  static Dataset open(const std::string& path, const ClassTable& classes,
                      const InputConversion& conversion = {});

  Layout layout() const { return layout_; }
  const std::string& path() const { return path_; }
  size_t size() const { return stems_.size(); }
  const std::vector<std::string>& stems() const { return stems_; }
  bool hasLabels() const { return has_labels_; }
  bool hasPredictions() const { return has_predictions_; }
  bool hasEvidence() const { return !evidence_dir_.empty(); }
  // "evidence", "alpha", "logits" or "probabilities" ("" without such files).
  const std::string& evidenceKind() const { return evidence_kind_; }
  // e.g. "logits/ files, softmax then confidence-scaled evidence, E=20".
  std::string describeEvidenceFiles() const;
  const Eigen::Matrix4d& pose(size_t i) const { return poses_W_S_.at(i); }

  // Loads scan i; throws std::runtime_error naming the file on size mismatches and unknown
  // label ids.
  Scan load(size_t i) const;

 private:
  // N x C evidence of one evidence/, alpha/, logits/ or probabilities/ file.
  std::vector<float> readEvidence(const std::string& file, size_t n, size_t C) const;

  Layout layout_ = Layout::kSemanticKitti;
  std::string path_;
  const ClassTable* classes_ = nullptr;
  std::vector<std::string> stems_;
  std::vector<std::string> bin_files_, label_files_, prediction_files_, evidence_files_;
  std::vector<Eigen::Matrix4d> poses_W_S_;
  bool has_labels_ = false, has_predictions_ = false;
  std::string evidence_dir_, evidence_kind_;
  InputConversion conversion_;
};

// --- low-level readers (each throws std::runtime_error naming the file) ----------------------
std::vector<float> readVelodyneBin(const std::string& path);   // N x 4
std::vector<uint32_t> readLabelFile(const std::string& path);   // N raw labels
// float32 N x C from raw .bin (size must be a multiple of C) or .npy ('<f4', C order, 2-D).
std::vector<float> readFloatMatrix(const std::string& path, size_t rows, size_t cols);
// Writes a 2-D C-ordered .npy (v1.0) of little-endian float32 ('<f4') or int32 ('<i4').
void writeNpy(const std::string& path, const float* values, size_t rows, size_t cols);
void writeNpy(const std::string& path, const int32_t* values, size_t rows, size_t cols);
Eigen::Matrix4d readKittiCalibTr(const std::string& calib_path);
std::vector<Eigen::Matrix4d> readKittiPoses(const std::string& poses_path);
// inv(Tr) * P * Tr
Eigen::Matrix4d velodynePose(const Eigen::Matrix4d& P_cam, const Eigen::Matrix4d& Tr);
// Classes of raw labels via the class table; unknown ids throw naming `file` and the id.
std::vector<int> classesOfLabels(const std::vector<uint32_t>& raw, const ClassTable& classes,
                                 const std::string& file);

}  // namespace evidential_octomap
