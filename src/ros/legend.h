// The legend rviz shows beside the map (an Image display on ~legend): one colour swatch and name
// per class of the class table, then the colour bars of the uncertainty and conflict views with
// their value range. Drawn with OpenCV; RGB, 8 bit.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "evidential_octomap/class_table.h"
#include "visualization.h"

namespace evidential_octomap {

struct LegendLayout {
  static constexpr int kWidth = 300;
  static constexpr int kRow = 20;     // height of one class row [px]
  static constexpr int kSwatch = 14;  // side of a class swatch [px]
  static constexpr int kMargin = 8;
  static constexpr int kBarHeight = 16;
  static constexpr int kBarWidth = kWidth - 2 * kMargin;
  // Top of the swatch of class c, and of the two bars (below the class rows).
  static int swatchTop(int c) { return kMargin + kRow + c * kRow + (kRow - kSwatch) / 2; }
  static int uncertaintyBarTop(int num_classes) {
    return kMargin + (num_classes + 2) * kRow + kRow;
  }
  static int conflictBarTop(int num_classes) {
    return uncertaintyBarTop(num_classes) + kBarHeight + 3 * kRow;
  }
  static int height(int num_classes) { return conflictBarTop(num_classes) + kBarHeight + 2 * kRow; }
};

// `uncertainty_name` says what the uncertainty is (the mass u for dempster, a scaled Dirichlet
// variance for sbki/ebs); `range` is the uncertainty view's colour range.
cv::Mat renderLegend(const ClassTable& classes, const UncertaintyRange& range,
                     const std::string& uncertainty_name);

}  // namespace evidential_octomap
