// Paired cluster bootstrap of the difference between two rows (a rule, or the input) evaluated on
// the same queries: is "ahead by 0.03 mIoU points" more than noise?
//
// Queries are not independent: neighbouring points fall in the same voxels and the scans of a
// sequence overlap, so resampling single queries would give intervals far too narrow, and
// resampling scans is impossible on one scan (RELLIS-3D) and nearly meaningless on ten scans of
// the same street. The unit resampled is a spatial block: the queries whose world x-y fall in
// one block_size x block_size square. A replicate draws as many blocks as there are, with
// replacement (std::mt19937_64 seeded with `seed`, uniform indices), and both rows get the same
// draw (paired). Statistics per replicate: mIoU over all queries from the summed confusion
// counts (classes present in the replicate's GT), and the mean Brier term. The interval is the
// percentile interval of the replicates' differences (row - reference): sorted values at
// positions floor(alpha/2) and ceil((1-alpha/2)(R-1)).
#pragma once

#include <cstdint>
#include <vector>

#include "evidential_octomap/evaluation/metrics.h"

namespace evidential_octomap {

struct BootstrapSettings {
  double block_size = 10.0;  // [m], side of the square blocks resampled
  int replicates = 1000;
  uint64_t seed = 1;
  double alpha = 0.05;  // 95 % intervals
};

// Block index of every query (dense ids 0..blocks-1 in order of first appearance).
std::vector<uint32_t> spatialBlocks(const std::vector<Query>& queries, double block_size,
                                    size_t* blocks);

// One row's per-block sufficient statistics: sparse confusion counts over all queries and the
// Brier sum and count.
class BlockScores {
 public:
  BlockScores(int num_classes, const std::vector<uint32_t>& block_of_query, size_t blocks,
              const std::vector<QueryOutcome>& outcomes);
  int numClasses() const { return num_classes_; }
  size_t blocks() const { return blocks_.size(); }
  // mIoU over all queries and mean Brier with each block counted `weight[b]` times.
  double miouAll(const std::vector<uint32_t>& weight, int ignore_class) const;
  double brier(const std::vector<uint32_t>& weight) const;

 private:
  struct Cell {
    int16_t gt, label;
    uint32_t count;
  };
  struct Block {
    std::vector<Cell> cells;
    double brier_sum = 0.0;
    uint64_t queries = 0;
  };
  int num_classes_;
  std::vector<Block> blocks_;
};

struct BootstrapInterval {
  double estimate = 0.0;  // the difference on the queries as they are
  double lower = 0.0, upper = 0.0;
  double share_positive = 0.0;  // share of replicates with a difference > 0
};

struct PairedDifference {
  BootstrapInterval miou_all, brier;  // row - reference (mIoU as a fraction, not %)
  size_t blocks = 0;
  BootstrapSettings settings;
};

// Throws std::invalid_argument when the rows have different class or block counts.
PairedDifference pairedBootstrap(const BlockScores& row, const BlockScores& reference,
                                 int ignore_class, const BootstrapSettings& settings);

}  // namespace evidential_octomap
