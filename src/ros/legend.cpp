#include "legend.h"

#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "evidential_octomap/io.h"

namespace evidential_octomap {
namespace {

using L = LegendLayout;
const cv::Scalar kBackground(40, 40, 40), kText(235, 235, 235);

void text(cv::Mat* image, const std::string& s, int x, int baseline, double scale = 0.45) {
  cv::putText(*image, s, cv::Point(x, baseline), cv::FONT_HERSHEY_SIMPLEX, scale, kText, 1,
              cv::LINE_AA);
}

cv::Scalar rgb(const ClassTable::Rgb& c) { return cv::Scalar(c[0], c[1], c[2]); }

// A horizontal bar of uncertaintyColor(0 .. 1) with its title above and the values at both ends
// and the middle below.
void colourBar(cv::Mat* image, int left, int top, const std::string& title, double lo, double hi) {
  text(image, title, left, top - 6, 0.42);
  for (int x = 0; x < L::kBarWidth; ++x) {
    const double t = double(x) / (L::kBarWidth - 1);
    cv::line(*image, cv::Point(left + x, top), cv::Point(left + x, top + L::kBarHeight - 1),
             rgb(uncertaintyColor(t)));
  }
  char label[32];
  const int below = top + L::kBarHeight + 14;
  std::snprintf(label, sizeof(label), "%.2g", lo);
  text(image, label, left, below, 0.4);
  std::snprintf(label, sizeof(label), "%.2g", 0.5 * (lo + hi));
  text(image, label, left + L::kBarWidth / 2 - 10, below, 0.4);
  std::snprintf(label, sizeof(label), "%.2g", hi);
  int unused_baseline = 0;  // right-aligned under the bar's end, whatever its length
  const int width = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &unused_baseline).width;
  text(image, label, left + L::kBarWidth - width, below, 0.4);
}

void swatch(cv::Mat* image, int i, int num_classes, const cv::Scalar& colour,
            const std::string& name) {
  const int left = L::swatchLeft(i, num_classes), top = L::swatchTop(i, num_classes);
  cv::rectangle(*image, cv::Rect(left, top, L::kSwatch, L::kSwatch), colour, cv::FILLED);
  text(image, name, left + L::kSwatch + 6, top + L::kSwatch - 2);
}

}  // namespace

cv::Mat renderLegend(const ClassTable& classes, const UncertaintyRange& range,
                     const std::string& uncertainty_name) {
  const int C = classes.numClasses();
  cv::Mat image(L::height(C), L::kWidth, CV_8UC3, kBackground);
  text(&image, "classes (" + classes.dataset + ")", L::kMargin, L::kTitle - 8, 0.5);
  for (int c = 0; c < C; ++c)
    swatch(&image, c, C, rgb(classes.colors[c]), std::to_string(c) + " " + classes.names[c]);
  swatch(&image, C, C, cv::Scalar(128, 128, 128), "no evidence");
  colourBar(&image, L::barLeft(0), L::barTop(C),
            uncertainty_name + (range.automatic ? " (5-95 %)" : ""), range.min, range.max);
  colourBar(&image, L::barLeft(1), L::barTop(C), "conflict", 0.0, 1.0);
  return image;
}

}  // namespace evidential_octomap
