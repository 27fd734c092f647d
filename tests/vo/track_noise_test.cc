// SPDX-License-Identifier: Apache-2.0
// TrackNoise: the per-axis noise σ recovered from each residual population it is fed (KLT
// forward-backward distances, 2-D pose residuals, epipolar distances), with outliers among
// them, its floor and its running average.

#include "../../vo/src/track_noise.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace rigcal::vo {
namespace {

constexpr double kSigma = 0.3;
constexpr int kSamples = 4000;

// Magnitudes of `dims`-dimensional Gaussian errors with per-axis deviation `scale`, and a
// fraction `outliers` of uniform magnitudes up to 20 scale.
std::vector<double> Magnitudes(int dims, double scale, double outliers, std::mt19937* rng) {
  std::normal_distribution<double> gauss(0.0, scale);
  std::uniform_real_distribution<double> uniform(0.0, 20.0 * scale);
  std::bernoulli_distribution is_outlier(outliers);
  std::vector<double> out;
  for (int i = 0; i < kSamples; ++i) {
    double sum2 = 0.0;
    for (int d = 0; d < dims; ++d) sum2 += std::pow(gauss(*rng), 2);
    out.push_back(is_outlier(*rng) ? uniform(*rng) : std::sqrt(sum2));
  }
  return out;
}

// The estimate of σ from n samples has a relative standard error of about 1 / sqrt(2 n) (RMS
// part) to 1.5 / sqrt(n) (median part); 5 of the larger is the tolerance. 10 % outliers bias it
// by less than the truncated-RMS correction leaves (a few percent).
double Tolerance() { return kSigma * (5.0 * 1.5 / std::sqrt(kSamples) + 0.05); }

TEST(TrackNoise, RecoversSigmaFromEachPopulation) {
  std::mt19937 rng(3);
  for (const double outliers : {0.0, 0.1}) {
    SCOPED_TRACE(outliers);
    TrackNoise fb(0.01, 3.03, 1);
    fb.AddForwardBackward(Magnitudes(2, std::sqrt(2.0) * kSigma, outliers, &rng));
    EXPECT_NEAR(fb.sigma_px(), kSigma, Tolerance());
    TrackNoise pose(0.01, 3.03, 1);
    pose.AddPoseResiduals(Magnitudes(2, kSigma, outliers, &rng));
    EXPECT_NEAR(pose.sigma_px(), kSigma, Tolerance());
    TrackNoise epipolar(0.01, 3.03, 1);
    epipolar.AddEpipolarDistances(Magnitudes(1, std::sqrt(2.0) * kSigma, outliers, &rng));
    EXPECT_NEAR(epipolar.sigma_px(), kSigma, Tolerance());
  }
}

TEST(TrackNoise, FloorUntilMeasuredAndGeometryWinsOverKlt) {
  std::mt19937 rng(4);
  TrackNoise noise(0.1, 3.03, 5);
  EXPECT_FALSE(noise.measured());
  EXPECT_DOUBLE_EQ(noise.sigma_px(), 0.1);
  noise.AddForwardBackward(Magnitudes(2, std::sqrt(2.0) * 0.02, 0.0, &rng));
  EXPECT_TRUE(noise.measured());
  EXPECT_DOUBLE_EQ(noise.sigma_px(), 0.1);  // below the floor
  noise.AddPoseResiduals(Magnitudes(2, 0.5, 0.0, &rng));
  EXPECT_NEAR(noise.sigma_px(), 0.5, 0.05);
  // Forward-backward figures no longer count once pose residuals exist.
  noise.AddForwardBackward(Magnitudes(2, std::sqrt(2.0) * 2.0, 0.0, &rng));
  EXPECT_NEAR(noise.sigma_px(), 0.5, 0.05);
}

// An exponential average over about `window` frames: a step from 0.2 to 0.6 px is followed with
// weight 2 / (window + 1) per frame.
TEST(TrackNoise, AveragesOverItsWindow) {
  std::mt19937 rng(5);
  TrackNoise noise(0.01, 3.03, 9);
  for (int i = 0; i < 30; ++i) noise.AddPoseResiduals(Magnitudes(2, 0.2, 0.0, &rng));
  EXPECT_NEAR(noise.sigma_px(), 0.2, 0.02);
  noise.AddPoseResiduals(Magnitudes(2, 0.6, 0.0, &rng));
  const double expected = std::sqrt(0.8 * 0.2 * 0.2 + 0.2 * 0.6 * 0.6);
  EXPECT_NEAR(noise.sigma_px(), expected, 0.03);
  EXPECT_EQ(TrackNoise::RobustSigma({}, 1.0, 2, 3.03), 0.0);
}

}  // namespace
}  // namespace rigcal::vo
