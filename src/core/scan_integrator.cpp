#include "scan_integrator.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "evidential_octomap/safe_key.h"
#include "evidential_octomap/subjective_logic.h"
#include "kept_buffers.h"
#include "kernel_pass.h"
#include "morton.h"
#include "phase_timer.h"
#include "radix_sort.h"
#include "ray_casting.h"
#include "scan_subtrees.h"
#include "semantic_points.h"

namespace evidential_octomap {
namespace {

// Validates everything before the map is touched: a bad message changes nothing.
void validateInput(const octomap::Pointcloud& points_W, const std::vector<float>& evidence,
                   int num_classes, int threads) {
  const size_t n = points_W.size();
  if (evidence.size() != n * size_t(num_classes)) {
    throw std::invalid_argument("evidence has " + std::to_string(evidence.size()) +
                                " values, expected points x classes = " + std::to_string(n) +
                                " x " + std::to_string(num_classes));
  }
  // One pass without a branch per value; which point and why only when one is not valid.
  int valid = 1;
  const size_t values = evidence.size();
#pragma omp parallel for num_threads(threads) schedule(static) reduction(& : valid)
  for (size_t i = 0; i < values; ++i) valid &= int(validEvidence(evidence[i]));
  if (valid) return;
  for (size_t i = 0; i < n; ++i) {
    const std::string problem = checkEvidence(&evidence[i * num_classes], num_classes);
    if (!problem.empty()) {
      throw std::invalid_argument("point " + std::to_string(i) + ": " + problem);
    }
  }
}

}  // namespace

// Buffers of one scan, kept for the next: clearing them costs nothing, allocating and
// page-faulting them every scan cost ~5 % of the CPU and 100 MB of peak RSS. What a scan did not
// need is released after it (kept_buffers.h): 53.5 MB stay for the bundled 123k-point scans
// at C = 20 and 2 threads, 20 MB of it the threads' kernel rows of their largest subtree.
struct ScanIntegrator::Scratch {
  std::vector<uint8_t> fate;                 // per input point: skipped, beyond range, kept
  std::vector<octomap::point3d> ray_points;  // every point inside the key range
  std::vector<VoxelBricks> bricks;           // ray casting, one per thread
  RawPoints raw;                             // points that may give semantic evidence
  SemanticScratch semantic;
  SemanticPoints points;  // after threshold and down-sampling
  std::vector<KernelPoint> kernel_points;
  std::optional<KernelPass> kernel;  // of the scan being inserted
  ScanSubtrees subtrees;

  size_t bytes() const;
  void releaseExcess();
};

size_t ScanIntegrator::Scratch::bytes() const {
  size_t total = vectorBytes(fate) + vectorBytes(ray_points) + vectorBytes(bricks) +
                 vectorBytes(raw.positions) + vectorBytes(raw.evidence) +
                 vectorBytes(semantic.uncertainty) +
                 vectorBytes(semantic.cells) + vectorBytes(semantic.buffer) +
                 vectorBytes(semantic.runs) + vectorBytes(points.positions) +
                 vectorBytes(points.evidence) + vectorBytes(points.own) +
                 vectorBytes(kernel_points) + subtrees.capacityBytes();
  for (const VoxelBricks& b : bricks) total += b.capacityBytes();
  return total;
}

void ScanIntegrator::Scratch::releaseExcess() {
  releaseOversized(&fate, fate.size());
  releaseOversized(&ray_points, ray_points.size());
  for (VoxelBricks& b : bricks) b.releaseExcess();
  releaseOversized(&raw.positions, raw.positions.size());
  releaseOversized(&raw.evidence, raw.evidence.size());
  const size_t cells = semantic.cells.size();
  releaseOversized(&semantic.uncertainty, semantic.uncertainty.size());
  releaseOversized(&semantic.cells, cells);
  releaseOversized(&semantic.buffer, cells);
  releaseOversized(&semantic.runs, semantic.runs.size());
  releaseOversized(&points.positions, points.positions.size());
  releaseOversized(&points.evidence, points.evidence.size());
  releaseOversized(&points.own, points.own.size());
  releaseOversized(&kernel_points, kernel_points.size());
  subtrees.releaseExcess();
}

ScanIntegrator::ScanIntegrator(const SemanticConfig& config)
    : config_(config), scratch_(std::make_unique<Scratch>()) {}
ScanIntegrator::~ScanIntegrator() = default;

size_t ScanIntegrator::scratchBytes() const { return scratch_->bytes(); }

int ScanIntegrator::threads() const {
  return config_.threads > 0 ? config_.threads : omp_get_max_threads();
}

SubtreeSource* ScanIntegrator::prepare(const octomap::Pointcloud& points_W,
                                       const std::vector<float>& evidence,
                                       const octomap::point3d& origin_W,
                                       const EvidentialOcTree& tree, bool keep_unobserved,
                                       InsertStats* stats) {
  const int num_classes = tree.numClasses();
  const size_t n = points_W.size();
  stats->points_in = n;
  validateInput(points_W, evidence, num_classes, threads());
  // A kernel the machine cannot afford is refused rather than left to run for hours or to
  // exhaust memory (SemanticConfig::kMaxSupportLeaves).
  const std::string support_problem = config_.supportProblem(tree.getResolution());
  if (!support_problem.empty()) throw std::invalid_argument(support_problem);
  octomap::OcTreeKey origin_key;
  if (!safeCoordToKey(tree, origin_W, &origin_key)) {
    throw std::invalid_argument("sensor origin is not finite or outside the map's range");
  }
  Scratch& scratch = *scratch_;
  const int threads = this->threads();

  // 1. Occupancy: ray casting with OctoMap's semantics into voxel bricks (ray_casting.h).
  PhaseTimer timer;
  std::vector<octomap::point3d>& cloud = scratch.ray_points;
  RawPoints& raw = scratch.raw;
  cloud.clear();
  raw.clear();
  // Each point's fate in parallel, then the kept ones in input order.
  enum Fate : uint8_t { kSkipped, kBeyondRange, kSemantic };
  std::vector<uint8_t>& fate = scratch.fate;
  fate.resize(n);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t i = 0; i < n; ++i) {
    const octomap::point3d& p = points_W.getPoint(i);
    octomap::OcTreeKey key;
    fate[i] = !safeCoordToKey(tree, p, &key) ? kSkipped  // NaN, inf or beyond the map
              : config_.max_range > 0.0 && (p - origin_W).norm() > config_.max_range
                  ? kBeyondRange
                  : kSemantic;
  }
  for (size_t i = 0; i < n; ++i) {
    if (fate[i] == kSkipped) {
      ++stats->points_skipped;
      continue;
    }
    const octomap::point3d& p = points_W.getPoint(i);
    cloud.push_back(p);
    if (fate[i] == kBeyondRange) {
      ++stats->points_beyond_range;
      continue;
    }
    raw.positions.push_back(p);
    raw.evidence.push_back(&evidence[i * num_classes]);
  }
  if (cloud.empty()) return nullptr;
  scratch.bricks.resize(threads);
  castRays(tree, cloud, origin_W, config_.max_range, config_.discretize, config_.fast_free_space,
           &scratch.bricks);
  timer.stop(&stats->ms_occupancy, &stats->cpu_ms_occupancy);

  // 2. Semantic points: percentile threshold, down-sampling, opinions and supports.
  timer = PhaseTimer();
  const bool uncertainty_kernel = tree.rule().usesUncertaintyKernel();
  const PointSelection selection = PointSelection::of(
      config_, num_classes, uncertainty_kernel && config_.effectiveThreshold(), tree.getResolution());
  selectSemanticPoints(raw, selection, threads, &scratch.semantic, &scratch.points, stats);
  stats->semantic_points = scratch.points.positions.size();
  // The subtrees run the kernel loop later, inside the tree's update pass: the kernel outlives
  // this call, in the scratch.
  KernelPass& kernel = scratch.kernel.emplace(config_, tree);
  kernel.preparePoints(scratch.points, threads, &scratch.kernel_points);
  using Targets = ScanSubtrees::Targets;
  const Targets targets = config_.semantic_occupied_only                     ? Targets::kOccupied
                          : config_.kernel_creates_leaves || keep_unobserved ? Targets::kEverywhere
                                                                             : Targets::kKept;
  scratch.subtrees.build(tree, scratch.bricks[0], scratch.points, scratch.kernel_points, kernel,
                         threads, targets);
  timer.stop(&stats->ms_kernel, &stats->cpu_ms_kernel);
  return &scratch.subtrees;
}

void ScanIntegrator::finish(InsertStats* stats) {
  const double kernel_loop = scratch_->subtrees.kernelCpuMs();
  stats->cpu_ms_kernel += kernel_loop;
  stats->cpu_ms_update = std::max(0.0, stats->cpu_ms_update - kernel_loop);
  scratch_->releaseExcess();
}

}  // namespace evidential_octomap
