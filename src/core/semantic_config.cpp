#include "evidential_octomap/semantic_config.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "evidential_octomap/fusion_rule.h"
#include "evidential_octomap/settings.h"

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
  const std::string problem = settingsProblem(*this);
  if (!problem.empty()) return problem;
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
  for (const Setting& s : settingList()) {
    const std::string name = s.name;
    out << name << ": " << s.valueText(*this);
    if (name == "gamma" && effectiveGamma() != gamma) out << " (0 used)";
    if (name == "uncertainty_threshold" && effectiveThreshold() != uncertainty_threshold)
      out << " (on: reference_compat)";
    if (name == "downsampling" && effectiveDownsampling() != downsampling)
      out << " (count_cap used)";
    out << "\n";
  }
}

double InsertSettings::clearingKeep(int clearings) {
  if (clearings <= 0) return 1.0;
  return std::pow(0.5 * kReleasedEvidence / kMaxStoredLogEvidence, 1.0 / clearings);
}

int InsertSettings::clearingsOf(bool movable) const {
  if (!movable || movable_clearing_observations <= 0) return clearing_observations;
  if (clearing_observations <= 0) return movable_clearing_observations;
  return std::min(clearing_observations, movable_clearing_observations);
}

double MapSettings::adaptiveEvidenceCap(double mean_point_log_evidence) {
  if (!(mean_point_log_evidence > 0.0)) return kMinAdaptiveCap;
  const double cap = kAdaptiveCapScale * std::pow(mean_point_log_evidence, kAdaptiveCapExponent);
  return std::clamp(cap, kMinAdaptiveCap, kMaxAdaptiveCap);
}

}  // namespace evidential_octomap
