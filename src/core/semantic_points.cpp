#include "semantic_points.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "evidential_octomap/kernel.h"
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

}  // namespace

void selectSemanticPoints(const RawPoints& raw, int num_classes, const SemanticConfig& config,
                          bool use_threshold, double resolution, int threads,
                          SemanticScratch* scratch, SemanticPoints* out, InsertStats* stats) {
  applyThreshold(raw, num_classes, use_threshold, config.drop_percent, threads, scratch, stats);
  const bool dropped = use_threshold;
  const std::vector<float>& u = scratch->uncertainty;
  // Cells: "average" cells of resolution / ds_multiplier; the authors' "count_cap" cells of
  // 2 x 2 x 2 voxels with at most ds_multiplier + 1 points; no down-sampling: a cell per point.
  const bool downsampling = config.ds_multiplier > 0.0;
  const bool count_cap = downsampling && config.effectiveDownsampling() == "count_cap";
  const double cell = count_cap ? 2.0 * resolution : resolution / config.ds_multiplier;
  const size_t cap = count_cap ? static_cast<size_t>(std::floor(config.ds_multiplier)) + 1 : 0;
  auto& cells = scratch->cells;
  cells.clear();
  for (size_t i = 0; i < raw.positions.size(); ++i) {
    if (dropped && u[i] < 0.0f) continue;
    cells.emplace_back(downsampling ? cellKey(raw.positions[i], cell) : uint64_t(i),
                       static_cast<uint32_t>(i));
  }
  if (downsampling) radixSort(&cells, 64, &scratch->buffer);  // stable: input order within a cell
  auto& runs = scratch->runs;
  runs.clear();
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i == 0 || cells[i].first != cells[i - 1].first || !downsampling) {
      runs.push_back(static_cast<uint32_t>(i));
    }
  }
  runs.push_back(static_cast<uint32_t>(cells.size()));
  // Averaging merges a cell into one point; the count cap keeps the first `cap` points of it.
  const bool average = downsampling && !count_cap;
  std::vector<uint32_t> first_out(runs.size(), 0);  // output index of each cell's first point
  for (size_t r = 0; r + 1 < runs.size(); ++r) {
    const size_t size = runs[r + 1] - runs[r];
    first_out[r + 1] = first_out[r] + static_cast<uint32_t>(
                                          average ? 1 : (count_cap ? std::min(size, cap) : size));
  }
  const size_t m = first_out.back();
  out->positions.resize(m);
  out->evidence.resize(m);
  // Rows of their own for averaged cells, and for every point under an evidence floor.
  const bool floored = config.evidence_floor > 0.0;
  out->own.resize(average || floored ? m * num_classes : 0);
  const float floor = static_cast<float>(config.evidence_floor);
  auto applyFloor = [&](float* row) {
    if (floored) std::replace_if(row, row + num_classes, [&](float e) { return e < floor; }, 0.0f);
  };
  const size_t num_cells = runs.size() - 1;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 256)
  for (size_t r = 0; r < num_cells; ++r) {
    const auto* begin = &cells[runs[r]];
    const auto* end = &cells[runs[r + 1]];
    if (!average) {
      size_t o = first_out[r];
      for (const auto* c = begin; c != end && o < first_out[r + 1]; ++c, ++o) {
        out->positions[o] = raw.positions[c->second];
        out->evidence[o] = raw.evidence[c->second];
        if (floored) {
          float* row = &out->own[o * num_classes];
          std::copy_n(raw.evidence[c->second], num_classes, row);
          applyFloor(row);
          out->evidence[o] = row;
        }
      }
      continue;
    }
    // Sums in double, so the mean of finite float evidence is finite and representable (two
    // values near FLT_MAX would overflow a float sum).
    double x = 0.0, y = 0.0, z = 0.0;
    double sums[256] = {0.0};
    for (const auto* c = begin; c != end; ++c) {
      const octomap::point3d& p = raw.positions[c->second];
      x += p.x();
      y += p.y();
      z += p.z();
      for (int k = 0; k < num_classes; ++k) sums[k] += raw.evidence[c->second][k];
    }
    const double count = double(end - begin);
    const size_t o = first_out[r];
    out->positions[o] = octomap::point3d(float(x / count), float(y / count), float(z / count));
    float* mean = &out->own[o * num_classes];
    for (int k = 0; k < num_classes; ++k) mean[k] = float(sums[k] / count);
    applyFloor(mean);
    out->evidence[o] = mean;
  }
}

}  // namespace evidential_octomap
