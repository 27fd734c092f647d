// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 1 of the batch calibrator (CalibrateSlave): the slave's motions in the solvers' working
// form, and the removal of the motions a model cannot use or that do not fit: too small a
// rotation (thesis alpha_threshold, 4.3.1), no translation (translational model, 4.5), master
// and slave rotation angles that differ (the scale-free invariant), and residual outliers
// (misfit removal, after each linear solution).

#include <string>
#include <vector>

#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// The motions in the solvers' form without the non-finite ones; sets counts->total and counts
// the non-finite ones as residual outliers.
std::vector<MotionData> FormMotions(const std::vector<RigMotion>& motions, MotionCounts* counts);

// Removes motions whose value exceeds median + factor * sigma (one-sided, for residual norms),
// or whose |value - median| does (two-sided); robust median and σ (1.4826 MAD). Never removes
// below `floor`. Returns how many were removed.
int RemoveOutliers(std::vector<MotionData>* motions, const std::vector<double>& values,
                   double factor, double floor, bool two_sided);

// Drops the motions the model cannot use (a rotating rig: master or slave rotation below
// alpha_threshold_deg; translational: no translation; counted as small_rotation), then those
// whose master and slave rotation angles differ by more than outlier_mad_factor robust σ, at
// least angle_invariant_floor_deg (counted as angle_mismatch).
void RemoveUnusableMotions(const CalibrationOptions& options, bool translational,
                           std::vector<MotionData>* motions, MotionCounts* counts);

// Why `count` usable motions are too few (fewer than options.min_motions).
std::string TooFewMotionsMessage(const CalibrationOptions& options, bool translational,
                                 size_t count, double max_rotation_deg);

}  // namespace rigcal::internal
