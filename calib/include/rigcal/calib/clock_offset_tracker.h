// SPDX-License-Identifier: Apache-2.0
#pragma once
// ClockOffsetTracker: the online clock offset of every slave camera that runs free (its own
// capture instants and its own clock), a state of the online estimator with its σ.
//
// The offset of slave i is τ_i = slave stamp - master clock at the same instant [s]. It is
//  1. initialised scale-free, without extrinsics: the angular speeds of master and slave over
//     the first init_window_s of poses are cross-correlated (CorrelateAngularSpeed,
//     clock_offset.h);
//  2. refined and followed by a Kalman filter with state [τ, ρ] (ρ = dτ/dt, the clock drift)
//     whose measurements are the offsets that minimise the rotation-angle residuals of the
//     motions of successive non-overlapping windows of measure_window_s
//     (MeasureOffsetFromAngles): the rotation angle of a rig motion is the same for every
//     camera, whatever the extrinsics and scales;
//  3. re-initialised after a jump (a camera restarted): jump_confirmations measurements in a
//     row that disagree with the prediction by more than jump_sigmas (innovation σ) and
//     jump_min_s, or that lie at the end of the searched interval, or windows whose slave poses
//     end before the predicted instants although the master is a window further and the slave
//     kept delivering (its clock stepped back), are a jump (counted when a measurement had
//     confirmed the offset, not when a (re)initialisation failed); it is logged as a warning
//     and the offset is estimated afresh from the poses since the first disagreeing window
//     (step 1, searched within ± search_window_s around the last offset; larger steps are the
//     SyncBuffer's: 4.);
//  4. re-acquired after a restart of the slave's clock that the SyncBuffer followed (a step
//     beyond what step 3 can search, e.g. stamps that restart near 0; FollowClockJump): the
//     slave's poses on the old clock are forgotten and step 1 runs on the new ones, searched
//     within ± search_window_s around the step's prior offset.
//  5. moved by a restart of the master's clock that the SyncBuffer followed
//     (FollowMasterClockJump): every offset steps by minus the master's step, confirmed by the
//     next measurement.
// Slaves whose offset is given are held at it (σ unknown) until the master's clock restarts.
//
// Memory: per camera, the poses of the last history_s seconds (a deque trimmed on every Add).
// Not thread-safe: OnlineCalibrator serialises the calls.

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/estimator_state.h"

namespace rigcal {

struct ClockOffsetOptions {
  // Cameras run free: slave poses are interpolated at the master's instants (the SyncBuffer's
  // interpolation) at the offsets below. false (default): stamps are synchronised and matched
  // as they are; nothing below is used.
  bool enabled = false;
  // Per slave (one entry each, or empty = every slave estimated): nullopt = estimated from the
  // data, a value = the given offset [s], held.
  std::vector<std::optional<double>> given_s;
  double init_window_s = 8.0;  // poses correlated for the initial estimate, > 2 s
  // The offset is searched within ± this (around 0 at the start, around the last offset after
  // a jump, around the step after a followed clock restart), > 0.
  double search_window_s = 0.5;
  double measure_window_s = 2.0;  // one refinement measurement per this much master time, > 0
  double motion_span_s = 0.5;     // span of the motions of a measurement, > 0
  // Kalman filter: prior σ of the drift rate and its random walk, random walk of τ.
  double drift_ppm = 100.0;                // >= 0
  double drift_walk_ppm_per_sqrt_s = 0.5;  // >= 0
  double offset_walk_s_per_sqrt_s = 2e-5;  // >= 0
  // Jumps: see the header comment.
  double jump_sigmas = 6.0;    // > 0
  double jump_min_s = 0.002;   // >= 0
  int jump_confirmations = 2;  // >= 1
  double history_s = 20.0;     // poses kept per camera, >= init_window_s + 2 measure windows

  // The first violated constraint as "time_offset.<field>: <constraint>".
  Status Check(int num_slaves) const;
};

// The offset of one slave as the tracker knows it.
struct SlaveClockOffset {
  bool estimated = false;  // estimated from the data (false: given)
  bool known = false;      // usable: given, or initialised and not in doubt (no suspected jump)
  double offset_s = 0.0;   // at the newest master stamp
  double std_s = std::numeric_limits<double>::quiet_NaN();  // NaN: unknown (given, or not yet)
  double drift_ppm = 0.0;                                   // dτ/dt, parts per million
  double drift_std_ppm = std::numeric_limits<double>::quiet_NaN();
  int measurements = 0;  // refinement measurements accepted since the last (re)initialisation
  int jumps = 0;         // jumps detected
  // Master stamp from which sets use this offset (after a (re)initialisation, sets matched
  // before it used another offset).
  int64_t usable_from_ns = 0;
};

class ClockOffsetTracker {
 public:
  // camera_names[0] is the master. `options` must be valid (Check). Starts no thread.
  ClockOffsetTracker(std::vector<std::string> camera_names, ClockOffsetOptions options);
  ~ClockOffsetTracker();

  // Takes one pose of any camera (stamp on its own clock, increasing per camera; others are
  // ignored). Returns true when the offset of some slave changed (initialised, refined, or
  // found to have jumped): SlaveOffset then has the new value.
  bool Add(const CameraPose& pose);

  int num_slaves() const;
  // Slave `slave` (0-based: camera slave + 1).
  SlaveClockOffset SlaveOffset(int slave) const;
  // The offset to match with [ns]: the estimate; while (re)initialising the prior of a followed
  // clock jump, else 0 before the first initialisation and the last estimate after a jump.
  int64_t MatchingOffsetNs(int slave) const;

  // The offset state of every slave (given ones: not initialised, their jumps 0), to continue
  // after a restart.
  std::vector<ClockOffsetState> SaveState() const;
  // Continues from `states` (one per slave, SaveState's): estimated slaves take their offset,
  // drift, covariance and counts and are usable at once when they had a measurement; given
  // slaves keep their value. Errors: a count other than num_slaves(), a non-finite value or a
  // covariance with a negative variance (naming the slave). Call before the first Add.
  Status RestoreState(const std::vector<ClockOffsetState>& states);

  // The SyncBuffer followed a restart of slave `slave`'s clock (SyncBuffer::ClockJumps) and
  // set its offset to `prior_s` (the step): the offset is re-acquired around it from the poses
  // added from now on (step 4). Counted as a jump when the slave had an offset before. Logged.
  void FollowClockJump(int slave, double prior_s);
  // The SyncBuffer followed a restart of the MASTER's clock (SyncBuffer::ClockJumps(0)) by
  // `step_s` (new master clock - old): the master's poses on the old clock are forgotten and
  // every slave's offset moves by -step_s (state, prior), its σ grows by a quarter of a master
  // frame, and it is usable again once the next measurement window confirms it (no new
  // correlation; a measurement at the end of its interval re-initialises it as in step 3). A
  // slave whose offset was given is estimated from then on, starting at the given value moved by
  // the step. Not counted in any slave's jumps (their clocks did not restart). Logged.
  void FollowMasterClockJump(double step_s);

 private:
  struct Slave;
  void Update(int slave);
  bool Initialise(int slave);
  bool Measure(int slave);
  // A measurement window of `slave` from `from_ns` disagrees with the prediction: counted, and
  // after jump_confirmations in a row a jump (re-initialised around `predicted_s`). Returns
  // whether measuring goes on.
  bool Outlier(int slave, int64_t from_ns, double measured_s, double predicted_s, double sigma_s);
  void Trim(std::deque<CameraPose>* poses) const;

  std::vector<std::string> names_;
  ClockOffsetOptions options_;
  std::vector<std::deque<CameraPose>> poses_;  // per camera, own clock
  std::vector<Slave> slaves_;
};

}  // namespace rigcal
