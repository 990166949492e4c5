#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

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
      << "uncertainty_threshold: " << (uncertainty_threshold ? "true" : "false") << "\n"
      << "reference_compat: " << (reference_compat ? "true" : "false") << "\n"
      << "sbki_prior: " << sbki_prior << "\n"
      << "downsampling: " << downsampling
      << (effectiveDownsampling() != downsampling ? " (count_cap used)" : "") << "\n"
      << "ds_multiplier: " << ds_multiplier << "\n"
      << "kernel_distance: " << kernel_distance << "\n"
      << "max_range: " << max_range << "\n"
      << "kernel_creates_leaves: " << (kernel_creates_leaves ? "true" : "false") << "\n"
      << "discretize: " << (discretize ? "true" : "false") << "\n"
      << "threads: " << threads << "\n";
}

}  // namespace evidential_octomap
