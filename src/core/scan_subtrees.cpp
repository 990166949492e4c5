#include "scan_subtrees.h"

#include <time.h>

#include <algorithm>
#include <limits>

#include "evidential_octomap/detail/leaf_walk.h"
#include "kept_buffers.h"
#include "morton.h"
#include "radix_sort.h"
#include "ray_casting.h"

namespace evidential_octomap {
namespace {

constexpr unsigned kBrickLevels = 3;  // VoxelBricks: 8^3 voxels
constexpr int kSubtreeSize = 1 << kSubtreeLevels;

uint64_t subtreeOfBrick(uint64_t brick_code) {
  return brick_code >> (3 * (kSubtreeLevels - kBrickLevels));
}

// The first voxel of the subtree with Morton code `code` (of its key >> kSubtreeLevels).
octomap::OcTreeKey subtreeBase(uint64_t code) {
  const octomap::OcTreeKey coarse = keyFromMorton(code);
  return octomap::OcTreeKey(static_cast<octomap::key_type>(coarse[0] << kSubtreeLevels),
                            static_cast<octomap::key_type>(coarse[1] << kSubtreeLevels),
                            static_cast<octomap::key_type>(coarse[2] << kSubtreeLevels));
}

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

}  // namespace

void ScanSubtrees::build(const EvidentialOcTree& tree, const VoxelBricks& rays,
                         const SemanticPoints& points,
                         const std::vector<KernelPoint>& kernel_points, const KernelPass& kernel,
                         int threads, Targets targets) {
  tree_ = &tree;
  targets_ = targets;
  rays_ = &rays;
  points_ = &points;
  kernel_points_ = &kernel_points;
  kernel_ = &kernel;
  threads_.resize(threads);
  for (PerThread& t : threads_) {
    t.kernel.index.resize(size_t(1) << (3 * kSubtreeLevels), KernelRows::kNone);
    t.kernel.mask.resize(size_t(1) << (2 * kSubtreeLevels));
    t.kernel_cpu_ms = 0.0;
    t.most_row_values = t.most_rows = t.most_updates = 0;
  }
  collectPointSubtrees();
  mergeSeeds();
}

// Every (subtree, point) pair where the point's support may reach the subtree: mostly its own
// subtree, two to eight for points near a subtree's faces.
void ScanSubtrees::collectPointSubtrees() {
  point_subtrees_.clear();
  const std::vector<KernelPoint>& points = *kernel_points_;
  for (size_t j = 0; j < points.size(); ++j) {
    const KernelPoint& p = points[j];
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, int(p.key[a]) - p.reach[a]) >> kSubtreeLevels;
      hi[a] = std::min(0xFFFF, int(p.key[a]) + p.reach[a]) >> kSubtreeLevels;
    }
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          const octomap::OcTreeKey coarse(static_cast<octomap::key_type>(x),
                                          static_cast<octomap::key_type>(y),
                                          static_cast<octomap::key_type>(z));
          point_subtrees_.emplace_back(mortonCode(coarse), static_cast<uint32_t>(j));
        }
  }
  std::vector<std::pair<uint64_t, uint32_t>> buffer;
  radixSort(&point_subtrees_, 3 * (16 - kSubtreeLevels), &buffer);  // stable: points in order
}

// The subtrees with ray voxels or points in reach, in Morton order.
void ScanSubtrees::mergeSeeds() {
  seeds_.clear();
  ranges_.clear();
  constexpr uint64_t kEnd = std::numeric_limits<uint64_t>::max();
  const size_t bricks = rays_->numBricks();
  size_t b = 0, p = 0;
  while (b < bricks || p < point_subtrees_.size()) {
    const uint64_t from_rays = b < bricks ? subtreeOfBrick(rays_->sortedCode(b)) : kEnd;
    const uint64_t from_points = p < point_subtrees_.size() ? point_subtrees_[p].first : kEnd;
    const uint64_t code = std::min(from_rays, from_points);
    Range range{b, b, p, p};
    uint8_t flags = 0;
    for (; b < bricks && subtreeOfBrick(rays_->sortedCode(b)) == code; ++b) {
      if (rays_->sortedAnyWithout(b, kRayFree, kRayOccupied)) flags |= SubtreeSeed::kHasMiss;
      if (rays_->sortedFlags(b) & (1u << kRayOccupied)) flags |= SubtreeSeed::kHasHit;
    }
    range.last_brick = b;
    for (; p < point_subtrees_.size() && point_subtrees_[p].first == code; ++p) {
      flags |= SubtreeSeed::kMayHaveRows;
    }
    range.last_point = p;
    if (flags == 0) continue;  // only rays clipped at max range ended here: no update
    seeds_.push_back({subtreeBase(code), flags});
    ranges_.push_back(range);
  }
}

constexpr int kBlockSize = 8;  // PerThread::reached: 8^3 blocks of 8^3 voxels
constexpr int kBlocks = kSubtreeSize / kBlockSize;
static_assert(kBlocks * kBlocks * kBlocks == 8 * 64, "PerThread::reached holds 8 words");

void ScanSubtrees::markReachedBlocks(size_t i, PerThread* t) const {
  t->reached.fill(0);
  const octomap::OcTreeKey& base = seeds_[i].key;
  for (size_t p = ranges_[i].first_point; p < ranges_[i].last_point; ++p) {
    const KernelPoint& point = (*kernel_points_)[point_subtrees_[p].second];
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const int at = int(point.key[a]) - int(base[a]);
      lo[a] = std::max(at - point.reach[a], 0) / kBlockSize;
      hi[a] = std::min(at + point.reach[a], kSubtreeSize - 1) / kBlockSize;
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const int block = (z * kBlocks + y) * kBlocks + x;
          t->reached[block / 64] |= uint64_t(1) << (block % 64);
        }
  }
}

// A leaf of the map covers a cube of voxels: one x-row of the subtree is one mask word. Nodes
// whose blocks no point reaches are not descended into, nor (kOccupied) nodes without an
// occupied leaf: an inner node's log-odds are its children's maximum.
void ScanSubtrees::markLeaves(const EvidentialOcTreeNode* node, int x, int y, int z, int size,
                              PerThread* t) const {
  if (targets_ == Targets::kOccupied && !tree_->isNodeOccupied(node)) return;
  if (size == kBlockSize) {
    const int block = ((z / kBlockSize) * kBlocks + y / kBlockSize) * kBlocks + x / kBlockSize;
    if (!(t->reached[block / 64] >> (block % 64) & 1)) return;
  }
  std::vector<uint64_t>& mask = t->kernel.mask;
  if (size == 2 && tree_->nodeHasChildren(node)) {  // its children are voxels: no recursion
    for (unsigned c = 0; c < 8; ++c) {
      if (!tree_->nodeChildExists(node, c)) continue;
      if (targets_ == Targets::kOccupied && !tree_->isNodeOccupied(tree_->getNodeChild(node, c)))
        continue;
      mask[size_t(z + (c >> 2 & 1)) << kSubtreeLevels | (y + (c >> 1 & 1))] |=
          uint64_t(1) << (x + (c & 1));
    }
    return;
  }
  if (tree_->nodeHasChildren(node)) {
    const int half = size / 2;
    detail::prefetchChildren(*tree_, node);
    for (unsigned c = 0; c < 8; ++c) {
      if (tree_->nodeChildExists(node, c)) {
        markLeaves(tree_->getNodeChild(node, c), x + (c & 1 ? half : 0), y + (c & 2 ? half : 0),
                   z + (c & 4 ? half : 0), half, t);
      }
    }
    return;
  }
  const uint64_t bits = size >= 64 ? ~uint64_t(0) : ((uint64_t(1) << size) - 1) << x;
  for (int zz = z; zz < z + size; ++zz)
    for (int yy = y; yy < y + size; ++yy) mask[size_t(zz) << kSubtreeLevels | yy] |= bits;
}

void ScanSubtrees::buildMask(size_t i, const EvidentialOcTreeNode* existing,
                             PerThread* t) const {
  KernelRows* rows = &t->kernel;
  rows->masked = targets_ == Targets::kOccupied ||
                 (targets_ == Targets::kKept && !(existing && !tree_->nodeHasChildren(existing)));
  if (!rows->masked) return;  // every voxel may get a row (or the subtree is one pruned leaf)
  std::fill(rows->mask.begin(), rows->mask.end(), 0);
  if (existing) {
    markReachedBlocks(i, t);
    markLeaves(existing, 0, 0, 0, kSubtreeSize, t);
  }
  const octomap::OcTreeKey& base = seeds_[i].key;
  const unsigned wanted =
      targets_ == Targets::kOccupied ? 1u << kRayOccupied : 1u << kRayFree | 1u << kRayOccupied;
  rays_->forEachSorted(ranges_[i].first_brick, ranges_[i].last_brick,
                       [&](const octomap::OcTreeKey& voxel, uint64_t, unsigned flags) {
                         if (!(flags & wanted)) return;
                         const int x = voxel[0] - base[0], y = voxel[1] - base[1],
                                   z = voxel[2] - base[2];
                         rows->mask[size_t(z) << kSubtreeLevels | y] |= uint64_t(1) << x;
                       });
}

SubtreeView ScanSubtrees::updates(size_t i, int thread, const EvidentialOcTreeNode* existing) {
  PerThread& t = threads_[thread];
  const Range& range = ranges_[i];
  const octomap::OcTreeKey& base = seeds_[i].key;
  // 1. The kernel rows of the subtree, in Morton order.
  const double start = threadCpuMs();
  KernelRows& kernel = t.kernel;
  if (range.first_point < range.last_point) buildMask(i, existing, &t);
  kernel.touched.clear();
  kernel.rows.clear();
  const bool class_aware = kernel_->classAware();
  for (size_t p = range.first_point; class_aware && p < range.last_point; ++p)
    kernel_->markClasses((*kernel_points_)[point_subtrees_[p].second], base, &kernel);
  if (class_aware) KernelPass::holdClasses(&kernel);
  // Consecutive points of one 2^3 block (a down-sampling cell) scattered as a group.
  KernelMember group[KernelPass::kMaxGroup];
  for (size_t p = range.first_point; p < range.last_point;) {
    int n = 0;
    do {
      const uint32_t j = point_subtrees_[p++].second;
      group[n++] = {&(*kernel_points_)[j], &points_->positions[j]};
    } while (n < KernelPass::kMaxGroup && p < range.last_point &&
             KernelPass::sameGroup(*group[0].point,
                                   (*kernel_points_)[point_subtrees_[p].second]));
    kernel_->scatter(group, n, base, &kernel);
  }
  kernel_->flushOneHot(&kernel);
  if (class_aware) KernelPass::clearClasses(&kernel);
  t.most_row_values = std::max(t.most_row_values, kernel.rows.size());
  t.most_rows = std::max(t.most_rows, kernel.touched.size());
  kernel_->finishRows(&kernel);
  t.order.clear();
  for (uint32_t row = 0; row < kernel.touched.size(); ++row) {
    const uint32_t local = kernel.touched[row];
    const uint64_t x = local % kSubtreeSize, y = (local >> kSubtreeLevels) % kSubtreeSize,
                   z = local >> (2 * kSubtreeLevels);
    t.order.emplace_back(
        static_cast<uint32_t>(spreadBits3(z) << 2 | spreadBits3(y) << 1 | spreadBits3(x)), row);
    kernel.index[local] = KernelRows::kNone;
  }
  // 3 * kSubtreeLevels = 18 bits in two 9-bit passes: a subtree has a few thousand rows.
  static_assert(3 * kSubtreeLevels <= 18, "two 9-bit passes");
  radixSort<9>(&t.order, 3 * kSubtreeLevels, &t.order_buffer);
  t.kernel_cpu_ms += threadCpuMs() - start;
  // 2. Merged with the ray voxels: occupied wins over free; one update per key.
  const uint64_t subtree_code = mortonCode(base);  // its low 3 * kSubtreeLevels bits are 0
  auto row = t.order.cbegin();
  auto emitRow = [&]() {
    const octomap::OcTreeKey local = keyFromMorton(row->first);
    t.updates.push_back({octomap::OcTreeKey(static_cast<octomap::key_type>(base[0] + local[0]),
                                            static_cast<octomap::key_type>(base[1] + local[1]),
                                            static_cast<octomap::key_type>(base[2] + local[2])),
                         0, row->second});
    ++row;
  };
  t.updates.clear();
  rays_->forEachSorted(range.first_brick, range.last_brick,
                       [&](const octomap::OcTreeKey& voxel, uint64_t code, unsigned flags) {
                         while (row != t.order.cend() && (subtree_code | row->first) < code) {
                           emitRow();
                         }
                         VoxelUpdate u{voxel, 0};
                         if (flags & (1u << kRayOccupied)) {
                           u.occupancy = +1;
                         } else if (flags & (1u << kRayFree)) {
                           u.occupancy = -1;
                         }
                         if (row != t.order.cend() && (subtree_code | row->first) == code) {
                           u.increments = (row++)->second;
                         }
                         if (u.occupancy != 0 || u.increments != VoxelUpdate::kNoIncrements) {
                           t.updates.push_back(u);
                         }
                       });
  while (row != t.order.cend()) emitRow();
  t.most_updates = std::max(t.most_updates, t.updates.size());
  return {t.updates.data(), t.updates.data() + t.updates.size(), kernel.rows.data()};
}

size_t ScanSubtrees::capacityBytes() const {
  size_t bytes = vectorBytes(point_subtrees_) + vectorBytes(seeds_) + vectorBytes(ranges_) +
                 vectorBytes(threads_);
  for (const PerThread& t : threads_) {
    const KernelRows& k = t.kernel;
    bytes += vectorBytes(k.mask) + vectorBytes(k.index) + vectorBytes(k.touched) +
             vectorBytes(k.rows) + vectorBytes(k.axis_terms) + vectorBytes(k.classes) +
             vectorBytes(k.classes_touched) + vectorBytes(k.pending_members) +
             vectorBytes(k.pending) + vectorBytes(k.pending_order) + vectorBytes(k.class_sums) +
             vectorBytes(k.class_lines) + vectorBytes(k.lines_touched) +
             vectorBytes(k.kept_lines) + vectorBytes(t.order) +
             vectorBytes(t.order_buffer) + vectorBytes(t.updates);
  }
  return bytes;
}

void ScanSubtrees::releaseExcess() {
  releaseOversized(&point_subtrees_, point_subtrees_.size());
  releaseOversized(&seeds_, seeds_.size());
  releaseOversized(&ranges_, ranges_.size());
  for (PerThread& t : threads_) {
    releaseOversized(&t.kernel.rows, t.most_row_values);
    releaseOversized(&t.kernel.touched, t.most_rows);
    releaseOversized(&t.order, t.most_rows);
    releaseOversized(&t.order_buffer, t.most_rows);
    releaseOversized(&t.updates, t.most_updates);
  }
}

double ScanSubtrees::kernelCpuMs() const {
  double sum = 0.0;
  for (const PerThread& t : threads_) sum += t.kernel_cpu_ms;
  return sum;
}

}  // namespace evidential_octomap
