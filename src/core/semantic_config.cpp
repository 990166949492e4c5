#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap {

void SemanticConfig::print(std::ostream& out) const {
  out << "rule: " << rule << "\n"
      << "length_scale: " << length_scale << "\n"
      << "sigma0: " << sigma0 << "\n"
      << "beta: " << beta << "\n"
      << "gamma: " << gamma << (reference_compat ? " (reference_compat: 0 used)" : "") << "\n"
      << "drop_percent: " << drop_percent << "\n"
      << "adaptive_length: " << (adaptive_length ? "true" : "false") << "\n"
      << "uncertainty_threshold: " << (uncertainty_threshold ? "true" : "false") << "\n"
      << "reference_compat: " << (reference_compat ? "true" : "false") << "\n"
      << "sbki_prior: " << sbki_prior << "\n"
      << "ds_multiplier: " << ds_multiplier << "\n"
      << "max_range: " << max_range << "\n"
      << "kernel_creates_leaves: " << (kernel_creates_leaves ? "true" : "false") << "\n"
      << "discretize: " << (discretize ? "true" : "false") << "\n"
      << "threads: " << threads << "\n";
}

}  // namespace evidential_octomap
