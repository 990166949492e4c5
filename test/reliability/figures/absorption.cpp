// Issue 16 item 8 before/after: one dempster voxel filled past 2^18 of log-evidence, then 1000
// small increments (tie and flip cases), beside the unbounded rule in long double.
// OLD_WRITERS: the payload update main had before the fix (payload[c] += float(increment)).
#include <cmath>
#include <cstdio>
#include <vector>

#include "evidential_octomap/fusion_rule.h"

using namespace evidential_octomap;

// Unbounded dempster read-out of log-evidence L: b_c = (e^L_c - 1) / (sum e^L - C + 1).
std::vector<long double> exactBeliefs(const std::vector<long double>& L) {
  long double top = L[0], sum = 0.0L;
  for (long double x : L) top = std::max(top, x);
  for (long double x : L) sum += std::exp(x - top);
  const long double denominator = sum - (L.size() - 1) * std::exp(-top);
  std::vector<long double> b;
  for (long double x : L) b.push_back((std::exp(x - top) - std::exp(-top)) / denominator);
  return b;
}

void run(const char* name, const std::vector<double>& first, const std::vector<double>& fill,
         int fills, const std::vector<double>& step) {
  const auto rule = FusionRule::create(FusionRuleType::kDempster);
  std::vector<float> payload(fill.size(), 0.f);
  std::vector<long double> exact(fill.size(), 0.0L);
  auto add = [&](const std::vector<double>& inc) {
#ifdef OLD_WRITERS
    for (size_t c = 0; c < inc.size(); ++c) payload[c] += static_cast<float>(inc[c]);
#else
    rule->add(payload.data(), inc.data(), int(inc.size()));
#endif
    for (size_t c = 0; c < inc.size(); ++c) exact[c] += inc[c];
  };
  add(first);
  for (int i = 0; i < fills; ++i) add(fill);
  for (int i = 0; i < 1000; ++i) add(step);
  const VoxelOpinion got = rule->readout(payload.data(), int(payload.size()));
  const std::vector<long double> b = exactBeliefs(exact);
  const int exact_label = b[1] > b[0] ? 1 : 0;
  std::printf("%s: map label %d, b = %.7f / %.7f; exact label %d, b = %.7Lf / %.7Lf\n", name,
              got.label, got.belief[0], got.belief[1], exact_label, b[0], b[1]);
}

int main() {
  // Tie: L = 3e5 on both classes, then 1000 x 0.005 on class 1 (below half a float step there).
  run("tie", {0.0, 0.0}, {1.0, 1.0}, 300000, {0.0, 0.005});
  // Flip: class 1 leads by 2, then 1000 x 0.012 on class 0 (exact: class 0 leads by 10).
  run("flip", {0.0, 2.0}, {1.0, 1.0}, 300000, {0.012, 0.0});
}
