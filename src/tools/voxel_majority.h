// Reference rows that bound what a voxel map can reach on the same queries, without any kernel:
// each query's voxel (at the map resolution) is labelled by the majority class of the mapped
// scans' points that fall in it, counting either their predictions (what any rule fed with
// one-hot evidence from those hard labels sees in that voxel), the labels of an evidence source
// (the argmax of each point's evidence: what a rule fed with that evidence sees) or their GT
// (the resolution's ceiling: the best label a voxel can have). Ties go to the lowest class
// index; a voxel without a counted point gives no label.
#pragma once

#include <vector>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evaluation/metrics.h"

namespace evidential_octomap::tools {

enum class MajorityOf { kPredictions, kGroundTruth };

// `queries` with Query::predicted replaced by the majority label of the query's voxel (-1: no
// mapped point there). Points of the ignore class (by the counted label) are not counted.
std::vector<Query> voxelMajorityAnswers(const std::vector<Scan>& scans,
                                        const std::vector<size_t>& map_scans,
                                        const std::vector<Query>& queries, double resolution,
                                        int num_classes, int ignore_class, MajorityOf what);

// The same with the labels given per scan (indexed like `scans`; labels[s] may be empty for a
// scan that is not mapped).
std::vector<Query> voxelMajorityAnswers(const std::vector<Scan>& scans,
                                        const std::vector<std::vector<int>>& labels,
                                        const std::vector<size_t>& map_scans,
                                        const std::vector<Query>& queries, double resolution,
                                        int num_classes, int ignore_class);

// Each point's class under N x C evidence (per scan): its largest evidence (ties to the lowest
// class), -1 when it has none.
std::vector<std::vector<int>> evidenceLabels(const std::vector<std::vector<float>>& evidence,
                                             int num_classes);

// An upper bound for any rule that labels a voxel with one of the classes predicted within its
// kernel support (what one-hot evidence allows): the query's answer is its GT when some mapped
// point predicting that class lies within `support` [m] of the query's voxel cube; otherwise the
// most frequent prediction within the support (wrong), or no label when there is none.
std::vector<Query> neighbourhoodOracleAnswers(const std::vector<Scan>& scans,
                                              const std::vector<size_t>& map_scans,
                                              const std::vector<Query>& queries, double resolution,
                                              double support, int num_classes, int ignore_class);

}  // namespace evidential_octomap::tools
