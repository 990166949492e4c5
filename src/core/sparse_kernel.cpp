#include "evidential_octomap/sparse_kernel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace evidential_octomap {

double sparseKernel(double distance, double length, double sigma0) {
  if (!(length > 0.0) || distance >= length) return 0.0;
  constexpr double kTwoPi = 2.0 * M_PI;
  const double r = distance / length;
  const double value =
      sigma0 * ((2.0 + std::cos(kTwoPi * r)) / 3.0 * (1.0 - r) + std::sin(kTwoPi * r) / kTwoPi);
  return std::max(value, 0.0);  // k' >= 0 on [0, L); rounding near d = L can dip below
}

double adaptiveLength(double length_scale, double beta, double gamma, double uncertainty) {
  return length_scale * beta * std::exp(1.0 - gamma * uncertainty);
}

double distanceToCube(double dx, double dy, double dz, double half_size) {
  return kernelDistance(dx, dy, dz, half_size, 1.0);
}

double kernelDistance(double dx, double dy, double dz, double half_size, double vertical_support) {
  const double x = std::max(std::fabs(dx) - half_size, 0.0);
  const double y = std::max(std::fabs(dy) - half_size, 0.0);
  const double z = std::max(std::fabs(dz) - half_size, 0.0) / vertical_support;
  return std::sqrt(x * x + y * y + z * z);
}

double uncertaintyThreshold(std::vector<float> values, double drop_percent) {
  if (drop_percent <= 0.0 || values.empty()) return std::numeric_limits<double>::infinity();
  const size_t n = values.size();
  const size_t dropped = std::min(n, static_cast<size_t>(std::floor(n * drop_percent / 100.0)));
  if (dropped == 0) return std::numeric_limits<double>::infinity();
  if (dropped == n) return -std::numeric_limits<double>::infinity();
  // The (n - dropped)-th smallest value is the largest one kept.
  auto kth = values.begin() + (n - dropped - 1);
  std::nth_element(values.begin(), kth, values.end());
  return *kth;
}

}  // namespace evidential_octomap
