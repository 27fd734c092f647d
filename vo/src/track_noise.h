// SPDX-License-Identifier: Apache-2.0
#pragma once
// The VO's measurement noise, measured on its own images instead of assumed: the per-axis
// standard deviation σ of a track's image position, in pixels of the camera's centre
// resolution. Every gate of the VO is a multiple of it (VoOptions::inlier_sigmas), so the same
// code gates rendered frames (σ of a few hundredths of a pixel) and blurred real ones (σ of a
// few tenths) without constants fitted to either.
//
// Each frame gives one robust σ from one of three residual populations, by the distribution
// its magnitudes follow when the per-axis errors are Gaussian with σ:
//  - KLT forward-backward distances: Rayleigh(√2 σ) (an error in each direction);
//  - 2-D residuals of tracks under an estimated pose: Rayleigh(σ);
//  - epipolar distances of correspondences: |N(0, 2 σ²)| (both views' errors, one axis).
// The frame's σ comes from the median (robust to a minority of outliers), refined once by the
// RMS of the residuals within inlier_sigmas of that first guess; frames are combined by an
// exponential average of σ² over about `window_frames` frames. Pose and epipolar residuals
// replace the forward-backward figure once they exist: they include what the tracks' geometry
// adds (landmark errors, the lens model), which the gates must accept.

#include <vector>

namespace rigcal::vo {

class TrackNoise {
 public:
  TrackNoise(double floor_px, double inlier_sigmas, int window_frames);

  // The current σ in pixels, never below the floor; the floor until a frame was measured.
  double sigma_px() const;
  bool measured() const { return geometric_ || klt_ > 0.0; }

  // One frame's forward-backward distances, pixels (used until geometric residuals exist).
  void AddForwardBackward(const std::vector<double>& distances_px);
  // One frame's 2-D residuals of tracks under an estimated pose, pixels.
  void AddPoseResiduals(const std::vector<double>& residuals_px);
  // Epipolar distances of the correspondences of two views, pixels.
  void AddEpipolarDistances(const std::vector<double>& distances_px);

  // σ of one population of magnitudes of `dims`-dimensional (1 or 2) Gaussian errors whose
  // per-axis deviation is `scale_per_sigma` σ (see above); 0 for no value.
  static double RobustSigma(std::vector<double> magnitudes, double scale_per_sigma, int dims,
                            double inlier_sigmas);

 private:
  void Average(double* state, double sigma) const;

  double floor_px_;
  double inlier_sigmas_;
  double alpha_;           // weight of a new frame in the average
  double klt_ = 0.0;       // σ² from forward-backward distances (0: none yet)
  double geometry_ = 0.0;  // σ² from pose and epipolar residuals
  bool geometric_ = false;
};

}  // namespace rigcal::vo
