// SPDX-License-Identifier: Apache-2.0
#pragma once
// The prior of a window refinement (RefinementPrior, refinement_prior.h) in the form Ceres
// minimises: square roots of its quadratic forms as residual blocks, so the refinement of a
// window with this prior minimises the same sum of squares as a refinement over every motion.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "rigcal/calib/refinement_prior.h"

namespace rigcal::internal {

// How C is parameterised in the problem the prior is added to.
enum class PriorPosition {
  kPlain,          // one block C (3)
  kAxis,           // blocks p (2) and h (1): C = t (p, h), t = [b_1 b_2 a]
  kTranslational,  // no C (the translational model, C = 0 in the residuals)
};

// L with L^T L = G, rows for the eigenvalues above 1e-14 of the largest (G positive
// semi-definite up to round-off: smaller or negative eigenvalues are dropped).
Eigen::MatrixXd SquareRootOf(const Eigen::MatrixXd& g);

// u^T G u of the position form for the given parameters (the prior's sum of squared position
// residuals, unwhitened), and q^T M q for the rotation form.
double PositionPriorValue(const RefinementPrior& prior, const Eigen::Quaterniond& q,
                          const Eigen::Vector3d& c, const std::vector<double>& segment_scales);
double RotationPriorValue(const RefinementPrior& prior, const Eigen::Quaterniond& q);

// Rotation residual block: L_M q / sigma over the quaternion (w, x, y, z) block.
ceres::CostFunction* MakeRotationPriorCost(const RefinementPrior& prior, double inv_sigma);

// Position residual block L_G u / sigma. Parameter blocks, in this order: q (4), then C (3) or
// p (2), h (1) or nothing as `layout` says, then one scale (1) per prior.segments entry.
// `t`: the basis of the axis layout (ignored otherwise).
ceres::CostFunction* MakePositionPriorCost(const RefinementPrior& prior, double inv_sigma,
                                           PriorPosition layout, const Eigen::Matrix3d& t);

}  // namespace rigcal::internal
