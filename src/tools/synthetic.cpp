#include "synthetic.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap::tools {

namespace {
uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
double unit(uint64_t bits) { return double(bits >> 11) * (1.0 / 9007199254740992.0); }
}  // namespace

std::string NoiseModel::describe() const {
  std::ostringstream s;
  s << "synthetic: GT corrupted by region confusion (" << region_size << " m cubes, rate "
    << region_rate << ") and point noise (rate " << point_rate << "), seed " << seed;
  return s.str();
}

std::vector<int> syntheticPredictions(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<int>& gt, int num_classes,
                                      int ignore_class, const NoiseModel& model) {
  if (points.size() != gt.size()) {
    throw std::invalid_argument("syntheticPredictions: points and labels differ in size");
  }
  std::vector<int> present;
  {
    std::vector<bool> seen(num_classes, false);
    for (int g : gt)
      if (g >= 0 && g < num_classes && g != ignore_class) seen[g] = true;
    for (int c = 0; c < num_classes; ++c)
      if (seen[c]) present.push_back(c);
  }
  std::vector<int> pred = gt;
  if (present.size() < 2) return pred;  // nothing to confuse with

  std::mt19937_64 rng(model.seed);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    const int64_t cx = int64_t(std::floor(p.x() / model.region_size));
    const int64_t cy = int64_t(std::floor(p.y() / model.region_size));
    const int64_t cz = int64_t(std::floor(p.z() / model.region_size));
    uint64_t h = splitmix64(model.seed ^ splitmix64(uint64_t(cx) ^ splitmix64(
                                                        uint64_t(cy) ^ splitmix64(uint64_t(cz)))));
    if (unit(h) < model.region_rate) {
      pred[i] = present[splitmix64(h) % present.size()];
      continue;
    }
    const uint64_t a = rng(), b = rng();  // two draws per point, always, for reproducibility
    if (gt[i] == ignore_class || gt[i] < 0) continue;
    if (unit(a) < model.point_rate) {
      // Uniform over the present classes other than gt[i] (which is among them).
      const size_t k = size_t(std::lower_bound(present.begin(), present.end(), gt[i]) -
                              present.begin());
      size_t idx = b % (present.size() - 1);
      if (idx >= k) ++idx;
      pred[i] = present[idx];
    }
  }
  return pred;
}

}  // namespace evidential_octomap::tools
