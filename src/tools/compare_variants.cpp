#include "compare_variants.h"

#include <sstream>
#include <stdexcept>

#include "evidential_octomap/settings.h"

namespace evidential_octomap::tools {

namespace {

// The published methods are compared with their own kernel: amplitude 1 and no class
// awareness, not the default's reliability discount and other-class weight (a named variant's
// overrides can still change them).
void publishedKernel(SemanticConfig* c) {
  c->sigma0 = 1.0;
  c->other_class_weight = 1.0;
}

// The paper's Table II rows are named relative to the paper's method (adaptive length and
// threshold both on), whatever the defaults: dempster-no-both is the default's kernel.
SemanticConfig namedVariantConfig(const std::string& v, SemanticConfig c) {
  const auto paper = [&c](bool adaptive, bool threshold) {
    c.rule = "dempster";
    c.adaptive_length = adaptive;
    c.uncertainty_threshold = threshold;
  };
  if (v == "dempster") {
    c.rule = "dempster";
  } else if (v == "dempster-paper") {
    paper(true, true);
  } else if (v == "dempster-no-adaptive") {
    paper(false, true);
  } else if (v == "dempster-no-threshold") {
    paper(true, false);
  } else if (v == "dempster-no-both") {
    paper(false, false);
  } else if (v == "dempster-no-cap") {  // Dempster's product read as is
    c.rule = "dempster";
    c.evidence_cap = 0.0;
  } else if (v == "dempster-centre") {  // kernel distance to voxel centres (a point can miss
    c.rule = "dempster";                // its own voxel)
    c.kernel_distance = "centre";
  } else if (v == "dempster-other-downsampling") {
    c.rule = "dempster";
    c.downsampling = c.downsampling == "average" ? "count_cap" : "average";
  } else if (v == "reference_compat") {  // the authors' released code: no cap either
    c.rule = "dempster";
    c.reference_compat = true;
    c.evidence_cap = 0.0;
    publishedKernel(&c);
  } else if (v == "sbki" || v == "ebs") {
    c.rule = v;
    publishedKernel(&c);
  } else {
    throw std::invalid_argument("unknown variant '" + v + "'");
  }
  return c;
}

}  // namespace

const std::vector<std::string>& variantNames() {
  static const std::vector<std::string> names{"dempster",
                                              "dempster-paper",
                                              "dempster-no-adaptive",
                                              "dempster-no-threshold",
                                              "dempster-no-both",
                                              "dempster-no-cap",
                                              "dempster-centre",
                                              "dempster-other-downsampling",
                                              "reference_compat",
                                              "sbki",
                                              "ebs"};
  return names;
}

SemanticConfig variantConfig(const std::string& variant, const SemanticConfig& base) {
  std::vector<std::string> parts;
  std::stringstream in(variant);
  for (std::string part; std::getline(in, part, ':');) parts.push_back(part);
  if (parts.empty()) throw std::invalid_argument("empty variant");
  SemanticConfig c = namedVariantConfig(parts[0], base);
  for (size_t i = 1; i < parts.size(); ++i) {
    const size_t eq = parts[i].find('=');
    const std::string key = parts[i].substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : parts[i].substr(eq + 1);
    const Setting* setting = findSetting(key);
    if (!setting || !setting->parse(value, &c)) {
      throw std::invalid_argument("variant '" + variant + "': cannot set '" + parts[i] +
                                  "' (key=value of a setting of docs/parameters.md; booleans "
                                  "0/1 or false/true)");
    }
  }
  const std::string problem = c.problem();
  if (!problem.empty()) throw std::invalid_argument("variant '" + variant + "': " + problem);
  return c;
}

std::vector<std::string> RunPlan::variantsFor(const std::string& protocol,
                                              const std::string& source) const {
  if (name == "full" || explicit_selection) return variants;
  if (protocol == "held-out") {
    return source == "onehot" ? std::vector<std::string>{"dempster", "sbki", "ebs"}
                              : std::vector<std::string>{};
  }
  if (source == "onehot") return variants;
  if (name == "extended") return {"dempster", "dempster-paper", "sbki", "ebs"};
  return {"dempster", "dempster-paper"};
}

}  // namespace evidential_octomap::tools
