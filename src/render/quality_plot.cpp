#include "quality_plot.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace evidential_octomap::tools {

namespace {

constexpr int kLine = 20;         // caption line height
constexpr int kWidth = 1120;      // image width
constexpr int kPlotHeight = 360;  // height of a panel's data area
constexpr int kLegendRows = 6;
const cv::Scalar kBlack(0, 0, 0), kGrey(170, 170, 170), kWhite(255, 255, 255);

int captionHeight(int lines) { return kLine * lines + 8; }

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45,
          const cv::Scalar& colour = kBlack) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

// Frame, ticks every `step` on both axes, axis titles.
void drawAxes(cv::Mat& img, const PlotFrame& f, double x_step, double y_step,
              const std::string& x_title, const std::string& y_title, const std::string& title) {
  cv::rectangle(img, f.area, kBlack, 1);
  for (double x = f.x0; x <= f.x1 + 1e-9; x += x_step) {
    const cv::Point p = f.toPixel(x, f.y0);
    cv::line(img, p, p + cv::Point(0, 5), kBlack, 1);
    text(img, fixed(x, 1), p + cv::Point(-10, 20), 0.4);
  }
  for (double y = f.y0; y <= f.y1 + 1e-9; y += y_step) {
    const cv::Point p = f.toPixel(f.x0, y);
    cv::line(img, p, p - cv::Point(5, 0), kBlack, 1);
    text(img, fixed(y, 2), p + cv::Point(-45, 5), 0.4);
  }
  text(img, x_title, cv::Point(f.area.x + 40, f.area.y + f.area.height + 40));
  text(img, y_title, cv::Point(f.area.x - 60, f.area.y - 10));
  text(img, title, cv::Point(f.area.x + 60, f.area.y - 10), 0.5);
}

// A polyline through the finite points; dashed lines skip every other segment half.
void drawSeries(cv::Mat& img, const PlotFrame& f, const std::vector<double>& x,
                const std::vector<double>& y, const cv::Scalar& colour, bool dashed) {
  std::vector<cv::Point> pts;
  for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
    if (std::isfinite(x[i]) && std::isfinite(y[i])) pts.push_back(f.toPixel(x[i], y[i]));
  }
  for (size_t i = 1; i < pts.size(); ++i) {
    const cv::Point mid = (pts[i - 1] + pts[i]) / 2;
    cv::line(img, pts[i - 1], dashed ? mid : pts[i], colour, 2, cv::LINE_AA);
  }
  for (const cv::Point& p : pts) cv::circle(img, p, 3, colour, cv::FILLED, cv::LINE_AA);
}

void legend(cv::Mat& img, const PlotFrame& f, int row, const cv::Scalar& colour,
            const std::string& label) {
  const int y = f.area.y + f.area.height + 60 + row * kLine;
  cv::line(img, cv::Point(f.area.x, y - 4), cv::Point(f.area.x + 24, y - 4), colour, 2);
  text(img, label, cv::Point(f.area.x + 32, y));
}

// Decile centres 0.05 .. 0.95: the share of labelled queries more certain than the tenth.
std::vector<double> decileCentres(size_t n) {
  std::vector<double> x(n);
  for (size_t i = 0; i < n; ++i) x[i] = (double(i) + 0.5) / double(n);
  return x;
}

void errorCurves(cv::Mat& img, const PlotFrame& f, const QualityMetrics& map,
                 const QualityMetrics& input) {
  drawAxes(img, f, 0.1, f.y1 > 0.5 ? 0.2 : 0.1,
           "labelled queries sorted by the output (certain -> uncertain)", "error rate",
           "error rate per tenth of the labelled queries");
  const cv::Point base0 = f.toPixel(f.x0, map.error_rate_labelled);
  const cv::Point base1 = f.toPixel(f.x1, map.error_rate_labelled);
  cv::line(img, base0, base1, kGrey, 1);  // the map's mean error rate: any random order
  int row = 0;
  for (size_t o = 0; o < map.error_detection.size(); ++o) {
    const ErrorDetection& d = map.error_detection[o];
    drawSeries(img, f, decileCentres(d.error_rate_by_decile.size()), d.error_rate_by_decile,
               outputColour(o), false);
    legend(img, f, row++, outputColour(o),
           "map " + d.output + " (AUROC " + fixed(d.auroc, 3) + ", AURC " + fixed(d.aurc, 4) + ")");
  }
  if (const ErrorDetection* d = input.detection("u")) {
    drawSeries(img, f, decileCentres(d->error_rate_by_decile.size()), d->error_rate_by_decile,
               kBlack, true);
    legend(img, f, row++, kBlack, "input u, per point (AUROC " + fixed(d->auroc, 3) + ")");
  }
  legend(img, f, row, kGrey,
         "map error rate, labelled (" + fixed(100 * map.error_rate_labelled, 1) + " %)");
}

void reliabilityDiagram(cv::Mat& img, const PlotFrame& f, const QualityMetrics& map,
                        const QualityMetrics& input) {
  drawAxes(img, f, 0.1, 0.1, "confidence max_c p (mean per bin)", "accuracy",
           "reliability diagram (all queries)");
  cv::line(img, f.toPixel(0, 0), f.toPixel(1, 1), kGrey, 1, cv::LINE_AA);
  auto series = [&](const QualityMetrics& q, const cv::Scalar& colour, bool dashed) {
    std::vector<double> x, y;
    for (const ReliabilityBin& b : q.reliability) {
      if (b.count == 0) continue;
      x.push_back(b.mean_confidence);
      y.push_back(b.accuracy);
    }
    drawSeries(img, f, x, y, colour, dashed);
  };
  series(input, kBlack, true);
  series(map, outputColour(0), false);
  legend(img, f, 0, outputColour(0),
         "map (ECE " + fixed(map.ece, 4) + ", Brier " + fixed(map.brier, 4) + ")");
  legend(img, f, 1, kBlack,
         "input, per point (ECE " + fixed(input.ece, 4) + ", Brier " + fixed(input.brier, 4) + ")");
  legend(img, f, 2, kGrey, "perfect calibration");
}

}  // namespace

cv::Point PlotFrame::toPixel(double x, double y) const {
  const double fx = (x - x0) / (x1 - x0), fy = (y - y0) / (y1 - y0);
  return {area.x + int(std::lround(fx * area.width)),
          area.y + area.height - int(std::lround(fy * area.height))};
}

PlotFrame errorCurveFrame(int caption_lines, double max_error_rate) {
  return {cv::Rect(80, captionHeight(caption_lines) + 40, 440, kPlotHeight), 0.0, 1.0, 0.0,
          max_error_rate};
}

PlotFrame reliabilityFrame(int caption_lines) {
  return {cv::Rect(660, captionHeight(caption_lines) + 40, 400, kPlotHeight), 0.0, 1.0, 0.0, 1.0};
}

cv::Scalar outputColour(size_t output) {
  static const cv::Scalar kColours[] = {{200, 90, 30},
                                        {40, 40, 220},
                                        {40, 160, 40},
                                        {180, 60, 170},
                                        {0, 140, 255}};  // BGR: blue, red, green, purple, orange
  return kColours[output % 5];
}

double errorAxisTop(const QualityMetrics& map, const QualityMetrics& input) {
  double top = 0.0;
  for (const QualityMetrics* q : {&map, &input}) {
    for (const ErrorDetection& d : q->error_detection) {
      for (double r : d.error_rate_by_decile) {
        if (std::isfinite(r)) top = std::max(top, r);
      }
    }
  }
  return std::clamp(std::ceil(top * 10.0 - 1e-9) / 10.0, 0.1, 1.0);
}

cv::Mat renderQualityCurves(const QualityMetrics& map, const QualityMetrics& input,
                            const std::vector<std::string>& caption) {
  const int lines = int(caption.size());
  const int height = captionHeight(lines) + 40 + kPlotHeight + 70 + kLegendRows * kLine;
  cv::Mat img(height, kWidth, CV_8UC3, kWhite);
  for (int i = 0; i < lines; ++i) text(img, caption[i], cv::Point(6, kLine * (i + 1)));
  errorCurves(img, errorCurveFrame(lines, errorAxisTop(map, input)), map, input);
  reliabilityDiagram(img, reliabilityFrame(lines), map, input);
  return img;
}

}  // namespace evidential_octomap::tools
