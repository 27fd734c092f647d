// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 3 of the recursive estimator (RigEstimator): an accepted motion enters a slave's
// statistics. Fixed-size sufficient statistics (motion_statistics.h) hold every motion:
//   long   all the information, forgotten exponentially with half_life_s (0 = never);
//   short  a twin forgotten with short_half_life_s, to detect decalibration;
//   window the last window_size motions, copied for the background non-linear refinement;
//   outside  the long statistics minus the window's motions (the refinement's prior), so that
//          long == outside + window, forgotten alike;
//   rotation_blocks  the long statistics' rotation information in time blocks (the
//          cluster-robust rotation σ, online_uncertainty.h).
// At most max_open_segments odometry segments keep their scale as a variable; older ones are
// marginalised at the current rotation.

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>

#include "models/motion_statistics.h"
#include "motions/motion_data.h"
#include "noise/rotation_blocks.h"
#include "rigcal/calib/refinement_job.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

struct WindowEntry {
  RigMotion motion;
  double weight = 1.0;     // its weight in the statistics when it was added
  MotionData data;         // as added (signs aligned)
  double log_decay = 0.0;  // the slave's cumulative log forgetting factor when it was added
};

struct SlaveStatistics {
  explicit SlaveStatistics(const RigEstimatorOptions& options);

  MotionStatistics long_stats;
  MotionStatistics short_stats;
  std::deque<WindowEntry> window;
  MotionStatistics outside;
  RotationBlocks rotation_blocks;
  double log_decay = 0.0;      // sum of the log forgetting factors applied to long_stats
  int64_t last_decay_ns = -1;  // stream time the statistics were last forgotten to
};

// Forgets the statistics to the motion's end time, then adds the motion (sign-aligned `md` of
// `motion`) with `weight`; marginalises the oldest open segments beyond max_open_segments at
// the rotation `marginalise_at`, and moves the window's oldest motion into `outside` when it
// is full.
void AccumulateMotion(const RigEstimatorOptions& options, const RigMotion& motion,
                      const MotionData& md, double weight, const Eigen::Quaterniond& marginalise_at,
                      SlaveStatistics* stats);

// The master's odometry re-initialised (a new master unit): positions and scales restart, the
// unit-free rotation information stays; the window is dropped into the prior.
void RestartPositions(SlaveStatistics* stats);

// Decalibration: the statistics restart from the window's motions that began at or after
// `since_ns` (the first disagreement of the windows, after the camera moved), the others
// dropped. The short window is not enough: its older motions, of the old mounting, keep
// their forgotten weight for ever in the long statistics (half_life_s 0) and bias the new
// estimate (measured: 16σ off at the end of a drive after a camera moved).
void RestartFromMotionsSince(const RigEstimatorOptions& options, int64_t since_ns,
                             SlaveStatistics* stats);

// The window (motions and how much of each the statistics still hold) and the prior of the
// motions before it, for a refinement job.
void CopyWindow(const SlaveStatistics& stats, RefinementJob* job);

}  // namespace rigcal::internal
