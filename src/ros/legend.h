// The legend rviz shows beside the map (an Image display on ~legend): one colour swatch and name
// per class of the class table, then the colour bars of the uncertainty and conflict views with
// their value range. Drawn with OpenCV; RGB, 8 bit; wider than tall so that rviz's image panel
// shrinks it little.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "evidential_octomap/class_table.h"
#include "visualization.h"

namespace evidential_octomap {

// Classes in two columns (plus "no evidence"), then the two colour bars side by side.
struct LegendLayout {
  static constexpr int kWidth = 440;
  static constexpr int kColumn = kWidth / 2;
  static constexpr int kRow = 18;     // height of one class row [px]
  static constexpr int kSwatch = 13;  // side of a class swatch [px]
  static constexpr int kMargin = 8;
  static constexpr int kTitle = 24;  // height of the title line [px]
  static constexpr int kBarHeight = 14;
  static constexpr int kBarWidth = kColumn - 2 * kMargin;
  // Rows per column for C classes and the "no evidence" entry.
  static int rows(int num_classes) { return (num_classes + 2) / 2; }
  // Top-left corner of the swatch of entry i (class i, or C: no evidence).
  static int swatchLeft(int i, int num_classes) {
    return kMargin + (i / rows(num_classes)) * kColumn;
  }
  static int swatchTop(int i, int num_classes) {
    return kTitle + (i % rows(num_classes)) * kRow + (kRow - kSwatch) / 2;
  }
  // Left edge of the uncertainty (0) and conflict (1) bars; both start at barTop.
  static int barLeft(int bar) { return kMargin + bar * kColumn; }
  static int barTop(int num_classes) { return kTitle + rows(num_classes) * kRow + 26; }
  static int height(int num_classes) { return barTop(num_classes) + kBarHeight + 22; }
};

// `uncertainty_name` says what the uncertainty is (the mass u for dempster, a scaled Dirichlet
// variance for sbki/ebs); `range` is the uncertainty view's colour range.
cv::Mat renderLegend(const ClassTable& classes, const UncertaintyRange& range,
                     const std::string& uncertainty_name);

}  // namespace evidential_octomap
