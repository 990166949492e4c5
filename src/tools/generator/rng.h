// Counter-based randomness of the generator: every random number is a hash of (seed, what, where),
// never a stateful engine or a std:: distribution (whose output is implementation-defined), so a
// value does not depend on the order in which threads compute it and the output is identical on
// every platform.
#pragma once

#include <cstdint>

namespace evidential_octomap::generator {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Hash of a key sequence; each argument is folded in through one SplitMix64 round.
inline uint64_t hashOf(uint64_t a) { return splitmix64(a); }
template <typename... Rest>
inline uint64_t hashOf(uint64_t a, uint64_t b, Rest... rest) {
  return hashOf(splitmix64(a) ^ (b + 0x632BE59BD9B4E019ull), uint64_t(rest)...);
}

// Uniform in [0, 1) from the upper 53 bits.
inline double unitOf(uint64_t h) { return double(h >> 11) * (1.0 / 9007199254740992.0); }

// Approximately standard normal from one hash: the sum of four 16-bit uniforms (Irwin-Hall),
// rescaled to unit variance. Bounded by +-3.46: no libm call, the same bits everywhere.
inline float normalOf(uint64_t h) {
  const double s = double(h & 0xFFFF) + double((h >> 16) & 0xFFFF) + double((h >> 32) & 0xFFFF) +
                   double(h >> 48);
  return float((s / 65535.0 - 2.0) * 1.7320508075688772);
}

// Stream tags keep the hashes of different purposes independent.
enum Stream : uint64_t {
  kStreamScene = 1,
  kStreamTerrain,
  kStreamObjects,
  kStreamRay,
  kStreamFoliage,
  kStreamNoise,
  kStreamDropout,
  kStreamRemission,
  kStreamNetwork,
  kStreamNetworkField,
  kStreamWrongCell,
  kStreamMovers,
  kStreamTrajectory,
};

}  // namespace evidential_octomap::generator
