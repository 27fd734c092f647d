#pragma once
// The auto pair policy of the batch calibrator (PairOptions::Policy::kAuto): per slave, the
// span whose solve reports the most certain estimate.

#include <string>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/types.h"

namespace rigcal::internal {

// Solves slave `slave` of `recording` with the pairs (k, k + N) of every span N of
// AutoSpanCandidates and with kWalk's pairs, and returns the result whose largest σ ratio to the
// best candidate (rotation; position when observable) is smallest, among the usable results when
// there are any. The result's `pairs` names the span and how it was chosen.
SlaveCalibration CalibrateSlaveAutoPairs(const RigRecording& recording, int slave,
                                         const CalibrationOptions& options);

}  // namespace rigcal::internal
