// Camera path: LiDAR points projected into an evidence image take the evidence of
// the pixel they land in. Pinhole + distortion through cv::projectPoints; free functions so the
// maths is tested with synthetic images whose right answer is known.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <octomap/Pointcloud.h>
#include <sensor_msgs/CameraInfo.h>

namespace evidential_octomap {

struct PinholeCamera {
  cv::Matx33d K = cv::Matx33d::eye();
  cv::Mat D;            // distortion coefficients as cv::projectPoints takes them (may be empty)
  int width = 0;
  int height = 0;
};

// K, D, width and height of a CameraInfo (plumb_bob / rational_polynomial distortion).
PinholeCamera cameraFromInfo(const sensor_msgs::CameraInfo& info);

// Pixel (row * width + col) of each point of points_S, or -1 when the point is behind the camera
// or lands outside the image. T_C_S = (R_C_S, t_C_S) maps sensor-frame points into the optical
// camera frame (z forward).
std::vector<long> projectToPixels(const octomap::Pointcloud& points_S, const cv::Matx33d& R_C_S,
                                  const cv::Vec3d& t_C_S, const PinholeCamera& camera);

// Evidence of each point from its pixel. `image` is CV_32FC(C) evidence or a CV_8UC1 / CV_16UC1
// class-id image (one-hot evidence of `label_magnitude`). Points with pixel -1 are dropped, or
// kept with zero evidence (occupancy only) when keep_outside. Returns "" or an error (wrong
// channel count or type, negative/non-finite evidence, label >= C).
std::string evidenceFromImage(const octomap::Pointcloud& points_S, const std::vector<long>& pixels,
                              const cv::Mat& image, int num_classes, float label_magnitude,
                              bool keep_outside, octomap::Pointcloud* points_out,
                              std::vector<float>* evidence_out);

}  // namespace evidential_octomap
