// `compare`'s rows: the named variants (the paper's Table II relative to its method, the rules),
// their key=value overrides (any setting of docs/parameters.md) and which variants each plan runs.
#pragma once

#include <string>
#include <vector>

#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::tools {

// The variant names --variants accepts (without overrides), in the default order.
const std::vector<std::string>& variantNames();

// A named variant, optionally followed by setting overrides that make an ablation row:
// "dempster:drop_percent=0:evidence_cap=2". Throws std::invalid_argument.
SemanticConfig variantConfig(const std::string& variant, const SemanticConfig& base);

// Which runs a plan makes. default: every variant with onehot evidence; dempster and
// dempster-paper for the other sources (what each source does to the paper's uncertainty
// mechanisms); held-out: dempster, sbki, ebs with onehot. extended: also sbki and ebs for the
// other sources. full (or an explicit --sources/--variants/--protocols): every variant.
struct RunPlan {
  std::string name = "default";  // default | extended | full
  bool explicit_selection = false;
  std::vector<std::string> variants = variantNames();
  std::vector<std::string> variantsFor(const std::string& protocol,
                                       const std::string& source) const;
};

}  // namespace evidential_octomap::tools
