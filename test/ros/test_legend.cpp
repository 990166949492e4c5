// The rviz legend image: one swatch per class in the class table's colour, the "no evidence"
// grey, and colour bars whose ends are the colour ramp's ends.
#include <gtest/gtest.h>

#include "evidential_octomap/io.h"
#include "legend.h"
#include "test_maps.h"

using namespace evidential_octomap;
using L = LegendLayout;

namespace {

cv::Vec3b pixel(const cv::Mat& image, int x, int y) { return image.at<cv::Vec3b>(y, x); }
cv::Vec3b rgb(const ClassTable::Rgb& c) { return cv::Vec3b(c[0], c[1], c[2]); }

}  // namespace

TEST(Legend, OneSwatchPerClassInItsColour) {
  const ClassTable classes = ros_test::fourClasses();
  const cv::Mat image = renderLegend(classes, UncertaintyRange(), "u");
  ASSERT_EQ(image.type(), CV_8UC3);
  EXPECT_EQ(image.cols, L::kWidth);
  EXPECT_EQ(image.rows, L::height(4));
  auto centre = [&](int i) {
    return pixel(image, L::swatchLeft(i, 4) + L::kSwatch / 2, L::swatchTop(i, 4) + L::kSwatch / 2);
  };
  for (int c = 0; c < 4; ++c) EXPECT_EQ(centre(c), rgb(classes.colors[c])) << "class " << c;
  EXPECT_EQ(centre(4), cv::Vec3b(128, 128, 128));  // no evidence
  // Two columns: class 3 sits in the right one.
  EXPECT_GT(L::swatchLeft(3, 4), L::kWidth / 2);
}

TEST(Legend, ColourBarsRunAlongTheColourRamp) {
  const cv::Mat image = renderLegend(ros_test::fourClasses(), UncertaintyRange(), "u");
  const int y = L::barTop(4) + L::kBarHeight / 2;
  for (int bar : {0, 1}) {
    const int left = L::barLeft(bar);
    EXPECT_EQ(pixel(image, left, y), rgb(uncertaintyColor(0.0)));
    EXPECT_EQ(pixel(image, left + L::kBarWidth - 1, y), rgb(uncertaintyColor(1.0)));
    EXPECT_EQ(pixel(image, left + (L::kBarWidth - 1) / 2, y),
              rgb(uncertaintyColor(double((L::kBarWidth - 1) / 2) / (L::kBarWidth - 1))));
  }
}

TEST(Legend, GrowsWithTheClassTable) {
  ClassTable many = ros_test::fourClasses();
  for (int c = 0; c < 16; ++c) {
    many.names.push_back("extra_" + std::to_string(c));
    many.colors.push_back({{uint8_t(c * 10), 0, 0}});
  }
  const cv::Mat image = renderLegend(many, UncertaintyRange(), "u");
  EXPECT_EQ(image.rows, L::height(20));
  EXPECT_EQ(pixel(image, L::swatchLeft(19, 20) + 2, L::swatchTop(19, 20) + 2),
            rgb(many.colors[19]));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
