#include "evidential_octomap/scan_integrator.h"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "evidential_octomap/kernel.h"
#include "evidential_octomap/subjective_logic.h"
#include "ray_casting.h"

namespace evidential_octomap {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Points and evidence that take part in the semantic pass.
struct SemanticPoints {
  std::vector<octomap::point3d> positions;
  std::vector<float> evidence;  // M x C
};

// Averages positions and evidence per cell of a grid of size `cell` (<= 0: no down-sampling).
SemanticPoints downsample(const std::vector<octomap::point3d>& points,
                          const std::vector<const float*>& evidence, int num_classes,
                          double cell) {
  SemanticPoints out;
  if (!(cell > 0.0)) {
    out.positions = points;
    out.evidence.reserve(points.size() * num_classes);
    for (const float* e : evidence) out.evidence.insert(out.evidence.end(), e, e + num_classes);
    return out;
  }
  std::unordered_map<int64_t, uint32_t> cell_index;
  cell_index.reserve(points.size());
  std::vector<double> sums;  // x, y, z, count per cell
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    const int64_t ix = static_cast<int64_t>(std::floor(p.x() / cell)) & 0x1FFFFF;
    const int64_t iy = static_cast<int64_t>(std::floor(p.y() / cell)) & 0x1FFFFF;
    const int64_t iz = static_cast<int64_t>(std::floor(p.z() / cell)) & 0x1FFFFF;
    const auto [it, inserted] =
        cell_index.emplace((ix << 42) | (iy << 21) | iz, static_cast<uint32_t>(sums.size() / 4));
    if (inserted) {
      sums.insert(sums.end(), {0.0, 0.0, 0.0, 0.0});
      out.evidence.insert(out.evidence.end(), num_classes, 0.0f);
    }
    double* s = &sums[size_t(it->second) * 4];
    s[0] += p.x();
    s[1] += p.y();
    s[2] += p.z();
    s[3] += 1.0;
    float* e = &out.evidence[size_t(it->second) * num_classes];
    for (int c = 0; c < num_classes; ++c) e[c] += evidence[i][c];
  }
  const size_t cells = sums.size() / 4;
  out.positions.resize(cells);
  for (size_t j = 0; j < cells; ++j) {
    const double* s = &sums[j * 4];
    out.positions[j] = octomap::point3d(float(s[0] / s[3]), float(s[1] / s[3]), float(s[2] / s[3]));
    float* e = &out.evidence[j * num_classes];
    for (int c = 0; c < num_classes; ++c) e[c] = static_cast<float>(e[c] / s[3]);
  }
  return out;
}

// Key offsets of every voxel whose centre can lie within `radius_cells` of a point in the
// centre voxel, i.e. |offset| <= radius_cells + sqrt(3)/2.
std::vector<octomap::OcTreeKey> sphereOffsets(double radius_cells) {
  const double reach = radius_cells + std::sqrt(3.0) / 2.0;
  const int n = static_cast<int>(std::ceil(reach));
  std::vector<octomap::OcTreeKey> offsets;
  for (int dx = -n; dx <= n; ++dx)
    for (int dy = -n; dy <= n; ++dy)
      for (int dz = -n; dz <= n; ++dz)
        if (dx * dx + dy * dy + dz * dz <= reach * reach)
          offsets.emplace_back(static_cast<octomap::key_type>(dx), static_cast<octomap::key_type>(dy),
                               static_cast<octomap::key_type>(dz));
  return offsets;
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

}  // namespace

InsertStats ScanIntegrator::integrate(const octomap::Pointcloud& points_W,
                                      const std::vector<float>& evidence,
                                      const octomap::point3d& origin_W,
                                      EvidentialOcTree* tree) const {
  const int num_classes = tree->numClasses();
  const size_t n = points_W.size();
  InsertStats stats;
  stats.points_in = n;

  // Validate everything before the map is touched: a bad message changes nothing.
  if (evidence.size() != n * size_t(num_classes)) {
    throw std::invalid_argument("evidence has " + std::to_string(evidence.size()) +
                                " values, expected points x classes = " + std::to_string(n) +
                                " x " + std::to_string(num_classes));
  }
  for (size_t i = 0; i < n; ++i) {
    const std::string problem = checkEvidence(&evidence[i * num_classes], num_classes);
    if (!problem.empty()) throw std::invalid_argument("point " + std::to_string(i) + ": " + problem);
  }
  // OctoMap's coordToKeyChecked casts coordinate / resolution to int, which is undefined for
  // NaN, inf and anything beyond the map (points at 1e30): test the extent first.
  const double extent = tree->getResolution() * 32768.0;  // 16-bit keys, tree_max_val
  const auto inside = [extent](const octomap::point3d& p) {
    return std::fabs(p.x()) < extent && std::fabs(p.y()) < extent && std::fabs(p.z()) < extent;
  };
  octomap::OcTreeKey origin_key;
  if (!inside(origin_W) || !tree->coordToKeyChecked(origin_W, origin_key)) {
    throw std::invalid_argument("sensor origin is not finite or outside the map's range");
  }

  // 1. Occupancy keys: ray casting with OctoMap's semantics (ray_casting.h).
  auto start = Clock::now();
  octomap::Pointcloud cloud;
  cloud.reserve(n);
  std::vector<octomap::point3d> semantic_positions;
  std::vector<const float*> semantic_evidence;
  semantic_positions.reserve(n);
  semantic_evidence.reserve(n);
  octomap::OcTreeKey key;
  for (size_t i = 0; i < n; ++i) {
    const octomap::point3d& p = points_W.getPoint(i);
    if (!inside(p) || !tree->coordToKeyChecked(p, key)) {
      ++stats.points_skipped;
      continue;
    }
    cloud.push_back(p);
    if (config_.max_range > 0.0 && (p - origin_W).norm() > config_.max_range) {
      ++stats.points_beyond_range;
      continue;
    }
    semantic_positions.push_back(p);
    semantic_evidence.push_back(&evidence[i * num_classes]);
  }
  if (cloud.size() == 0) return stats;
  const int threads = config_.threads > 0 ? config_.threads : omp_get_max_threads();
  const ScanKeys keys =
      castRays(*tree, cloud, origin_W, config_.max_range, config_.discretize, threads);
  stats.ms_occupancy = msSince(start);

  // 2. Opinions of the (down-sampled) points, percentile threshold and support lengths.
  start = Clock::now();
  const double resolution = tree->getResolution();
  const SemanticPoints points = downsample(
      semantic_positions, semantic_evidence, num_classes,
      config_.ds_multiplier > 0.0 ? resolution / config_.ds_multiplier : 0.0);
  const size_t m = points.positions.size();
  stats.semantic_points = m;

  const FusionRule& rule = tree->rule();
  const bool uncertainty_kernel = rule.usesUncertaintyKernel();
  std::vector<PointOpinion> opinions(m);
  std::vector<float> uncertainties(m);
  for (size_t j = 0; j < m; ++j) {
    PointOpinion& o = opinions[j];
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
    uncertainties[j] = static_cast<float>(o.uncertainty);
  }
  const bool use_threshold = uncertainty_kernel && config_.uncertainty_threshold;
  const double threshold = use_threshold
                               ? uncertaintyThreshold(uncertainties, config_.drop_percent)
                               : std::numeric_limits<double>::infinity();
  stats.uncertainty_threshold = threshold;

  // Support length per point, and the key-offset sphere for its quantised radius.
  constexpr double kRadiusSteps = 4.0;  // radii quantised to quarter cells
  const bool adaptive = uncertainty_kernel && config_.adaptive_length;
  std::vector<float> lengths(m, 0.0f);
  std::vector<int> radius_ids(m, -1);
  std::unordered_map<int, std::vector<octomap::OcTreeKey>> offsets_by_radius;
  for (size_t j = 0; j < m; ++j) {
    if (uncertainties[j] > threshold) {  // the same float values the threshold came from
      ++stats.points_dropped_uncertain;
      continue;
    }
    const double length = adaptive ? adaptiveLength(config_.length_scale, config_.beta,
                                                    config_.effectiveGamma(), opinions[j].uncertainty)
                                   : config_.length_scale;
    lengths[j] = static_cast<float>(length);
    radius_ids[j] = static_cast<int>(std::ceil(length / resolution * kRadiusSteps));
    if (!offsets_by_radius.count(radius_ids[j])) {
      offsets_by_radius.emplace(radius_ids[j], sphereOffsets(radius_ids[j] / kRadiusSteps));
    }
  }

  // 3. One kernel loop: every kept point adds k-weighted increments to each voxel whose centre
  //    lies within its support; per-thread maps, merged afterwards.
  std::vector<Aggregate> aggregates(threads);
#pragma omp parallel num_threads(threads)
  {
    Aggregate& local = aggregates[omp_get_thread_num()];
    local.rows.reserve(4 * m / threads + 16);
#pragma omp for schedule(dynamic, 256)
    for (size_t j = 0; j < m; ++j) {
      if (radius_ids[j] < 0) continue;
      const octomap::point3d& p = points.positions[j];
      const octomap::OcTreeKey centre = tree->coordToKey(p);
      const double length = lengths[j];
      for (const octomap::OcTreeKey& offset : offsets_by_radius.at(radius_ids[j])) {
        const octomap::OcTreeKey voxel(static_cast<octomap::key_type>(centre[0] + offset[0]),
                                       static_cast<octomap::key_type>(centre[1] + offset[1]),
                                       static_cast<octomap::key_type>(centre[2] + offset[2]));
        const double distance = (tree->keyToCoord(voxel) - p).norm();
        const double k = sparseKernel(distance, length, config_.sigma0);
        if (k <= 0.0) continue;
        rule.contribute(opinions[j], k, num_classes, local.row(voxel, num_classes));
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
  stats.ms_kernel = msSince(start);

  // 4. One pass over the tree: occupancy and semantic updates, each touched leaf once, then the
  //    inner nodes above them.
  start = Clock::now();
  std::vector<VoxelUpdate> updates;
  updates.reserve(keys.free.size() + keys.occupied.size() + total.rows.size());
  for (const octomap::OcTreeKey& voxel : keys.free) updates.push_back({voxel, -1});
  for (const octomap::OcTreeKey& voxel : keys.occupied) updates.push_back({voxel, +1});
  for (const auto& [voxel, index] : total.rows) updates.push_back({voxel, 0, index});
  stats.voxels_updated =
      tree->applyUpdates(std::move(updates), total.increments, config_.kernel_creates_leaves);
  stats.ms_update = msSince(start);
  return stats;
}

}  // namespace evidential_octomap
