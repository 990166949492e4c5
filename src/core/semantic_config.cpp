#include "evidential_octomap/semantic_config.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "evidential_octomap/fusion_rule.h"

namespace evidential_octomap {
namespace {

// "name = value must be <what>" for the first failing check.
std::string outOfRange(const char* name, double value, const char* what) {
  std::ostringstream s;
  s << name << " = " << value << " must be " << what;
  return s.str();
}

}  // namespace

double SemanticConfig::maxSupportLength() const {
  // Uncertainty kernels: l * beta * exp(1 - gamma * u) over u in [0, 1] (gamma 0 without the
  // adaptive length); S-BKI: l.
  const double adaptive = length_scale * beta * std::exp(1.0 + std::max(0.0, -effectiveGamma()));
  return std::max(adaptive, length_scale);
}

std::string SemanticConfig::problem() const {
  if (std::find(kFusionRuleNames.begin(), kFusionRuleNames.end(), rule) == kFusionRuleNames.end())
    return "rule '" + rule + "' is unknown; use dempster, sbki or ebs";
  // Written so that NaN fails every check.
  if (!(std::isfinite(length_scale) && length_scale > 0.0))
    return outOfRange("length_scale", length_scale, "finite and > 0");
  if (!(std::isfinite(beta) && beta > 0.0)) return outOfRange("beta", beta, "finite and > 0");
  if (!std::isfinite(gamma)) return outOfRange("gamma", gamma, "finite");
  if (!(std::isfinite(sigma0) && sigma0 > 0.0))
    return outOfRange("sigma0", sigma0, "finite and > 0");
  if (!(drop_percent >= 0.0 && drop_percent < 100.0))
    return outOfRange("drop_percent", drop_percent, "in [0, 100)");
  if (!(std::isfinite(sbki_prior) && sbki_prior > 0.0f))
    return outOfRange("sbki_prior", sbki_prior, "finite and > 0");
  if (!(evidence_cap == kAdaptiveCap || (std::isfinite(evidence_cap) && evidence_cap >= 0.0)))
    return outOfRange("evidence_cap", evidence_cap, "-1 (adaptive) or finite and >= 0 (0: no cap)");
  if (!(std::isfinite(evidence_floor) && evidence_floor >= 0.0))
    return outOfRange("evidence_floor", evidence_floor, "finite and >= 0 (0: off)");
  if (downsampling != "average" && downsampling != "count_cap")
    return "downsampling '" + downsampling + "' is unknown; use average or count_cap";
  if (kernel_distance != "voxel" && kernel_distance != "centre")
    return "kernel_distance '" + kernel_distance + "' is unknown; use voxel or centre";
  if (!(ds_multiplier <= kMaxDsMultiplier))  // <= 0 (and -inf) switch down-sampling off
    return outOfRange("ds_multiplier", ds_multiplier, "<= 1000 (<= 0: off)");
  if (std::isnan(max_range)) return outOfRange("max_range", max_range, "a number (< 0: unlimited)");
  if (!(clearing_observations >= 0 && clearing_observations <= kMaxClearingObservations))
    return outOfRange("clearing_observations", clearing_observations, "in [0, 1000] (0: off)");
  if (!(threads >= 0 && threads <= kMaxThreads))
    return outOfRange("threads", threads, "in [0, 1024] (0: OpenMP default)");
  if (!std::isfinite(maxSupportLength()))
    return outOfRange("length_scale * beta * exp(1 - gamma * u)", maxSupportLength(), "finite");
  return "";
}

std::string SemanticConfig::supportProblem(double resolution) const {
  const double support = maxSupportLength();
  const double limit = kMaxSupportLeaves * resolution;
  if (support <= limit) return "";
  std::ostringstream s;
  s << "kernel support up to " << support << " m (length_scale " << length_scale << " * beta "
    << beta << " * e^(1 - gamma u), u -> " << (effectiveGamma() < 0.0 ? "1" : "0") << ") is "
    << support / resolution << " leaves at resolution " << resolution << " m; at most "
    << kMaxSupportLeaves << " leaves (" << limit
    << " m) are affordable: lower length_scale or beta, or use a coarser resolution";
  return s.str();
}

const std::string& SemanticConfig::effectiveDownsampling() const {
  static const std::string count_cap = "count_cap";
  return reference_compat ? count_cap : downsampling;
}

void SemanticConfig::print(std::ostream& out) const {
  out << "rule: " << rule << "\n"
      << "length_scale: " << length_scale << "\n"
      << "sigma0: " << sigma0 << "\n"
      << "beta: " << beta << "\n"
      << "gamma: " << gamma << (effectiveGamma() != gamma ? " (0 used)" : "") << "\n"
      << "drop_percent: " << drop_percent << "\n"
      << "adaptive_length: " << (adaptive_length ? "true" : "false") << "\n"
      << "uncertainty_threshold: " << (uncertainty_threshold ? "true" : "false")
      << (effectiveThreshold() != uncertainty_threshold ? " (on: reference_compat)" : "") << "\n"
      << "reference_compat: " << (reference_compat ? "true" : "false") << "\n"
      << "sbki_prior: " << sbki_prior << "\n"
      << "evidence_cap: " << evidence_cap << "\n"

      << "downsampling: " << downsampling
      << (effectiveDownsampling() != downsampling ? " (count_cap used)" : "") << "\n"
      << "ds_multiplier: " << ds_multiplier << "\n"
      << "kernel_distance: " << kernel_distance << "\n"
      << "max_range: " << max_range << "\n"
      << "kernel_creates_leaves: " << (kernel_creates_leaves ? "true" : "false") << "\n"
      << "discretize: " << (discretize ? "true" : "false") << "\n"
      << "fast_free_space: " << (fast_free_space ? "true" : "false") << "\n"
      << "semantic_occupied_only: " << (semantic_occupied_only ? "true" : "false") << "\n"
      << "evidence_floor: " << evidence_floor << "\n"
      << "clearing_observations: " << clearing_observations << "\n"
      << "threads: " << threads << "\n";
}

double SemanticConfig::clearingKeep() const {
  if (clearing_observations <= 0) return 1.0;
  return std::pow(0.5 * kReleasedEvidence / kMaxStoredLogEvidence, 1.0 / clearing_observations);
}

double SemanticConfig::adaptiveEvidenceCap(double mean_point_log_evidence) {
  if (!(mean_point_log_evidence > 0.0)) return kMinAdaptiveCap;
  const double cap = kAdaptiveCapScale * std::pow(mean_point_log_evidence, kAdaptiveCapExponent);
  return std::clamp(cap, kMinAdaptiveCap, kMaxAdaptiveCap);
}

}  // namespace evidential_octomap
