// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 4 of the batch calibrator (CalibrateSlave): the non-linear refinement of the linear
// estimate (thesis 4.26-4.27, refinement.h) and its covariance. The linear residuals give the
// noise levels that whiten the problem; the scale measurements (4.18/4.31) give the scale
// priors of (4.27); the mean rotation axis reduces C to the plane (planar model, C along the
// axis held at the nominal mounting's or 0) or adds the nominal's weighted prior along it.

#include <Eigen/Core>
#include <vector>

#include "batch/batch_linear_solution.h"
#include "models/scale_measurement.h"
#include "motions/motion_data.h"
#include "refinement/refinement.h"
#include "rigcal/calib/calibration_options.h"

namespace rigcal::internal {

struct BatchRefinement {
  RefinementResult refined;  // with the covariance when options.compute_covariance
  // Per scale index: the scale measurements' summary (the result's measured_* figures).
  std::vector<ScaleSummary> summaries;
  bool solved = false;  // options.method is non-linear (else only the covariance is computed)
  int time_blocks = 0;  // blocks of the cluster-robust covariance (0 = none)
};

// Refines `linear` on the motions; `axis`: the mean rotation axis of a rotating rig, `planar`:
// the planar model; `epsilon`: the scale measurements' error (ScaleModelChoice).
BatchRefinement RefineBatch(const CalibrationOptions& options, const BatchSetting& setting,
                            const std::vector<MotionData>& motions, const LinearEstimate& linear,
                            const Eigen::Vector3d& axis, bool planar, double epsilon);

}  // namespace rigcal::internal
