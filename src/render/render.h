// Top-down PNG renders of a map (OpenCV, tools only): semantic classes with a legend,
// uncertainty with a colour bar, and errors of the evaluation queries (right / wrong / no label).
// Each column of the map shows its highest occupied leaf; north (+y) is up.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/evaluation/metrics.h"

namespace evidential_octomap::tools {

struct TopDownGrid {
  double x0 = 0.0, y0 = 0.0;  // world coordinates of the lower-left corner
  double pixel = 0.2;         // metres per pixel
  int width = 1, height = 1;
  bool toPixel(double x, double y, int* col, int* row) const;
};

// Bounds of the occupied leaves (and the queries, when given); pixel = resolution, coarsened so
// that neither side exceeds max_pixels.
TopDownGrid makeGrid(const EvidentialOcTree& tree, const std::vector<Query>* queries,
                     int max_pixels = 1600);

// caption: lines printed above the image (rule, evidence source, protocol, ...).
cv::Mat renderSemantic(const EvidentialOcTree& tree, const ClassTable& classes,
                       const TopDownGrid& grid, const std::vector<std::string>& caption);
// The map's probability that each drawn voxel's label is wrong, 1 - max_c p_c
// (FusionRule::errorProbability, the default uncertainty: docs/experiments/results.md).
cv::Mat renderUncertainty(const EvidentialOcTree& tree, const TopDownGrid& grid,
                          const std::vector<std::string>& caption);
cv::Mat renderError(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                    const TopDownGrid& grid, const std::vector<std::string>& caption);

// The map layers alone (no caption, legend or scale bar), one pixel per grid cell, BGR; white
// where nothing is occupied, light grey (228) for occupied voxels without evidence. Error layer: per pixel
// the mix of right (green), wrong (red) and unlabelled (blue) queries.
cv::Mat semanticLayer(const EvidentialOcTree& tree, const ClassTable& classes,
                      const TopDownGrid& grid, std::set<int>* classes_shown = nullptr);
// Uncertainty (1 - max p) is coloured on a quantile scale of the drawn voxels' values (equal
// colour steps = equal shares of the voxels; renderUncertainty's legend gives 0/25/50/75/100 %).
cv::Mat uncertaintyLayer(const EvidentialOcTree& tree, const TopDownGrid& grid);
cv::Mat errorLayer(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                   const TopDownGrid& grid);

// Throws std::runtime_error naming the path when the PNG cannot be written.
void writePng(const std::string& path, const cv::Mat& image);

}  // namespace evidential_octomap::tools
