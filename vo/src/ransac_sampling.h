// SPDX-License-Identifier: Apache-2.0
#pragma once
// Sampling helpers shared by the RANSAC estimators of the VO.

#include <array>
#include <cmath>
#include <random>

namespace rigcal::vo {

// K distinct indices in [0, n), n >= K. `rng` must not be null.
template <size_t K>
void SampleDistinct(int n, std::array<int, K>* sample, std::mt19937* rng) {
  std::uniform_int_distribution<int> pick(0, n - 1);
  for (size_t k = 0; k < K; ++k) {
    bool repeated = true;
    while (repeated) {
      (*sample)[k] = pick(*rng);
      repeated = false;
      for (size_t j = 0; j < k; ++j) repeated |= (*sample)[j] == (*sample)[k];
    }
  }
}

// Iterations a RANSAC with minimal samples of `sample_size` needs to draw one all-inlier
// sample with probability `confidence` when a fraction `inlier_ratio` of the data are inliers.
inline int RansacIterations(double inlier_ratio, int sample_size, double confidence) {
  const double all_inliers = std::pow(inlier_ratio, sample_size);
  if (all_inliers >= 1.0 - 1e-12) return 1;
  if (all_inliers <= 1e-12) return 1 << 30;
  const double n = std::log(1.0 - confidence) / std::log(1.0 - all_inliers);
  return n > 1e9 ? (1 << 30) : static_cast<int>(std::ceil(n));
}

}  // namespace rigcal::vo
