// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 0 of the recursive estimator (RigEstimator::AddSet): the online counterpart of
// pose_glitches.h. A glitched incoming pose (a jump by far more than the camera moves, a rotated
// pose) must not become a keyframe nor enter a motion pair, so it is rejected before the
// keyframe offer.
//
// Per camera the gate keeps its last accepted pose and the robust statistics (median, 1.4826
// MAD) of its last accepted step speeds and angular speeds, in rings of 2 window + 1 steps
// (bounded memory); per slave, those of the master-minus-slave rotation angle of each step
// (scale-free: zero whatever the extrinsics). A pose is rejected when its step from the last
// accepted pose is an outlier against these (OutlierSpeed of pose_glitches.h, the typical speed
// being the larger of the median and the last accepted step's, so that real accelerations
// pass), or when master and slave rotate by angles that differ beyond outlier_sigmas robust σ
// (the glitch is then the camera whose angular speed is the further out).
//
// The bridged test of the batch comes for free: the next pose is compared with the last
// accepted one, across the glitch, and only a rejected run that the camera returns from (a pose
// whose step from the last accepted one is normal again, and below the jump into the run by
// jump_factor) is counted as glitches. A camera whose poses are rejected more than max_run
// times in a row changed its motion for real (a sudden turn, a jump the odometry keeps): its
// pose is accepted, its statistics restart and the run is not counted (it cost those sets
// their keyframe offer, nothing else).
//
// A camera's first min_steps + 1 poses (after the start, a new odometry segment or such a
// restart) only warm its statistics up: a glitch among them could not be told, so none of them
// is offered as a keyframe (a glitched anchor would enter every motion paired with it), and
// they are not counted. The angle differences are kept over 10 window + 1 steps and tested
// once that many were accepted: their noise is stationary, and its σ must be known well for a
// test that sees only one side of the glitch (the MAD of 21 steps misjudges σ by 25 %).

#include <cstdint>
#include <optional>
#include <vector>

#include "motions/pose_glitches.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "sync/fixed_ring.h"

namespace rigcal::internal {

class PoseGlitchGate {
 public:
  // `cameras`: the master and the slaves.
  explicit PoseGlitchGate(int cameras, GlitchTest test = {});

  // What the gate says of a set.
  struct Verdict {
    // Per camera (poses[0] the master): kNone when accepted or absent, else the cause of its
    // rejection.
    std::vector<GlitchCause> rejected;
    // Per camera: the causes of the run of rejected poses that this set's pose, back on the
    // camera's trajectory, showed to be glitches (usually empty).
    std::vector<std::vector<GlitchCause>> confirmed;
    // Per camera: the pose only warms the statistics up (not offered, not a glitch).
    std::vector<bool> warming_up;
  };

  // The verdict on the set. Sets come in increasing time; non-finite poses are ignored (kNone,
  // and they do not enter the statistics).
  Verdict Check(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses);

 private:
  // What Check finds of each camera's step in a set (indexed by camera, the cameras of the set
  // that the gate knows): its speed and angular speed since the camera's last accepted pose (a
  // step that continues it), the angular speed over its limit, and per slave (c >= 1) the
  // master-minus-slave rotation angle since the pair's anchor.
  struct SetSteps {
    explicit SetSteps(size_t n)
        : speed(n, 0.0),
          turn(n, 0.0),
          turn_ratio(n, 0.0),
          continues(n, false),
          diff(n, 0.0),
          has_diff(n, false) {}
    std::vector<double> speed, turn, turn_ratio;
    std::vector<bool> continues;
    std::vector<double> diff;
    std::vector<bool> has_diff;
  };
  // The steps of Check: each camera's step from its last accepted pose against its recent steps
  // (position and rotation jumps); master and slave rotating by the same angle since the pair's
  // anchor (angle mismatches); the accepted poses entering the statistics and confirming the
  // rejected run before them as glitches (a camera rejected more than max_run times in a row
  // moved for real and restarts); the pairs' anchors and angle differences.
  void TestSteps(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses, SetSteps* steps,
                 Verdict* out) const;
  void TestAngles(const std::vector<std::optional<CameraPose>>& poses, SetSteps* steps,
                  Verdict* out) const;
  void AcceptCameras(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses,
                     const SetSteps& steps, Verdict* out);
  void AcceptPairs(const std::vector<std::optional<CameraPose>>& poses, const SetSteps& steps,
                   const Verdict& out);
  // Camera c's pose is in the set, finite and of a camera the gate knows.
  static bool Present(const std::vector<std::optional<CameraPose>>& poses, const SetSteps& steps,
                      size_t c);

  struct Camera {
    explicit Camera(size_t capacity) : speeds(capacity, 0.0), turns(capacity, 0.0) {}
    bool have = false;
    int64_t t_ns = 0;
    Pose pose;
    int segment = 0;
    FixedRing<double> speeds, turns;  // accepted steps: |dC| / dt and angle / dt
    double last_speed = 0.0, last_turn = 0.0;
    int rejected_in_row = 0;
    std::vector<GlitchCause> run;  // causes of the rejected run (at most max_run)
    double run_jump = 0.0;         // the speed (angular speed) of the step into the run
  };
  struct Pair {  // the master and one slave
    explicit Pair(size_t capacity) : diffs(capacity, 0.0) {}
    bool have = false;  // the anchor: the last set in which both poses were accepted
    Eigen::Quaterniond master = Eigen::Quaterniond::Identity();
    Eigen::Quaterniond slave = Eigen::Quaterniond::Identity();
    int master_segment = 0, slave_segment = 0;
    FixedRing<double> diffs;  // master minus slave rotation angle of the accepted steps
  };

  GlitchTest test_;
  std::vector<Camera> cameras_;
  std::vector<Pair> pairs_;  // per slave
};

// Counts the glitches the verdict confirms in the master and in slave `slave` into `counts`
// and returns whether the slave skips the set (its pose or the master's was rejected or only
// warms up).
bool CountGlitch(const PoseGlitchGate::Verdict& verdict, int slave, GlitchCounts* counts);

}  // namespace rigcal::internal
