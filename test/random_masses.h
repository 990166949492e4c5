// Reproducible random opinions and evidence vectors for the property tests (fixed seeds).
#pragma once

#include <random>
#include <vector>

#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap {
namespace test {

class RandomMasses {
 public:
  explicit RandomMasses(unsigned seed) : rng_(seed) {}

  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }

  // A random opinion: a mix of dense, sparse (most beliefs zero), nearly dogmatic and vacuous.
  Opinion opinion(int num_classes) {
    Opinion o;
    o.belief.assign(num_classes, 0.0);
    const int kind = integer(0, 9);
    if (kind == 0) return Opinion::vacuous(num_classes);
    double u = uniform(0.0, 1.0);
    if (kind == 1) u = uniform(1e-6, 1e-3);  // nearly dogmatic
    if (u <= 0.0) u = 1e-9;
    double total = 0.0;
    for (int c = 0; c < num_classes; ++c) {
      const bool sparse = kind == 2 && integer(0, 3) != 0;
      o.belief[c] = sparse ? 0.0 : uniform(0.0, 1.0);
      total += o.belief[c];
    }
    if (total <= 0.0) {
      o.belief[integer(0, num_classes - 1)] = 1.0;
      total = 1.0;
    }
    for (double& b : o.belief) b *= (1.0 - u) / total;
    o.uncertainty = u;
    return o;
  }

  // A random EDL evidence vector: one class usually stronger than the rest.
  std::vector<float> evidence(int num_classes, double max_evidence = 10.0) {
    std::vector<float> e(num_classes);
    for (float& x : e) x = static_cast<float>(uniform(0.0, max_evidence * 0.2));
    e[integer(0, num_classes - 1)] += static_cast<float>(uniform(0.0, max_evidence));
    return e;
  }

  std::mt19937_64& engine() { return rng_; }

 private:
  std::mt19937_64 rng_;
};

}  // namespace test
}  // namespace evidential_octomap
