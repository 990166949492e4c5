#include "camera_projection.h"

#include <cmath>

#include <opencv2/calib3d.hpp>

#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {

PinholeCamera cameraFromInfo(const sensor_msgs::CameraInfo& info) {
  PinholeCamera cam;
  for (int i = 0; i < 9; ++i) cam.K.val[i] = info.K[i];
  if (!info.D.empty()) cam.D = cv::Mat(info.D, true).reshape(1, 1);
  cam.width = static_cast<int>(info.width);
  cam.height = static_cast<int>(info.height);
  return cam;
}

std::vector<long> projectToPixels(const octomap::Pointcloud& points_S, const cv::Matx33d& R_C_S,
                                  const cv::Vec3d& t_C_S, const PinholeCamera& camera) {
  const size_t n = points_S.size();
  std::vector<long> pixels(n, -1);
  std::vector<cv::Point3d> in_front;
  std::vector<size_t> index;
  in_front.reserve(n);
  index.reserve(n);
  const double fx = camera.K(0, 0), fy = camera.K(1, 1), cx = camera.K(0, 2), cy = camera.K(1, 2);
  for (size_t i = 0; i < n; ++i) {
    const cv::Vec3d p_S(points_S[i].x(), points_S[i].y(), points_S[i].z());
    const cv::Vec3d p_C = R_C_S * p_S + t_C_S;
    if (!(p_C[2] > 1e-6)) continue;  // behind the camera
    // Distortion polynomials fold far-off-axis points back into the image: keep only points
    // whose undistorted projection lies within the image plus a margin of half its size.
    const double u = fx * p_C[0] / p_C[2] + cx, v = fy * p_C[1] / p_C[2] + cy;
    if (u < -0.5 * camera.width || u > 1.5 * camera.width || v < -0.5 * camera.height ||
        v > 1.5 * camera.height)
      continue;
    in_front.emplace_back(p_C[0], p_C[1], p_C[2]);
    index.push_back(i);
  }
  if (in_front.empty()) return pixels;
  std::vector<cv::Point2d> uv;
  const cv::Mat D = camera.D.empty() ? cv::Mat::zeros(1, 5, CV_64F) : camera.D;
  cv::projectPoints(in_front, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(camera.K), D, uv);
  for (size_t j = 0; j < uv.size(); ++j) {
    const long col = static_cast<long>(std::floor(uv[j].x));
    const long row = static_cast<long>(std::floor(uv[j].y));
    if (col < 0 || row < 0 || col >= camera.width || row >= camera.height) continue;
    pixels[index[j]] = row * camera.width + col;
  }
  return pixels;
}

std::string evidenceFromImage(const octomap::Pointcloud& points_S, const std::vector<long>& pixels,
                              const cv::Mat& image, int num_classes, float label_magnitude,
                              bool keep_outside, octomap::Pointcloud* points_out,
                              std::vector<float>* evidence_out) {
  const int C = num_classes;
  const bool is_label = image.type() == CV_8UC1 || image.type() == CV_16UC1;
  if (!is_label && image.depth() != CV_32F)
    return "evidence image must be 32FC(C) or a mono8/mono16 label image";
  if (!is_label && image.channels() != C)
    return "evidence image has " + std::to_string(image.channels()) + " channels, expected C = " +
           std::to_string(C);
  if (pixels.size() != points_S.size()) return "pixels and points differ in size";
  const cv::Mat img = image.isContinuous() ? image : image.clone();
  points_out->clear();
  evidence_out->clear();
  std::vector<float> row(C);
  for (size_t i = 0; i < points_S.size(); ++i) {
    const long px = pixels[i];
    if (px < 0) {
      if (!keep_outside) continue;
      std::fill(row.begin(), row.end(), 0.f);
    } else if (is_label) {
      const int label = img.type() == CV_8UC1 ? img.ptr<uint8_t>()[px] : img.ptr<uint16_t>()[px];
      if (label >= C)
        return "label image: pixel " + std::to_string(px) + " has class " + std::to_string(label) +
               " >= C = " + std::to_string(C);
      evidenceFromLabel(label, C, label_magnitude, row.data());
    } else {
      const float* e = img.ptr<float>() + size_t(px) * C;
      for (int c = 0; c < C; ++c) {
        if (!std::isfinite(e[c]) || e[c] < 0.f)
          return "evidence image: pixel " + std::to_string(px) + " class " + std::to_string(c) +
                 " has evidence " + std::to_string(e[c]) + " (must be finite and >= 0)";
        row[c] = e[c];
      }
    }
    points_out->push_back(points_S[i]);
    evidence_out->insert(evidence_out->end(), row.begin(), row.end());
  }
  return "";
}

}  // namespace evidential_octomap
