// SPDX-License-Identifier: Apache-2.0
#pragma once
// Exposure and gain steps between frames, compensated before tracking. KLT and the patch
// alignment compare grey levels: when a camera's auto exposure or gain steps, every patch
// changes by a factor and the tracks slip or fail at once. The step shows as a jump of the
// logarithm of the image's mean grey level between consecutive frames, far beyond the jumps
// the camera's motion makes (the scene's content changing at the border): those are measured
// as a robust σ over the last `window_frames` frames, and a jump beyond `gate_sigmas` σ (and
// beyond the 10 % that tracking follows by itself) is taken as an exposure step. The frames
// after it are scaled back by the accumulated factor of the steps, so that the tracked images
// keep the brightness of the frames before the first step. A steady exposure leaves the images
// untouched (bit for bit).

#include <deque>
#include <opencv2/core.hpp>

namespace rigcal::vo {

class ExposureCompensation {
 public:
  ExposureCompensation(double gate_sigmas, int window_frames);

  // The image to track: `grey` (CV_8UC1) itself, or scaled by the accumulated gain (saturating).
  cv::Mat Apply(const cv::Mat& grey);
  // The factor applied to the last image (1 with no step so far).
  double gain() const { return gain_; }
  int steps() const { return steps_; }

 private:
  double gate_sigmas_;
  size_t window_frames_;
  double previous_log_mean_ = 0.0;
  bool has_previous_ = false;
  double gain_ = 1.0;
  int steps_ = 0;
  std::deque<double> jumps_;  // |log mean ratio| of the recent frames without a step
};

}  // namespace rigcal::vo
