// SPDX-License-Identifier: Apache-2.0
#include "exposure_compensation.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace rigcal::vo {
namespace {

// A mean below one grey level: a covered lens or a black frame, whose ratio says nothing.
constexpr double kMinMeanGrey = 1.0;
// KLT and the patch alignment (which fits a brightness offset) follow brightness changes of a
// few percent between frames; smaller jumps are never compensated, which keeps the scene's
// own changes of brightness (a bright object entering the view) from being taken for steps.
const double kMinStepLog = std::log(1.1);

}  // namespace

ExposureCompensation::ExposureCompensation(double gate_sigmas, int window_frames)
    : gate_sigmas_(gate_sigmas), window_frames_(static_cast<size_t>(std::max(window_frames, 2))) {}

cv::Mat ExposureCompensation::Apply(const cv::Mat& grey) {
  const double mean = cv::mean(grey)[0];
  if (mean >= kMinMeanGrey) {
    const double log_mean = std::log(mean);
    if (has_previous_) {
      const double jump = log_mean - previous_log_mean_;
      // Half-normal |jump|: σ = 1.4826 median; a quantisation floor of half a grey level.
      double sigma = 0.5 / mean;
      if (jumps_.size() >= window_frames_ / 2) {
        std::vector<double> sorted(jumps_.begin(), jumps_.end());
        std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
        sigma = std::max(sigma, 1.4826 * sorted[sorted.size() / 2]);
      }
      if (jumps_.size() >= window_frames_ / 2 &&
          std::abs(jump) > std::max(gate_sigmas_ * sigma, kMinStepLog)) {
        gain_ *= std::exp(-jump);
        ++steps_;
      } else {
        jumps_.push_back(std::abs(jump));
        if (jumps_.size() > window_frames_) jumps_.pop_front();
      }
    }
    previous_log_mean_ = log_mean;
    has_previous_ = true;
  }
  if (gain_ == 1.0) return grey;
  cv::Mat scaled;
  grey.convertTo(scaled, CV_8U, gain_);
  return scaled;
}

}  // namespace rigcal::vo
