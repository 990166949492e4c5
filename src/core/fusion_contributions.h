// What one point adds to a voxel's row under each rule (fusion_rule.h), as a function of the
// kernel value k: set up once per point, applied to every voxel of its support. A row holds
// kRowWidth doubles per class while contributions accumulate; finish() turns it into the C
// increments the rule's add() takes, in its first C doubles. The rules'
// FusionRule::contribute and the kernel loop (kernel_pass.h, templated on these, so the inner
// loop makes no virtual call) both use them: one implementation per rule. Private to the core.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/fusion_rule.h"
#include "fast_log1p.h"

namespace evidential_octomap {

// dempster: L^c += log1p(e_hat^c / C) over the classes with evidence. A row sums a voxel's
// contributions as a running product instead of one log1p each: sum log1p(x_i) = log1p(y) with
// 1 + y = prod (1 + x_i), kept as y += x + x y (exact for small x, where 1 + x would round x
// away), so a row costs one log1p per class at finish() rather than one per contribution (20 per
// contribution with dense learned evidence). A row is 2 C doubles: the log-evidence folded out
// of y before it could overflow, then y.
class DempsterContribution {
 public:
  static constexpr int kRowWidth = 2;  // doubles per class while accumulating

  DempsterContribution(const PointOpinion& point, int num_classes)
      : strength_(point.strength), num_classes_(num_classes) {
    for (int c = 0; c < num_classes; ++c) {
      evidence_[c] = point.evidence[c];
      if (point.evidence[c] > 0.0f) classes_[count_++] = static_cast<uint8_t>(c);
    }
  }
  void operator()(double k, double* row) const {
    if (k <= 0.0) return;
    // The extended belief is an opinion only for k in [0, 1] (sigma0 > 1 can exceed 1).
    k = std::min(k, 1.0);
    // Extended belief b~ = k b, u~ = 1 - k (1 - u); e_hat / C = b~ / u~ = k e / (S (1 - k) + k C),
    // written so that huge S (evidence near FLT_MAX) does not cancel to 0 at k = 1.
    const double factor = k / (strength_ * (1.0 - k) + k * num_classes_);
    double* __restrict y = row + num_classes_;
    uint64_t seen = 0;                // the bits of every new y ORed: its exponent bounds theirs
    if (2 * count_ > num_classes_) {  // dense: one contiguous loop the compiler vectorises
      const double* __restrict evidence = evidence_;
      const int n = num_classes_;
      for (int c = 0; c < n; ++c) {
        const double x = evidence[c] * factor;  // 0 for a class without evidence: y unchanged
        seen |= update(y + c, x);
      }
    } else {
      for (int i = 0; i < count_; ++i) {
        const int c = classes_[i];
        seen |= update(y + c, evidence_[c] * factor);
      }
    }
    // y grows by at most a factor 1 + FLT_MAX (2^128) per contribution: folded into the log at
    // 2^664 it stays far from overflow.
    if ((seen >> 52) >= kFoldExponent) {
      for (int c = 0; c < num_classes_; ++c) {
        if (y[c] >= kFoldAbove) {
          row[c] += fastLog1p(y[c]);
          y[c] = 0.0;
        }
      }
    }
  }
  // The row's log-evidence increments, into its first C doubles.
  static void finish(double* row, int num_classes) {
    for (int c = 0; c < num_classes; ++c) {
      const double y = row[num_classes + c];
      if (y > 0.0) row[c] += fastLog1p(y);  // most classes of a one-hot row stay at 0
    }
  }

 private:
  static constexpr double kFoldAbove = 0x1p664;
  static constexpr uint64_t kFoldExponent = 1023 + 664;  // biased exponent of kFoldAbove
  // y += x + x y; returns the new y's bits (y >= 0: no sign bit).
  static uint64_t update(double* y, double x) {
    const double next = *y + (x + x * *y);
    *y = next;
    uint64_t bits;
    std::memcpy(&bits, &next, sizeof bits);
    return bits;
  }
  double strength_;
  int num_classes_;
  int count_ = 0;  // classes with evidence: the first count_ entries of classes_
  uint8_t classes_[EvidentialOcTree::kMaxClasses];
  double evidence_[EvidentialOcTree::kMaxClasses];
};

// sbki: alpha^argmax += k.
class SbkiContribution {
 public:
  static constexpr int kRowWidth = 1;
  static void finish(double*, int) {}
  SbkiContribution(const PointOpinion& point, int) : argmax_(point.argmax) {}
  void operator()(double k, double* row) const {
    if (argmax_ >= 0) row[argmax_] += k;
  }

 private:
  int argmax_;
};

// ebs: alpha^c += k alpha_i^c / S_i.
class EbsContribution {
 public:
  static constexpr int kRowWidth = 1;
  static void finish(double*, int) {}
  EbsContribution(const PointOpinion& point, int num_classes)
      : point_(point), num_classes_(num_classes) {}
  void operator()(double k, double* row) const {
    const double scale = k / point_.strength;  // p = alpha / S
    for (int c = 0; c < num_classes_; ++c) row[c] += scale * (point_.evidence[c] + 1.0);
  }

 private:
  const PointOpinion& point_;
  int num_classes_;
};

// One point's contribution at kernel value k added to C increments (FusionRule::contribute).
template <class Contribution>
void contributeOnce(const PointOpinion& point, double k, int num_classes, double* increments) {
  const Contribution contribution(point, num_classes);
  if constexpr (Contribution::kRowWidth == 1) {
    contribution(k, increments);
  } else {
    std::vector<double> row(size_t(Contribution::kRowWidth) * num_classes, 0.0);
    contribution(k, row.data());
    Contribution::finish(row.data(), num_classes);
    for (int c = 0; c < num_classes; ++c) increments[c] += row[c];
  }
}

}  // namespace evidential_octomap
