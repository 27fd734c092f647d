// SPDX-License-Identifier: Apache-2.0
#pragma once
// Small, portable, deterministic random numbers for the simulated rig (the same numbers with
// every standard library), and counter-based hashing so that a frame's randomness does not
// depend on the order in which threads render frames. Private to rigcal_sim.

#include <cmath>
#include <cstdint>

namespace rigcal::sim::internal {

inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Hash of a tuple of integers (seed, purpose, camera, frame, ...).
inline uint64_t HashKey(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0) {
  uint64_t h = SplitMix64(a);
  h = SplitMix64(h ^ b);
  h = SplitMix64(h ^ c);
  return SplitMix64(h ^ d);
}

class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    state_ += 0x9E3779B97F4A7C15ull;
    return SplitMix64(state_);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [0, n).
  uint32_t Below(uint32_t n) { return static_cast<uint32_t>((Next() >> 32) * n >> 32); }
  // Standard normal (Box-Muller).
  double Gaussian() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  uint64_t state_;
};

// Purposes of HashKey's second argument.
enum RandomPurpose : uint64_t {
  kPurposeTexture = 1,
  kPurposeLayout = 2,
  kPurposeNoise = 3,
  kPurposeDrop = 4,
  kPurposeJitter = 5,
  kPurposeNoiseTable = 6,
  kPurposeSurface = 7,
  kPurposeExposure = 8,
  kPurposeMovingTexture = 9,  // the moving objects' texture offsets
  kPurposeMovingPath = 10,    // the moving objects' lines and phases
};

}  // namespace rigcal::sim::internal
