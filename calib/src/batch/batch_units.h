// SPDX-License-Identifier: Apache-2.0
#pragma once
// The batch calibrator's arithmetic in the data's own length unit: every position divided by a
// power of two near the RMS distance of the master's centres from their mean, so that the
// refinement and its covariance (Ceres refuses a covariance whose reciprocal condition number is
// below 1e-14) are conditioned alike for a drive in micrometres or in kilometres. A power of two
// divides exactly: data already of unit size (RMS within [0.71, 1.41]) is solved bit for bit as
// before, and positions and their σ return to the input's unit exactly.

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// The power of two nearest (in log) to the RMS distance of the master's centres from their
// mean; 1 when that is zero or not finite.
double LengthUnitOf(const RigRecording& recording);

// The recording, the options (nominal centres, their σ, scale_dot_epsilon) and a result moved
// to and from the unit `length`. Scales are unchanged (every camera's positions are divided
// alike).
RigRecording InLengthUnit(const RigRecording& recording, double length);
CalibrationOptions InLengthUnit(const CalibrationOptions& options, double length);
void FromLengthUnit(double length, SlaveCalibration* result);

}  // namespace rigcal::internal
