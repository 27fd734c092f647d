// SPDX-License-Identifier: Apache-2.0
#pragma once
// The σ of an auto or gls batch result, held to what the recording supports (the last stage of
// CalibrateRig for those pair policies; it changes σ only, never the estimate).
//
// The reported σ come from the chosen pairs' own refinement: its noise fitted to, and its
// cluster-robust sandwich cut into time blocks of, those pairs. On a short recording the chosen
// span is long (a walk's 28 frames of 100), the chains hold 2-3 motions each, and the sandwich
// has 4 blocks for 7 parameters (a meat of rank 3): the σ fall back to those of independent
// motions in most directions and are 2-4 times too small on drifting odometry
// (tests/calib/short_history_sigma_eval_test.cc).
//
// The floor: generalised least squares on every consecutive motion (k, k+1) of the recording,
// its noise fitted to n - 1 increments (well determined whatever the length), at the result's
// estimate. With the right noise it is the efficient estimate (Gauss-Markov; gls_refinement.h),
// so the result's error is its error plus the difference d of the two estimates, and d is
// uncorrelated with the efficient estimate's error (Hausman 1978): Var = Var_gls + E[d dᵀ].
// The one observed d stands for its expectation; every σ is raised to sqrt(σ_gls² + d²) where
// that is larger (per axis of C, per scale; the rotation angle between the two estimates for
// the rotation's largest-axis σ). A result whose error is mostly d is then covered by d itself:
// (e_gls + d)² / (σ_gls² + d²) ≤ (e_gls / σ_gls)² + 1. One d per parameter has one degree of
// freedom (a small d by chance left σ at σ_gls), so Var(d) is also taken as λ Σ_gls per block,
// λ = dᵀ Σ_gls⁻¹ d / k from the block's k differences together: for C and the scales Var(d)
// is the mean of d² and λ σ_gls², for the rotation (its d the angle of three differences) the
// larger of d² and λ σ_gls².

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// Raises the σ of the solved result `r` of slave `slave` of `recording` (in the data's length
// unit) to the floor above, and says so in its message when any was raised. Nothing when `r`
// is not solved, has time-partitioned scales, or the GLS cannot run on the consecutive motions,
// nor with options.covariance_time_blocks 0 (the σ of independent motions asked for).
void HoldSigmaToConsecutiveGls(const RigRecording& recording, int slave,
                               const CalibrationOptions& options, SlaveCalibration* r);

}  // namespace rigcal::internal
