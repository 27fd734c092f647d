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
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_result.h"

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
  double weight = 0.0;        // sum of the motions' weights
  double max_rotation = 0.0;  // largest master rotation angle seen, radians
  int motions = 0;
  std::map<int, SegmentSums> segments;  // open scale segments by id
  std::map<int, double> closed_scales;  // last scale of each marginalised segment
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

struct RigEstimatorState {
  std::vector<std::string> cameras;         // camera names, [0] the master
  int master_segment = 0;                   // the master's current odometry segment
  bool have_master_segment = false;         // false until the first set
  std::vector<SlaveEstimatorState> slaves;  // one per slave, cameras[i + 1]
  // Per camera, the newest stamp [ns] of its poses in a set the estimator took (-1: none): how
  // far each input was consumed, so that the same poses after a resume are skipped. Empty when
  // unknown (state files before version 4).
  std::vector<int64_t> consumed_t_ns;
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
