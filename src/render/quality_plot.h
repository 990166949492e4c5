// The picture of how far a map's uncertainty can be trusted (OpenCV, tools only):
//   left   error-vs-uncertainty curves: the error rate of each tenth of the labelled queries
//          sorted by an uncertainty output (most certain tenth first), one curve per output of
//          the map and the input's u; a useful output rises from left to right;
//   right  reliability diagram: accuracy against mean confidence (max_c p) per confidence bin,
//          map and input, with the diagonal of perfect calibration.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "evidential_octomap/evaluation/metrics.h"

namespace evidential_octomap::tools {

// A data rectangle [x0, x1] x [y0, y1] drawn in the pixel rectangle `area` (y grows upwards).
struct PlotFrame {
  cv::Rect area;
  double x0 = 0.0, x1 = 1.0, y0 = 0.0, y1 = 1.0;
  cv::Point toPixel(double x, double y) const;
};

// Pixel frames of the two panels in an image of renderQualityCurves (caption of `caption_lines`).
PlotFrame errorCurveFrame(int caption_lines, double max_error_rate);
PlotFrame reliabilityFrame(int caption_lines);

// Line colour (BGR) of each output of kUncertaintyOutputs, in that order; the input is black.
cv::Scalar outputColour(size_t output);

cv::Mat renderQualityCurves(const QualityMetrics& map, const QualityMetrics& input,
                            const std::vector<std::string>& caption);

// Largest error rate the left panel shows: the largest decile rate, rounded up to 0.1.
double errorAxisTop(const QualityMetrics& map, const QualityMetrics& input);

}  // namespace evidential_octomap::tools
