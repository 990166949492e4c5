#include "evidential_octomap/subjective_logic.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap {

Opinion Opinion::vacuous(int num_classes) {
  Opinion o;
  o.belief.assign(num_classes, 0.0);
  o.uncertainty = 1.0;
  return o;
}

int Opinion::argmax() const {
  int best = -1;
  double best_value = 0.0;
  for (int c = 0; c < numClasses(); ++c) {
    if (belief[c] > best_value) {
      best_value = belief[c];
      best = c;
    }
  }
  return best;
}

Opinion opinionFromEvidence(const float* evidence, int num_classes) {
  double strength = num_classes;  // S = sum(e + 1)
  for (int c = 0; c < num_classes; ++c) strength += evidence[c];
  Opinion o;
  o.belief.resize(num_classes);
  for (int c = 0; c < num_classes; ++c) o.belief[c] = evidence[c] / strength;
  o.uncertainty = num_classes / strength;
  return o;
}

Opinion dempsterCombine(const Opinion& m1, const Opinion& m2) {
  const int num_classes = m1.numClasses();
  Opinion out;
  out.belief.resize(num_classes);
  // 1 - delta equals the total unnormalised mass: summing the numerators avoids computing
  // 1 - (conflict) by cancellation, which loses all digits near total conflict.
  double normaliser = m1.uncertainty * m2.uncertainty;
  for (int c = 0; c < num_classes; ++c) {
    out.belief[c] = m1.belief[c] * m2.belief[c] + m1.belief[c] * m2.uncertainty +
                    m2.belief[c] * m1.uncertainty;
    normaliser += out.belief[c];
  }
  if (!(normaliser > 0.0)) return Opinion::vacuous(num_classes);  // total conflict: no NaN
  for (double& b : out.belief) b /= normaliser;
  out.uncertainty = m1.uncertainty * m2.uncertainty / normaliser;
  return out;
}

std::string checkEvidence(const float* evidence, int num_classes) {
  for (int c = 0; c < num_classes; ++c) {
    const float e = evidence[c];
    if (!validEvidence(e)) {
      std::ostringstream msg;
      msg << "evidence of class " << c << " is " << e << " (must be finite and >= 0)";
      return msg.str();
    }
  }
  return {};
}

void evidenceFromAlpha(const float* alpha, int num_classes, float* evidence_out) {
  for (int c = 0; c < num_classes; ++c) evidence_out[c] = alpha[c] - 1.0f;
}

void evidenceFromLabel(int label, int num_classes, float magnitude, float* evidence_out) {
  for (int c = 0; c < num_classes; ++c) evidence_out[c] = (c == label) ? magnitude : 0.0f;
}

std::string evidenceFromProbabilities(const float* p, int num_classes, float magnitude,
                                      float* evidence_out) {
  double sum = 0.0, max = 0.0;
  for (int c = 0; c < num_classes; ++c) {
    if (!std::isfinite(p[c]) || p[c] < 0.0f) {
      std::ostringstream msg;
      msg << "probability of class " << c << " is " << p[c] << " (must be finite and >= 0)";
      return msg.str();
    }
    sum += p[c];
    max = std::max(max, double(p[c]));
  }
  if (!(sum > 0.0)) return "probabilities sum to 0";
  const int C = num_classes;
  const double confidence = C > 1 ? std::max(0.0, (C * max / sum - 1.0) / (C - 1)) : 1.0;
  for (int c = 0; c < C; ++c) {
    evidence_out[c] = float(magnitude * (p[c] / sum) * confidence);
  }
  return {};
}

LogitTransform logitTransformFromName(const std::string& name) {
  if (name == "softmax") return LogitTransform::kSoftmax;
  if (name == "exp") return LogitTransform::kExp;
  if (name == "softplus") return LogitTransform::kSoftplus;
  throw std::invalid_argument("logit transform '" + name +
                              "' is unknown; use softmax, exp or softplus");
}

std::string logitTransformName(LogitTransform transform) {
  switch (transform) {
    case LogitTransform::kSoftmax: return "softmax";
    case LogitTransform::kExp: return "exp";
    case LogitTransform::kSoftplus: return "softplus";
  }
  return "?";
}

std::string evidenceFromLogits(const float* z, int num_classes, LogitTransform transform,
                               float magnitude, float* evidence_out) {
  double zmax = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < num_classes; ++c) {
    if (!std::isfinite(z[c])) {
      std::ostringstream msg;
      msg << "logit of class " << c << " is " << z[c] << " (must be finite)";
      return msg.str();
    }
    zmax = std::max(zmax, double(z[c]));
  }
  switch (transform) {
    case LogitTransform::kExp:
      for (int c = 0; c < num_classes; ++c) evidence_out[c] = float(std::exp(std::min(z[c], 80.0f)));
      return {};
    case LogitTransform::kSoftplus:
      for (int c = 0; c < num_classes; ++c) {
        evidence_out[c] = z[c] > 20.0f ? z[c] : float(std::log1p(std::exp(double(z[c]))));
      }
      return {};
    case LogitTransform::kSoftmax: {
      std::vector<float> p(static_cast<size_t>(num_classes));
      for (int c = 0; c < num_classes; ++c) p[size_t(c)] = float(std::exp(double(z[c]) - zmax));
      return evidenceFromProbabilities(p.data(), num_classes, magnitude, evidence_out);
    }
  }
  return {};
}

double dissonance(const std::vector<float>& belief) {
  double total = 0.0;
  const size_t n = belief.size();
  for (size_t k = 0; k < n; ++k) {
    if (!(belief[k] > 0.0f)) continue;
    double others = 0.0, balanced = 0.0;
    for (size_t j = 0; j < n; ++j) {
      if (j == k || !(belief[j] > 0.0f)) continue;
      others += belief[j];
      balanced += belief[j] * (1.0 - std::fabs(double(belief[j]) - belief[k]) /
                                         (double(belief[j]) + belief[k]));
    }
    if (others > 0.0) total += belief[k] * balanced / others;
  }
  return total;
}

}  // namespace evidential_octomap
