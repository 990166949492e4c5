// The three fusion rules behind FusionRule (see fusion_rule.h for what each payload holds).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "evidential_octomap/fusion_rule.h"

#include "evidential_octomap/error_model.h"
#include "fusion_contributions.h"

namespace evidential_octomap {
namespace {

int argmaxAbove(const float* values, int num_classes, float floor) {
  int best = -1;
  float best_value = floor;
  for (int c = 0; c < num_classes; ++c) {
    if (values[c] > best_value) {
      best_value = values[c];
      best = c;
    }
  }
  return best;
}

// Evidence-space Dempster (docs/design.md, "Fusion"): L^c = sum log1p(e_hat^c / C).
class DempsterRule : public FusionRule {
 public:
  explicit DempsterRule(double evidence_cap) : cap_(evidence_cap) {}
  FusionRuleType type() const override { return FusionRuleType::kDempster; }
  float prior() const override { return 0.0f; }  // vacuous
  bool usesUncertaintyKernel() const override { return true; }
  bool uncertaintyIsMass() const override { return true; }

  void contribute(const PointOpinion& point, double k, int num_classes,
                  double* increments) const override {
    contributeOnce<DempsterContribution>(point, k, num_classes, increments);
  }

  void add(float* payload, const double* increments, int num_classes) const override {
    double total = 0.0;
    for (int c = 0; c < num_classes; ++c) total += double(payload[c]) + increments[c];
    const double scale = total > kMaxStoredLogEvidence ? kMaxStoredLogEvidence / total : 1.0;
    for (int c = 0; c < num_classes; ++c) {
      payload[c] = static_cast<float>((double(payload[c]) + increments[c]) * scale);
    }
  }

  VoxelOpinion readout(const float* payload, int num_classes) const override {
    VoxelOpinion out;
    out.belief.assign(num_classes, 0.0f);
    double total = 0.0, m = 0.0;
    for (int c = 0; c < num_classes; ++c) {
      total += payload[c];
      m = std::max(m, double(payload[c]));
    }
    if (!(m > 0.0)) return out;  // vacuous: u = 1, no label
    out.label = argmaxAbove(payload, num_classes, 0.0f);
    // The opinion of the log-evidence capped at cap_ (scaled in proportion); the conflict of
    // the evidence actually fused.
    const double scale = cap_ > 0.0 && total > cap_ ? cap_ / total : 1.0;
    const double kept = read(payload, num_classes, scale, m * scale, &out);
    const double kept_uncapped = scale == 1.0 ? kept : read(payload, num_classes, 1.0, m, nullptr);
    out.conflict = static_cast<float>(std::clamp(1.0 - kept_uncapped / total, 0.0, 1.0));
    if (error_model_) {
      out.error_probability = float(error_model_->probability(payload, out, num_classes));
    }
    return out;
  }

 private:
  // u = 1 / (sum e^L - C + 1), b = (e^L - 1) u for L = scale * payload (into `out` when given),
  // evaluated with the largest L (m) subtracted. Every term is >= 0, so nothing cancels:
  // e^(L-m) - e^-m = e^(L-m) * -expm1(-L). Returns -ln u: the log-evidence the opinion kept.
  static double read(const float* payload, int num_classes, double scale, double m,
                     VoxelOpinion* out) {
    const double floor = std::exp(-m);
    double denominator = floor;
    for (int c = 0; c < num_classes; ++c) {
      // A class without evidence has mass 0 (e^(-m) * 0): most of a voxel's classes, and the
      // two exponentials are most of a read-out's cost.
      if (payload[c] == 0.0f) continue;
      const double l = scale * payload[c];
      const double mass = std::exp(l - m) * -std::expm1(-l);
      if (out) out->belief[c] = static_cast<float>(mass);  // divided below
      denominator += mass;
    }
    if (out) {
      for (int c = 0; c < num_classes; ++c) out->belief[c] = float(out->belief[c] / denominator);
      out->uncertainty = static_cast<float>(floor / denominator);
    }
    return m + std::log(denominator);
  }

  double cap_;
};

// Dirichlet-count rules (S-BKI and evidential BKI) share their read-out.
class DirichletRule : public FusionRule {
 public:
  explicit DirichletRule(float prior) : prior_(prior) {}
  float prior() const override { return prior_; }
  bool uncertaintyIsMass() const override { return false; }

  VoxelOpinion readout(const float* alpha, int num_classes) const override {
    VoxelOpinion out;
    out.belief.assign(num_classes, 0.0f);
    double strength = 0.0;
    for (int c = 0; c < num_classes; ++c) strength += alpha[c];
    for (int c = 0; c < num_classes; ++c) out.belief[c] = float(alpha[c] / strength);
    out.label = argmaxAbove(alpha, num_classes, prior_);
    const double added = strength - num_classes * double(prior_);
    if (out.label >= 0 && added > 0.0) {
      out.conflict =
          static_cast<float>(std::clamp(1.0 - (alpha[out.label] - prior_) / added, 0.0, 1.0));
    }
    if (out.label < 0) {
      out.uncertainty = float(1.0 / num_classes * (1.0 - 1.0 / num_classes) / (strength + 1.0));
      return out;
    }
    const double p = alpha[out.label] / strength;
    out.uncertainty = static_cast<float>(p * (1.0 - p) / (strength + 1.0));  // Dirichlet variance
    return out;
  }

 private:
  float prior_;
};

class SbkiRule : public DirichletRule {
 public:
  explicit SbkiRule(float prior) : DirichletRule(prior) {}
  FusionRuleType type() const override { return FusionRuleType::kSbki; }
  bool usesUncertaintyKernel() const override { return false; }
  void contribute(const PointOpinion& point, double k, int num_classes,
                  double* increments) const override {
    contributeOnce<SbkiContribution>(point, k, num_classes, increments);
  }
};

class EbsRule : public DirichletRule {
 public:
  EbsRule() : DirichletRule(1.0f) {}
  FusionRuleType type() const override { return FusionRuleType::kEbs; }
  bool usesUncertaintyKernel() const override { return true; }
  void contribute(const PointOpinion& point, double k, int num_classes,
                  double* increments) const override {
    contributeOnce<EbsContribution>(point, k, num_classes, increments);
  }
};

}  // namespace

FusionRuleType fusionRuleFromName(const std::string& name) {
  for (size_t i = 0; i < kFusionRuleNames.size(); ++i) {
    if (kFusionRuleNames[i] == name) return static_cast<FusionRuleType>(i);
  }
  std::string valid;
  for (const auto& n : kFusionRuleNames) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown fusion rule '" + name + "' (valid: " + valid + ")");
}

std::vector<float> FusionRule::probabilities(const VoxelOpinion& opinion) const {
  if (!uncertaintyIsMass()) return opinion.belief;  // alpha / S
  const float share = opinion.uncertainty / float(opinion.belief.size());
  std::vector<float> p(opinion.belief);
  for (float& value : p) value += share;
  if (opinion.error_probability >= 0.0f && opinion.label >= 0) {
    const double rest = 1.0 - p[opinion.label], error = opinion.error_probability;
    for (size_t c = 0; c < p.size(); ++c) {
      p[c] = int(c) == opinion.label ? float(1.0 - error)
             : rest > 0.0            ? float(p[c] * error / rest)
                                     : float(error / double(p.size() - 1));
    }
  }
  return p;
}

float FusionRule::errorProbability(const VoxelOpinion& opinion) const {
  if (opinion.label < 0 || opinion.belief.empty()) return 1.0f;  // no label: none is right
  if (opinion.error_probability >= 0.0f) return opinion.error_probability;
  // max_c p_c without building p: dempster adds the same share u / C to every class.
  const float best = *std::max_element(opinion.belief.begin(), opinion.belief.end());
  const float share = uncertaintyIsMass() ? opinion.uncertainty / float(opinion.belief.size()) : 0;
  return 1.0f - (best + share);
}

void FusionRule::setErrorModel(std::shared_ptr<const ErrorModel> model) {
  if (model && type() != FusionRuleType::kDempster) {
    throw std::invalid_argument("an error model reads dempster maps, not '" + name() + "'");
  }
  error_model_ = std::move(model);
}

void FusionRule::add(float* payload, const double* increments, int num_classes) const {
  for (int c = 0; c < num_classes; ++c) {
    payload[c] = static_cast<float>(
        std::min(double(payload[c]) + increments[c], double(std::numeric_limits<float>::max())));
  }
}

std::unique_ptr<FusionRule> FusionRule::create(const SemanticConfig& config) {
  return create(fusionRuleFromName(config.rule), config.sbki_prior, config.evidence_cap);
}

std::unique_ptr<FusionRule> FusionRule::create(FusionRuleType type, float sbki_prior,
                                               double evidence_cap) {
  switch (type) {
    case FusionRuleType::kDempster:
      return std::make_unique<DempsterRule>(evidence_cap);
    case FusionRuleType::kSbki:
      return std::make_unique<SbkiRule>(sbki_prior);
    case FusionRuleType::kEbs:
      return std::make_unique<EbsRule>();
  }
  throw std::invalid_argument("unknown fusion rule type");
}

std::unique_ptr<FusionRule> FusionRule::create(const std::string& name, float sbki_prior) {
  return create(fusionRuleFromName(name), sbki_prior);
}

}  // namespace evidential_octomap
