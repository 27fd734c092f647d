// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 5 of the batch calibrator (CalibrateSlave): the result in the Ceres Summary style
// (calibration_result.h): the estimate and its σ, what the motions could not determine, the
// termination and a message that says which models were chosen and why
// (model_explanation.h), or why there is no estimate.

#include <optional>
#include <string>
#include <vector>

#include "batch/batch_linear_solution.h"
#include "batch/batch_model_selection.h"
#include "batch/batch_refinement.h"
#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// `r` terminated with `termination` and `message`.
SlaveCalibration Failed(SlaveCalibration r, Termination termination, const std::string& message);

// The linear estimate's outcome in `r`: `used` motions, and for a rotating rig the figures of
// its solution and the model chosen (general or planar).
void TakeLinearFigures(const BatchSetting& setting, const LinearEstimate& linear, int used,
                       SlaveCalibration* r);

// The failed result when the linear estimate leaves the slave undetermined: fewer than
// min_motions consistent motions; planar motion under the forced general model (the rotation
// about the axis and C along it are not determined, whether or not the equations happen to be
// singular; a merely large σ along the axis is reported, not failed); singular position
// equations. nullopt when the slave is determined.
std::optional<SlaveCalibration> UndeterminedResult(const CalibrationOptions& options,
                                                   const BatchSetting& setting,
                                                   const LinearEstimate& linear,
                                                   const SlaveCalibration& r);

// The refined estimate, scales, σ, unobservable directions, termination and message in `r`.
void AssembleResult(const CalibrationOptions& options, const BatchSetting& setting,
                    const std::vector<MotionData>& motions, const LinearEstimate& linear,
                    const BatchRefinement& refinement, const ScaleModelChoice& scale,
                    SlaveCalibration* r);

}  // namespace rigcal::internal
