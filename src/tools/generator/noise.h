// Value noise (hash-lattice, smoothstep-interpolated) and its fractal sum: the roughness of the
// terrain and the spatially smooth part of the network model's errors.
#pragma once

#include <cstdint>

namespace evidential_octomap::generator {

// In [-1, 1], smooth, lattice spacing 1; `key` selects an independent field.
float valueNoise2(uint64_t key, double x, double y);
float valueNoise3(uint64_t key, double x, double y, double z);

// Sum of `octaves` value-noise octaves, the first at wavelength `scale`, each next one at half
// the wavelength and `gain` times the amplitude; normalised to about [-1, 1].
float fbm2(uint64_t key, double x, double y, double scale, int octaves, float gain = 0.5f);

}  // namespace evidential_octomap::generator
