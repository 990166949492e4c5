// Writes a generated sequence in the SemanticKITTI layout the evaluation library reads
// (include/evidential_octomap/evaluation/dataset.h):
//   velodyne/NNNNNN.bin   float32 x y z remission (end-of-sweep sensor frame, valid returns only)
//   labels/NNNNNN.label   uint32 raw class id | instance << 16 (movers; static points 0)
//   predictions/          uint32 raw class id of the argmax
//   evidence/ logits/ probabilities/   float32 N x C (.bin, or .npy)
//   poses.txt, calib.txt  KITTI: camera poses P(i) with T_W_S(i) = inv(Tr) P(i) Tr, and a
//                         non-identity Tr (KITTI odometry's Velodyne -> camera)
//   movers.csv            per scan and mover present: box centre, yaw, size, points hit
// Files are written to a temporary name and renamed: a killed run leaves whole files only.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "agents.h"
#include "lidar.h"
#include "network_model.h"

namespace evidential_octomap::generator {

struct OutputSet {
  bool evidence = true, logits = false, probabilities = false;
  bool npy = false;
  static OutputSet parse(const std::string& list, const std::string& format);  // "evidence,logits"
};

// KITTI odometry's Velodyne -> left camera transform (sequences 04-10).
Eigen::Matrix4d kittiTr();

class DatasetWriter {
 public:
  DatasetWriter(const std::string& dir, const OutputSet& outputs, int num_classes,
                const std::vector<uint32_t>& raw_of_class, const KindClasses& classes);
  void writeScan(int scan, const std::vector<LidarPoint>& points, const NetworkOutput& net);
  void addMoverRows(int scan, const std::vector<Mover>& movers, double t, const Terrain& terrain,
                    const std::vector<LidarPoint>& points);
  void writePoses(const std::vector<Eigen::Isometry3d>& T_W_S) const;
  void writeText(const std::string& name, const std::string& text) const;
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  OutputSet outputs_;
  int C_;
  std::vector<uint32_t> raw_of_class_;
  KindClasses classes_;
  std::ofstream movers_;
};

// Writes bytes to path via a temporary file and a rename.
void writeFileBytes(const std::string& path, const void* data, size_t bytes,
                    const std::string& npy_header = "");

}  // namespace evidential_octomap::generator
