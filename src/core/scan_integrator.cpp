#include "evidential_octomap/scan_integrator.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "evidential_octomap/kernel.h"
#include "evidential_octomap/safe_key.h"
#include "evidential_octomap/subjective_logic.h"
#include "morton.h"
#include "ray_casting.h"

namespace evidential_octomap {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Points that may give semantic evidence: inside the map and within max_range.
struct RawPoints {
  std::vector<octomap::point3d> positions;
  std::vector<const float*> evidence;  // C values each, into the caller's array
};

// Points and evidence that take part in the kernel pass.
struct SemanticPoints {
  std::vector<octomap::point3d> positions;
  std::vector<float> evidence;  // M x C
};

double uncertaintyOf(const float* evidence, int num_classes) {
  double strength = num_classes;
  for (int c = 0; c < num_classes; ++c) strength += evidence[c];
  return num_classes / strength;
}

// Cell index of a point on a grid of size `cell`, packed into 63 bits (21 per axis).
int64_t cellKey(const octomap::point3d& p, double cell) {
  const int64_t ix = static_cast<int64_t>(std::floor(p.x() / cell)) & 0x1FFFFF;
  const int64_t iy = static_cast<int64_t>(std::floor(p.y() / cell)) & 0x1FFFFF;
  const int64_t iz = static_cast<int64_t>(std::floor(p.z() / cell)) & 0x1FFFFF;
  return (ix << 42) | (iy << 21) | iz;
}

// Drops the points above the per-scan percentile U_thr of their uncertainty (the paper's
// indicator 1[u_i <= U_thr], over the scan's points before any down-sampling, as the authors do).
RawPoints applyThreshold(RawPoints points, int num_classes, bool enabled, double drop_percent,
                         InsertStats* stats) {
  stats->uncertainty_threshold = std::numeric_limits<double>::infinity();
  if (!enabled) return points;
  std::vector<float> u(points.positions.size());
  for (size_t i = 0; i < u.size(); ++i) {
    u[i] = static_cast<float>(uncertaintyOf(points.evidence[i], num_classes));
  }
  const double threshold = uncertaintyThreshold(u, drop_percent);
  stats->uncertainty_threshold = threshold;
  RawPoints kept;
  for (size_t i = 0; i < u.size(); ++i) {
    if (u[i] > threshold) {  // the same float values the threshold came from
      ++stats->points_dropped_uncertain;
      continue;
    }
    kept.positions.push_back(points.positions[i]);
    kept.evidence.push_back(points.evidence[i]);
  }
  return kept;
}

SemanticPoints copyAll(const RawPoints& points, int num_classes) {
  SemanticPoints out;
  out.positions = points.positions;
  out.evidence.reserve(points.positions.size() * num_classes);
  for (const float* e : points.evidence)
    out.evidence.insert(out.evidence.end(), e, e + num_classes);
  return out;
}

// Averages positions and evidence per cell of size `cell`. Sums are kept in double, so the
// mean of finite float evidence is finite and representable (two values near FLT_MAX would
// overflow a float sum and poison the voxel with NaN).
SemanticPoints averagePerCell(const RawPoints& points, int num_classes, double cell) {
  std::unordered_map<int64_t, uint32_t> cell_index;
  cell_index.reserve(points.positions.size());
  std::vector<double> sums;  // per cell: x, y, z, count, then C evidence sums
  const size_t stride = 4 + size_t(num_classes);
  for (size_t i = 0; i < points.positions.size(); ++i) {
    const octomap::point3d& p = points.positions[i];
    const auto [it, inserted] =
        cell_index.emplace(cellKey(p, cell), static_cast<uint32_t>(sums.size() / stride));
    if (inserted) sums.resize(sums.size() + stride, 0.0);
    double* s = &sums[size_t(it->second) * stride];
    s[0] += p.x();
    s[1] += p.y();
    s[2] += p.z();
    s[3] += 1.0;
    for (int c = 0; c < num_classes; ++c) s[4 + c] += points.evidence[i][c];
  }
  const size_t cells = sums.size() / stride;
  SemanticPoints out;
  out.positions.resize(cells);
  out.evidence.resize(cells * num_classes);
  for (size_t j = 0; j < cells; ++j) {
    const double* s = &sums[j * stride];
    out.positions[j] = octomap::point3d(float(s[0] / s[3]), float(s[1] / s[3]), float(s[2] / s[3]));
    for (int c = 0; c < num_classes; ++c)
      out.evidence[j * num_classes + c] = float(s[4 + c] / s[3]);
  }
  return out;
}

// The authors' count cap: keeps the first `cap` points of every cell of size `cell`.
SemanticPoints capPerCell(const RawPoints& points, int num_classes, double cell, int cap) {
  std::unordered_map<int64_t, int> counts;
  counts.reserve(points.positions.size() / 2 + 1);
  RawPoints kept;
  for (size_t i = 0; i < points.positions.size(); ++i) {
    int& count = counts[cellKey(points.positions[i], cell)];
    if (count >= cap) continue;
    ++count;
    kept.positions.push_back(points.positions[i]);
    kept.evidence.push_back(points.evidence[i]);
  }
  return copyAll(kept, num_classes);
}

SemanticPoints downsample(const RawPoints& points, int num_classes, const SemanticConfig& config,
                          double resolution) {
  if (!(config.ds_multiplier > 0.0)) return copyAll(points, num_classes);
  if (config.effectiveDownsampling() == "count_cap") {
    const int cap = static_cast<int>(std::floor(config.ds_multiplier)) + 1;
    return capPerCell(points, num_classes, 2.0 * resolution, cap);
  }
  return averagePerCell(points, num_classes, resolution / config.ds_multiplier);
}

// Key offsets of every voxel that can lie within `radius_cells` of a point in the centre voxel:
// measured to voxel centres, |offset| <= radius + sqrt(3)/2; to voxel cubes, radius + sqrt(3).
std::vector<octomap::OcTreeKey> sphereOffsets(double radius_cells, bool to_cube) {
  const double reach = radius_cells + (to_cube ? 2.0 : 1.0) * std::sqrt(3.0) / 2.0;
  const int n = static_cast<int>(std::ceil(reach));
  std::vector<octomap::OcTreeKey> offsets;
  for (int dx = -n; dx <= n; ++dx)
    for (int dy = -n; dy <= n; ++dy)
      for (int dz = -n; dz <= n; ++dz)
        if (dx * dx + dy * dy + dz * dz <= reach * reach)
          offsets.emplace_back(static_cast<octomap::key_type>(dx),
                               static_cast<octomap::key_type>(dy),
                               static_cast<octomap::key_type>(dz));
  return offsets;
}

// Opinions, support lengths and key-offset spheres of the semantic points.
struct KernelInputs {
  std::vector<PointOpinion> opinions;
  std::vector<float> lengths;
  std::vector<int> radius_ids;  // quantised support radius, key of `offsets`
  std::unordered_map<int, std::vector<octomap::OcTreeKey>> offsets;
};

KernelInputs prepareKernel(const SemanticPoints& points, int num_classes,
                           const SemanticConfig& config, bool uncertainty_kernel,
                           double resolution) {
  constexpr double kRadiusSteps = 4.0;  // radii quantised to quarter cells
  const size_t m = points.positions.size();
  KernelInputs in;
  in.opinions.resize(m);
  in.lengths.resize(m);
  in.radius_ids.resize(m);
  for (size_t j = 0; j < m; ++j) {
    PointOpinion& o = in.opinions[j];
    o.evidence = &points.evidence[j * num_classes];
    o.strength = num_classes;
    float best = 0.0f;
    for (int c = 0; c < num_classes; ++c) {
      o.strength += o.evidence[c];
      if (o.evidence[c] > best) {
        best = o.evidence[c];
        o.argmax = c;
      }
    }
    o.uncertainty = num_classes / o.strength;
    // S-BKI uses the plain length l; the uncertainty kernels l beta e^{1 - gamma u}.
    const double length = uncertainty_kernel
                              ? adaptiveLength(config.length_scale, config.beta,
                                               config.effectiveGamma(), o.uncertainty)
                              : config.length_scale;
    in.lengths[j] = static_cast<float>(length);
    in.radius_ids[j] = static_cast<int>(std::ceil(length / resolution * kRadiusSteps));
    if (!in.offsets.count(in.radius_ids[j])) {
      in.offsets.emplace(in.radius_ids[j], sphereOffsets(in.radius_ids[j] / kRadiusSteps,
                                                         config.kernel_distance == "voxel"));
    }
  }
  return in;
}

// Per-thread aggregation: voxel key -> row of C summed increments.
struct Aggregate {
  std::unordered_map<octomap::OcTreeKey, uint32_t, octomap::OcTreeKey::KeyHash> rows;
  std::vector<double> increments;

  double* row(const octomap::OcTreeKey& key, int num_classes) {
    const auto [it, inserted] = rows.emplace(key, static_cast<uint32_t>(rows.size()));
    if (inserted) increments.insert(increments.end(), num_classes, 0.0);
    return &increments[size_t(it->second) * num_classes];
  }
};

// One kernel loop: every point adds k-weighted increments to each voxel within its support;
// per-thread maps, merged into the first.
Aggregate kernelPass(const SemanticPoints& points, const KernelInputs& in,
                     const SemanticConfig& config, const EvidentialOcTree& tree, int threads) {
  const int num_classes = tree.numClasses();
  const FusionRule& rule = tree.rule();
  const double half_voxel = tree.getResolution() / 2.0;
  const bool to_cube = config.kernel_distance == "voxel";
  const size_t m = points.positions.size();
  std::vector<Aggregate> aggregates(threads);
#pragma omp parallel num_threads(threads)
  {
    Aggregate& local = aggregates[omp_get_thread_num()];
    local.rows.reserve(4 * m / threads + 16);
#pragma omp for schedule(dynamic, 256)
    for (size_t j = 0; j < m; ++j) {
      const octomap::point3d& p = points.positions[j];
      const octomap::OcTreeKey centre = tree.coordToKey(p);
      for (const octomap::OcTreeKey& offset : in.offsets.at(in.radius_ids[j])) {
        const octomap::OcTreeKey voxel(static_cast<octomap::key_type>(centre[0] + offset[0]),
                                       static_cast<octomap::key_type>(centre[1] + offset[1]),
                                       static_cast<octomap::key_type>(centre[2] + offset[2]));
        const octomap::point3d d = p - tree.keyToCoord(voxel);
        const double distance =
            to_cube ? distanceToCube(d.x(), d.y(), d.z(), half_voxel) : d.norm();
        const double k = sparseKernel(distance, in.lengths[j], config.sigma0);
        if (k <= 0.0) continue;
        rule.contribute(in.opinions[j], k, num_classes, local.row(voxel, num_classes));
      }
    }
  }
  Aggregate& total = aggregates[0];
  for (int t = 1; t < threads; ++t) {
    for (const auto& [voxel, index] : aggregates[t].rows) {
      double* into = total.row(voxel, num_classes);
      const double* from = &aggregates[t].increments[size_t(index) * num_classes];
      for (int c = 0; c < num_classes; ++c) into[c] += from[c];
    }
  }
  return std::move(total);
}

// Validates everything before the map is touched: a bad message changes nothing.
void validateInput(const octomap::Pointcloud& points_W, const std::vector<float>& evidence,
                   int num_classes) {
  const size_t n = points_W.size();
  if (evidence.size() != n * size_t(num_classes)) {
    throw std::invalid_argument("evidence has " + std::to_string(evidence.size()) +
                                " values, expected points x classes = " + std::to_string(n) +
                                " x " + std::to_string(num_classes));
  }
  for (size_t i = 0; i < n; ++i) {
    const std::string problem = checkEvidence(&evidence[i * num_classes], num_classes);
    if (!problem.empty())
      throw std::invalid_argument("point " + std::to_string(i) + ": " + problem);
  }
}

// The scan's updates in Morton order: ray voxels (occupied wins over free) merged with the
// kernel rows (sorted by Morton code), one update per key.
void mergeUpdates(const VoxelBricks& rays, const std::vector<std::pair<uint64_t, uint32_t>>& rows,
                  std::vector<VoxelUpdate>* updates) {
  updates->clear();
  auto row = rows.cbegin();
  rays.forEachSorted([&](const octomap::OcTreeKey& voxel, uint64_t code, unsigned flags) {
    for (; row != rows.cend() && row->first < code; ++row) {
      updates->push_back({keyFromMorton(row->first), 0, row->second});
    }
    VoxelUpdate u{voxel, 0};
    if (flags & (1u << kRayOccupied)) {
      u.occupancy = +1;
    } else if (flags & (1u << kRayFree)) {
      u.occupancy = -1;
    }
    if (row != rows.cend() && row->first == code) u.increments = (row++)->second;
    if (u.occupancy != 0 || u.increments != VoxelUpdate::kNoIncrements) updates->push_back(u);
  });
  for (; row != rows.cend(); ++row) updates->push_back({keyFromMorton(row->first), 0, row->second});
}

}  // namespace

// Buffers of one scan, kept for the next: clearing them costs nothing, allocating and
// page-faulting them every scan cost ~5 % of the CPU and 100 MB of peak RSS.
struct ScanIntegrator::Scratch {
  std::vector<octomap::point3d> ray_points;         // every point inside the key range
  std::vector<VoxelBricks> bricks;                  // ray casting, one per thread
  std::vector<std::pair<uint64_t, uint32_t>> rows;  // kernel rows by Morton code
  std::vector<VoxelUpdate> updates;
};

ScanIntegrator::ScanIntegrator(const SemanticConfig& config)
    : config_(config), scratch_(std::make_unique<Scratch>()) {}
ScanIntegrator::~ScanIntegrator() = default;

InsertStats ScanIntegrator::integrate(const octomap::Pointcloud& points_W,
                                      const std::vector<float>& evidence,
                                      const octomap::point3d& origin_W, EvidentialOcTree* tree,
                                      EvidentialOcTree* unobserved) {
  const int num_classes = tree->numClasses();
  const size_t n = points_W.size();
  InsertStats stats;
  stats.points_in = n;
  validateInput(points_W, evidence, num_classes);
  // A kernel the machine cannot afford is refused rather than left to run for hours or to
  // exhaust memory (SemanticConfig::kMaxSupportLeaves).
  const std::string support_problem = config_.supportProblem(tree->getResolution());
  if (!support_problem.empty()) throw std::invalid_argument(support_problem);
  octomap::OcTreeKey origin_key;
  if (!safeCoordToKey(*tree, origin_W, &origin_key)) {
    throw std::invalid_argument("sensor origin is not finite or outside the map's range");
  }

  // 1. Occupancy keys: ray casting with OctoMap's semantics (ray_casting.h).
  auto start = Clock::now();
  Scratch& scratch = *scratch_;
  std::vector<octomap::point3d>& cloud = scratch.ray_points;
  cloud.clear();
  cloud.reserve(n);
  RawPoints raw;
  raw.positions.reserve(n);
  raw.evidence.reserve(n);
  octomap::OcTreeKey key;
  for (size_t i = 0; i < n; ++i) {
    const octomap::point3d& p = points_W.getPoint(i);
    if (!safeCoordToKey(*tree, p, &key)) {  // NaN, inf or beyond the map
      ++stats.points_skipped;
      continue;
    }
    cloud.push_back(p);
    if (config_.max_range > 0.0 && (p - origin_W).norm() > config_.max_range) {
      ++stats.points_beyond_range;
      continue;
    }
    raw.positions.push_back(p);
    raw.evidence.push_back(&evidence[i * num_classes]);
  }
  if (cloud.empty()) return stats;
  const int threads = config_.threads > 0 ? config_.threads : omp_get_max_threads();
  scratch.bricks.resize(threads);
  castRays(*tree, cloud, origin_W, config_.max_range, config_.discretize, &scratch.bricks);
  stats.ms_occupancy = msSince(start);

  // 2. Percentile threshold, down-sampling, opinions and support lengths.
  start = Clock::now();
  const double resolution = tree->getResolution();
  const bool uncertainty_kernel = tree->rule().usesUncertaintyKernel();
  raw = applyThreshold(std::move(raw), num_classes,
                       uncertainty_kernel && config_.uncertainty_threshold, config_.drop_percent,
                       &stats);
  const SemanticPoints points = downsample(raw, num_classes, config_, resolution);
  stats.semantic_points = points.positions.size();
  const KernelInputs kernel =
      prepareKernel(points, num_classes, config_, uncertainty_kernel, resolution);

  // 3. One kernel loop, aggregated per voxel key for the whole scan.
  Aggregate total = kernelPass(points, kernel, config_, *tree, threads);
  auto& rows = scratch.rows;
  rows.clear();
  for (const auto& [voxel, index] : total.rows) rows.emplace_back(mortonCode(voxel), index);
  std::sort(rows.begin(), rows.end());
  stats.ms_kernel = msSince(start);

  // 4. One pass over the tree: occupancy and semantic updates, each touched leaf once, then the
  //    inner nodes above them. Ray voxels and kernel rows merge in Morton order.
  start = Clock::now();
  mergeUpdates(scratch.bricks[0], rows, &scratch.updates);
  stats.voxels_updated =
      tree->applySortedUpdates(scratch.updates.data(), scratch.updates.size(), total.increments,
                               config_.kernel_creates_leaves);
  if (unobserved && !config_.kernel_creates_leaves) {
    // Leaves are never removed, so a voxel without one now had none before and got none from
    // this scan's rays: the map dropped its evidence, which `unobserved` keeps.
    std::vector<VoxelUpdate> dropped;
    for (const auto& [code, index] : rows) {
      const octomap::OcTreeKey voxel = keyFromMorton(code);
      if (!tree->search(voxel)) dropped.push_back({voxel, 0, index});
    }
    unobserved->applySortedUpdates(dropped.data(), dropped.size(), total.increments, true);
  }
  stats.ms_update = msSince(start);
  return stats;
}

}  // namespace evidential_octomap
