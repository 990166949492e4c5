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

// A horizontal bar of uncertaintyColor(0 .. 1) with the values at both ends and the middle.
void colourBar(cv::Mat* image, int top, const std::string& title, double lo, double hi) {
  text(image, title, L::kMargin, top - 6);
  for (int x = 0; x < L::kBarWidth; ++x) {
    const double t = double(x) / (L::kBarWidth - 1);
    cv::line(*image, cv::Point(L::kMargin + x, top), cv::Point(L::kMargin + x, top + L::kBarHeight),
             rgb(uncertaintyColor(t)));
  }
  char label[32];
  const int below = top + L::kBarHeight + 14;
  std::snprintf(label, sizeof(label), "%.2g", lo);
  text(image, label, L::kMargin, below, 0.4);
  std::snprintf(label, sizeof(label), "%.2g", 0.5 * (lo + hi));
  text(image, label, L::kMargin + L::kBarWidth / 2 - 10, below, 0.4);
  std::snprintf(label, sizeof(label), "%.2g", hi);
  text(image, label, L::kMargin + L::kBarWidth - 24, below, 0.4);
}

}  // namespace

cv::Mat renderLegend(const ClassTable& classes, const UncertaintyRange& range,
                     const std::string& uncertainty_name) {
  const int C = classes.numClasses();
  cv::Mat image(L::height(C), L::kWidth, CV_8UC3, kBackground);
  text(&image, "classes (" + classes.dataset + ")", L::kMargin, L::kMargin + L::kRow - 6, 0.5);
  for (int c = 0; c < C; ++c) {
    const int top = L::swatchTop(c);
    cv::rectangle(image, cv::Rect(L::kMargin, top, L::kSwatch, L::kSwatch), rgb(classes.colors[c]),
                  cv::FILLED);
    text(&image, std::to_string(c) + "  " + classes.names[c], L::kMargin + L::kSwatch + 8,
         top + L::kSwatch - 2);
  }
  const int grey_top = L::swatchTop(C);
  cv::rectangle(image, cv::Rect(L::kMargin, grey_top, L::kSwatch, L::kSwatch),
                cv::Scalar(128, 128, 128), cv::FILLED);
  text(&image, "no evidence", L::kMargin + L::kSwatch + 8, grey_top + L::kSwatch - 2);
  colourBar(&image, L::uncertaintyBarTop(C), uncertainty_name, range.min, range.max);
  colourBar(&image, L::conflictBarTop(C), "conflict (disagreeing evidence)", 0.0, 1.0);
  return image;
}

}  // namespace evidential_octomap
