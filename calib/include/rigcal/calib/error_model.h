// SPDX-License-Identifier: Apache-2.0
#pragma once
// Error model of thesis 5.1.1: compares an estimate with the true rig parameters.

#include <limits>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal {

struct CalibrationError {
  double rot_deg = 0.0;    // rotation orientation error: 2 acos(q_hat^* q)_w
  double dir_deg = 0.0;    // position orientation error: angle between C and C_hat
  double dist_pct = 0.0;   // distance error: | |C| - |C_hat| | / |C| in percent
  double trans_err = 0.0;  // |C - C_hat| in master units
  double scale_pct = 0.0;  // | s - s_hat | / s in percent
  // |C - C_hat| split at a unit axis (the mean rotation axis of planar motion): the error
  // orthogonal to it (in the plane) and along it. NaN when no axis is given.
  double plane_err = std::numeric_limits<double>::quiet_NaN();
  double axis_err = std::numeric_limits<double>::quiet_NaN();
};

// `axis`: the direction to split the position error at; a zero vector = none.
CalibrationError CompareToTruth(const Similarity& estimate, const Similarity& truth,
                                const Eigen::Vector3d& axis = Eigen::Vector3d::Zero());

// Constraint residua of one motion against given rig parameters (thesis 5.1.1, fig. 5.11), and
// its direct scale measurement (4.18, fig. 5.12).
struct ConstraintResidual {
  double rotation_deg = 0.0;      // angle between R_0 dR and dR R_i
  double position_dir_deg = 0.0;  // angle between R_0 dC + C_0 and s dR C_i + dC
  double position_abs = 0.0;      // |(R_0 - I) dC + C_0 - s dR C_i|
  double scale_pct = 0.0;         // |s - lambda_meas| / s, percent (0 if degenerate)
  // The products C_0^T r_0 and C_i^T r_i of (4.18) (r: unit rotation axis of the motion, in its
  // canonical w >= 0 form) and their ratio, the measured scale λ^k; NaN without a rotation axis
  // (or, for the scale, when C_i^T r_i is 0). (4.23) rejects λ^k when |C_i^T r_i| <= 3 ε
  // (ScaleDotEpsilon).
  double master_axis_dot = std::numeric_limits<double>::quiet_NaN();
  double slave_axis_dot = std::numeric_limits<double>::quiet_NaN();
  double measured_scale = std::numeric_limits<double>::quiet_NaN();
};

ConstraintResidual ResidualOf(const RigMotion& motion, const Similarity& rig);

// ε of (4.23), the absolute error expected on the products C^T r of (4.18): `configured`
// (CalibrationOptions::scale_dot_epsilon) when > 0, else 1e-3 of the RMS length of the slave
// translations C_i of the motions. A measured scale is used when |C_i^T r_i| > 3 ε.
double ScaleDotEpsilon(double configured, const std::vector<Eigen::Vector3d>& slave_translations);

}  // namespace rigcal
