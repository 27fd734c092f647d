// SPDX-License-Identifier: Apache-2.0
#pragma once
// Non-linear refinement of all parameters of one slave (thesis 4.4) with Ceres, and the
// covariance of the refined parameters.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/refinement_prior.h"

namespace rigcal::internal {

struct ScalePrior {
  double value = 0.0;
  double sigma = 0.0;  // <= 0: no prior for this scale
};

struct RefinementInput {
  Eigen::Quaterniond q;
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::vector<double> scales;
  std::vector<ScalePrior> priors;  // one per scale
  bool translational = false;      // (4.28) residuals, no position parameter
  // Noise levels used to whiten the residuals (from the linear solution's residuals).
  double sigma_rotation = 1.0;  // of the 4-vector A dq
  double sigma_position = 1.0;  // of the 3-vector position residual
  // Axis parameterisation of C (the reduced parameter set of planar motion): when `axis` is a
  // unit vector, C = B p + h axis with B = PlaneBasis(axis), starting from the projection of
  // `C`. h is held constant when axis_offset_fixed; axis_prior_sigma > 0 adds the weighted
  // term (h - axis_prior) / axis_prior_sigma. A zero axis: C is a plain 3-vector.
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  bool axis_offset_fixed = false;
  double axis_prior = 0.0;
  double axis_prior_sigma = 0.0;
  // Motions outside the given ones as quadratic forms (RefinementPrior, refinement_prior.h),
  // added as residual blocks whitened by the same sigmas, without robust loss;
  // prior_scale_index[k] is the scale variable of prior->segments[k]. Null: no prior.
  const RefinementPrior* prior = nullptr;
  std::vector<int> prior_scale_index;
  // Per motion, a weight of its squared residuals (empty: all 1).
  std::vector<double> weights;
  // Per motion, its time block (time_blocks.h), or empty. Given, the covariance is at least
  // the cluster-robust (sandwich) one, H⁻¹ (sum_b g_b g_bᵀ) H⁻¹ · B / (B - 1) with g_b the
  // gradient of block b's residuals: errors are independent between blocks only.
  std::vector<int> blocks;
};

struct RefinementResult {
  Eigen::Quaterniond q;
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::vector<double> scales;
  bool converged = false;
  std::string message;  // Ceres termination message
  // Covariance (0 and covariance_ok false when not computed or rank deficient).
  bool covariance_ok = false;
  Eigen::Matrix3d cov_rotation = Eigen::Matrix3d::Zero();  // rotation vector, rad^2
  Eigen::Matrix3d cov_position = Eigen::Matrix3d::Zero();  // of C; 0 along a fixed axis offset
  std::vector<double> scale_std;                           // NaN when not computed
  double axis_std = 0.0;  // σ of h with the axis parameterisation (0 when h is fixed)
  // With input.blocks: the cluster-robust covariance was larger than the one of independent
  // motions in some direction, and the covariance above is the smallest one above both.
  bool clustered_larger = false;
  // The covariance of independent motions of equal error (the one above before the
  // cluster-robust raise).
  Eigen::Matrix3d independent_cov_rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d independent_cov_position = Eigen::Matrix3d::Zero();
};

// Minimises eq. (4.26)+(4.27): rotation residuals q0·dq - dq·qi and position residuals
// (I - R0) dC + dλ dR C_i - C_0, each whitened by its sigma, plus the scale priors. The unit
// norm of dq is kept by Ceres's quaternion manifold instead of the thesis's penalty term.
// With compute_covariance, the covariance is scaled by the reduced chi-square of the fit (and
// raised to the cluster-robust one with input.blocks).
RefinementResult RefineNonlinear(const std::vector<MotionData>& motions,
                                 const RefinementInput& input, const CalibrationOptions& options,
                                 bool solve = true);

}  // namespace rigcal::internal
