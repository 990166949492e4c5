#include "render.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "evidential_octomap/io.h"

namespace evidential_octomap::tools {

namespace {

const cv::Vec3b kBackground(255, 255, 255);
const cv::Vec3b kNoSemantics(228, 228, 228);  // lighter than any grey class colour
const cv::Vec3d kRight(60, 170, 40), kWrong(30, 30, 220), kNoLabel(200, 140, 60);  // BGR
constexpr int kLine = 20;
constexpr int kPanel = 220;

cv::Vec3b bgr(const ClassTable::Rgb& rgb) { return cv::Vec3b(rgb[2], rgb[1], rgb[0]); }

// Top-most occupied leaf of every pixel column: the node pointer and its z.
struct TopLeaf {
  const EvidentialOcTreeNode* node = nullptr;
  double z = -std::numeric_limits<double>::infinity();
};

std::vector<TopLeaf> topLeaves(const EvidentialOcTree& tree, const TopDownGrid& g) {
  std::vector<TopLeaf> top(size_t(g.width) * g.height);
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double half = 0.5 * it.getSize();
    int c0, r0, c1, r1;
    // Pixel range of the leaf's footprint (rows grow downwards, so r1 < r0).
    if (!g.toPixel(it.getX() - half + 1e-6, it.getY() - half + 1e-6, &c0, &r0)) continue;
    if (!g.toPixel(it.getX() + half - 1e-6, it.getY() + half - 1e-6, &c1, &r1)) continue;
    const double z = it.getZ();
    for (int r = r1; r <= r0; ++r)
      for (int c = c0; c <= c1; ++c) {
        TopLeaf& t = top[size_t(r) * g.width + c];
        if (z > t.z) t = {&*it, z};
      }
  }
  return top;
}

// Caption above, side panel right, map in between.
cv::Mat compose(const cv::Mat& map, const std::vector<std::string>& caption, cv::Mat* panel) {
  const int top = kLine * int(caption.size()) + 8;
  const int h = std::max(map.rows + top, top + 300);
  cv::Mat canvas(h, map.cols + kPanel, CV_8UC3, cv::Scalar(255, 255, 255));
  map.copyTo(canvas(cv::Rect(0, top, map.cols, map.rows)));
  cv::rectangle(canvas, cv::Rect(0, top, map.cols, map.rows), cv::Scalar(120, 120, 120), 1);
  for (size_t i = 0; i < caption.size(); ++i) {
    cv::putText(canvas, caption[i], cv::Point(6, kLine * int(i + 1)), cv::FONT_HERSHEY_SIMPLEX,
                0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  *panel = canvas(cv::Rect(map.cols, top, kPanel, h - top));
  return canvas;
}

void legendEntry(cv::Mat& panel, int row, const cv::Vec3b& color, const std::string& text) {
  const int y = 10 + row * kLine;
  cv::rectangle(panel, cv::Rect(10, y, 14, 14), cv::Scalar(color[0], color[1], color[2]),
                cv::FILLED);
  cv::rectangle(panel, cv::Rect(10, y, 14, 14), cv::Scalar(0, 0, 0), 1);
  cv::putText(panel, text, cv::Point(30, y + 12), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

void drawScaleBar(cv::Mat& map, const TopDownGrid& g) {
  const double metres = 20.0;
  const int len = int(std::lround(metres / g.pixel));
  if (len + 20 > map.cols || map.rows < 30) return;
  const cv::Point a(10, map.rows - 12), b(10 + len, map.rows - 12);
  cv::line(map, a, b, cv::Scalar(0, 0, 0), 2);
  cv::putText(map, "20 m", cv::Point(10, map.rows - 18), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

}  // namespace

bool TopDownGrid::toPixel(double x, double y, int* col, int* row) const {
  const int c = int(std::floor((x - x0) / pixel));
  const int r = height - 1 - int(std::floor((y - y0) / pixel));
  if (c < 0 || c >= width || r < 0 || r >= height) return false;
  *col = c;
  *row = r;
  return true;
}

TopDownGrid makeGrid(const EvidentialOcTree& tree, const std::vector<Query>* queries,
                     int max_pixels) {
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin;
  double xmax = -xmin, ymax = -xmin;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double half = 0.5 * it.getSize();
    xmin = std::min(xmin, it.getX() - half);
    xmax = std::max(xmax, it.getX() + half);
    ymin = std::min(ymin, it.getY() - half);
    ymax = std::max(ymax, it.getY() + half);
  }
  if (queries) {
    for (const Query& q : *queries) {
      xmin = std::min(xmin, double(q.point_W.x()));
      xmax = std::max(xmax, double(q.point_W.x()));
      ymin = std::min(ymin, double(q.point_W.y()));
      ymax = std::max(ymax, double(q.point_W.y()));
    }
  }
  TopDownGrid g;
  if (!(xmin < xmax && ymin < ymax)) return g;  // empty map: 1 x 1
  g.pixel = tree.getResolution();
  const double extent = std::max(xmax - xmin, ymax - ymin);
  if (extent / g.pixel > max_pixels) g.pixel = extent / max_pixels;
  g.x0 = xmin;
  g.y0 = ymin;
  g.width = std::max(1, int(std::ceil((xmax - xmin) / g.pixel)) + 1);
  g.height = std::max(1, int(std::ceil((ymax - ymin) / g.pixel)) + 1);
  return g;
}

cv::Mat semanticLayer(const EvidentialOcTree& tree, const ClassTable& classes,
                      const TopDownGrid& g, std::set<int>* shown_out) {
  cv::Mat map(g.height, g.width, CV_8UC3, cv::Scalar(255, 255, 255));
  std::set<int> shown;
  const auto top = topLeaves(tree, g);
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const TopLeaf& t = top[size_t(r) * g.width + c];
      if (!t.node) continue;
      const int label = t.node->hasSemantics() ? tree.opinion(t.node).label : -1;
      if (label >= 0 && label < classes.numClasses()) {
        map.at<cv::Vec3b>(r, c) = bgr(classes.colors[label]);
        shown.insert(label);
      } else {
        map.at<cv::Vec3b>(r, c) = kNoSemantics;
      }
    }
  if (shown_out) *shown_out = shown;
  return map;
}

cv::Mat renderSemantic(const EvidentialOcTree& tree, const ClassTable& classes,
                       const TopDownGrid& g, const std::vector<std::string>& caption) {
  std::set<int> shown;
  cv::Mat map = semanticLayer(tree, classes, g, &shown);
  drawScaleBar(map, g);
  cv::Mat panel;
  cv::Mat canvas = compose(map, caption, &panel);
  int row = 0;
  for (int label : shown) legendEntry(panel, row++, bgr(classes.colors[label]), classes.names[label]);
  legendEntry(panel, row++, kNoSemantics, "occupied, no label");
  return canvas;
}

namespace {

// Colour by rank: a map's u is far from uniform (most voxels sit near the read-out floor, a few
// are high), so a linear 0..1 scale paints nearly the whole map one colour. Here equal colour
// steps hold equal shares of the drawn voxels, and the legend gives u at those shares.
class QuantileScale {
 public:
  explicit QuantileScale(std::vector<double> values) : sorted_(std::move(values)) {
    std::sort(sorted_.begin(), sorted_.end());
  }
  // Share of the drawn voxels below u (ties take the middle of their run), in [0, 1].
  double colourPosition(double u) const {
    if (sorted_.size() < 2) return 0.0;
    const auto lo = std::lower_bound(sorted_.begin(), sorted_.end(), u);
    const auto hi = std::upper_bound(lo, sorted_.end(), u);
    const double rank = 0.5 * double((lo - sorted_.begin()) + (hi - sorted_.begin()) - 1);
    return std::clamp(rank / double(sorted_.size() - 1), 0.0, 1.0);
  }
  double quantile(double q) const {
    if (sorted_.empty()) return 0.0;
    return sorted_[size_t(std::lround(q * double(sorted_.size() - 1)))];
  }

 private:
  std::vector<double> sorted_;
};

// What the picture shows of each column's highest occupied leaf: the probability that its label
// is wrong; NaN where nothing with semantics is drawn. Read once, for the scale and the colours.
std::vector<double> shownUncertainties(const EvidentialOcTree& tree,
                                       const std::vector<TopLeaf>& top) {
  std::vector<double> shown(top.size(), std::nan(""));
  for (size_t i = 0; i < top.size(); ++i)
    if (top[i].node && top[i].node->hasSemantics())
      shown[i] = tree.rule().errorProbability(tree.opinion(top[i].node));
  return shown;
}

QuantileScale scaleOf(const std::vector<double>& shown) {
  std::vector<double> drawn;
  for (double v : shown)
    if (!std::isnan(v)) drawn.push_back(v);
  return QuantileScale(std::move(drawn));
}

cv::Mat drawUncertainty(const std::vector<TopLeaf>& top, const std::vector<double>& shown,
                        const QuantileScale& scale, const TopDownGrid& g) {
  cv::Mat map(g.height, g.width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const size_t i = size_t(r) * g.width + c;
      if (!top[i].node) continue;
      map.at<cv::Vec3b>(r, c) = std::isnan(shown[i])
                                    ? kNoSemantics
                                    : bgr(uncertaintyColor(scale.colourPosition(shown[i])));
    }
  return map;
}

}  // namespace

cv::Mat uncertaintyLayer(const EvidentialOcTree& tree, const TopDownGrid& g) {
  const auto top = topLeaves(tree, g);
  const std::vector<double> shown = shownUncertainties(tree, top);
  return drawUncertainty(top, shown, scaleOf(shown), g);
}

cv::Mat renderUncertainty(const EvidentialOcTree& tree, const TopDownGrid& g,
                          const std::vector<std::string>& caption) {
  const auto top = topLeaves(tree, g);
  const std::vector<double> shown = shownUncertainties(tree, top);
  const QuantileScale scale = scaleOf(shown);
  cv::Mat map = drawUncertainty(top, shown, scale, g);
  drawScaleBar(map, g);
  cv::Mat panel;
  cv::Mat canvas = compose(map, caption, &panel);
  // Vertical colour bar: the lowest value at the bottom, the highest at the top, labelled at the
  // 0, 25, 50, 75 and 100 % shares of the drawn voxels.
  const int bar_h = std::min(240, panel.rows - 130);
  for (int y = 0; y < bar_h; ++y) {
    const double t = 1.0 - double(y) / std::max(1, bar_h - 1);
    const cv::Vec3b col = bgr(uncertaintyColor(t));
    cv::line(panel, cv::Point(14, 20 + y), cv::Point(40, 20 + y),
             cv::Scalar(col[0], col[1], col[2]));
  }
  cv::rectangle(panel, cv::Rect(14, 20, 27, bar_h), cv::Scalar(0, 0, 0), 1);
  auto label = [&](int y, const std::string& text) {
    cv::putText(panel, text, cv::Point(48, y), cv::FONT_HERSHEY_SIMPLEX, 0.42, cv::Scalar(0, 0, 0),
                1, cv::LINE_AA);
  };
  for (int i = 0; i <= 4; ++i) {
    std::ostringstream s;
    s << std::setprecision(3) << scale.quantile(i / 4.0) << " (" << 25 * i << " %)";
    label(25 + int((1.0 - i / 4.0) * (bar_h - 1)), s.str());
  }
  label(44 + bar_h, "quantile scale: each");
  label(60 + bar_h, "step = an equal share");
  label(76 + bar_h, "of the drawn voxels");
  label(92 + bar_h, "P(label wrong)");
  label(108 + bar_h, "= 1 - max p");
  legendEntry(panel, (bar_h + 126) / kLine, kNoSemantics, "no evidence");
  return canvas;
}

cv::Mat errorLayer(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                   const TopDownGrid& g) {
  // Per pixel: counts of right / wrong / unlabelled queries, drawn as a colour mix.
  std::vector<cv::Vec3i> counts(size_t(g.width) * g.height, cv::Vec3i(0, 0, 0));
  for (const Query& q : queries) {
    int c, r;
    if (!g.toPixel(q.point_W.x(), q.point_W.y(), &c, &r)) continue;
    const EvidentialOcTreeNode* node = tree.nodeAt(q.point_W);
    int kind = 2;  // no label: the voxel holds no evidence
    if (node && node->hasSemantics()) kind = tree.opinion(node).label == q.gt ? 0 : 1;
    ++counts[size_t(r) * g.width + c][kind];
  }
  const cv::Vec3d colors[3] = {kRight, kWrong, kNoLabel};
  cv::Mat map(g.height, g.width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const cv::Vec3i& n = counts[size_t(r) * g.width + c];
      const int total = n[0] + n[1] + n[2];
      if (total == 0) continue;
      cv::Vec3d mix(0, 0, 0);
      for (int k = 0; k < 3; ++k) mix += colors[k] * (double(n[k]) / total);
      map.at<cv::Vec3b>(r, c) = cv::Vec3b(cv::saturate_cast<uchar>(mix[0]),
                                          cv::saturate_cast<uchar>(mix[1]),
                                          cv::saturate_cast<uchar>(mix[2]));
    }
  return map;
}

cv::Mat renderError(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                    const TopDownGrid& g, const std::vector<std::string>& caption) {
  cv::Mat map = errorLayer(tree, queries, g);
  drawScaleBar(map, g);
  cv::Mat panel;
  cv::Mat canvas = compose(map, caption, &panel);
  legendEntry(panel, 0, cv::Vec3b(kRight), "right");
  legendEntry(panel, 1, cv::Vec3b(kWrong), "wrong label");
  legendEntry(panel, 2, cv::Vec3b(kNoLabel), "no label (no evidence)");
  cv::putText(panel, "colours mix per pixel", cv::Point(10, 80), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return canvas;
}

void writePng(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": cannot encode PNG: " + e.what());
  }
  if (!ok) throw std::runtime_error(path + ": cannot encode PNG");
  writeFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace evidential_octomap::tools
