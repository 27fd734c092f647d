// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the recursive estimator (RigEstimator, rig_estimator.h) publishes: per slave the result
// in the batch schema (calibration_result.h) and the online facts beside it.

#include <cstdint>
#include <limits>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/slave_state.h"

namespace rigcal {

struct SlaveOnlineState {
  uint32_t flags = 0;               // SlaveFlags (slave_state.h): facts beside the state
  int segment = 0;                  // current odometry segment of the slave
  int64_t last_update_ns = 0;       // stream time of the last accepted motion
  double short_long_rot_deg = 0.0;  // disagreement of the short and long windows
  int keyframes = 0;
  int gated_scale = 0;  // rejected by the screw-pitch scale gate
  int decalibration_events = 0;
  // Sets not used because the master's or this slave's pose was poorly tracked (a quality far
  // below the camera's usual one; motions/pose_quality_gate.h), and the last threshold that
  // rejected one. Not saved in the state file: a resumed run counts from 0.
  int poorly_tracked = 0;
  double quality_threshold = std::numeric_limits<double>::quiet_NaN();
  // Cameras that run free (OnlineOptions::time_offset; set by OnlineCalibrator::Estimate): the
  // clock offset is estimated from the data (else given), it is known (usable), the clock drift
  // dτ/dt in ppm, and the jumps of the offset detected (a camera restarted).
  bool clock_offset_estimated = false;
  bool clock_offset_known = false;
  double clock_drift_ppm = 0.0;
  double clock_drift_std_ppm = std::numeric_limits<double>::quiet_NaN();  // NaN: unknown
  int clock_jumps = 0;
};

struct RigEstimate {
  int64_t t_ns = 0;            // stream time of the last set
  uint64_t sets = 0;           // sets consumed
  uint64_t rejected_sets = 0;  // sets ignored: time not increasing, no or non-finite master
  RigCalibration rig;          // per slave: the result in the batch schema
  std::vector<SlaveOnlineState> online;  // per slave
  // Cameras that run free: restarts of the master's clock followed (SyncBuffer::ClockJumps(0);
  // OnlineCalibrator). A slave's online.clock_jumps counts its own clock's.
  int master_clock_jumps = 0;
};

}  // namespace rigcal
