// SPDX-License-Identifier: Apache-2.0
#pragma once
// How well one frame tracked against how well the camera usually tracks, for
// CameraPose::quality. Each tracked frame measures its own track noise σ_f (the robust σ of its
// PnP residuals, TrackNoise::RobustSigma). The camera's usual σ_f is taken from the last
// kFrames frames: their median m plus kSpreadSigmas of their robust spread s (1.4826 MAD), as
// σ_f of well tracked frames varies from frame to frame with their tracks and the scene. A burst
// of blurred, dark or noisy frames shorter than half of that window does not move it, while a
// scene that changes for good becomes the new usual. A pose's information about the camera's
// motion goes as 1/σ_f² (the covariance of a pose from n bearings of per-axis noise σ is σ²/n
// times a geometry factor), so the frame's factor in the quality is
//     min(1, ((m + kSpreadSigmas s) / σ_f)²)
// in (0, 1]: 1 for a frame that tracked as usual or better, about 1/4 for one whose tracks are
// twice as noisy.

#include <cstddef>
#include <vector>

namespace rigcal::vo {

class FrameNoiseReference {
 public:
  static constexpr int kFrames = 201;  // about 10 s at 20 Hz
  // A usual frame's σ_f lies within this many robust spreads above the median.
  static constexpr double kSpreadSigmas = 3.0;

  // One frame's σ_f in pixels (ignored when not positive and finite); returns the frame's
  // factor, against the usual σ before this frame (1 for the first frame).
  double Add(double frame_sigma_px);

  // The usual σ_f, m + kSpreadSigmas s, of the frames so far (0 before the first).
  double UsualSigmaPx() const;

 private:
  std::vector<double> ring_;  // the last kFrames σ_f, oldest at next_
  std::size_t next_ = 0;
};

}  // namespace rigcal::vo
