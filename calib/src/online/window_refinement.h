// SPDX-License-Identifier: Apache-2.0
#pragma once
// The background non-linear refinement of the recursive estimator (RigEstimator): a copy of a
// slave's window of motions with the statistics of the motions before it as a prior
// (RefinementJob, RefineWindow in refinement_job.h), refined on another thread, and published
// when it agrees with the current linear estimate.

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

// The refinement is published instead of the linear estimate when its rotation lies within
// gate_sigmas times the linear rotation σ (inflated by `rotation_inflation` for the drift shared
// by overlapping pairs, at least 1e-3 deg) of the linear rotation.
bool RefinementAgrees(const RigEstimatorOptions& options, const SlaveCalibration& refined,
                      const SlaveCalibration& linear, double rotation_inflation);

}  // namespace rigcal::internal
