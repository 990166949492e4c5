#include "evidential_octomap/subjective_logic.h"

#include <cmath>
#include <sstream>

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
    if (!std::isfinite(e) || e < 0.0f) {
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

}  // namespace evidential_octomap
