// SPDX-License-Identifier: Apache-2.0
#pragma once
// The batch rig calibrator (thesis chapter 4): linear estimate, model selection, misfit
// removal, non-linear refinement and uncertainty, for N slave cameras at once.

#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal {

// Calibrates every slave of `recording` against its master. Poses where a camera's trajectory
// jumps (glitches) are dropped first, with every camera's pose at that time, and counted in
// each slave's `glitches`; pairs are chosen by options.pairs on the rest. Thread-compatible (no
// shared state); never throws on bad data: problems are reported in the result's termination and
// message.
RigCalibration CalibrateRig(const RigRecording& recording, const CalibrationOptions& options);

// The recording CalibrateRig calibrates: `recording` without the times at which some camera's
// pose is a glitch (a jump, a rotated pose; calib/src/motions/pose_glitches.h). `dropped`, when not
// null, gets the indices of those times in `recording`, ascending.
RigRecording WithoutGlitches(const RigRecording& recording, std::vector<int>* dropped = nullptr);

// Calibrates one slave from its motions. `name` is copied into the result.
SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name = "");

}  // namespace rigcal
