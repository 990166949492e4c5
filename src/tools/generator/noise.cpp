#include "noise.h"

#include <cmath>

#include "rng.h"

namespace evidential_octomap::generator {

namespace {
inline float lattice(uint64_t key, int64_t i, int64_t j, int64_t k = 0) {
  return float(unitOf(hashOf(key, uint64_t(i), uint64_t(j), uint64_t(k))) * 2.0 - 1.0);
}
inline double smooth(double t) { return t * t * (3.0 - 2.0 * t); }
}  // namespace

float valueNoise2(uint64_t key, double x, double y) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t i = int64_t(fx), j = int64_t(fy);
  const double u = smooth(x - fx), v = smooth(y - fy);
  const double a = lattice(key, i, j), b = lattice(key, i + 1, j);
  const double c = lattice(key, i, j + 1), d = lattice(key, i + 1, j + 1);
  return float((a + (b - a) * u) + ((c + (d - c) * u) - (a + (b - a) * u)) * v);
}

float valueNoise3(uint64_t key, double x, double y, double z) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const int64_t i = int64_t(fx), j = int64_t(fy), k = int64_t(fz);
  const double u = smooth(x - fx), v = smooth(y - fy), w = smooth(z - fz);
  double layer[2];
  for (int dz = 0; dz < 2; ++dz) {
    const double a = lattice(key, i, j, k + dz), b = lattice(key, i + 1, j, k + dz);
    const double c = lattice(key, i, j + 1, k + dz), d = lattice(key, i + 1, j + 1, k + dz);
    const double ab = a + (b - a) * u, cd = c + (d - c) * u;
    layer[dz] = ab + (cd - ab) * v;
  }
  return float(layer[0] + (layer[1] - layer[0]) * w);
}

float fbm2(uint64_t key, double x, double y, double scale, int octaves, float gain) {
  double sum = 0.0, amplitude = 1.0, norm = 0.0, f = 1.0 / scale;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * valueNoise2(hashOf(key, uint64_t(o)), x * f, y * f);
    norm += amplitude;
    amplitude *= gain;
    f *= 2.0;
  }
  return float(sum / norm);
}

}  // namespace evidential_octomap::generator
