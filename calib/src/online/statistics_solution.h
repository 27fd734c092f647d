// SPDX-License-Identifier: Apache-2.0
#pragma once
// The recursive estimator's linear solution (RigEstimator): one slave's statistics solved in the
// motion model that applies, in the batch result schema. Its linear least-squares solution equals
// the batch calibrator's on the same motions (motion_statistics.h).
//
// Motion model (thesis 5.2): purely translational (4.5) until a formed motion rotates by the
// equal-error boundary at the rotation noise measured so far; then rotating, general or planar
// by the figures of model_selection.h, with hysteresis (RigEstimatorOptions).

#include <optional>

#include "models/motion_statistics.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

// The motion model of a slave: rotating once a formed motion rotated by the equal-error
// boundary at the rotation noise measured so far.
struct MotionModelChoice {
  bool rotating = false;
  double noise_deg = 0.0;     // running RMS of the master-minus-slave rotation angle difference
  double boundary_deg = 0.0;  // translational below this largest rotation
};

// The equal-error boundary (degrees) at the running angle-invariant variance `angle_var`
// (deg^2): the fixed max(alpha_maxrot_deg, pair_min_angle_deg) until gate_after_motions motions
// measured it, or when alpha_maxrot_noise_deg = 0 (RigEstimatorOptions::model_selection).
double OnlineTranslationalBelowDeg(const RigEstimatorOptions& options,
                                   const RunningMeanSquare& angle_var);

// The choice for a slave that is `rotating`, with the noise and boundary of `angle_var`.
MotionModelChoice ChooseMotionModel(const RigEstimatorOptions& options, bool rotating,
                                    const RunningMeanSquare& angle_var);

// Linear solution of one set of statistics in the motion model `choice`, C along an
// unobservable axis from `nominal` when given. `general` is the hysteresis state of a rotating
// rig (true: the general model was chosen last time); it is updated when not null. The result's
// message is the model selection's reason (or why there is no estimate yet).
SlaveCalibration SolveStatistics(const MotionStatistics& stats, const RigEstimatorOptions& options,
                                 const std::optional<Similarity>& nominal, int current_segment,
                                 const MotionModelChoice& choice, bool* general);

}  // namespace rigcal::internal
