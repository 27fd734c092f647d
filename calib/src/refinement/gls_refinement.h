// SPDX-License-Identifier: Apache-2.0
#pragma once
// Generalised least squares on the consecutive motions (k, k+1) of one slave: the rig's
// residuals of every increment, whitened per component by the pose noise fitted to them
// (noise_whitening.h), minimised by Gauss-Newton over the rig's few parameters. Every fixed
// span's motion is (to first order) a linear combination of the increments, so with the
// right noise this estimate is at least as good as any span's (Gauss-Markov).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <atomic>
#include <string>
#include <vector>

#include "motions/motion_data.h"
#include "rigcal/calib/noise_whitening.h"

namespace rigcal::internal {

struct GlsInput {
  // The start (a solved estimate); scales indexed by the motions' scale_index.
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::vector<double> scales;
  bool translational = false;  // (4.28) residuals only; no rotation residual, no C
  // C = B p + h axis about a unit `axis` (zero: C is a plain 3-vector); h held at its start
  // value when axis_offset_fixed (planar model), else pulled to axis_prior by
  // axis_prior_sigma > 0 (the nominal mounting's weighted prior).
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  bool axis_offset_fixed = false;
  double axis_prior = 0.0;
  double axis_prior_sigma = 0.0;
  // A prior on the rotation: another estimate of it with its covariance (rotation vector, rad²;
  // zero: no prior), e.g. from the chains of the span that determines the rotation best.
  Eigen::Quaterniond rotation_prior = Eigen::Quaterniond::Identity();
  Eigen::Matrix3d rotation_prior_cov = Eigen::Matrix3d::Zero();
  int noise_rounds = 2;  // fit the noise, solve; repeated on the new residuals
  int time_blocks = 0;   // blocks of the cluster-robust check on the whitened residuals
  // After the first round, motions with a whitened residual beyond this many robust σ are
  // dropped (0: none).
  double outlier_factor = 6.0;
  // Set by another thread to end the refinement early (CalibrationOptions::cancel): checked by
  // the noise fit and at every Gauss-Newton step; the result is then not ok ("cancelled").
  const std::atomic<bool>* cancel = nullptr;
};

struct GlsResult {
  bool ok = false;
  std::string message;  // why not, when !ok
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::vector<double> scales;
  // Covariances: rotation vector (rad²), C (master units², 0 along a fixed axis offset).
  Eigen::Matrix3d cov_rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d cov_position = Eigen::Matrix3d::Zero();
  std::vector<double> scale_std;
  double axis_std = 0.0;          // σ of h when it is free
  bool clustered_larger = false;  // the cluster-robust covariance raised the σ
  // C corrected for the rotation noise in its regressor (regressor_noise.h); false when the
  // motions turn too little for the first-order correction (or the model has no C).
  bool regressor_noise_corrected = false;
  double chi2 = 0.0;              // mean square of the whitened residuals (about 1)
  int increments = 0;             // motions used
  int runs = 0;                   // stretches of consecutive motions (restarts of the filter)
  int outliers = 0;               // motions dropped by their whitened residual
  std::vector<LevelNoise> noise;  // per residual component (rotation x y z, position x y z)
};

// `motions`: consecutive motions in time order (a run restarts where one does not begin at
// the previous one's end, or the segment or scale variable changes).
GlsResult RefineGls(const std::vector<MotionData>& motions, const GlsInput& input);

}  // namespace rigcal::internal
