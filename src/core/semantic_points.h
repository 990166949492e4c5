// The points of a scan that give semantic evidence: the percentile threshold and the
// down-sampling of SemanticConfig, computed in parallel with sorting instead of hash maps.
// Private to the core.
#pragma once

#include <octomap/octomap_types.h>

#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

// Points that may give semantic evidence: inside the map and within max_range.
struct RawPoints {
  std::vector<octomap::point3d> positions;
  std::vector<const float*> evidence;  // C values each, into the caller's array
  void clear() {
    positions.clear();
    evidence.clear();
  }
};

// Points and evidence that take part in the kernel pass. A point kept as it came names the
// caller's evidence row rather than copying it (C floats per point, 10 MB a scan at C = 20).
struct SemanticPoints {
  std::vector<octomap::point3d> positions;
  std::vector<const float*> evidence;  // C values each: the caller's row, or one of `own`
  std::vector<float> own;  // C values per point: averaged cells' means, floored evidence
};

// Buffers of selectSemanticPoints, kept from scan to scan.
struct SemanticScratch {
  std::vector<float> uncertainty;
  std::vector<std::pair<uint64_t, uint32_t>> cells, buffer;  // (cell key, point), sorted
  std::vector<uint32_t> runs;                                // first point of every cell
};

// How a scan's points are selected, read once from the settings: the percentile threshold, the
// down-sampling cells and the evidence floor.
struct PointSelection {
  // kAverage: cells of resolution / ds_multiplier merged into one point each; kCountCap (the
  // authors'): cells of 2 x 2 x 2 voxels keeping their first ds_multiplier + 1 points;
  // kPerPoint: no down-sampling.
  enum class Cells { kPerPoint, kAverage, kCountCap };

  int num_classes = 1;
  bool threshold = false;  // drop the drop_percent most uncertain points
  double drop_percent = 0.0;
  Cells cells = Cells::kPerPoint;
  double cell_size = 0.0;  // [m]
  size_t cap = 0;          // points kept per kCountCap cell
  float evidence_floor = 0.0f;

  static PointSelection of(const SemanticConfig& config, int num_classes, bool use_threshold,
                           double resolution);
};

// Drops the points above the scan's percentile U_thr of their uncertainty (over the points
// before any down-sampling, as the authors do), then down-samples what is left; `stats` gets
// U_thr and the number of points dropped. The result is in the order of the down-sampling
// cells' keys; the evidence of a cell sums in the input order. Evidence below the floor is then
// set to 0.
void selectSemanticPoints(const RawPoints& raw, const PointSelection& how, int threads,
                          SemanticScratch* scratch, SemanticPoints* out, InsertStats* stats);

}  // namespace evidential_octomap
