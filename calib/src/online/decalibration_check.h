// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 4 of the recursive estimator (RigEstimator): a camera that moved on the rig. The long
// statistics hold the old mounting for a long time; their short-window twin (forgotten with
// short_half_life_s) follows a new one within seconds. When the two windows' rotations differ by
// more than decalibration_sigmas times their σ (at least decalibration_min_deg; or C by more
// than decalibration_min_translation when > 0) for decalibration_confirmations consecutive
// keyframes spanning at least decalibration_confirm_s, the slave is decalibrated: the estimator
// re-converges on the recent motions.
//
// Only a settled long-window estimate is compared: enough motions and a rotation with a small σ
// (the first keyframes of a planar drive can look general with the rotation about the axis
// undetermined in both windows; the translational model has no σ, and a car driving straight
// does not determine the rotation about its direction of travel). Planar motion is not compared
// (the short window determines the rotation about the axis from a few translations only), and
// across a change of the motion model the short window still holds the other model's motions: no
// comparison until it has forgotten them.

#include <cstdint>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

// Saved in the estimator state (estimator_state.h), so that the alarm survives a restart.
using DecalibrationState = DecalibrationAlarmState;

struct WindowComparison {
  bool compared = false;
  double rot_diff_deg = 0.0;  // angle between the windows' rotations (0 when not compared)
  bool decalibrated = false;  // confirmed now: the caller restarts from the short window
};

// The motion model last changed at model_changed_ns (-1: never) long enough before now_ns for
// the short window to have forgotten the other model's motions.
bool ModelSettled(const RigEstimatorOptions& options, int64_t model_changed_ns, int64_t now_ns);

// Compares the long-window estimate with the short-window one at stream time now_ns. `overlap`:
// the σ inflation of overlapping pairs (online_uncertainty.h), for both windows' σ. Counts the
// disagreements in `state`; a confirmed decalibration is recorded there at now_ns.
WindowComparison CompareWindows(const RigEstimatorOptions& options,
                                const SlaveCalibration& long_window,
                                const SlaveCalibration& short_window, double overlap,
                                bool model_settled, int64_t now_ns, DecalibrationState* state);

// A stream clock that restarted (a resumed run on a clock that began again, as CLOCK_MONOTONIC
// after a reboot) is behind the stamps of a restored alarm: they move to now_ns, so that the
// alarm holds for short_half_life_s of the new clock instead of until the new clock passes the
// old stamps.
void FollowRestartedClock(int64_t now_ns, DecalibrationState* state);

// Within short_half_life_s of the last decalibration: the estimate is re-converging.
bool RecentlyDecalibrated(const RigEstimatorOptions& options, const DecalibrationState& state,
                          int64_t now_ns);

}  // namespace rigcal::internal
