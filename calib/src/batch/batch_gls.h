// SPDX-License-Identifier: Apache-2.0
#pragma once
// The gls pair policy of the batch calibrator (PairOptions::Policy::kGls): per slave, the
// auto policy's result (batch_pair_choice.h) refined by generalised least squares on every
// consecutive motion (k, k+1) with the pose noise fitted to their residuals
// (gls_refinement.h): no span is chosen, every pose's information counts with its weight.

#include "batch/batch_pair_choice.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// The auto result of slave `slave` refined by GLS on its consecutive motions (same motion and
// scale models; the result's pairs "gls"). The auto result, with the reason in its message,
// when the GLS cannot run (no estimate, time partitions of the scale, too few motions).
SlaveCalibration CalibrateSlaveGls(const RigRecording& recording,
                                   const AutoPairCandidates& candidates, int slave,
                                   const CalibrationOptions& options);

}  // namespace rigcal::internal
