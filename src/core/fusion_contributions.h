// What one point adds to a voxel's row under each rule (fusion_rule.h), as a function of the
// kernel value k: set up once per point, applied to every voxel of its support. The rules'
// FusionRule::contribute and the kernel loop (kernel_pass.h, templated on these, so the inner
// loop makes no virtual call) both use them: one implementation per rule. Private to the core.
#pragma once

#include <algorithm>
#include <cstdint>

#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/fusion_rule.h"
#include "fast_log1p.h"

namespace evidential_octomap {

// dempster: L^c += log1p(e_hat^c / C) over the classes with evidence (one for one-hot input).
class DempsterContribution {
 public:
  DempsterContribution(const PointOpinion& point, int num_classes)
      : strength_(point.strength), num_classes_(num_classes) {
    for (int c = 0; c < num_classes; ++c) {
      if (point.evidence[c] > 0.0f) {
        classes_[count_] = static_cast<uint8_t>(c);
        evidence_[count_++] = point.evidence[c];
      }
    }
  }
  void operator()(double k, double* row) const {
    if (k <= 0.0) return;
    // The extended belief is an opinion only for k in [0, 1] (sigma0 > 1 can exceed 1).
    k = std::min(k, 1.0);
    // Extended belief b~ = k b, u~ = 1 - k (1 - u); e_hat / C = b~ / u~ = k e / (S (1 - k) + k C),
    // written so that huge S (evidence near FLT_MAX) does not cancel to 0 at k = 1.
    const double factor = k / (strength_ * (1.0 - k) + k * num_classes_);
    for (int i = 0; i < count_; ++i) row[classes_[i]] += fastLog1p(evidence_[i] * factor);
  }

 private:
  double strength_;
  int num_classes_;
  int count_ = 0;  // classes with evidence: the first count_ entries below
  uint8_t classes_[EvidentialOcTree::kMaxClasses];
  double evidence_[EvidentialOcTree::kMaxClasses];
};

// sbki: alpha^argmax += k.
class SbkiContribution {
 public:
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

}  // namespace evidential_octomap
