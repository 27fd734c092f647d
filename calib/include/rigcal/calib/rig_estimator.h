// SPDX-License-Identifier: Apache-2.0
#pragma once
// RigEstimator: the recursive, bounded-memory online counterpart of the batch calibrator.
//
// Feed it time-corresponding sets of camera poses (master + slaves, from the SyncBuffer); it
// picks keyframes, forms motion pairs between keyframes, gates them with the scale-free
// invariants, and accumulates fixed-size sufficient statistics per slave whose linear
// solution equals the batch linear least squares of the same motions. Closed odometry scale
// segments are marginalised, old information is forgotten exponentially, and a short-window
// twin of the statistics detects a camera that moved (decalibration).
//
// Not thread-safe: one estimator thread owns it (see OnlineCalibrator for the threads).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/refinement_job.h"
#include "rigcal/calib/rig_estimate.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal {
namespace internal {
class PoseGlitchGate;
class PoseQualityGate;
class MasterTravel;
}  // namespace internal

class RigEstimator {
 public:
  // camera_names[0] is the master. Throws InvalidOptions when options.Check() fails.
  RigEstimator(std::vector<std::string> camera_names, RigEstimatorOptions options);
  ~RigEstimator();
  RigEstimator(const RigEstimator&) = delete;
  RigEstimator& operator=(const RigEstimator&) = delete;

  // Consumes one time-corresponding set: poses[0] master, poses[i] slave i (nullopt when the
  // slave is missing from this set). Sets must come in increasing time. Non-finite poses are
  // counted as rejected and ignored; glitched poses (a jump, a rotated pose: pose_glitch_gate)
  // are skipped and counted in the slave's `glitches`.
  void AddSet(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses);

  // The current estimate of every slave (cheap: cached at each accepted motion).
  const RigEstimate& Estimate() const;

  // Background refinement support: a copy of a slave's window, and the outcome to publish
  // when it is consistent with the current linear estimate (within gate_sigmas).
  // `final`: a history refinement even when not due (the end of a stream).
  RefinementJob MakeRefinementJob(int slave, bool final = false) const;
  bool ApplyRefinement(const RefinementJob& job, const SlaveCalibration& refined);

  // The statistics of every slave, to continue after a restart (estimator_state.h; the file
  // format is tools/io's estimator_state_file.h).
  RigEstimatorState SaveState() const;
  // Continues from a saved state: the refinement window starts empty (every saved motion is in
  // its prior) and the estimate is re-solved. A state of other cameras (names, count) or with
  // another number of slaves is rejected with a message, and the estimator is left unchanged.
  Status RestoreState(const RigEstimatorState& state);

 private:
  struct Slave;
  // The stages of one slave's update (calib/src/motions/keyframe_pairing,
  // calib/src/online/: motion_gates, statistics_accumulation), then Publish.
  // `keyframe_min_translation`: the master's travel in keyframe_min_travel_s (master_travel.h).
  void UpdateSlave(int index, int64_t t_ns, const CameraPose& master, const CameraPose& slave,
                   double keyframe_min_translation);
  // Solves and publishes a slave's estimate (calib/src/online/: statistics_solution,
  // decalibration_check, window_refinement, online_uncertainty, convergence_check; then
  // models/model_explanation).
  void Publish(int index);
  void PublishCounts(int index);
  // The nominal mounting of slave `index`, when the options give one.
  std::optional<Similarity> NominalOf(int index) const;

  std::vector<std::string> names_;
  RigEstimatorOptions options_;
  std::vector<std::unique_ptr<Slave>> slaves_;
  std::unique_ptr<internal::PoseGlitchGate> glitch_gate_;    // pose_glitch_gate
  std::unique_ptr<internal::PoseQualityGate> quality_gate_;  // pose_quality_gate
  std::unique_ptr<internal::MasterTravel> master_travel_;    // master_travel
  RigEstimate estimate_;
  int master_segment_ = 0;
  bool have_master_segment_ = false;
  uint64_t generation_ = 0;
  std::vector<int64_t> consumed_t_ns_;  // RigEstimatorState::consumed_t_ns, per camera
  // RigEstimatorState::first_consumed / last_consumed, per camera.
  std::vector<PoseFingerprint> first_consumed_, last_consumed_;
};

}  // namespace rigcal
