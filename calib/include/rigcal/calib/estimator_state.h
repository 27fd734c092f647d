// SPDX-License-Identifier: Apache-2.0
#pragma once
// RigEstimatorState: what a RigEstimator keeps across a restart, as plain data
// (RigEstimator::SaveState / RestoreState). calib does no I/O: the versioned text file of it is
// tools/io's estimator_state_file.h.
//
// Saved: per slave the sufficient statistics of the long and short windows, the motion counts,
// the running noise levels and the motion-model state. Not saved: the keyframes, the refinement
// window (a restored estimator holds every motion in the window's prior) and the rotation time
// blocks (rebuilt from new motions).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/rig_estimate.h"

namespace rigcal {

// Running mean of a squared quantity over roughly the last 50 samples: the estimator's noise
// levels (variances) of the motions.
struct RunningMeanSquare {
  double value = 0.0;
  int count = 0;
  void Add(double sq) {
    ++count;
    const double alpha = 1.0 / std::min(count, 50);
    value += alpha * (sq - value);
  }
};

// Sums of the planar solver (calib/src/models/planar_solver.h) over motions with weights w, not per
// scale segment.
struct PlanarMotionSums {
  // Rotation vector parts v = sin(θ/2) r of the sign-aligned master and slave quaternions.
  Eigen::Matrix3d v00 = Eigen::Matrix3d::Zero();  // sum w v_0 v_0^T
  Eigen::Matrix3d vii = Eigen::Matrix3d::Zero();  // sum w v_i v_i^T
  Eigen::Matrix3d v0i = Eigen::Matrix3d::Zero();  // sum w v_0 v_i^T
  // sum w (I - R_0)^T (C_0^T ⊗ I3), so that sum w (I - R_0)^T X C_0 = k vec(X).
  Eigen::Matrix<double, 3, 9> k = Eigen::Matrix<double, 3, 9>::Zero();
  Eigen::Matrix3d c0c0 = Eigen::Matrix3d::Zero();  // sum w C_0 C_0^T
  // Closed (marginalised) segments: Schur complement of their (u, w) on dC (3-D form).
  Eigen::Matrix3d h_marg = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g_marg = Eigen::Vector3d::Zero();
  double c_marg = 0.0;
};

// Sums of the position/scale equations (4.16)/(4.17) of one open scale segment.
struct SegmentSums {
  Eigen::Matrix<double, 3, 9> P =
      Eigen::Matrix<double, 3, 9>::Zero();      // sum w (I-R0)^T (C_i^T ⊗ I3)
  double n = 0.0;                               // sum w |C_i|^2
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();  // sum w C_0 C_i^T
  double len_cross = 0.0;                       // sum w |C_i| |C_0|   (4.32)
  double len_sq = 0.0;                          // sum w |C_i|^2       (4.32), equals n
  double weight = 0.0;                          // sum of motion weights
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();  // sum w C_i C_i^T (planar solver)
  double last_scale = 0.0;  // scale at the last solve (reported after marginalisation)
};

// The fixed-size sufficient statistics of one slave's linear rig equations (the sums of
// calib/src/models/motion_statistics.h, which documents them), over the motions since the start or
// the last reset, forgotten alike.
struct MotionSums {
  Eigen::Matrix4d rotation = Eigen::Matrix4d::Zero();  // M = sum w A^T A (4.10)
  PlanarMotionSums planar;
  Eigen::Matrix3d h_cc = Eigen::Matrix3d::Zero();   // sum w (I-R0)^T (I-R0)
  Eigen::Vector3d g_c = Eigen::Vector3d::Zero();    // sum w (I-R0)^T C_0
  double c0_sq = 0.0;                               // sum w |C_0|^2
  Eigen::Matrix3d s_dir = Eigen::Matrix3d::Zero();  // sum w c_i c_0^T (unit translations)
  Eigen::Matrix3d d_dir = Eigen::Matrix3d::Zero();  // sum w c_i c_i^T
  // The closed (marginalised) segments' information on C.
  Eigen::Matrix3d h_marg = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g_marg = Eigen::Vector3d::Zero();
  double c0_sq_marg = 0.0;
  double weight = 0.0;  // sum of the motions' weights
  // Sum of the weights of the motions in the position sums (h_cc ... segments): `weight` until
  // the master odometry re-initialised (new master unit: the position sums restart, the
  // rotation's stay), then only the motions since; the position σ's count of equations.
  // None in a state before version 8: taken as `weight`.
  std::optional<double> position_weight;
  double max_rotation = 0.0;  // largest master rotation angle seen, radians
  int motions = 0;
  std::map<int, SegmentSums> segments;  // open scale segments by id
  std::map<int, double> closed_scales;  // last scale of each marginalised segment
};

// One contiguous time block of a slave's rotation information (calib/src/noise/rotation_blocks.h).
struct RotationBlockState {
  int64_t start_ns = 0;
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();  // sum w A^T A of the block's motions (4.10)
  double weight = 0.0;
};

// The decalibration alarm of a slave (calib/src/online/decalibration_check.h): the disagreements
// of its short and long windows being counted, and the last confirmed decalibration, which keeps
// the slave decalibrated for short_half_life_s of stream time.
struct DecalibrationAlarmState {
  int disagreements = 0;            // consecutive keyframes at which the windows disagreed
  int64_t disagree_since_ns = -1;   // stream time of the first of them (-1: none)
  int64_t decalibrated_at_ns = -1;  // stream time of the last decalibration (-1: never)
};

// What a slave's published estimate rests on beyond its statistics (state version 6): the
// estimate as last published (a refinement's, with its σ), the inputs of the σ inflation
// (calib/src/online/online_uncertainty.h: the drift of the pairs, the rotation time blocks), the
// forgetting clock, the convergence count and the glitches skipped. A resume without new data
// publishes `published` as it is; new data go on from all of it.
struct SlavePublishedState {
  bool present = false;  // false: a state file before version 6 (re-solved from the statistics)
  SlaveCalibration published;  // name, state and message included
  SlaveOnlineState online;     // the facts published with it
  // The background refinement kept beside the linear solution (published while they agree),
  // and whether it is the batch calibrator's on the pose history.
  std::optional<SlaveCalibration> refined;
  bool refined_from_history = false;
  RunningMeanSquare consecutive_angle_var, pair_span;  // online_uncertainty's DriftState
  int64_t block_ns = 0;                                // current length of a rotation block
  std::vector<RotationBlockState> blocks;
  double log_decay = 0.0;      // forgetting applied to the long statistics so far (log)
  int64_t last_decay_ns = -1;  // stream time they were last forgotten to (-1: never)
  int stable = 0;              // convergence_check's stable count
  Eigen::Quaterniond last_q = Eigen::Quaterniond::Identity();  // ... and the rotation then
  GlitchCounts glitches;
  // The decalibration alarm (state version 7; none in a version-6 state).
  DecalibrationAlarmState decalibration;
};

// One slave's saved state.
struct SlaveEstimatorState {
  MotionCounts counts;  // motions formed, used and rejected (by reason)
  // Running noise levels: the master-minus-slave rotation angle difference (deg^2), the
  // rotation and position residuals of the accepted motions, and |C_i|^2.
  RunningMeanSquare angle_var, rot_var, pos_var, ci_sq;
  int segment = 0;             // current odometry segment of the slave
  bool rotating = false;       // some motion rotated by the equal-error boundary (thesis 5.2)
  bool general_model = false;  // rotating rig: the general (not planar) model, with hysteresis
  MotionSums long_stats;       // all the information (forgotten by half_life_s)
  MotionSums short_stats;      // the short-window twin (decalibration detection)
  SlavePublishedState resume;  // version 6
};

// One free-running slave's clock offset as the online tracker knows it
// (ClockOffsetTracker::SaveState): the Kalman state [τ, ρ] and its covariance.
struct ClockOffsetState {
  bool initialised = false;  // an offset was estimated; false: still searching (only the
                             // counts below hold)
  double offset_s = 0.0;     // τ = slave stamp - master clock at t_ns [s]
  double drift = 0.0;        // ρ = dτ/dt [s/s]
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  // of [τ, ρ]
  int64_t t_ns = 0;                                      // master time of offset_s
  int measurements = 0;  // refinement measurements since the last (re)initialisation
  int jumps = 0;         // jumps detected so far
};

// A pose the estimator took: a resume recognises the same data again by it (ResumeCheck).
struct PoseFingerprint {
  int64_t t_ns = -1;  // -1: none taken
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
};

struct RigEstimatorState {
  std::vector<std::string> cameras;         // camera names, [0] the master
  int master_segment = 0;                   // the master's current odometry segment
  bool have_master_segment = false;         // false until the first set
  std::vector<SlaveEstimatorState> slaves;  // one per slave, cameras[i + 1]
  // Per camera, the newest stamp [ns] of its poses in a set the estimator took (-1: none): how
  // far each input was consumed, so that the same poses after a resume are skipped. Empty when
  // unknown (state files before version 4).
  std::vector<int64_t> consumed_t_ns;
  // Per camera, the first and the newest pose the estimator took (state version 6; empty
  // before): a resumed run whose poses are stamped at or before consumed_t_ns is the same data
  // again only when it holds these poses at their stamps.
  std::vector<PoseFingerprint> first_consumed, last_consumed;
  // Per slave, the online clock offset when the cameras run free (OnlineOptions::time_offset);
  // empty when they do not, and in state files before version 5.
  std::vector<ClockOffsetState> clock_offsets;
};

// The direction moments d_dir = sum w c_i c_i^T of statistics saved without them (state files of
// version 2), from their cross moments s_dir = sum w c_i c_0^T and total weight: c_0 ≈ dR c_i
// gives D ≈ S dR with dR from S (Horn, 4.29-4.30), and tr D is the sum of the weights (unit
// directions; every motion but a standing one has them). Zero when s_dir has no positive trace.
Eigen::Matrix3d DirectionMomentsFromCrossMoments(const Eigen::Matrix3d& s_dir, double weight);

}  // namespace rigcal
