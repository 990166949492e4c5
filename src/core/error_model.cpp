#include "evidential_octomap/error_model.h"

#include "evidential_octomap/subjective_logic.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap {

namespace {

double logit(double p) {
  p = std::clamp(p, 1e-7, 1.0 - 1e-7);
  return std::log(p / (1.0 - p));
}

double sigmoid(double z) { return z >= 0 ? 1.0 / (1.0 + std::exp(-z)) : std::exp(z) / (1.0 + std::exp(z)); }

// ln of sum_c e^(L^c) over the classes c with `include(c)`, without overflow or underflow
// (L reaches 1024); -inf for none.
template <class Include>
double logSumExp(const float* payload, int num_classes, Include include) {
  double top = -INFINITY;
  for (int c = 0; c < num_classes; ++c)
    if (include(c)) top = std::max(top, double(payload[c]));
  if (top == -INFINITY) return top;
  double sum = 0.0;
  for (int c = 0; c < num_classes; ++c)
    if (include(c)) sum += std::exp(double(payload[c]) - top);
  return top + std::log(sum);
}

// ln of the label's Dirichlet variance p (1 - p) / (S + 1) with alpha^c = e^(L^c), in logs.
// Bounded below so that a voxel whose other classes hold no evidence at all stays finite.
double logDirichletVariance(const float* payload, int label, int num_classes) {
  const double log_s = logSumExp(payload, num_classes, [](int) { return true; });
  const double log_rest = logSumExp(payload, num_classes, [label](int c) { return c != label; });
  const double log_p = double(payload[label]) - log_s;
  const double log_s1 = log_s > 30.0 ? log_s : std::log1p(std::exp(log_s));
  return std::max(log_p + log_rest - log_s - log_s1, -4096.0);
}

}  // namespace

const std::array<const char*, ErrorModel::kNumFeatures>& ErrorModel::featureNames() {
  static const std::array<const char*, kNumFeatures> names{
      "error_readout", "vacuity", "dissonance", "conflict", "dirichlet_variance",
      "evidence_mass", "label_share"};
  return names;
}

ErrorModel::Features ErrorModel::features(const float* payload, const VoxelOpinion& o,
                                          int num_classes) {
  double total = 0.0;
  for (int c = 0; c < num_classes; ++c) total += payload[c];
  const double best = *std::max_element(o.belief.begin(), o.belief.end());
  const double error = 1.0 - (best + o.uncertainty / num_classes);
  return {logit(error),
          std::log(std::max(double(o.uncertainty), 1e-12)),
          dissonance(o.belief),
          double(o.conflict),
          logDirichletVariance(payload, o.label, num_classes),
          std::log1p(total),
          total > 0.0 ? payload[o.label] / total : 0.0};
}

ErrorModel::Term ErrorModel::parse(const std::string& text) {
  Term t;
  if (text == "intercept") return t;
  if (text.rfind("label=", 0) == 0) {
    size_t used = 0;
    try {
      t.index = std::stoi(text.substr(6), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != text.size() - 6 || t.index < 0) {
      throw std::invalid_argument("error model term '" + text + "': label=<class index>");
    }
    t.kind = Term::kLabel;
    return t;
  }
  const size_t gt = text.find('>');
  const std::string name = text.substr(0, gt);
  const auto& names = featureNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    throw std::invalid_argument("error model term '" + text + "': unknown feature '" + name + "'");
  }
  t.index = int(it - names.begin());
  t.kind = gt == std::string::npos ? Term::kFeature : Term::kHinge;
  if (t.kind == Term::kHinge) {
    size_t used = 0;
    const std::string knot = text.substr(gt + 1);
    try {
      t.knot = std::stod(knot, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != knot.size() || !std::isfinite(t.knot)) {
      throw std::invalid_argument("error model term '" + text + "': the knot is not a number");
    }
  }
  return t;
}

ErrorModel::ErrorModel(const std::vector<std::string>& terms, const std::vector<double>& weights)
    : weights_(weights) {
  if (terms.size() != weights.size() || terms.empty()) {
    throw std::invalid_argument("error model: " + std::to_string(terms.size()) + " terms but " +
                                std::to_string(weights.size()) + " weights");
  }
  for (const std::string& text : terms) terms_.push_back(parse(text));
  for (double w : weights) {
    if (!std::isfinite(w)) throw std::invalid_argument("error model: a weight is not finite");
  }
}

double ErrorModel::value(const Term& t, const Features& x, int label) {
  switch (t.kind) {
    case Term::kIntercept:
      return 1.0;
    case Term::kFeature:
      return x[t.index];
    case Term::kHinge:
      return std::max(0.0, x[t.index] - t.knot);
    case Term::kLabel:
      return label == t.index ? 1.0 : 0.0;
  }
  return 0.0;
}

double ErrorModel::probability(const Features& x, int label) const {
  double z = 0.0;
  for (size_t j = 0; j < terms_.size(); ++j) z += weights_[j] * value(terms_[j], x, label);
  return sigmoid(z);
}

std::vector<std::string> ErrorModel::terms() const {
  std::vector<std::string> out;
  for (const Term& t : terms_) {
    std::ostringstream s;
    s.precision(17);
    if (t.kind == Term::kIntercept) s << "intercept";
    if (t.kind == Term::kFeature) s << featureNames()[t.index];
    if (t.kind == Term::kHinge) s << featureNames()[t.index] << '>' << t.knot;
    if (t.kind == Term::kLabel) s << "label=" << t.index;
    out.push_back(s.str());
  }
  return out;
}

}  // namespace evidential_octomap
