// Camera path: LiDAR points projected into synthetic evidence / label images whose right answer
// is known by construction (pinhole maths done by hand below).
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "camera_projection.h"

using namespace evidential_octomap;

namespace {

constexpr int kC = 4;

// 100 x 80 image, f = 100, principal point (50, 40), no distortion.
PinholeCamera camera() {
  PinholeCamera cam;
  cam.K = cv::Matx33d(100, 0, 50, 0, 100, 40, 0, 0, 1);
  cam.width = 100;
  cam.height = 80;
  return cam;
}

// LiDAR (x forward, y left, z up) -> optical camera frame (x right, y down, z forward).
const cv::Matx33d kR_C_S(0, -1, 0, 0, 0, -1, 1, 0, 0);

// Four vertical stripes: column c / 25 is the class; evidence 10 + row for it.
cv::Mat stripeEvidence() {
  cv::Mat img(80, 100, CV_32FC(kC), cv::Scalar::all(0));
  for (int r = 0; r < 80; ++r)
    for (int c = 0; c < 100; ++c) img.ptr<float>(r)[c * kC + c / 25] = 10.f + r;
  return img;
}

cv::Mat stripeLabels() {
  cv::Mat img(80, 100, CV_8UC1);
  for (int r = 0; r < 80; ++r)
    for (int c = 0; c < 100; ++c) img.at<uint8_t>(r, c) = c / 25;
  return img;
}

}  // namespace

TEST(ProjectToPixels, PinholeGivesTheHandComputedPixel) {
  octomap::Pointcloud pts;
  pts.push_back(5, 0, 0);     // optical axis -> (50, 40)
  pts.push_back(5, -1, 0);    // 1 m right at 5 m -> u = 50 + 100 / 5 = 70
  pts.push_back(10, 1, 1);    // left and up -> u = 40, v = 30
  pts.push_back(-5, 0, 0);    // behind the camera
  pts.push_back(5, -5, 0);    // u = 150: outside
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), camera());
  ASSERT_EQ(px.size(), 5u);
  EXPECT_EQ(px[0], 40 * 100 + 50);
  EXPECT_EQ(px[1], 40 * 100 + 70);
  EXPECT_EQ(px[2], 30 * 100 + 40);
  EXPECT_EQ(px[3], -1);
  EXPECT_EQ(px[4], -1);
}

TEST(ProjectToPixels, TranslationOfTheExtrinsicsIsApplied) {
  octomap::Pointcloud pts;
  pts.push_back(5, 0, 0);
  // Camera 1 m to the right of the LiDAR: in the camera frame the point sits at x = +1... i.e.
  // t_C_S = -R_C_S * (position of the camera in S) = -R * (0, -1, 0) = (-1, 0, 0).
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(-1, 0, 0), camera());
  EXPECT_EQ(px[0], 40 * 100 + 30);  // u = 50 - 100 / 5
}

TEST(ProjectToPixels, RadialDistortionMovesThePixelAsThePlumbBobModelSays) {
  PinholeCamera cam = camera();
  cam.D = (cv::Mat_<double>(1, 5) << 0.1, 0, 0, 0, 0);
  octomap::Pointcloud pts;
  pts.push_back(5, -1, 0.5);  // x' = 0.2, y' = -0.1, r^2 = 0.05, factor 1.005
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), cam);
  const double u = 50 + 100 * 0.2 * 1.005, v = 40 + 100 * -0.1 * 1.005;  // 70.1, 29.95
  EXPECT_EQ(px[0], long(std::floor(v)) * 100 + long(std::floor(u)));
}

TEST(EvidenceFromImage, EachPointTakesItsPixelsEvidence) {
  octomap::Pointcloud pts;
  pts.push_back(5, 0, 0);     // column 50 -> class 2, row 40
  pts.push_back(10, 1, 1);    // column 40 -> class 1, row 30
  pts.push_back(-5, 0, 0);    // behind: dropped
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), camera());
  octomap::Pointcloud out;
  std::vector<float> ev;
  ASSERT_EQ(evidenceFromImage(pts, px, stripeEvidence(), kC, 7.f, false, &out, &ev), "");
  ASSERT_EQ(out.size(), 2u);
  ASSERT_EQ(ev.size(), 2u * kC);
  for (int c = 0; c < kC; ++c) {
    EXPECT_FLOAT_EQ(ev[c], c == 2 ? 50.f : 0.f);
    EXPECT_FLOAT_EQ(ev[kC + c], c == 1 ? 40.f : 0.f);
  }
}

TEST(EvidenceFromImage, OutsidePointsKeptOccupancyOnlyWhenAsked) {
  octomap::Pointcloud pts;
  pts.push_back(5, 0, 0);
  pts.push_back(-5, 0, 0);
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), camera());
  octomap::Pointcloud out;
  std::vector<float> ev;
  ASSERT_EQ(evidenceFromImage(pts, px, stripeEvidence(), kC, 7.f, true, &out, &ev), "");
  ASSERT_EQ(out.size(), 2u);
  for (int c = 0; c < kC; ++c) EXPECT_FLOAT_EQ(ev[kC + c], 0.f);  // vacuous: occupancy only
}

TEST(EvidenceFromImage, LabelImageGivesOneHotEvidence) {
  octomap::Pointcloud pts;
  pts.push_back(5, -2, 0);  // u = 90 -> class 3
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), camera());
  octomap::Pointcloud out;
  std::vector<float> ev;
  ASSERT_EQ(evidenceFromImage(pts, px, stripeLabels(), kC, 7.f, false, &out, &ev), "");
  for (int c = 0; c < kC; ++c) EXPECT_FLOAT_EQ(ev[c], c == 3 ? 7.f : 0.f);
}

TEST(EvidenceFromImage, WrongChannelCountAndBadEvidenceAreRejected) {
  octomap::Pointcloud pts;
  pts.push_back(5, 0, 0);
  const auto px = projectToPixels(pts, kR_C_S, cv::Vec3d(0, 0, 0), camera());
  octomap::Pointcloud out;
  std::vector<float> ev;
  cv::Mat three(80, 100, CV_32FC3, cv::Scalar::all(1));
  EXPECT_NE(evidenceFromImage(pts, px, three, kC, 7.f, false, &out, &ev).find("expected C = 4"),
            std::string::npos);
  cv::Mat bad = stripeEvidence();
  bad.ptr<float>(40)[50 * kC + 1] = -1.f;
  EXPECT_NE(evidenceFromImage(pts, px, bad, kC, 7.f, false, &out, &ev).find("finite and >= 0"),
            std::string::npos);
  cv::Mat labels = stripeLabels();
  labels.at<uint8_t>(40, 50) = 9;
  EXPECT_NE(evidenceFromImage(pts, px, labels, kC, 7.f, false, &out, &ev).find(">= C = 4"),
            std::string::npos);
}

TEST(CameraFromInfo, ReadsIntrinsicsAndDistortion) {
  sensor_msgs::CameraInfo info;
  info.width = 100;
  info.height = 80;
  info.K = {100, 0, 50, 0, 100, 40, 0, 0, 1};
  info.D = {0.1, 0, 0, 0, 0};
  const PinholeCamera cam = cameraFromInfo(info);
  EXPECT_EQ(cam.width, 100);
  EXPECT_DOUBLE_EQ(cam.K(0, 2), 50);
  ASSERT_EQ(cam.D.cols, 5);
  EXPECT_DOUBLE_EQ(cam.D.at<double>(0, 0), 0.1);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
