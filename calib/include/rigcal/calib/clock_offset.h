// SPDX-License-Identifier: Apache-2.0
#pragma once
// Clock offset of a camera that runs free, from the data (time offset = slave stamp - master
// clock at the same instant).
//
// 1. Scale-free: the angular speed |ω| of master and slave (rotation angle of consecutive
//    relative motions per second) is the same whatever the extrinsics and scales. Both are
//    sampled on a common grid and cross-correlated over a search window; the peak is refined
//    to sub-sample by a parabola through it and its neighbours.
// 2. Refined with the extrinsic rotation X = master_from_slave (the slave's orientation in the
//    master frame) of a calibration: the hand-eye rotation residuals angle(A X, X B(τ)) of
//    disjoint motions are minimised over τ (golden-section search around the correlation peak).
//    Both cameras are interpolated at the motions' ends, whose phases within a master frame cycle
//    through 8 even steps: an interpolated pose averages its neighbours' noise, so comparing the
//    master's own frames with the slave interpolated at frame + τ made the cost lowest midway
//    between frames whatever the truth. σ by a sandwich over the Gauss-Newton step (motions that
//    share a pose or overlap correlate); where the noise's slope rivals the signal's (slow
//    drives, noisy poses) from straight-line fits of the residuals over ±2 frames.

#include <Eigen/Geometry>
#include <limits>
#include <optional>

#include "rigcal/base/status.h"
#include "rigcal/calib/timed_trajectory.h"

namespace rigcal {

struct TimeOffsetOptions {
  double search_window_s = 0.5;  // the offset is searched within ± this around center_s
  double center_s = 0.0;         // the prior offset (e.g. the step of a clock that restarted)
  double min_overlap_s = 2.0;    // least common time of master and slave at every lag
  double motion_span_s = 0.5;    // span of the motions of the refinement
};

struct TimeOffsetEstimate {
  double offset_s = 0.0;
  double std_s = std::numeric_limits<double>::quiet_NaN();        // NaN = unknown
  double correlation = std::numeric_limits<double>::quiet_NaN();  // peak correlation
  int motions = 0;                                                // motions of the refinement
};

// Step 1. Errors (naming the slave): too few poses (fewer than 10), no angular speed samples,
// or the master and slave overlap by less than min_overlap_s at every lag in the window.
Expected<TimeOffsetEstimate> CorrelateAngularSpeed(const TimedTrajectory& master,
                                                   const TimedTrajectory& slave,
                                                   const TimeOffsetOptions& options = {});

// Step 2, around `initial` (searched within ± one slave frame interval, moved up to 6 times to a
// minimum at its end: the correlation can be frames off on slow, noisy drives), with X =
// `master_from_slave` the slave's orientation in the master frame. Returns `initial` unchanged
// when fewer than 5 motions can be formed.
TimeOffsetEstimate RefineTimeOffset(const TimedTrajectory& master, const TimedTrajectory& slave,
                                    const Eigen::Quaterniond& master_from_slave,
                                    const TimeOffsetEstimate& initial,
                                    const TimeOffsetOptions& options = {});

// Online refinement (ClockOffsetTracker), needing no extrinsics: the rotation angle of a rig
// motion is the same for every camera whatever the extrinsics and scales, so the offset is
// the one that minimises sum_k (angle(A_k) - angle(B_k(τ)))² over the motions (k, k + span)
// of master poses starting in [from_ns, to_ns) (master clock), B_k(τ) the slave's rotation
// between the master instants + τ (interpolated, InterpolatePose). Golden-section search in
// [center_s - half_width_s, center_s + half_width_s]. Both cameras are interpolated at each
// motion's ends, moved on by (k mod 8) / 8 of a master frame (as in RefineTimeOffset). σ from
// the Gauss-Newton step with the residuals' autocovariance over the lags at which motions share
// a pose or overlap. nullopt with fewer than 5 motions.
struct AngleOffsetMeasurement {
  double offset_s = 0.0;
  double std_s = std::numeric_limits<double>::quiet_NaN();  // NaN: not determined
  int motions = 0;
  bool at_bound = false;  // the minimum lies at an end of the searched interval
  double rms_rad = 0.0;   // RMS angle residual at the minimum
};
std::optional<AngleOffsetMeasurement> MeasureOffsetFromAngles(const TimedTrajectory& master,
                                                              const TimedTrajectory& slave,
                                                              int64_t from_ns, int64_t to_ns,
                                                              double center_s, double half_width_s,
                                                              double motion_span_s);

}  // namespace rigcal
