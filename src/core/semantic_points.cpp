#include "semantic_points.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "evidential_octomap/sparse_kernel.h"
#include "radix_sort.h"

namespace evidential_octomap {
namespace {

double uncertaintyOf(const float* evidence, int num_classes) {
  double strength = num_classes;
  for (int c = 0; c < num_classes; ++c) strength += evidence[c];
  return num_classes / strength;
}

// Cell index of a point on a grid of size `cell`, packed into 63 bits (21 per axis).
uint64_t cellKey(const octomap::point3d& p, double cell) {
  const uint64_t ix =
      static_cast<uint64_t>(static_cast<int64_t>(std::floor(p.x() / cell))) & 0x1FFFFF;
  const uint64_t iy =
      static_cast<uint64_t>(static_cast<int64_t>(std::floor(p.y() / cell))) & 0x1FFFFF;
  const uint64_t iz =
      static_cast<uint64_t>(static_cast<int64_t>(std::floor(p.z() / cell))) & 0x1FFFFF;
  return (ix << 42) | (iy << 21) | iz;
}

// U_thr over every raw point; +inf when the threshold is off. Marks the dropped points with a
// negative uncertainty in scratch->uncertainty.
void applyThreshold(const RawPoints& raw, int num_classes, bool enabled, double drop_percent,
                    int threads, SemanticScratch* scratch, InsertStats* stats) {
  const size_t n = raw.positions.size();
  std::vector<float>& u = scratch->uncertainty;
  u.resize(n);
  stats->uncertainty_threshold = std::numeric_limits<double>::infinity();
  if (!enabled) return;
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t i = 0; i < n; ++i)
    u[i] = static_cast<float>(uncertaintyOf(raw.evidence[i], num_classes));
  const double threshold = uncertaintyThreshold(u, drop_percent);
  stats->uncertainty_threshold = threshold;
  for (float& value : u) {
    if (value > threshold) {  // the same float values the threshold came from
      value = -1.0f;
      ++stats->points_dropped_uncertain;
    }
  }
}

// The kept points' cells as (cell key, point) pairs in cell order (input order within a cell),
// and the first pair of every cell (plus the end).
void sortIntoCells(const RawPoints& raw, const PointSelection& how, SemanticScratch* scratch) {
  const std::vector<float>& u = scratch->uncertainty;
  const bool per_point = how.cells == PointSelection::Cells::kPerPoint;
  auto& cells = scratch->cells;
  cells.clear();
  for (size_t i = 0; i < raw.positions.size(); ++i) {
    if (how.threshold && u[i] < 0.0f) continue;
    cells.emplace_back(per_point ? uint64_t(i) : cellKey(raw.positions[i], how.cell_size),
                       static_cast<uint32_t>(i));
  }
  if (!per_point) radixSort(&cells, 64, &scratch->buffer);  // stable: input order within a cell
  auto& runs = scratch->runs;
  runs.clear();
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i == 0 || cells[i].first != cells[i - 1].first || per_point) {
      runs.push_back(static_cast<uint32_t>(i));
    }
  }
  runs.push_back(static_cast<uint32_t>(cells.size()));
}

// Output index of each cell's first point: averaging merges a cell into one point, the count
// cap keeps its first `cap` points.
std::vector<uint32_t> outputOffsets(const std::vector<uint32_t>& runs, const PointSelection& how) {
  std::vector<uint32_t> first_out(runs.size(), 0);
  for (size_t r = 0; r + 1 < runs.size(); ++r) {
    const size_t size = runs[r + 1] - runs[r];
    const size_t kept = how.cells == PointSelection::Cells::kAverage    ? 1
                        : how.cells == PointSelection::Cells::kCountCap ? std::min(size, how.cap)
                                                                        : size;
    first_out[r + 1] = first_out[r] + static_cast<uint32_t>(kept);
  }
  return first_out;
}

void applyFloor(const PointSelection& how, float* row) {
  if (how.evidence_floor <= 0.0f) return;
  std::replace_if(row, row + how.num_classes, [&](float e) { return e < how.evidence_floor; },
                  0.0f);
}

using CellPair = std::pair<uint64_t, uint32_t>;

// A cell's points as they came (up to the output slots it has), floored into rows of their own.
void keepPoints(const RawPoints& raw, const PointSelection& how, const CellPair* begin,
                const CellPair* end, size_t o, size_t o_end, SemanticPoints* out) {
  for (const CellPair* c = begin; c != end && o < o_end; ++c, ++o) {
    out->positions[o] = raw.positions[c->second];
    out->evidence[o] = raw.evidence[c->second];
    if (how.evidence_floor > 0.0f) {
      float* row = &out->own[o * how.num_classes];
      std::copy_n(raw.evidence[c->second], how.num_classes, row);
      applyFloor(how, row);
      out->evidence[o] = row;
    }
  }
}

// A cell merged into one point: the mean position and the mean evidence, floored.
void averageCell(const RawPoints& raw, const PointSelection& how, const CellPair* begin,
                 const CellPair* end, size_t o, SemanticPoints* out) {
  // Sums in double, so the mean of finite float evidence is finite and representable (two
  // values near FLT_MAX would overflow a float sum).
  double x = 0.0, y = 0.0, z = 0.0;
  double sums[256] = {0.0};
  for (const CellPair* c = begin; c != end; ++c) {
    const octomap::point3d& p = raw.positions[c->second];
    x += p.x();
    y += p.y();
    z += p.z();
    for (int k = 0; k < how.num_classes; ++k) sums[k] += raw.evidence[c->second][k];
  }
  const double count = double(end - begin);
  out->positions[o] = octomap::point3d(float(x / count), float(y / count), float(z / count));
  float* mean = &out->own[o * how.num_classes];
  for (int k = 0; k < how.num_classes; ++k) mean[k] = float(sums[k] / count);
  applyFloor(how, mean);
  out->evidence[o] = mean;
}

}  // namespace

PointSelection PointSelection::of(const SemanticConfig& config, int num_classes,
                                  bool use_threshold, double resolution) {
  PointSelection how;
  how.num_classes = num_classes;
  how.threshold = use_threshold;
  how.drop_percent = config.drop_percent;
  how.evidence_floor = static_cast<float>(config.evidence_floor);
  if (config.ds_multiplier <= 0.0) return how;
  if (config.effectiveDownsampling() == "count_cap") {
    how.cells = Cells::kCountCap;
    how.cell_size = 2.0 * resolution;
    how.cap = static_cast<size_t>(std::floor(config.ds_multiplier)) + 1;
  } else {
    how.cells = Cells::kAverage;
    how.cell_size = resolution / config.ds_multiplier;
  }
  return how;
}

void selectSemanticPoints(const RawPoints& raw, const PointSelection& how, int threads,
                          SemanticScratch* scratch, SemanticPoints* out, InsertStats* stats) {
  applyThreshold(raw, how.num_classes, how.threshold, how.drop_percent, threads, scratch, stats);
  sortIntoCells(raw, how, scratch);
  const std::vector<uint32_t>& runs = scratch->runs;
  const std::vector<uint32_t> first_out = outputOffsets(runs, how);
  const size_t m = first_out.back();
  out->positions.resize(m);
  out->evidence.resize(m);
  // Rows of their own for averaged cells, and for every point under an evidence floor.
  const bool average = how.cells == PointSelection::Cells::kAverage;
  out->own.resize(average || how.evidence_floor > 0.0f ? m * how.num_classes : 0);
  const auto& cells = scratch->cells;
  const size_t num_cells = runs.size() - 1;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 256)
  for (size_t r = 0; r < num_cells; ++r) {
    const CellPair* begin = &cells[runs[r]];
    const CellPair* end = &cells[runs[r + 1]];
    if (average) {
      averageCell(raw, how, begin, end, first_out[r], out);
    } else {
      keepPoints(raw, how, begin, end, first_out[r], first_out[r + 1], out);
    }
  }
}

}  // namespace evidential_octomap
