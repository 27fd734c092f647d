// SPDX-License-Identifier: Apache-2.0
#pragma once
// Replays a recording through the online path (SyncBuffer -> RigEstimator), deterministically
// in one thread, and records how the estimate converges over stream time.

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/sync_buffer.h"

namespace rigcal::pipeline {

struct OnlineReplayOptions {
  RigEstimatorOptions estimator;
  // Convergence is sampled every this many seconds of stream time.
  double report_every_s = 10.0;
  // Run the non-linear window refinement once at the end (as the background thread would).
  bool refine_at_end = true;
};

struct ConvergencePoint {
  double t_s = 0.0;  // seconds since the first stamp
  std::string slave;
  Similarity estimate;
  double rot_std_deg = std::numeric_limits<double>::quiet_NaN();  // NaN = unknown
  int motions_used = 0;
  SlaveState state = SlaveState::kInitialising;
  uint32_t flags = 0;                     // SlaveFlags: facts beside the state
  std::optional<CalibrationError> error;  // with truth
};

struct OnlineReplayResult {
  RigEstimate estimate;
  std::vector<ConvergencePoint> history;
  SyncStats sync;
};

// Poses of all cameras are pushed in time order (master first at equal stamps); the frame
// period for matching is the median stamp step. `truth` (nullable) adds errors to the history.
OnlineReplayResult ReplayOnline(const RigRecording& recording, const OnlineReplayOptions& options,
                                const std::map<std::string, Similarity>* truth);

// One line per history point: time, slave, flags, motions, σ, and the errors when known.
std::string FormatConvergence(const std::vector<ConvergencePoint>& history);

}  // namespace rigcal::pipeline
