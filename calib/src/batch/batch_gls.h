// SPDX-License-Identifier: Apache-2.0
#pragma once
// The gls pair policy of the batch calibrator (PairOptions::Policy::kGls): per slave, the
// auto policy's result (batch_pair_choice.h) refined by generalised least squares on every
// consecutive motion (k, k+1) with the pose noise fitted to their residuals
// (gls_refinement.h): no span is chosen, every pose's information counts with its weight.

#include <vector>

#include "batch/batch_pair_choice.h"
#include "motions/motion_data.h"
#include "refinement/gls_refinement.h"
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

// The motions (k, k + span) of the slave as `span` chains of consecutive motions (k ≡ j mod
// span, in time order), with the scale variables of `r` (its scale keys: the segment ids, or
// one scale); motions of a segment without a scale are left out.
std::vector<MotionData> ChainMotions(const RigRecording& recording, int slave, int span,
                                     const SlaveCalibration& r);

// The GLS input that starts from the solved result `r`: its estimate, motion model and axis
// (planar: the offset held; a nominal mounting with options.nominal_sigma: weighted).
GlsInput GlsStartOf(const SlaveCalibration& r, const CalibrationOptions& options);

// The GLS estimate `g` of `in` and its σ in `out` (as the refinement's in batch_result.cc).
void TakeGls(const GlsResult& g, const GlsInput& in, const CalibrationOptions& options,
             SlaveCalibration* out);

}  // namespace rigcal::internal
