#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/io.h"
#include "quality_plot.h"
#include "render.h"
#include "test_helpers.h"

using namespace evidential_octomap;
using namespace evidential_octomap::tools;

namespace {
cv::Vec3b bgr(const ClassTable::Rgb& c) { return cv::Vec3b(c[2], c[1], c[0]); }

// C = 3 at 0.5 m: a (class 1) with c (class 2) stacked above it, b (class 2) beside, d occupied
// without evidence. Payload (0, ln 3, 0) -> label 1, u = 1/3.
struct Scene {
  EvidentialOcTree tree{0.5, 3};
  ClassTable classes;
  octomap::point3d a{0.25f, 0.25f, 0.25f}, b{1.25f, 0.25f, 0.25f}, c{0.25f, 0.25f, 1.25f},
      d{1.25f, 1.25f, 0.25f};
  Scene() {
    classes.dataset = "test";
    classes.names = {"void", "one", "two"};
    classes.colors = {{{0, 0, 0}}, {{10, 20, 30}}, {{200, 100, 50}}};
    classes.ignore_class = 0;
    const float l3 = std::log(3.0f);
    set(a, {0.0f, l3, 0.0f});
    set(b, {0.0f, 0.0f, l3});
    set(c, {0.0f, 0.0f, l3});
    set(d, {});
  }
  void set(const octomap::point3d& p, const std::vector<float>& payload) {
    const auto key = tree.coordToKey(p);
    tree.updateNode(key, true);
    if (payload.empty()) return;
    std::vector<float> values(tree.numClasses(), tree.rule().prior());
    std::copy(payload.begin(), payload.end(), values.begin());
    detail::TreeEditing::setPayload(tree, detail::TreeEditing::leafForUpdate(tree, key, false), values.data());
  }
};
}  // namespace

TEST(TopDownGrid, CoversTheOccupiedLeavesAtTheMapResolution) {
  Scene s;
  const TopDownGrid g = makeGrid(s.tree, nullptr);
  EXPECT_DOUBLE_EQ(g.pixel, 0.5);
  EXPECT_EQ(g.width, 4);
  EXPECT_EQ(g.height, 4);
  int col, row;
  ASSERT_TRUE(g.toPixel(0.25, 0.25, &col, &row));
  EXPECT_EQ(col, 0);
  EXPECT_EQ(row, 3);  // north up: the lowest y is the last row
  EXPECT_FALSE(g.toPixel(-3.0, 0.25, &col, &row));
}

TEST(SemanticLayer, ShowsTheHighestOccupiedLeafInClassColours) {
  Scene s;
  const TopDownGrid g = makeGrid(s.tree, nullptr);
  std::set<int> shown;
  const cv::Mat m = semanticLayer(s.tree, s.classes, g, &shown);
  EXPECT_EQ(m.at<cv::Vec3b>(3, 0), bgr(s.classes.colors[2]));  // c (class 2) hides a (class 1)
  EXPECT_EQ(m.at<cv::Vec3b>(3, 2), bgr(s.classes.colors[2]));  // b
  EXPECT_EQ(m.at<cv::Vec3b>(1, 2), cv::Vec3b(228, 228, 228));  // d: occupied, no evidence
  EXPECT_EQ(m.at<cv::Vec3b>(3, 1), cv::Vec3b(255, 255, 255));  // nothing there
  EXPECT_EQ(shown, (std::set<int>{2}));
}

// Quantile scale: of the two drawn semantic columns (b: u = 1/3 alone; c over a: u = 1/3 too)
// both tie, so both take the middle colour; a third, more uncertain voxel takes the top colour
// and pushes the tied ones to the bottom share.
TEST(UncertaintyLayer, ColoursByTheRankOfUAmongTheDrawnVoxels) {
  Scene s;
  const TopDownGrid g = makeGrid(s.tree, nullptr);
  EXPECT_EQ(uncertaintyLayer(s.tree, g).at<cv::Vec3b>(3, 2), bgr(uncertaintyColor(0.5)));
  s.set(s.d, {0.0f, 0.1f, 0.0f});  // d: weak evidence, u close to 1
  const cv::Mat m = uncertaintyLayer(s.tree, g);
  EXPECT_EQ(m.at<cv::Vec3b>(1, 2), bgr(uncertaintyColor(1.0)));        // d, the most uncertain
  EXPECT_EQ(m.at<cv::Vec3b>(3, 2), bgr(uncertaintyColor(0.25)));       // b: ranks 0-1 of 0..2
  EXPECT_EQ(m.at<cv::Vec3b>(3, 0), m.at<cv::Vec3b>(3, 2));             // c ties with b
}

TEST(ErrorLayer, RightWrongAndUncoveredQueriesHaveTheirColours) {
  Scene s;
  const TopDownGrid g = makeGrid(s.tree, nullptr);
  const std::vector<Query> q{{s.a, 1, 1},                                     // right
                             {s.b, 1, 1},                                     // wrong (b says 2)
                             {octomap::point3d(0.25f, 1.25f, 0.25f), 1, 1}};  // unknown
  const cv::Mat m = errorLayer(s.tree, q, g);
  EXPECT_EQ(m.at<cv::Vec3b>(3, 0), cv::Vec3b(60, 170, 40));
  EXPECT_EQ(m.at<cv::Vec3b>(3, 2), cv::Vec3b(30, 30, 220));
  EXPECT_EQ(m.at<cv::Vec3b>(1, 0), cv::Vec3b(200, 140, 60));
}

TEST(Render, FullImageHasCaptionAndPanelAndWritesAPng) {
  Scene s;
  const TopDownGrid g = makeGrid(s.tree, nullptr);
  const cv::Mat img = renderSemantic(s.tree, s.classes, g, {"line one", "line two"});
  EXPECT_GT(img.cols, g.width + 100);  // legend panel on the right
  EXPECT_GT(img.rows, g.height + 40);  // two caption lines on top
  const std::string path = tools_test::freshDir("render") + "/semantic.png";
  writePng(path, img);
  const cv::Mat back = cv::imread(path);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(back.size(), img.size());
  EXPECT_THROW(writePng("/nonexistent/dir/x.png", img), std::runtime_error);
}

// The quality picture puts each decile's error rate and each reliability bin where the axes say.
TEST(QualityCurves, PointsSitAtTheirDataCoordinates) {
  QualityMetrics map, input;
  map.error_rate_labelled = 0.2;
  ErrorDetection u;
  u.output = "u";
  for (int i = 0; i < 10; ++i) u.error_rate_by_decile.push_back(0.043 * i);  // top 0.387
  map.error_detection.push_back(u);
  map.reliability.push_back({0.4, 0.5, 7, 0.45, 0.25});
  const std::vector<std::string> caption{"one line"};
  const cv::Mat img = renderQualityCurves(map, input, caption);
  EXPECT_DOUBLE_EQ(errorAxisTop(map, input), 0.4);
  const PlotFrame left = errorCurveFrame(1, 0.4);
  const cv::Scalar c = outputColour(0);
  const cv::Vec3b colour(c[0], c[1], c[2]);
  EXPECT_EQ(img.at<cv::Vec3b>(left.toPixel(0.05, 0.0)), colour);
  EXPECT_EQ(img.at<cv::Vec3b>(left.toPixel(0.95, 0.387)), colour);
  EXPECT_EQ(img.at<cv::Vec3b>(reliabilityFrame(1).toPixel(0.45, 0.25)), colour);
  EXPECT_EQ(left.toPixel(1.0, 0.4), cv::Point(left.area.x + left.area.width, left.area.y));
}
