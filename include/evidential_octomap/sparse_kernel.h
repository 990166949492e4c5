// The sparse kernel of Melkumyan & Ramos and its uncertainty-adaptive length (docs/design.md).
#pragma once

#include <vector>

namespace evidential_octomap {

// k'(d, L, sigma0) = sigma0 [ (2 + cos(2 pi d/L))/3 (1 - d/L) + sin(2 pi d/L)/(2 pi) ] for d < L,
// 0 otherwise. Not clamped: sbki and ebs use it as is (sigma0 > 1 scales their counts); the
// dempster rule clamps k to [0, 1] itself, where the extended belief needs it.
double sparseKernel(double distance, double length, double sigma0);

// Support length of a point with uncertainty u: l * beta * exp(1 - gamma * u).
double adaptiveLength(double length_scale, double beta, double gamma, double uncertainty);

// Euclidean distance from a point to an axis-aligned cube of half side `half_size`, given the
// point's offset (dx, dy, dz) from the cube's centre; 0 inside the cube.
double distanceToCube(double dx, double dy, double dz, double half_size);

// The kernel's distance (SemanticConfig::kernel_distance, vertical_support): the gap on each axis
// between a point at offset (dx, dy, dz) from a voxel's centre and the voxel's cube of half side
// `half_size` (0: its centre), the z gap divided by `vertical_support`, then Euclidean.
double kernelDistance(double dx, double dy, double dz, double half_size, double vertical_support);

// U_thr such that the `drop_percent` % most uncertain values lie above it (O(N), nth_element).
// Points with u <= U_thr are kept. drop_percent <= 0 keeps everything (+inf is returned).
// `values` is taken by value because nth_element reorders it.
double uncertaintyThreshold(std::vector<float> values, double drop_percent);

}  // namespace evidential_octomap
