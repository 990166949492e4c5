// Map and input-prediction metrics of DESIGN §6, defined so anyone can recompute them:
//   queries   = GT-labelled points (ignore class excluded) of the evaluated scans, world frame;
//   covered   = the query's voxel is occupied (tree.isNodeOccupied(tree.search(p)));
//   O.Acc     = covered / queries;
//   IoU^c     = TP / (TP + FP + FN) over covered queries, mIoU over the classes present in GT;
//   Acc       = correct / covered;
//   BS        = mean over covered queries of (u_bar - 1[s != gt])^2, u_bar the voxel uncertainty,
//               min-max scaled over the map's semantic leaves when the rule's uncertainty is not
//               already a mass in [0, 1] (UncertaintyScale says which was done).
// An occupied voxel without semantic evidence has s = "no label" (wrong) and u_bar = 1.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <octomap/octomap_types.h>

#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

// One evaluation query: a GT-labelled point in the world frame, with the input's prediction.
struct Query {
  octomap::point3d point_W;
  int gt = -1;         // ground-truth class
  int predicted = -1;  // the input's per-point class (-1: none)
};

// C x C counts, rows = GT, columns = predicted class, plus one "no label" column: a query
// whose prediction is -1 is wrong for its GT class and a false positive for no class.
class ConfusionMatrix {
 public:
  explicit ConfusionMatrix(int num_classes = 0);

  void add(int gt, int predicted, uint64_t count = 1);  // predicted -1 = no label
  void merge(const ConfusionMatrix& other);

  int numClasses() const { return num_classes_; }
  uint64_t at(int gt, int predicted) const;  // predicted -1 = the no-label column
  uint64_t total() const { return total_; }
  uint64_t correct() const;
  uint64_t gtCount(int c) const;    // row sum, no-label column included
  uint64_t predCount(int c) const;  // column sum
  bool presentInGt(int c) const { return gtCount(c) > 0; }

  // TP / (TP + FP + FN); NaN when the class appears neither in GT nor in the predictions.
  double iou(int c) const;
  // Mean IoU over the classes present in GT, `ignore_class` excluded. NaN when none is.
  double meanIou(int ignore_class = -1) const;
  // correct / total; NaN when empty.
  double accuracy() const;

 private:
  int num_classes_ = 0;
  std::vector<uint64_t> counts_;  // num_classes x (num_classes + 1), last column = no label
  uint64_t total_ = 0;
};

// How voxel uncertainty becomes u_bar in [0, 1] for the Brier score.
struct UncertaintyScale {
  bool scaled = false;  // false: the rule's uncertainty is a mass, used as is
  double min = 0.0;     // over the map's semantic leaves (when scaled)
  double max = 1.0;
  double apply(double u) const;  // clamped to [0, 1]
  std::string describe() const;
};

// Identity for rules whose uncertainty is a mass, else min-max over every semantic leaf.
UncertaintyScale uncertaintyScale(const EvidentialOcTree& tree);

struct MapMetrics {
  size_t queries = 0;
  size_t covered = 0;
  double occupied_accuracy = 0.0;  // O.Acc
  ConfusionMatrix confusion;       // covered queries only (the paper's mIoU / Acc)
  ConfusionMatrix confusion_all;   // every query; uncovered ones count as "no label"
  double miou = 0.0;               // over covered queries
  double accuracy = 0.0;           // over covered queries
  double miou_all = 0.0;           // every query, uncovered = wrong (BENCHMARKS.md convention)
  double accuracy_all = 0.0;
  double brier = 0.0;              // over covered queries
  UncertaintyScale scale;
  double mean_u_correct = 0.0;     // mean u_bar of covered correct / wrong queries
  double mean_u_wrong = 0.0;
};

// Queries whose gt is `ignore_class` or outside [0, C) are skipped (not counted).
MapMetrics evaluateMap(const EvidentialOcTree& tree, const std::vector<Query>& queries,
                       int ignore_class);

// The input predictions' per-point metrics on the same queries (every query is "covered").
struct PredictionMetrics {
  size_t queries = 0;
  ConfusionMatrix confusion;
  double miou = 0.0;
  double accuracy = 0.0;
};

PredictionMetrics evaluatePredictions(const std::vector<Query>& queries, int num_classes,
                                      int ignore_class);

}  // namespace evidential_octomap
