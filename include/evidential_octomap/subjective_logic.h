// Subjective-logic opinions and the reduced Dempster rule in belief space (docs/design.md).
// The map itself stores the evidence-space form (see fusion_rule.h); these plain functions are
// for users who want to combine opinions directly and for the cross-checks in the tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace evidential_octomap {

// A subjective opinion over C singleton classes: sum(belief) + uncertainty == 1.
struct Opinion {
  std::vector<double> belief;
  double uncertainty = 1.0;

  static Opinion vacuous(int num_classes);
  int numClasses() const { return static_cast<int>(belief.size()); }
  int argmax() const;  // -1 when every belief is zero
};

// EDL opinion of one point: alpha = e + 1, S = sum(alpha), b = e / S, u = C / S.
Opinion opinionFromEvidence(const float* evidence, int num_classes);

// Reduced Dempster rule M1 (+) M2 in O(C). The normaliser 1 - conflict is taken as the sum of the
// unnormalised masses (equal for valid opinions, and free of the cancellation that
// 1 - [(sum b1)(sum b2) - sum b1 b2] suffers near total conflict). Under total conflict the
// result is the vacuous opinion rather than NaN.
Opinion dempsterCombine(const Opinion& m1, const Opinion& m2);

// Dissonance of belief masses (Josang 2018, 4.4.3): sum_k b_k [sum_{j!=k} b_j Bal(b_j, b_k)] /
// [sum_{j!=k} b_j], Bal(a, b) = 1 - |a - b| / (a + b); 0 when one class holds all belief.
double dissonance(const std::vector<float>& belief);

// One evidence value is valid when finite and >= 0 (-0 too). Read from its bits: no branch, so a
// pass over a whole scan's values vectorises.
inline bool validEvidence(float e) {
  uint32_t bits;
  std::memcpy(&bits, &e, sizeof(bits));
  return bits < 0x7F800000u || bits == 0x80000000u;
}

// Checks one evidence vector: every value valid. Returns an empty string when valid, otherwise
// a message naming the offending class and value.
std::string checkEvidence(const float* evidence, int num_classes);

// The evidence E that a derived input (a hard label, or a confident probability vector) gives its
// class: the one default of every such conversion (ROS, CLI, Python, the player).
constexpr float kEvidenceMagnitude = 20.0f;

// Conversions for inputs that are not raw evidence (docs/learned_evidence.md, "your own network").
void evidenceFromAlpha(const float* alpha, int num_classes, float* evidence_out);   // e = alpha - 1
void evidenceFromLabel(int label, int num_classes, float magnitude, float* evidence_out);  // one-hot

// Class probabilities p (e.g. a softmax) -> confidence-scaled evidence
//   e_c = E * p_c * (C * p_max - 1) / (C - 1),
// so a one-hot p gives E on its class (as evidenceFromLabel) and a uniform p gives no evidence
// (u = 1); the argmax is kept and u grows as p flattens. p is normalised by its sum first.
// Returns "" or what is wrong (a value negative or not finite, a sum <= 0).
std::string evidenceFromProbabilities(const float* p, int num_classes, float magnitude,
                                      float* evidence_out);

// How per-class logits z become evidence:
//   softmax   an ordinary (cross-entropy) network: p = softmax(z), then evidenceFromProbabilities;
//   exp       an EDL network trained with exp evidence: e = exp(min(z, 80));
//   softplus  an EDL network trained with softplus evidence: e = log(1 + exp(z)).
enum class LogitTransform { kSoftmax, kExp, kSoftplus };
LogitTransform logitTransformFromName(const std::string& name);  // throws std::invalid_argument
std::string logitTransformName(LogitTransform transform);
// Returns "" or what is wrong (a logit not finite).
std::string evidenceFromLogits(const float* logits, int num_classes, LogitTransform transform,
                               float magnitude, float* evidence_out);

}  // namespace evidential_octomap
