#pragma once
// Clock offset of a camera that runs free, from the data (time offset = slave stamp - master
// clock at the same instant).
//
// 1. Scale-free: the angular speed |ω| of master and slave (rotation angle of consecutive
//    relative motions per second) is the same whatever the extrinsics and scales. Both are
//    sampled on a common grid and cross-correlated over a search window; the peak is refined
//    to sub-sample by a parabola through it and its neighbours.
// 2. Refined with the extrinsic rotation X (slave orientation in the master frame) of a
//    calibration: the hand-eye rotation residuals angle(A X, X B(τ)) of the motions between
//    master instants, B(τ) interpolated from the slave at the master instants + τ, are
//    minimised over τ (golden-section search around the correlation peak); σ from the
//    curvature of that cost (Gauss-Newton: σ² = s² / Σ |∂r/∂τ|², s² the residual variance).

#include <limits>

#include "rigcal/calib/status.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::tools {

struct TimeOffsetOptions {
  double search_window_s = 0.5;  // the offset is searched within ± this
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

// Step 2, around `initial` (searched within ± one slave frame interval), with `x` the slave's
// orientation in the master frame. Returns `initial` unchanged when fewer than 5 motions can
// be formed.
TimeOffsetEstimate RefineTimeOffset(const TimedTrajectory& master, const TimedTrajectory& slave,
                                    const Eigen::Quaterniond& x, const TimeOffsetEstimate& initial,
                                    const TimeOffsetOptions& options = {});

}  // namespace rigcal::tools

#include <optional>
#include <vector>

#include "rigcal/calib/calibration_options.h"

namespace rigcal::tools {

// The recording of a rig whose cameras may run free, matched at the slaves' time offsets
// (MatchFreeRunning), and those offsets.
struct OffsetMatch {
  RigRecording recording;
  std::vector<TimeOffsetEstimate> offsets;  // per slave
  std::vector<bool> interpolated;           // per slave: interpolated, not matched by stamp
};

// `given_offset_s`: every slave's offset (σ unknown); nullopt: estimated per slave
// (CorrelateAngularSpeed, a calibration with `options` at those offsets, RefineTimeOffset for
// every slave whose rotation it solved). Errors: those of CorrelateAngularSpeed and
// MatchFreeRunning.
Expected<OffsetMatch> MatchWithTimeOffsets(const TimedTrajectory& master,
                                           const std::vector<TimedTrajectory>& slaves,
                                           std::optional<double> given_offset_s,
                                           int64_t tolerance_ns, const CalibrationOptions& options,
                                           const TimeOffsetOptions& offset_options = {});

}  // namespace rigcal::tools
