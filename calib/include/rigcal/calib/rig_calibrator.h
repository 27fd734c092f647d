#pragma once
// The batch rig calibrator (thesis chapter 4): linear estimate, model selection, misfit
// removal, non-linear refinement and uncertainty, for N slave cameras at once.

#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/types.h"

namespace rigcal {

// Calibrates every slave of `recording` against its master. Pairs are chosen by
// options.pairs. Thread-compatible (no shared state); never throws on bad data: problems are
// reported in the result's termination and message.
RigCalibration CalibrateRig(const RigRecording& recording, const CalibrationOptions& options);

// Calibrates one slave from its motions. `name` is copied into the result.
SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name = "");

}  // namespace rigcal
