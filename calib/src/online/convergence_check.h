// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 6 of the recursive estimator (RigEstimator): the state of a published estimate
// (slave_state.h) and its facts (SlaveFlags): initialising until solved, decalibrated while it
// re-converges after a decalibration; else translational-only or planar by the motion model,
// and converged (not just usable) once it rests on converged_min_motions motions, its σ (inflated,
// online_uncertainty.h) are below converged_rot_std_deg and converged_pos_std_fraction, the
// linear estimate has been stable over converged_stable_keyframes keyframes, and it is not
// re-converging after a decalibration.

#include <Eigen/Geometry>
#include <cstdint>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

struct ConvergenceState {
  int stable = 0;  // consecutive updates the linear rotation moved within its σ
  Eigen::Quaterniond last_q = Eigen::Quaterniond::Identity();  // the linear rotation then
};

// Sets published->state and returns the facts kFlagTranslationalOnly and kFlagPlanar of
// `published`; counts the stability of `linear` (a refinement being published is no change),
// whose rotation σ is inflated by `rotation_inflation`. The position σ is measured against
// max(|C|, master_motion_length): the median length of the master's motions in the window
// stands for |C| when the cameras sit close together, in the master's own unit.
uint32_t ConvergenceCheck(const RigEstimatorOptions& options, SlaveCalibration* published,
                          const SlaveCalibration& linear, double rotation_inflation,
                          bool decalibrated, double master_motion_length, ConvergenceState* state);

}  // namespace rigcal::internal
