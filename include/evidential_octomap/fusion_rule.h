// One fusion interface, three rules (docs/design.md): dempster (the paper), sbki, ebs.
//
// Every rule keeps C floats per semantic voxel (the "payload") and every rule is additive in its
// own representation, so a scan's contributions can be summed per voxel first and applied once:
//   dempster: payload^c = L^c = sum log1p(e_hat^c / C)   (evidence-space Dempster, exact, stable)
//   sbki:     payload^c = alpha^c, prior alpha0, += k'(d, l, sigma0) * onehot(argmax e_i)
//   ebs:      payload^c = alpha^c, prior 1,     += k(x_i, x) * alpha_i^c / S_i
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

enum class FusionRuleType { kDempster = 0, kSbki = 1, kEbs = 2 };
inline const std::vector<std::string> kFusionRuleNames{"dempster", "sbki", "ebs"};

// What one point brings to the map: its evidence and the opinion derived from it.
struct PointOpinion {
  const float* evidence = nullptr;  // C values, each finite and >= 0
  double strength = 0.0;            // S = sum(e) + C
  double uncertainty = 1.0;         // u = C / S
  int argmax = -1;                  // class with most evidence, -1 when all evidence is zero
};

// What a voxel says when read back.
struct VoxelOpinion {
  int label = -1;             // argmax class; -1 when the voxel has no semantic evidence
  float uncertainty = 1.0f;   // dempster: mass u in (0, 1]; sbki/ebs: Dirichlet variance of label
  std::vector<float> belief;  // dempster: belief masses b^c; sbki/ebs: expected probabilities
  // Conflict in [0, 1): how much of the evidence fused into the voxel disagreed, 0 when it all
  // supports one class (or there is none).
  //   dempster: 1 + ln(u) / sum_c L^c, the share of the fused log-evidence that Dempster's
  //             normalisation discarded (for one-hot inputs exactly the accumulated conflict
  //             -sum ln(1 - delta) over all fusions, divided by the log-evidence brought in);
  //   sbki/ebs: the share of the added counts sum(alpha - prior) not on the label.
  float conflict = 0.0f;
  // P(label wrong) of the calibration's error model (error_model.h) when the rule has one, else
  // -1; FusionRule::errorProbability answers either way.
  float error_probability = -1.0f;
};

class ErrorModel;

class FusionRule {
 public:
  virtual ~FusionRule() = default;

  virtual FusionRuleType type() const = 0;
  const std::string& name() const { return kFusionRuleNames[static_cast<int>(type())]; }

  // Value of every class entry in a voxel that has seen no evidence yet.
  virtual float prior() const = 0;
  // Whether the kernel length adapts to u and the most uncertain points are dropped
  // (S-BKI uses the plain sparse kernel on every point).
  virtual bool usesUncertaintyKernel() const = 0;
  // Whether VoxelOpinion::uncertainty is a mass in [0, 1] (else it needs scaling for the BS).
  virtual bool uncertaintyIsMass() const = 0;

  // Adds the contribution of `point`, weighted by kernel value k in [0, 1], to `increments` (C).
  virtual void contribute(const PointOpinion& point, double k, int num_classes,
                          double* increments) const = 0;
  // Adds a row of increments (or another map's payload minus the prior) to a stored payload,
  // rounding once, and keeps it within what a float stores faithfully (dempster: sum L <=
  // kMaxStoredLogEvidence, scaled down in proportion beyond it).
  virtual void add(float* payload, const double* increments, int num_classes) const;
  // Interprets a payload of C floats.
  virtual VoxelOpinion readout(const float* payload, int num_classes) const = 0;
  // The class probabilities an opinion projects to (C = its belief's size): dempster b^c + u/C,
  // sbki/ebs the expected probabilities it holds; with an error model the label's is 1 - its
  // error probability and the others share the rest in proportion. The Brier score and ECE are
  // of these.
  std::vector<float> probabilities(const VoxelOpinion& opinion) const;
  // The map's probability that the voxel's label is wrong: the error model's when the rule has
  // one (fitted by `calibrate`), else 1 - max_c p_c, the read-out that detects wrong labels best
  // across datasets without labels (docs/experiments/results.md); 1 without a label.
  float errorProbability(const VoxelOpinion& opinion) const;
  // The error model the read-out applies (dempster only: ErrorModel's features are of L);
  // null removes it. Throws std::invalid_argument for another rule.
  void setErrorModel(std::shared_ptr<const ErrorModel> model);
  const std::shared_ptr<const ErrorModel>& errorModel() const { return error_model_; }

  // The rule of a map's settings (rule, sbki_prior, evidence_cap).
  static std::unique_ptr<FusionRule> create(const SemanticConfig& config);
  static std::unique_ptr<FusionRule> create(FusionRuleType type, float sbki_prior = 0.001f,
                                            double evidence_cap = 0.0);
  // Throws std::invalid_argument naming the valid rules when `name` is unknown.
  static std::unique_ptr<FusionRule> create(const std::string& name, float sbki_prior = 0.001f);

 protected:
  std::shared_ptr<const ErrorModel> error_model_;
};

FusionRuleType fusionRuleFromName(const std::string& name);

// Bound of the dempster payload, sum_c L^c. A float holding L < 1024 keeps
// increments down to 2^-15 (3e-5); without a bound L passes 2^18 after ~10^4 scans of one voxel
// and whole scans of evidence vanish in rounding. At the bound the map forgets old evidence in
// proportion, like OctoMap's clamping: from there on the result depends on the order of the
// scans, and merged chunk maps equal the sequential map only while no voxel has reached it
// (tens of scans of one voxel; none on the bundled 10-scan sequence, where the bound changes no
// metric). The read-out cap (SemanticConfig::evidence_cap) only sees proportions, which the
// bound keeps.
inline constexpr double kMaxStoredLogEvidence = 1024.0;

}  // namespace evidential_octomap
