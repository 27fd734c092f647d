// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 2 of the batch calibrator (CalibrateSlave): the models. Motion model (thesis 5.2): the
// purely translational model (4.5) when no motion rotates by the equal-error boundary at the
// rotation noise measured from the motions, else a rotating rig, general or planar by the
// figures of its linear solution (model_selection.h). Scale model (thesis 5.5): one scale per
// odometry segment when the data has several, time-dependent scales (partitions) when the
// measured scales drift, else one time-fixed scale.

#include <string>
#include <vector>

#include "batch/batch_linear_solution.h"
#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// The motion model requested for the slave `name` (options.motion_model; kAuto becomes
// translational below the equal-error boundary), with the model-selection thresholds and the
// nominal prior of `name`. Sets the figures behind it: max_rotation_deg, rotation_noise_deg and
// translational_below_deg.
BatchSetting SelectMotionModel(const CalibrationOptions& options, const std::string& name,
                               const std::vector<MotionData>& motions, Observability* figures);

struct ScaleModelChoice {
  ScaleModel model = ScaleModel::kFixed;
  std::string why;  // the message's phrase (empty when the model was given)
  // Expected error of the products C^T r of (4.18), the measurements' threshold (4.23).
  double epsilon = 0.0;
};

// Chooses the scale model (options.scale_model; kAuto decided as above) and assigns the motions'
// scale keys: segment ids, partition numbers of the time-ordered motions, or 0.
ScaleModelChoice SelectScaleModel(const CalibrationOptions& options, const BatchSetting& setting,
                                  std::vector<MotionData>* motions);

}  // namespace rigcal::internal
