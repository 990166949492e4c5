// A slow, obviously-correct reference for the reduced Dempster rule (docs/design.md), in long
// double and in belief space, with the conflict summed pair by pair in O(C^2). The tests
// cross-check the library's belief-space function and its evidence-space map storage against it.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace evidential_octomap {
namespace test {

struct RefOpinion {
  std::vector<long double> belief;
  long double uncertainty = 1.0L;
};

inline RefOpinion refVacuous(int num_classes) {
  RefOpinion o;
  o.belief.assign(num_classes, 0.0L);
  return o;
}

// EDL: alpha = e + 1, S = sum alpha, b = e / S, u = C / S.
inline RefOpinion refFromEvidence(const std::vector<float>& evidence) {
  const int num_classes = static_cast<int>(evidence.size());
  long double strength = num_classes;
  for (float e : evidence) strength += e;
  RefOpinion o;
  for (float e : evidence) o.belief.push_back(e / strength);
  o.uncertainty = num_classes / strength;
  return o;
}

// Extended belief of a point at kernel value k: b~ = k b, u~ = 1 - k (1 - u).
inline RefOpinion refExtend(const RefOpinion& m, long double k) {
  RefOpinion o;
  for (long double b : m.belief) o.belief.push_back(k * b);
  o.uncertainty = 1.0L - k * (1.0L - m.uncertainty);
  return o;
}

// M1 (+) M2 with delta = sum over i != j of b1^i b2^j. Returns false under total conflict.
inline bool refCombine(const RefOpinion& m1, const RefOpinion& m2, RefOpinion* out) {
  const size_t n = m1.belief.size();
  long double conflict = 0.0L;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i != j) conflict += m1.belief[i] * m2.belief[j];
    }
  }
  const long double norm = 1.0L - conflict;
  if (!(norm > 0.0L)) return false;
  out->belief.assign(n, 0.0L);
  for (size_t c = 0; c < n; ++c) {
    out->belief[c] = (m1.belief[c] * m2.belief[c] + m1.belief[c] * m2.uncertainty +
                      m2.belief[c] * m1.uncertainty) /
                     norm;
  }
  out->uncertainty = m1.uncertainty * m2.uncertainty / norm;
  return true;
}

inline RefOpinion refCombine(const RefOpinion& m1, const RefOpinion& m2) {
  RefOpinion out;
  if (!refCombine(m1, m2, &out)) return refVacuous(static_cast<int>(m1.belief.size()));
  return out;
}

// The evidence-space form worked out independently: with e_hat = C b / u, the quantity
// 1 + e_hat / C multiplies under (+). Fusing the opinions m_i gives
//   L^c = sum_i log(1 + b_i^c / u_i),  u = 1 / (sum_c e^{L^c} - C + 1),  b^c = (e^{L^c} - 1) u.
// Used where thousands of sequential belief-space steps would themselves lose precision.
struct RefEvidenceSum {
  std::vector<long double> log_factor;  // L^c
  explicit RefEvidenceSum(int num_classes) : log_factor(num_classes, 0.0L) {}
  void add(const RefOpinion& m) {
    for (size_t c = 0; c < log_factor.size(); ++c) {
      log_factor[c] += std::log1p(m.belief[c] / m.uncertainty);
    }
  }
  RefOpinion opinion() const {
    long double m = 0.0L;
    for (long double l : log_factor) m = std::fmax(m, l);
    // Scaled by e^-m: u = e^-m / (sum_c (e^{L-m} - e^-m) + e^-m).
    const long double scale = std::exp(-m);
    long double denominator = scale;
    std::vector<long double> mass;
    for (long double l : log_factor) {
      mass.push_back(std::exp(l - m) - scale);
      denominator += mass.back();
    }
    RefOpinion o;
    for (long double x : mass) o.belief.push_back(x / denominator);
    o.uncertainty = scale / denominator;
    return o;
  }
};

// The map's rule as defined (fusion_rule.h), in long double: L^c accumulates the log-factors of
// each update; when sum L passes `bound` every L^c is scaled down to sum L = bound; the opinion
// is read with L scaled to sum L <= cap (cap <= 0: no cap).
struct RefBoundedEvidence {
  std::vector<long double> log_factor;
  long double bound, cap;
  RefBoundedEvidence(int num_classes, long double bound, long double cap)
      : log_factor(num_classes, 0.0L), bound(bound), cap(cap) {}
  // One voxel update: the summed increments of a scan.
  void add(const std::vector<long double>& increments) {
    long double total = 0.0L;
    for (size_t c = 0; c < log_factor.size(); ++c) total += log_factor[c] + increments[c];
    const long double scale = total > bound ? bound / total : 1.0L;
    for (size_t c = 0; c < log_factor.size(); ++c) {
      log_factor[c] = (log_factor[c] + increments[c]) * scale;
    }
  }
  RefOpinion opinion() const {
    long double total = 0.0L;
    for (long double l : log_factor) total += l;
    RefEvidenceSum capped(static_cast<int>(log_factor.size()));
    const long double scale = cap > 0.0L && total > cap ? cap / total : 1.0L;
    for (size_t c = 0; c < log_factor.size(); ++c) capped.log_factor[c] = log_factor[c] * scale;
    return capped.opinion();
  }
};

}  // namespace test
}  // namespace evidential_octomap
