// Label-free pseudo-labels for calibration: what the OTHER scans' predictions say about each
// point's voxel. A point of scan t gets the class most of the points of scans != t in its voxel
// (of `resolution` metres, world frame) were predicted as, when at least `min_votes` of them
// agree on it; else -1. Agreement with it measures how consistent the network is across
// viewpoints, which bounds its accuracy from above: a region the network gets wrong from every
// viewpoint agrees with itself, so a calibration fitted on these labels can be no better than
// the network's consistency (docs/calibration.md).
#pragma once

#include <vector>

#include "dataset.h"

namespace evidential_octomap::tools {

// `evidence[s]` (N x C) gives each point's predicted class (argmax; no evidence: no vote) for
// every scan s in `which`; the result has one label per point for those scans (empty otherwise).
std::vector<std::vector<int>> consensusLabels(const std::vector<Scan>& scans,
                                              const std::vector<size_t>& which,
                                              const std::vector<std::vector<float>>& evidence,
                                              int num_classes, double resolution,
                                              int min_votes = 2);

}  // namespace evidential_octomap::tools
