// The one kernel loop (docs/design.md): every kept point adds its rule's contribution, weighted by the
// sparse kernel k(d, L_i), to each voxel within its support, aggregated per voxel for the scan.
// Run per subtree of the tree update (subtree_source.h), so rows exist only for the subtree at
// hand and threads never share one.
//
// The kernel is not recomputed per (point, voxel): d^2 splits into per-axis terms that are
// computed once per point and axis offset, and sigma0 k'(r) is looked up at r^2 = d^2 / L^2 in a
// table of 4096 steps with linear interpolation. The geometry stays exact (no quantised point
// positions or supports); the table's error is at most 5e-7 sigma0 (test_sparse_kernel checks it), so
// the map differs from direct evaluation by at most that error times each contribution's
// derivative in k (plus dempster's fastLog1p, 3e-14 relative). Rows are computed only for voxels
// the map keeps (KernelRows::mask).
//
// One-hot dempster points (one class with evidence, labels made into evidence: most points of
// most scans) take a shorter road. Their increment log1p(e f(w k)) depends on s = r^2 alone for
// a given evidence e and class weight w, so it is tabulated over s as k is (OneHotTable: no
// division and no product per voxel, within the same error bound per contribution), and the
// points of one 2 x 2 x 2 block (a down-sampling cell: up to 6 points) with the same class and
// evidence are scattered as a group, the sum of its members' increments per voxel. A subtree's
// groups wait until its last scatter and then go class by class, each class's in scatter order,
// into a dense sum per voxel, so a row is looked up and written once per class (not once per
// group) and holds the same sums bit for bit; rows of one-hot groups alone are C wide from the
// start (no running products to finish, half the memory to fill). Private to the core.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/fusion_rule.h"
#include "semantic_points.h"

namespace evidential_octomap {

// sigma0 k'(r) of the sparse kernel (sparse_kernel.h) as a function of s = r^2, tabulated.
class KernelTable {
 public:
  static constexpr int kSteps = 4096;
  static constexpr double kMaxError = 5e-7;  // times sigma0

  explicit KernelTable(double sigma0);
  double sigma0() const { return sigma0_; }
  // 0 at s >= 1 (outside the support).
  double operator()(double s) const {
    if (!(s < 1.0)) return 0.0;
    const double x = s * kSteps;
    const int i = static_cast<int>(x);
    return values_[i] + (x - i) * (values_[i + 1] - values_[i]);
  }

 private:
  double sigma0_;
  std::vector<double> values_;  // kSteps + 1 samples
};

// The dempster increment log1p(e f(w k'(r))) (fusion_contributions.h) of a one-hot point with
// evidence e in its class and strength S = e + C, at class weight w, as a function of s = r^2,
// tabulated with KernelTable's steps. Its interpolation error, at most e S / C^2 (the largest
// slope of the increment in k) times KernelTable::kMaxError sigma0, is KernelTable's bound
// carried through the increment; test_kernel_pass checks it. Used for sigma0 <= 1 only, where
// w k <= 1 needs no clamp.
class OneHotTable {
 public:
  OneHotTable(double sigma0, float evidence, int num_classes, double weight);
  struct Step {
    float value, slope;  // at step i, and to step i + 1: 32 KB, in the L1 cache
  };
  float evidence() const { return evidence_; }
  double operator()(double s) const { return at(steps_.data(), s); }
  // The steps, for a loop that picks one of two tables per voxel without an extra load.
  const Step* steps() const { return steps_.data(); }
  // std::min(s, 1.0), as minsd on x86: the compiler makes a branch of std::min there, and
  // s >= 1 (a tenth of the evaluations) is the data's, unpredictable.
  static double atMostOne(double s) {
#if defined(__SSE2__)
    return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(1.0), _mm_set_sd(s)));
#else
    return std::min(s, 1.0);
#endif
  }
  // Without a branch: s >= 1 (or +inf) reads the last step, 0 with slope 0.
  static double at(const Step* steps, double s) {
    const double x = atMostOne(s) * KernelTable::kSteps;
    const int i = static_cast<int>(x);
    return double(steps[i].value) + (x - i) * double(steps[i].slope);
  }

 private:
  float evidence_;
  std::vector<Step> steps_;  // kSteps + 1: the last is 0, 0
};

// A semantic point ready for the kernel.
struct KernelPoint {
  octomap::OcTreeKey key;    // its voxel
  double inv_length2 = 0.0;     // 1 / L^2 of its support across
  double inv_length2_z = 0.0;   // and along z: 1 / (L vertical_support)^2 (ground: its own)
  std::array<int, 3> reach{};  // voxels it may reach: |offset| <= reach[a] along axis a
  PointOpinion opinion;
  int table = -1;  // one-hot dempster: its evidence's tables (KernelPass), else -1
};

// A point of a group and its position.
struct KernelMember {
  const KernelPoint* point;
  const octomap::point3d* position;
};

// Kernel rows of one subtree: a dense index over its 64^3 voxels (reset after use) and C
// doubles per row. One per thread.
struct KernelRows {
  // Which local voxels may get a row, one bit each (word z * 64 + y, bit x); every voxel when
  // `masked` is false. The map keeps rows only for voxels it has a leaf for, so the rows of the
  // others (behind surfaces, under the ground: about half the support) are not computed.
  std::vector<uint64_t> mask;
  bool masked = false;
  std::vector<uint32_t> index;     // local voxel -> row, kNone when untouched
  std::vector<uint32_t> touched;   // local voxels with a row, in row order
  std::vector<double> rows;        // while scattering: the contribution's row width, then C
  bool narrow = false;             // C wide while scattering too (one-hot groups' rows alone)
  std::vector<double> axis_terms;  // per-axis d^2 terms of the point (or group) at hand
  // SemanticConfig::other_class_weight < 1: per voxel of the subtree and of a one-voxel shell
  // around it, one bit per class (c mod 64) of this scan's points in it (0 for a voxel no point
  // hit), and the classes whose points weigh other_class_weight there: every class it has no
  // point of, if it holds a class (two of its points, or one of them and a point in a
  // neighbouring voxel), else none; while marking, the classes it has two points of. Reset
  // after use (classes_touched).
  std::vector<uint64_t> classes;
  std::vector<uint64_t> classes_weaker;
  std::vector<uint32_t> classes_touched;
  // Per line of the subtree (as `mask`), the voxels whose classes_weaker is not 0: the loop
  // reads one word a line instead of the large padded array at every voxel.
  std::vector<uint64_t> weaker_lines;
  // One-hot groups wait for KernelPass::flushOneHot, which scatters them class by class: each
  // class into a dense sum per local voxel (class_sums, 0 between classes; class_lines: per
  // line, its voxels with a sum; lines_touched: those lines), so that a row is looked up and
  // written once per class rather than once per group.
  struct PendingGroup {
    uint32_t first;  // in pending_members
    int n;
    int cls;
  };
  std::vector<KernelMember> pending_members;
  std::vector<PendingGroup> pending;
  octomap::OcTreeKey pending_base;
  std::vector<double> class_sums;
  std::vector<uint64_t> class_lines;
  std::vector<uint32_t> lines_touched;
  std::vector<uint32_t> pending_order;
  std::vector<uint64_t> kept_lines;  // per z of the subtree, bit y: line (z, y) has a kept voxel
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
};

class KernelPass {
 public:
  KernelPass(const SemanticConfig& config, const EvidentialOcTree& tree);

  // Opinions, supports and voxels of the semantic points (in parallel), and the one-hot
  // tables of the evidence values most of them share.
  void preparePoints(const SemanticPoints& points, int threads, std::vector<KernelPoint>* out);

  // Points scattered together: one-hot points of one class and evidence in one 2^3 block.
  static constexpr int kMaxGroup = 8;
  static bool sameGroup(const KernelPoint& first, const KernelPoint& next) {
    return first.table >= 0 && next.table == first.table &&
           next.opinion.argmax == first.opinion.argmax &&
           (first.key[0] >> 1) == (next.key[0] >> 1) &&
           (first.key[1] >> 1) == (next.key[1] >> 1) && (first.key[2] >> 1) == (next.key[2] >> 1);
  }
  // Adds the contributions of the n (<= kMaxGroup) points of `group` (one point, or points of
  // which each is sameGroup as the first) to the voxels of the subtree whose first voxel is
  // `base` (64^3 voxels, kSubtreeLevels) into `rows`; a one-hot group's at flushOneHot (the
  // points and positions its members name must live until then).
  void scatter(const KernelMember* group, int n, const octomap::OcTreeKey& base,
               KernelRows* rows) const;
  // After the last scatter of a subtree, before clearClasses: the one-hot groups' contributions,
  // class by class, each class's in the groups' order, so each row gets the sums it got when
  // they were scattered at once, in the same order (bit for bit; only a general point's running
  // product folded into its log-evidence, at evidence near FLT_MAX, now precedes them).
  void flushOneHot(KernelRows* rows) const;
  // After flushOneHot: C increments per row (KernelRows::rows), as the rule's add() takes them.
  void finishRows(KernelRows* rows) const;
  // SemanticConfig::other_class_weight < 1: the classes of the points that lie in the subtree
  // at `base` (markClasses for each, then holdClasses, before its scatters), and their reset
  // (after).
  bool classAware() const { return other_class_weight_ < 1.0; }
  void markClasses(const KernelPoint& point, const octomap::OcTreeKey& base,
                   KernelRows* rows) const;
  static void holdClasses(KernelRows* rows);
  static void clearClasses(KernelRows* rows);

 private:
  // The loop itself, for one rule's contribution (fusion_contributions.h): inlined, no virtual
  // call per voxel.
  template <class Contribution>
  void scatterWith(const Contribution& contribute, const KernelPoint& point,
                   const octomap::point3d& position, const octomap::OcTreeKey& base,
                   KernelRows* rows) const;
  // The loop for a group of one-hot points: the sum of their tabulated increments per voxel,
  // into KernelRows::class_sums.
  void scatterOneHot(const KernelMember* group, int n, const octomap::OcTreeKey& base,
                     KernelRows* rows) const;
  // The class sums into the rows' entries of class `cls`, and their reset.
  void addClassSums(int cls, KernelRows* rows) const;
  void buildOneHotTables(std::vector<KernelPoint>* points);

  const EvidentialOcTree& tree_;
  const FusionRule& rule_;
  int num_classes_;
  double length_scale_, beta_, gamma_;
  double vertical_support_;
  double ground_vertical_support_;
  bool uncertainty_kernel_;
  bool to_cube_;
  double other_class_weight_;
  double sigma0_;
  KernelTable table_;
  // Per evidence value of the tables: weight 1, then (class-aware) other_class_weight.
  std::vector<OneHotTable> one_hot_;
  int tables_per_value_ = 1;
};

}  // namespace evidential_octomap
