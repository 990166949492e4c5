#include "kernel_pass.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "evidential_octomap/sparse_kernel.h"
#include "fusion_contributions.h"
#include "subtree_source.h"

namespace evidential_octomap {

KernelTable::KernelTable(double sigma0) : sigma0_(sigma0), values_(kSteps + 1) {
  for (int i = 0; i <= kSteps; ++i)
    values_[i] = sparseKernel(std::sqrt(double(i) / kSteps), 1.0, sigma0);
}

OneHotTable::OneHotTable(double sigma0, float evidence, int num_classes, double weight)
    : evidence_(evidence), steps_(KernelTable::kSteps + 1, Step{0.0, 0.0}) {
  const double strength = double(num_classes) + evidence;
  std::vector<double> values(KernelTable::kSteps + 1);
  for (int i = 0; i <= KernelTable::kSteps; ++i) {
    const double r = std::sqrt(double(i) / KernelTable::kSteps);
    const double k = std::min(weight * sparseKernel(r, 1.0, sigma0), 1.0);
    values[i] = std::log1p(evidence * k / (strength * (1.0 - k) + k * num_classes));
  }
  for (int i = 0; i < KernelTable::kSteps; ++i)
    steps_[i] = {float(values[i]), float(values[i + 1] - values[i])};
}

KernelPass::KernelPass(const SemanticConfig& config, const EvidentialOcTree& tree)
    : tree_(tree),
      rule_(tree.rule()),
      num_classes_(tree.numClasses()),
      length_scale_(config.length_scale),
      beta_(config.beta),
      gamma_(config.effectiveGamma()),
      vertical_support_(config.vertical_support),
      ground_vertical_support_(config.ground_vertical_support),
      uncertainty_kernel_(tree.rule().usesUncertaintyKernel()),
      to_cube_(config.kernel_distance == "voxel"),
      other_class_weight_(config.other_class_weight),
      sigma0_(config.sigma0),
      table_(config.sigma0),
      tables_per_value_(other_class_weight_ > 0.0 && other_class_weight_ < 1.0 ? 2 : 1) {}

// Marks a one-hot dempster point while preparing, before its table is known.
constexpr int kOneHot = -2;

void KernelPass::preparePoints(const SemanticPoints& points, int threads,
                               std::vector<KernelPoint>* out) {
  const size_t m = points.positions.size();
  const double resolution = tree_.getResolution();
  out->resize(m);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (size_t j = 0; j < m; ++j) {
    KernelPoint& kp = (*out)[j];
    PointOpinion& o = kp.opinion;
    o = PointOpinion();
    o.evidence = points.evidence[j];
    o.strength = num_classes_;
    float best = 0.0f;
    int with_evidence = 0;
    for (int c = 0; c < num_classes_; ++c) {
      o.strength += o.evidence[c];
      with_evidence += o.evidence[c] > 0.0f ? 1 : 0;
      if (o.evidence[c] > best) {
        best = o.evidence[c];
        o.argmax = c;
      }
    }
    kp.table = with_evidence == 1 && rule_.type() == FusionRuleType::kDempster ? kOneHot : -1;
    o.uncertainty = num_classes_ / o.strength;
    // S-BKI uses the plain length l; the uncertainty kernels l beta e^{1 - gamma u}.
    const float length = static_cast<float>(
        uncertainty_kernel_ ? adaptiveLength(length_scale_, beta_, gamma_, o.uncertainty)
                            : length_scale_);
    kp.inv_length2 = 1.0 / (double(length) * length);
    const double vertical =
        tree_.isGroundClass(o.argmax) ? ground_vertical_support_ : vertical_support_;
    kp.inv_length2_z = kp.inv_length2 / (vertical * vertical);
    // A voxel can take part when its cube (or centre) is within L on x and y, and within
    // L * vertical on z. The point lies anywhere in its own voxel, so at offset o that gap is
    // at least (|o| - 1) res ((|o| - 1/2) res to the centre): o is reached while that is < L.
    // A hundredth of a voxel more covers the rounding of float positions; beyond the reach
    // every voxel's kernel is 0, so the reach bounds work, not the map.
    const double extra = (to_cube_ ? 1.0 : 0.5) + 0.01;
    kp.reach[0] = kp.reach[1] = static_cast<int>(std::floor(length / resolution + extra));
    kp.reach[2] = static_cast<int>(std::floor(length * vertical / resolution + extra));
    kp.key = tree_.coordToKey(points.positions[j]);
  }
  buildOneHotTables(out);
}

// Tables for the evidence values that many one-hot points share (derived evidence: one value,
// e.g. 20); the other points keep the general loop. A table costs ~0.3 ms to build.
void KernelPass::buildOneHotTables(std::vector<KernelPoint>* points) {
  constexpr size_t kMaxValues = 16, kMaxTables = 8, kMinPoints = 64;
  std::vector<std::pair<float, size_t>> values;  // (evidence, points)
  const auto evidenceOf = [](const KernelPoint& p) { return p.opinion.evidence[p.opinion.argmax]; };
  for (const KernelPoint& p : *points) {
    if (p.table != kOneHot) continue;
    const float e = evidenceOf(p);
    auto v =
        std::find_if(values.begin(), values.end(), [&](const auto& x) { return x.first == e; });
    if (v != values.end()) {
      ++v->second;
    } else if (values.size() < kMaxValues) {
      values.emplace_back(e, 1);
    }
  }
  std::stable_sort(values.begin(), values.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  // sigma0 > 1: k is clamped at 1 inside the support, a kink the interpolation would blur.
  if (sigma0_ > 1.0) values.clear();
  one_hot_.clear();
  for (size_t v = 0; v < values.size() && v < kMaxTables && values[v].second >= kMinPoints; ++v) {
    one_hot_.emplace_back(sigma0_, values[v].first, num_classes_, 1.0);
    if (tables_per_value_ == 2)
      one_hot_.emplace_back(sigma0_, values[v].first, num_classes_, other_class_weight_);
  }
  for (KernelPoint& p : *points) {
    if (p.table != kOneHot) continue;
    p.table = -1;
    const float e = evidenceOf(p);
    for (size_t t = 0; t < one_hot_.size(); t += tables_per_value_) {
      if (one_hot_[t].evidence() == e) p.table = int(t);
    }
  }
}

void KernelPass::scatter(const KernelMember* group, int n, const octomap::OcTreeKey& base,
                         KernelRows* out) const {
  if (group[0].point->table >= 0) {
    if (out->pending.empty()) {
      out->pending_base = base;
    } else if (!(out->pending_base == base)) {
      throw std::logic_error("KernelPass::scatter: flushOneHot before the next subtree");
    }
    out->pending.push_back(
        {uint32_t(out->pending_members.size()), n, group[0].point->opinion.argmax});
    out->pending_members.insert(out->pending_members.end(), group, group + n);
    return;
  }
  const KernelPoint& point = *group[0].point;
  const octomap::point3d& position = *group[0].position;
  switch (rule_.type()) {
    case FusionRuleType::kDempster:
      return scatterWith(DempsterContribution(point.opinion, num_classes_), point, position, base,
                         out);
    case FusionRuleType::kSbki:
      return scatterWith(SbkiContribution(point.opinion, num_classes_), point, position, base, out);
    case FusionRuleType::kEbs:
      return scatterWith(EbsContribution(point.opinion, num_classes_), point, position, base, out);
  }
}

static uint64_t classBit(int argmax) { return uint64_t(1) << (argmax & 63); }

// The class arrays cover the subtree and a shell of one voxel around it, so that a voxel at
// its face sees its neighbours in the next subtree: index of local voxel offsets in [-1, 64].
constexpr int kPadded = (1 << kSubtreeLevels) + 2;
static uint32_t paddedIndex(int x, int y, int z) {
  return uint32_t(((z + 1) * kPadded + (y + 1)) * kPadded + (x + 1));
}

void KernelPass::markClasses(const KernelPoint& point, const octomap::OcTreeKey& base,
                             KernelRows* rows) const {
  if (point.opinion.argmax < 0) return;  // no evidence: no class to protect
  constexpr int kSize = 1 << kSubtreeLevels;
  int offset[3];
  for (int a = 0; a < 3; ++a) {
    offset[a] = int(point.key[a]) - int(base[a]);
    if (offset[a] < -1 || offset[a] > kSize) return;  // beyond the shell around the subtree
  }
  const uint32_t local = paddedIndex(offset[0], offset[1], offset[2]);
  if (rows->classes.empty()) {
    rows->classes.resize(size_t(kPadded) * kPadded * kPadded, 0);
    rows->classes_weaker.resize(rows->classes.size(), 0);
  }
  uint64_t& seen = rows->classes[local];
  if (!seen) rows->classes_touched.push_back(local);
  const uint64_t bit = classBit(point.opinion.argmax);
  rows->classes_weaker[local] |= seen & bit;  // its second point of this class: held
  seen |= bit;
}

// A class one point alone shows is held only if a point beside it agrees: a lone point of
// another class (a network's noise) does not keep its neighbours' evidence out, a thin object's
// few points do. (Shell voxels see only part of their neighbours, but no point scatters there.)
void KernelPass::holdClasses(KernelRows* rows) {
  constexpr int kSize = 1 << kSubtreeLevels;
  if (rows->weaker_lines.empty()) rows->weaker_lines.resize(size_t(kSize) * kSize, 0);
  const std::vector<uint64_t>& seen = rows->classes;
  for (uint32_t local : rows->classes_touched) {
    const int x = int(local % kPadded), y = int(local / kPadded % kPadded),
              z = int(local / (kPadded * kPadded));
    uint64_t beside = 0;
    for (int nz = std::max(z - 1, 0); nz <= std::min(z + 1, kPadded - 1); ++nz)
      for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, kPadded - 1); ++ny)
        for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, kPadded - 1); ++nx) {
          const uint32_t n = uint32_t((nz * kPadded + ny) * kPadded + nx);
          if (n != local) beside |= seen[n];
        }
    const bool holds = rows->classes_weaker[local] || (seen[local] & beside);
    rows->classes_weaker[local] = holds ? ~seen[local] : 0;
    if (!holds || x == 0 || y == 0 || z == 0 || x > kSize || y > kSize || z > kSize) continue;
    rows->weaker_lines[size_t(z - 1) * kSize + (y - 1)] |= uint64_t(1) << (x - 1);
  }
}

void KernelPass::flushOneHot(KernelRows* out) const {
  if (out->pending.empty()) return;
  constexpr size_t kVoxels = size_t(1) << (3 * kSubtreeLevels);
  if (out->class_sums.empty()) {
    out->class_sums.assign(kVoxels, 0.0);
    out->class_lines.assign(kVoxels >> kSubtreeLevels, 0);
  }
  constexpr int kSize = 1 << kSubtreeLevels;
  out->kept_lines.assign(kSize, ~uint64_t(0));
  for (int z = 0; out->masked && z < kSize; ++z) {
    uint64_t lines = 0;
    for (int y = 0; y < kSize; ++y) lines |= uint64_t(out->mask[z << kSubtreeLevels | y] != 0) << y;
    out->kept_lines[z] = lines;
  }
  // Rows made by one-hot groups alone need no second half (Dempster's running products): C wide.
  if (out->touched.empty()) out->narrow = true;
  // The groups in class order, each class's in scatter order (a counting sort).
  std::vector<uint32_t> count(num_classes_ + 1, 0);
  for (const KernelRows::PendingGroup& g : out->pending) ++count[g.cls + 1];
  for (int c = 0; c < num_classes_; ++c) count[c + 1] += count[c];
  out->pending_order.resize(out->pending.size());
  for (uint32_t i = 0; i < out->pending.size(); ++i)
    out->pending_order[count[out->pending[i].cls]++] = i;
  for (size_t i = 0; i < out->pending_order.size(); ++i) {
    const KernelRows::PendingGroup& g = out->pending[out->pending_order[i]];
    scatterOneHot(&out->pending_members[g.first], g.n, out->pending_base, out);
    const bool last_of_class = i + 1 == out->pending_order.size() ||
                               out->pending[out->pending_order[i + 1]].cls != g.cls;
    if (last_of_class) addClassSums(g.cls, out);
  }
  out->pending.clear();
  out->pending_members.clear();
}

void KernelPass::addClassSums(int cls, KernelRows* out) const {
  const size_t width = size_t(out->narrow ? 1 : DempsterContribution::kRowWidth) * num_classes_;
  for (uint32_t line : out->lines_touched) {
    for (uint64_t voxels = out->class_lines[line]; voxels; voxels &= voxels - 1) {
      const uint32_t local = line << kSubtreeLevels | uint32_t(__builtin_ctzll(voxels));
      uint32_t& row = out->index[local];
      if (row == KernelRows::kNone) {
        row = static_cast<uint32_t>(out->touched.size());
        out->touched.push_back(local);
        out->rows.resize(out->rows.size() + width, 0.0);
      }
      out->rows[size_t(row) * width + cls] += out->class_sums[local];  // the log-evidence part
      out->class_sums[local] = 0.0;
    }
    out->class_lines[line] = 0;
  }
  out->lines_touched.clear();
}

void KernelPass::clearClasses(KernelRows* rows) {
  if (!rows->pending.empty())
    throw std::logic_error("KernelPass::clearClasses: flushOneHot first");
  constexpr int kSize = 1 << kSubtreeLevels;
  for (uint32_t local : rows->classes_touched) {
    rows->classes[local] = 0;
    rows->classes_weaker[local] = 0;
    const int y = int(local / kPadded % kPadded), z = int(local / (kPadded * kPadded));
    if (y >= 1 && z >= 1 && y <= kSize && z <= kSize)
      rows->weaker_lines[size_t(z - 1) * kSize + (y - 1)] = 0;
  }
  rows->classes_touched.clear();
}

template <class Contribution>
void finishRowsWith(int num_classes, KernelRows* out) {
  if constexpr (Contribution::kRowWidth > 1) {
    if (out->narrow) return;  // already the C increments
    const size_t width = size_t(Contribution::kRowWidth) * num_classes;
    const size_t rows = out->touched.size();
    for (size_t r = 0; r < rows; ++r) {
      double* row = &out->rows[r * width];
      Contribution::finish(row, num_classes);
      // Row r moves to r * C: below its old place, and past every row already moved.
      std::copy(row, row + num_classes, &out->rows[r * num_classes]);
    }
    out->rows.resize(rows * num_classes);
  }
}

void KernelPass::finishRows(KernelRows* out) const {
  flushOneHot(out);
  switch (rule_.type()) {
    case FusionRuleType::kDempster:
      return finishRowsWith<DempsterContribution>(num_classes_, out);
    case FusionRuleType::kSbki:
      return finishRowsWith<SbkiContribution>(num_classes_, out);
    case FusionRuleType::kEbs:
      return finishRowsWith<EbsContribution>(num_classes_, out);
  }
}

template <class Contribution>
void KernelPass::scatterWith(const Contribution& contribute, const KernelPoint& point,
                             const octomap::point3d& position, const octomap::OcTreeKey& base,
                             KernelRows* out) const {
  constexpr int kSize = 1 << kSubtreeLevels;
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(-point.reach[a], int(base[a]) - int(point.key[a]));
    hi[a] = std::min(point.reach[a], int(base[a]) + kSize - 1 - int(point.key[a]));
    if (lo[a] > hi[a]) return;
  }
  // d^2 = sum over the axes of a term per axis offset: the gap between the point and the
  // voxel's cube (or centre) along that axis, squared and divided by L^2 (on z by
  // (L vertical)^2, the point's vertical fraction).
  const double half = tree_.getResolution() / 2.0;
  std::vector<double>& terms = out->axis_terms;
  const int stride = 2 * point.reach[0] + 1;  // the widest axis
  terms.resize(3 * stride);
  double* axis[3];
  for (int a = 0; a < 3; ++a) {
    axis[a] = &terms[a * stride] - lo[a];
    const double inv_length2 = a == 2 ? point.inv_length2_z : point.inv_length2;
    for (int o = lo[a]; o <= hi[a]; ++o) {
      const float centre =
          static_cast<float>(tree_.keyToCoord(static_cast<octomap::key_type>(point.key[a] + o)));
      const float d = position(a) - centre;
      const double gap = to_cube_ ? std::max(std::fabs(double(d)) - half, 0.0) : double(d);
      axis[a][o] = gap * gap * inv_length2;
    }
  }
  const size_t width = size_t(Contribution::kRowWidth) * num_classes_;
  // Voxels that hold other classes but not the point's get other_class_weight of its weight
  // (none when not class-aware).
  const bool weigh_others =
      other_class_weight_ < 1.0 && !out->classes_touched.empty() && point.opinion.argmax >= 0;
  const uint64_t own_class = weigh_others ? classBit(point.opinion.argmax) : 0;
  const int x0 = int(point.key[0]) - int(base[0]), y0 = int(point.key[1]) - int(base[1]),
            z0 = int(point.key[2]) - int(base[2]);
  const int reach_x = hi[0] - lo[0] + 1;
  const uint64_t reachable = (reach_x >= 64 ? ~uint64_t(0) : (uint64_t(1) << reach_x) - 1)
                             << (x0 + lo[0]);
  // The x offset of the smallest x term (the point's own column, or the subtree's edge nearest
  // it), and the ends of the last line's interval.
  const int nearest_x = std::clamp(0, lo[0], hi[0]);
  int first_x = nearest_x, last_x = nearest_x;
  // x innermost: consecutive voxels of a mask word, the index and (mostly) the rows.
  for (int oz = lo[2]; oz <= hi[2]; ++oz) {
    const double sz = axis[2][oz];
    if (sz >= 1.0) continue;
    for (int oy = lo[1]; oy <= hi[1]; ++oy) {
      const double syz = sz + axis[1][oy];
      if (syz >= 1.0) continue;
      const uint32_t line = uint32_t((z0 + oz) << kSubtreeLevels | (y0 + oy));
      // A line without a kept voxel costs one load (most lines of a surface-only map).
      const uint64_t kept = out->masked ? out->mask[line] & reachable : ~uint64_t(0);
      if (!kept) continue;
      // The x offsets within the support on this line: an interval around the smallest x term,
      // since that term grows away from the point (a hair wider than exact; the table gives 0
      // beyond s = 1). Its ends move little from line to line: found from the last line's.
      const auto inside = [&](int o) { return axis[0][o] + syz < 1.0 + 1e-9; };
      if (!inside(nearest_x)) continue;
      int a = std::min(first_x, nearest_x), b = std::max(last_x, nearest_x);
      if (inside(a)) {
        while (a > lo[0] && inside(a - 1)) --a;
      } else {
        while (!inside(a)) ++a;
      }
      if (inside(b)) {
        while (b < hi[0] && inside(b + 1)) ++b;
      } else {
        while (!inside(b)) --b;
      }
      first_x = a;
      last_x = b;
      const int width_x = b - a + 1;
      const uint64_t interval = (width_x >= 64 ? ~uint64_t(0) : (uint64_t(1) << width_x) - 1)
                                << (x0 + a);
      uint64_t voxels = interval & kept;
      // Only the voxels kept and in the support: no unpredictable branch per candidate voxel.
      while (voxels) {
        const int ox = __builtin_ctzll(voxels) - x0;
        voxels &= voxels - 1;
        const uint32_t local = line << kSubtreeLevels | uint32_t(x0 + ox);
        double weight = 1.0;
        if (weigh_others && (out->weaker_lines[line] >> (x0 + ox) & 1)) {
          if (out->classes_weaker[paddedIndex(x0 + ox, y0 + oy, z0 + oz)] & own_class) {
            if (other_class_weight_ <= 0.0) continue;
            weight = other_class_weight_;
          }
        }
        // Summed as (x + y) + z, whatever the loop order, so the rounding never depends on it.
        const double k = weight * table_((axis[0][ox] + axis[1][oy]) + sz);
        if (k <= 0.0) continue;
        uint32_t& row = out->index[local];
        if (row == KernelRows::kNone) {
          if (out->touched.empty()) out->narrow = false;  // the subtree's first row
          row = static_cast<uint32_t>(out->touched.size());
          out->touched.push_back(local);
          out->rows.resize(out->rows.size() + width, 0.0);
        }
        contribute(k, &out->rows[size_t(row) * width]);
      }
    }
  }
}

// The axis terms of one member of a group, d^2 per axis offset from the group's first point
// (as scatterWith's, +inf beyond the member's reach).
struct MemberTerms {
  const double* axis[3];  // indexed by the offset from the group's first point
  double syz;             // its y + z term on the line at hand
  double x;               // its x, from the centre of the group's first voxel [voxels]
  double length;          // its support across, L [voxels]
};

void KernelPass::scatterOneHot(const KernelMember* group, int n, const octomap::OcTreeKey& base,
                               KernelRows* out) const {
  constexpr int kSize = 1 << kSubtreeLevels;
  const octomap::OcTreeKey& ref = group[0].point->key;
  // The union of the members' reaches, as offsets from ref, within the subtree.
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<int>::max();
    hi[a] = std::numeric_limits<int>::min();
    for (int i = 0; i < n; ++i) {
      const int at = int(group[i].point->key[a]) - int(ref[a]);
      lo[a] = std::min(lo[a], at - group[i].point->reach[a]);
      hi[a] = std::max(hi[a], at + group[i].point->reach[a]);
    }
    lo[a] = std::max(lo[a], int(base[a]) - int(ref[a]));
    hi[a] = std::min(hi[a], int(base[a]) + kSize - 1 - int(ref[a]));
    if (lo[a] > hi[a]) return;
  }
  const double resolution = tree_.getResolution(), half = resolution / 2.0;
  const int stride = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) + 1;
  out->axis_terms.resize(size_t(3) * stride * n);
  MemberTerms terms[kMaxGroup];
  const double ref_x = static_cast<float>(tree_.keyToCoord(ref[0]));
  for (int i = 0; i < n; ++i) {
    const KernelPoint& point = *group[i].point;
    MemberTerms& t = terms[i];
    t.x = (double((*group[i].position)(0)) - ref_x) / resolution;
    t.length = 1.0 / (std::sqrt(point.inv_length2) * resolution);
    for (int a = 0; a < 3; ++a) {
      double* axis = &out->axis_terms[(size_t(i) * 3 + a) * stride] - lo[a];
      t.axis[a] = axis;
      const int at = int(point.key[a]) - int(ref[a]);
      const double inv_length2 = a == 2 ? point.inv_length2_z : point.inv_length2;
      for (int o = lo[a]; o <= hi[a]; ++o) {
        if (std::abs(o - at) > point.reach[a]) {
          axis[o] = std::numeric_limits<double>::infinity();
          continue;
        }
        const float centre =
            static_cast<float>(tree_.keyToCoord(static_cast<octomap::key_type>(ref[a] + o)));
        const float d = (*group[i].position)(a) - centre;
        const double gap = to_cube_ ? std::max(std::fabs(double(d)) - half, 0.0) : double(d);
        axis[o] = gap * gap * inv_length2;
      }
    }
  }
  // The members share a class and an evidence value: one table (two when class-aware).
  const int cls = group[0].point->opinion.argmax;
  const OneHotTable& full = one_hot_[group[0].point->table];
  const OneHotTable& weaker_table =
      tables_per_value_ == 2 ? one_hot_[group[0].point->table + 1] : full;
  const OneHotTable::Step* full_steps = full.steps();
  const OneHotTable::Step* weaker_steps = weaker_table.steps();
  const uint64_t own_class =
      other_class_weight_ < 1.0 && !out->classes_touched.empty() ? classBit(cls) : 0;
  const int x0 = int(ref[0]) - int(base[0]), y0 = int(ref[1]) - int(base[1]),
            z0 = int(ref[2]) - int(base[2]);
  const int reach_x = hi[0] - lo[0] + 1;
  const uint64_t reachable = (reach_x >= 64 ? ~uint64_t(0) : (uint64_t(1) << reach_x) - 1)
                             << (x0 + lo[0]);
  int on_line[kMaxGroup];  // the members within the support on the line at hand
  const int reach_y = hi[1] - lo[1] + 1;
  const uint64_t reachable_y = (reach_y >= 64 ? ~uint64_t(0) : (uint64_t(1) << reach_y) - 1)
                               << (y0 + lo[1]);
  for (int oz = lo[2]; oz <= hi[2]; ++oz) {
    // Only the lines with a kept voxel: a surface's few of the group's box.
    for (uint64_t lines = out->kept_lines[z0 + oz] & reachable_y; lines; lines &= lines - 1) {
      const int oy = __builtin_ctzll(lines) - y0;
      const uint32_t line = uint32_t((z0 + oz) << kSubtreeLevels | (y0 + oy));
      const uint64_t kept = (out->masked ? out->mask[line] : ~uint64_t(0)) & reachable;
      if (!kept) continue;
      // The members whose support crosses this line, and the x offsets within one of them:
      // |x - o| < L sqrt(1 - syz) (+ half a voxel to the cube), widened by a hundredth of a
      // voxel for rounding. Each kept voxel there is summed over the members without a branch
      // (a member's table gives 0 beyond its support, so the sums are those of the whole line).
      int members = 0;
      double first = hi[0] + 1.0, last = lo[0] - 1.0;
      for (int i = 0; i < n; ++i) {
        MemberTerms& t = terms[i];
        t.syz = t.axis[2][oz] + t.axis[1][oy];
        if (!(t.syz < 1.0)) continue;
        on_line[members++] = i;
        const double across = t.length * std::sqrt(1.0 - t.syz) + (to_cube_ ? 0.5 : 0.0) + 0.01;
        first = std::min(first, t.x - across);
        last = std::max(last, t.x + across);
      }
      if (!members) continue;
      const int a = std::max(lo[0], int(std::ceil(first)));
      const int b = std::min(hi[0], int(std::floor(last)));
      if (a > b) continue;
      const int width_x = b - a + 1;
      const uint64_t inside = (width_x >= 64 ? ~uint64_t(0) : (uint64_t(1) << width_x) - 1)
                              << (x0 + a);
      const uint64_t weaker_line = own_class ? out->weaker_lines[line] : 0;
      double* class_sums = &out->class_sums[size_t(line) << kSubtreeLevels];
      uint64_t summed = 0;  // the voxels this group adds to
      for (uint64_t voxels = kept & inside; voxels; voxels &= voxels - 1) {
        const int x = __builtin_ctzll(voxels);
        const OneHotTable::Step* steps = full_steps;
        if ((weaker_line >> x & 1) &&
            (out->classes_weaker[paddedIndex(x, y0 + oy, z0 + oz)] & own_class)) {
          if (other_class_weight_ <= 0.0) continue;
          steps = weaker_steps;
        }
        // No branch per member: beyond its support (or reach: +inf) its table gives 0.
        double sum = 0.0;
        for (int m = 0; m < members; ++m) {
          const MemberTerms& t = terms[on_line[m]];
          sum += OneHotTable::at(steps, t.axis[0][x - x0] + t.syz);
        }
        // No row from this group where its sum is 0, as from the full loop; adding that 0 to
        // the voxel's sum changes no bit, and costs less than a branch the data decides.
        summed |= uint64_t(sum > 0.0) << x;
        class_sums[x] += sum;
      }
      if (!summed) continue;
      if (!out->class_lines[line]) out->lines_touched.push_back(line);
      out->class_lines[line] |= summed;
    }
  }
}

}  // namespace evidential_octomap
