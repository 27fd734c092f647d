// SPDX-License-Identifier: Apache-2.0
#pragma once
// Gaussian pixel noise for simulated detections: sigma px per axis, x drawn before y (the same
// draws with every compiler), none at all when sigma is 0 (std::normal_distribution needs
// sigma > 0, and noiseless views draw nothing). Header-only.

#include <Eigen/Core>
#include <random>

namespace rigcal::test_support {

class PixelNoise {
 public:
  explicit PixelNoise(double sigma_px)
      : sigma_px_(sigma_px), gauss_(0.0, sigma_px > 0 ? sigma_px : 1.0) {}

  Eigen::Vector2d operator()(std::mt19937& rng) {
    if (!(sigma_px_ > 0)) return Eigen::Vector2d::Zero();
    const double dx = gauss_(rng);
    const double dy = gauss_(rng);
    return {dx, dy};
  }

 private:
  double sigma_px_;
  std::normal_distribution<double> gauss_;
};

}  // namespace rigcal::test_support
