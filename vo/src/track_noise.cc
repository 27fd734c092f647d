// SPDX-License-Identifier: Apache-2.0
#include "track_noise.h"

#include <algorithm>
#include <cmath>

namespace rigcal::vo {
namespace {

// Medians of |e| for e ~ N(0, I s²) in 1 and 2 dimensions: 0.6745 s (half-normal) and
// s sqrt(2 ln 2) (Rayleigh); the mean of |e|² is dims s².
constexpr double kHalfNormalMedian = 0.6744897501960817;
constexpr double kRayleighMedian = 1.1774100225154747;

}  // namespace

TrackNoise::TrackNoise(double floor_px, double inlier_sigmas, int window_frames)
    : floor_px_(floor_px),
      inlier_sigmas_(inlier_sigmas),
      alpha_(2.0 / (std::max(1, window_frames) + 1.0)) {}

double TrackNoise::sigma_px() const {
  const double variance = geometric_ ? geometry_ : klt_;
  return std::max(floor_px_, std::sqrt(variance));
}

double TrackNoise::RobustSigma(std::vector<double> magnitudes, double scale_per_sigma, int dims,
                               double inlier_sigmas) {
  if (magnitudes.empty()) return 0.0;
  const auto middle = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
  std::nth_element(magnitudes.begin(), middle, magnitudes.end());
  const double median_per_scale = dims == 1 ? kHalfNormalMedian : kRayleighMedian;
  const double first = *middle / (median_per_scale * scale_per_sigma);
  // RMS of the magnitudes within the gate of the first guess (outliers left out).
  const double gate = inlier_sigmas * scale_per_sigma * first;
  double sum2 = 0.0;
  int n = 0;
  for (double m : magnitudes) {
    if (m > gate) continue;
    sum2 += m * m;
    ++n;
  }
  if (n == 0 || !(first > 0.0)) return first;
  return std::sqrt(sum2 / n / dims) / scale_per_sigma;
}

void TrackNoise::Average(double* state, double sigma) const {
  if (!(sigma > 0.0) || !std::isfinite(sigma)) return;
  const double variance = sigma * sigma;
  *state = *state > 0.0 ? (1.0 - alpha_) * *state + alpha_ * variance : variance;
}

void TrackNoise::AddForwardBackward(const std::vector<double>& distances_px) {
  Average(&klt_, RobustSigma(distances_px, std::sqrt(2.0), 2, inlier_sigmas_));
}

void TrackNoise::AddPoseResiduals(const std::vector<double>& residuals_px) {
  const double sigma = RobustSigma(residuals_px, 1.0, 2, inlier_sigmas_);
  if (!(sigma > 0.0)) return;
  Average(&geometry_, sigma);
  geometric_ = true;
}

void TrackNoise::AddEpipolarDistances(const std::vector<double>& distances_px) {
  const double sigma = RobustSigma(distances_px, std::sqrt(2.0), 1, inlier_sigmas_);
  if (!(sigma > 0.0)) return;
  Average(&geometry_, sigma);
  geometric_ = true;
}

}  // namespace rigcal::vo
