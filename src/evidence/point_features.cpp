#include "evidential_octomap/evidence/point_features.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "evidential_octomap/evidence/neighbour_grid.h"

namespace evidential_octomap {

namespace {

constexpr int kNeighbours = 16;
constexpr float kNeighbourRadius = 1.0f;  // [m]
constexpr float kGroundCell = 1.0f;       // [m], 2-D cells for ground and column height
constexpr int kGeometric = 13;            // features before pred_<c>, vote_<c>

bool noReturn(const float* p) { return p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f; }

// Lowest and highest z of every 2-D ground cell, then of each point's 3 x 3 cells.
class GroundCells {
 public:
  GroundCells(const ScanInput& scan, const std::vector<uint8_t>& skip) {
    for (size_t i = 0; i < scan.num_points; ++i) {
      if (skip[i]) continue;
      const float* p = scan.xyz + 3 * i;
      auto [it, fresh] = cells_.try_emplace(key(cellOf(p[0]), cellOf(p[1])), p[2], p[2]);
      if (!fresh) {
        it->second.first = std::min(it->second.first, p[2]);
        it->second.second = std::max(it->second.second, p[2]);
      }
    }
  }
  // (lowest, highest) z over the 3 x 3 cells around (x, y).
  std::pair<float, float> around(float x, float y) const {
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    const int cx = cellOf(x), cy = cellOf(y);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(key(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        lo = std::min(lo, it->second.first);
        hi = std::max(hi, it->second.second);
      }
    return {lo, hi};
  }

 private:
  static int cellOf(float v) { return int(std::floor(v / kGroundCell)); }
  static uint64_t key(int x, int y) { return (uint64_t(uint32_t(x)) << 32) | uint32_t(y); }
  std::unordered_map<uint64_t, std::pair<float, float>> cells_;
};

// Eigenvalues l1 >= l2 >= l3 of a symmetric 3 x 3 matrix (trigonometric closed form) and the
// |z| of the unit eigenvector of l3 (the surface normal).
struct Eigen3 {
  double l1 = 0, l2 = 0, l3 = 0, normal_z = 0;
};

Eigen3 symmetricEigen(const double a[3][3]) {
  Eigen3 r;
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  if (p1 <= 1e-30) {
    double d[3] = {a[0][0], a[1][1], a[2][2]};
    std::sort(d, d + 3);
    r.l1 = d[2], r.l2 = d[1], r.l3 = d[0];
    // Diagonal: the normal is the axis of the smallest value.
    r.normal_z = (a[2][2] <= a[0][0] && a[2][2] <= a[1][1]) ? 1.0 : 0.0;
    return r;
  }
  const double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) +
                    (a[2][2] - q) * (a[2][2] - q) + 2.0 * p1;
  const double p = std::sqrt(p2 / 6.0);
  double b[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) b[i][j] = (a[i][j] - (i == j ? q : 0.0)) / p;
  const double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                     b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                     b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
  const double phi = std::acos(std::clamp(det / 2.0, -1.0, 1.0)) / 3.0;
  r.l1 = q + 2.0 * p * std::cos(phi);
  r.l3 = q + 2.0 * p * std::cos(phi + 2.0 * M_PI / 3.0);
  r.l2 = 3.0 * q - r.l1 - r.l3;
  // Eigenvector of l3: the largest cross product of two rows of (A - l3 I).
  double m[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = a[i][j] - (i == j ? r.l3 : 0.0);
  double best[3] = {0, 0, 0}, best_norm = 0.0;
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (const auto& pr : pairs) {
    const double* u = m[pr[0]];
    const double* v = m[pr[1]];
    const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double n = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    if (n > best_norm) {
      best_norm = n;
      std::memcpy(best, c, sizeof(best));
    }
  }
  r.normal_z = best_norm > 0.0 ? std::abs(best[2]) / std::sqrt(best_norm) : 0.0;
  return r;
}

// The 13 geometric features of point i from its neighbours (self included, nearest first).
void geometricFeatures(const ScanInput& scan, size_t i,
                       const std::vector<std::pair<float, uint32_t>>& nbrs,
                       const GroundCells& ground, float* f) {
  const float* p = scan.xyz + 3 * i;
  const auto [lo, hi] = ground.around(p[0], p[1]);
  f[0] = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  f[1] = p[2];
  f[2] = p[2] - lo;
  f[3] = hi - lo;
  f[4] = scan.remission ? scan.remission[i] : 0.0f;
  const size_t n = nbrs.size();
  f[5] = float(n) / float(kNeighbours);
  double mean[3] = {0, 0, 0}, dist = 0.0;
  float zmin = p[2], zmax = p[2];
  for (const auto& [d2, j] : nbrs) {
    const float* q = scan.xyz + 3 * size_t(j);
    for (int a = 0; a < 3; ++a) mean[a] += q[a];
    dist += std::sqrt(double(d2));
    zmin = std::min(zmin, q[2]);
    zmax = std::max(zmax, q[2]);
  }
  for (double& m : mean) m /= double(n);
  f[6] = n > 1 ? float(dist / double(n - 1)) : kNeighbourRadius;  // self contributes 0
  double cov[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (const auto& nb : nbrs) {
    const float* q = scan.xyz + 3 * size_t(nb.second);
    const double d[3] = {q[0] - mean[0], q[1] - mean[1], q[2] - mean[2]};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) cov[a][b] += d[a] * d[b] / double(n);
  }
  if (n >= 3) {
    const Eigen3 e = symmetricEigen(cov);
    const double l1 = std::max(e.l1, 1e-12);
    f[7] = float((e.l1 - e.l2) / l1);
    f[8] = float((e.l2 - std::max(e.l3, 0.0)) / l1);
    f[9] = float(std::max(e.l3, 0.0) / l1);
    f[10] = float(e.normal_z);
  } else {
    f[7] = f[8] = f[9] = f[10] = 0.0f;
  }
  f[11] = zmax - zmin;
  f[12] = float(p[2] - mean[2]);
}

}  // namespace

std::vector<std::string> pointFeatureNames(int num_classes) {
  std::vector<std::string> names{"range",           "z",           "height_above_ground",
                                 "column_height",   "remission",   "knn_fill",
                                 "knn_mean_dist",   "linearity",   "planarity",
                                 "scattering",      "verticality", "knn_z_extent",
                                 "z_minus_knn_mean"};
  for (int c = 0; c < num_classes; ++c) names.push_back("pred_" + std::to_string(c));
  for (int c = 0; c < num_classes; ++c) names.push_back("vote_" + std::to_string(c));
  return names;
}

FeatureMatrix computePointFeatures(const ScanInput& scan, int num_classes) {
  if (scan.num_points > 0 && (scan.xyz == nullptr || scan.predicted == nullptr)) {
    throw std::invalid_argument(
        "point features need the points and the network's hard prediction of every point");
  }
  if (num_classes <= 0) throw std::invalid_argument("point features: num_classes must be > 0");
  const size_t N = scan.num_points;
  const int C = num_classes;
  for (size_t i = 0; i < N; ++i) {
    if (scan.predicted[i] >= C) {
      throw std::invalid_argument("point " + std::to_string(i) + ": prediction " +
                                  std::to_string(scan.predicted[i]) + " is outside [0, " +
                                  std::to_string(C) + ")");
    }
  }
  FeatureMatrix m;
  m.rows = N;
  m.cols = kGeometric + 2 * C;
  m.values.assign(N * size_t(m.cols), 0.0f);
  std::vector<uint8_t> skip(N);
  for (size_t i = 0; i < N; ++i) skip[i] = noReturn(scan.xyz + 3 * i);
  const GroundCells ground(scan, skip);
  const NeighbourGrid grid(scan.xyz, N, kNeighbourRadius, &skip);

#pragma omp parallel
  {
    std::vector<std::pair<float, uint32_t>> nbrs;
#pragma omp for schedule(dynamic, 1024)
    for (size_t i = 0; i < N; ++i) {
      if (skip[i]) continue;
      float* f = m.values.data() + i * size_t(m.cols);
      grid.nearest(i, kNeighbours, &nbrs);
      geometricFeatures(scan, i, nbrs, ground, f);
      if (scan.predicted[i] >= 0) f[kGeometric + scan.predicted[i]] = 1.0f;
      int others = 0;
      for (const auto& nb : nbrs) others += nb.second != i;
      for (const auto& nb : nbrs) {
        const int c = scan.predicted[nb.second];
        if (nb.second != i && c >= 0) f[kGeometric + C + c] += 1.0f / float(others);
      }
    }
  }
  return m;
}

uint64_t scanFingerprint(const ScanInput& scan) {
  uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis
  auto mix = [&h](float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    for (int b = 0; b < 4; ++b) {
      h ^= (bits >> (8 * b)) & 0xFFu;
      h *= 1099511628211ull;
    }
  };
  for (size_t i = 0; i < scan.num_points; ++i) {
    const float* p = scan.xyz + 3 * i;
    if (noReturn(p)) continue;
    mix(p[0]), mix(p[1]), mix(p[2]);
    mix(scan.remission ? scan.remission[i] : 0.0f);
  }
  return h;
}

std::string fingerprintHex(uint64_t fingerprint) {
  static const char* digits = "0123456789abcdef";
  std::string s(16, '0');
  for (int k = 15; k >= 0; --k, fingerprint >>= 4) s[size_t(k)] = digits[fingerprint & 0xF];
  return s;
}

}  // namespace evidential_octomap
