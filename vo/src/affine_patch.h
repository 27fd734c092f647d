// SPDX-License-Identifier: Apache-2.0
#pragma once
// Affine patch alignment (inverse-compositional Lucas-Kanade with an affine warp and an
// intensity offset) of a feature's reference patch into a later image.
//
// Frame-to-frame translational KLT drifts where a patch deforms between frames (zoom when the
// camera moves towards or away from a surface, perspective, fisheye distortion): every frame
// adds a small bias of the same sign, so a track walks away from its 3D point by a twentieth
// of a pixel per frame in a pipe, which biases triangulation and makes the VO's scale drift.
// Aligning the track's *reference* patch (taken when the track was born or re-anchored) with
// an affine warp removes both: no accumulation, and the deformation is modelled.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace rigcal::vo {

struct AffinePatchOptions {
  int half_size = 5;  // the patch is (2 half_size + 1)^2 pixels
  int max_iterations = 8;
  double min_step_px = 0.01;  // converged when the centre moves less than this
  // The alignment fails when the warp's area ratio leaves [1 / max_area_ratio, max_area_ratio]
  // or its RMS intensity residual exceeds this (grey levels).
  double max_area_ratio = 3.0;
  double max_rms = 12.0;
};

// A reference patch: intensities and the steepest-descent images of the affine warp, with
// the inverse of its Gauss-Newton Hessian.
struct PatchTemplate {
  // Values per pixel in `sd`: the 7 parameters' and a zero, so that the alignment accumulates
  // them in whole SIMD registers.
  static constexpr int kSdStride = 8;
  std::vector<float> values;  // (2 h + 1)^2, row-major
  std::vector<float> sd;      // per pixel: gx x, gx y, gy x, gy y, gx, gy, 1 (offset), 0
  Eigen::Matrix<double, 7, 7> inverse_hessian;
  int half_size = 0;
  bool valid = false;
};

// Samples the reference patch of image `grey` (CV_8UC1) centred at `centre`. False (template
// invalid) when the patch leaves the image or has too little texture to fix an affine warp.
bool MakePatchTemplate(const cv::Mat& grey, const cv::Point2f& centre, int half_size,
                       PatchTemplate* patch);

// Aligns `patch` into `grey`: on entry *warp (2x2) and *centre are the initial guess (the
// patch's pixel offset x maps to centre + warp x), on success they hold the alignment and the
// function returns true; *rms (may be null) receives the residual. On failure they are left
// in an unspecified state.
bool AlignPatch(const PatchTemplate& patch, const cv::Mat& grey, const AffinePatchOptions& options,
                Eigen::Matrix2d* warp, Eigen::Vector2d* centre, double* rms = nullptr);

}  // namespace rigcal::vo
