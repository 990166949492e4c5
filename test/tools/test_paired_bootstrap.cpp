// The paired block bootstrap of paired_bootstrap.h against an exact enumeration: with three
// blocks there are 27 equally likely ordered draws, so the bootstrap distribution of a
// difference is known exactly. Each of its atoms has probability >= 1/27 > 2.5 %, so the 95 %
// percentile interval must be [smallest, largest] exact value, and the share of positive
// replicates must approach the exact probability. The exact values are recomputed here from
// the raw query lists (IoU counted by hand), not with ConfusionMatrix.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "evidential_octomap/evaluation/paired_bootstrap.h"

using namespace evidential_octomap;

namespace {
constexpr int kClasses = 3;  // class 0 is the ignore class
constexpr int kIgnore = 0;

struct Item {  // one query: its block, its GT and each row's label and Brier term
  int block, gt, row_label, ref_label;
  float row_brier, ref_brier;
};

// Block 0: the row is right where the reference has no label; block 1: the row is wrong where
// the reference is right; block 2: both mixed, class 2 only here.
const std::vector<Item> kItems = {
    {0, 1, 1, -1, 0.1f, 0.6f}, {0, 1, 1, 1, 0.2f, 0.3f},  {0, 1, 2, 1, 0.9f, 0.4f},
    {1, 1, 2, 1, 1.2f, 0.2f},  {1, 1, 1, 1, 0.1f, 0.1f},  {2, 2, 2, 2, 0.3f, 0.2f},
    {2, 2, 1, 2, 1.1f, 0.5f},  {2, 2, 2, -1, 0.2f, 0.7f}, {2, 1, 1, 2, 0.0f, 1.3f},
    {2, 2, 2, 2, 0.1f, 0.4f},
};

// mIoU over the classes present in GT (ignore class excluded), counted by hand.
double handMiou(const std::vector<std::pair<int, int>>& gt_label) {
  double sum = 0.0;
  int present = 0;
  for (int c = 0; c < kClasses; ++c) {
    if (c == kIgnore) continue;
    int tp = 0, fp = 0, fn = 0, in_gt = 0;
    for (const auto& [gt, label] : gt_label) {
      in_gt += gt == c;
      tp += gt == c && label == c;
      fp += gt != c && label == c;
      fn += gt == c && label != c;
    }
    if (in_gt == 0) continue;
    ++present;
    sum += double(tp) / double(tp + fp + fn);
  }
  return present ? sum / present : std::nan("");
}

// The difference (row - reference) of mIoU and mean Brier on the queries of the blocks drawn.
std::pair<double, double> exactDifference(const std::vector<int>& draw) {
  std::vector<std::pair<int, int>> row, ref;
  double row_brier = 0.0, ref_brier = 0.0;
  for (int b : draw) {
    for (const Item& it : kItems) {
      if (it.block != b) continue;
      row.push_back({it.gt, it.row_label});
      ref.push_back({it.gt, it.ref_label});
      row_brier += it.row_brier;
      ref_brier += it.ref_brier;
    }
  }
  return {handMiou(row) - handMiou(ref), (row_brier - ref_brier) / double(row.size())};
}

struct Rows {
  std::vector<Query> queries;
  std::vector<QueryOutcome> row, ref;
};

Rows makeRows() {
  Rows r;
  for (const Item& it : kItems) {
    Query q;
    q.point_W = octomap::point3d(10.0f * it.block + 3.0f, -2.0f, 0.5f);  // 10 m blocks
    q.gt = it.gt;
    r.queries.push_back(q);
    r.row.push_back({int16_t(it.gt), int16_t(it.row_label), it.row_brier});
    r.ref.push_back({int16_t(it.gt), int16_t(it.ref_label), it.ref_brier});
  }
  // One uncounted query (ignore class) in block 0: it must change nothing.
  Query ignored;
  ignored.point_W = octomap::point3d(1.0f, -1.0f, 0.0f);
  r.queries.push_back(ignored);
  r.row.push_back(QueryOutcome());
  r.ref.push_back(QueryOutcome());
  return r;
}
}  // namespace

TEST(SpatialBlocks, SquaresOfTheBlockSizeInXyInOrderOfAppearance) {
  std::vector<Query> q(5);
  q[0].point_W = octomap::point3d(0.5f, 0.5f, 0.0f);
  q[1].point_W = octomap::point3d(9.9f, 0.1f, 7.0f);   // same square, other z
  q[2].point_W = octomap::point3d(-0.1f, 0.5f, 0.0f);  // x < 0: the square to the left
  q[3].point_W = octomap::point3d(0.5f, 10.0f, 0.0f);  // next square in y
  q[4].point_W = octomap::point3d(-5.0f, 3.0f, 0.0f);  // same square as q[2]
  size_t blocks = 0;
  const std::vector<uint32_t> b = spatialBlocks(q, 10.0, &blocks);
  EXPECT_EQ(blocks, 3u);
  EXPECT_EQ(b, (std::vector<uint32_t>{0, 0, 1, 2, 1}));
  EXPECT_THROW(spatialBlocks(q, 0.0, &blocks), std::invalid_argument);
}

TEST(PairedBootstrap, IntervalAndShareMatchTheExactEnumerationOfThreeBlocks) {
  const Rows rows = makeRows();
  size_t blocks = 0;
  const std::vector<uint32_t> block = spatialBlocks(rows.queries, 10.0, &blocks);
  ASSERT_EQ(blocks, 3u);
  const BlockScores row(kClasses, block, blocks, rows.row);
  const BlockScores ref(kClasses, block, blocks, rows.ref);

  // Exact distribution: all 27 ordered draws, equally likely.
  std::vector<double> miou, brier;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c) {
        const auto [dm, db] = exactDifference({a, b, c});
        miou.push_back(dm);
        brier.push_back(db);
      }
  const auto share = [](const std::vector<double>& v) {
    return double(std::count_if(v.begin(), v.end(), [](double x) { return x > 1e-12; })) /
           double(v.size());
  };
  // The data must make the test able to fail: the differences change sign across draws.
  ASSERT_LT(*std::min_element(miou.begin(), miou.end()), 0.0);
  ASSERT_GT(*std::max_element(miou.begin(), miou.end()), 0.0);
  ASSERT_LT(*std::min_element(brier.begin(), brier.end()), 0.0);
  ASSERT_GT(*std::max_element(brier.begin(), brier.end()), 0.0);

  BootstrapSettings s;
  s.replicates = 20000;
  s.seed = 7;
  const PairedDifference d = pairedBootstrap(row, ref, kIgnore, s);
  const auto [full_miou, full_brier] = exactDifference({0, 1, 2});
  EXPECT_EQ(d.blocks, 3u);
  EXPECT_NEAR(d.miou_all.estimate, full_miou, 1e-12);
  EXPECT_NEAR(d.brier.estimate, full_brier, 1e-7);
  EXPECT_NEAR(d.miou_all.lower, *std::min_element(miou.begin(), miou.end()), 1e-12);
  EXPECT_NEAR(d.miou_all.upper, *std::max_element(miou.begin(), miou.end()), 1e-12);
  EXPECT_NEAR(d.brier.lower, *std::min_element(brier.begin(), brier.end()), 1e-7);
  EXPECT_NEAR(d.brier.upper, *std::max_element(brier.begin(), brier.end()), 1e-7);
  // Monte Carlo share: binomial standard error sqrt(p(1-p)/20000) < 0.004.
  EXPECT_NEAR(d.miou_all.share_positive, share(miou), 0.015);
  EXPECT_NEAR(d.brier.share_positive, share(brier), 0.015);
}

TEST(PairedBootstrap, SameSeedSameIntervalsAndMismatchedRowsAreRejected) {
  const Rows rows = makeRows();
  size_t blocks = 0;
  const std::vector<uint32_t> block = spatialBlocks(rows.queries, 10.0, &blocks);
  const BlockScores row(kClasses, block, blocks, rows.row);
  const BlockScores ref(kClasses, block, blocks, rows.ref);
  const PairedDifference a = pairedBootstrap(row, ref, kIgnore, BootstrapSettings());
  const PairedDifference b = pairedBootstrap(row, ref, kIgnore, BootstrapSettings());
  EXPECT_EQ(a.miou_all.lower, b.miou_all.lower);
  EXPECT_EQ(a.brier.upper, b.brier.upper);
  // A row against itself: every replicate's difference is 0.
  const PairedDifference self = pairedBootstrap(row, row, kIgnore, BootstrapSettings());
  EXPECT_EQ(self.miou_all.lower, 0.0);
  EXPECT_EQ(self.miou_all.upper, 0.0);
  EXPECT_EQ(self.brier.share_positive, 0.0);
  const BlockScores other_blocks(kClasses, std::vector<uint32_t>(rows.row.size(), 0), 1, rows.row);
  EXPECT_THROW(pairedBootstrap(row, other_blocks, kIgnore, BootstrapSettings()),
               std::invalid_argument);
}
