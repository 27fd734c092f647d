// SPDX-License-Identifier: Apache-2.0
#pragma once
// Result of the batch rig calibrator, Ceres Summary style: every slave result says whether it
// is usable and why, never a silent garbage answer.

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/slave_state.h"

namespace rigcal {

enum class Termination {
  kSolved,              // the solve produced an estimate (see SlaveCalibration::state)
  kNoConvergence,       // refinement hit the iteration limit; linear estimate kept
  kInsufficientMotion,  // too few usable motions; no estimate
  kDegenerate,          // the motions do not determine the parameters (see message)
  kInvalidInput,
  kCancelled,  // ended early by CalibrationOptions::cancel; no estimate, only to be dropped
};

// The scale of one segment (or partition) of the slave's odometry.
struct SegmentScale {
  int segment = 0;  // segment id, or partition index for the partition model
  double scale = 1.0;
  // Standard deviation from the covariance; NaN = unknown (the covariance was not computed or
  // failed), never a silent 0.
  double std = std::numeric_limits<double>::quiet_NaN();
  // Scale measurements of eq. (4.18) / (4.31) in this segment: mean, std, count.
  double measured_mean = 0.0;
  double measured_std = 0.0;
  int measured_count = 0;
};

struct MotionCounts {
  int total = 0;
  int used = 0;
  int small_rotation = 0;  // below alpha_threshold (general model)
  int angle_mismatch = 0;  // master/slave rotation angles differ (invariant)
  int residual_outlier = 0;
  int rejected() const { return small_rotation + angle_mismatch + residual_outlier; }
};

// Poses dropped before any motion is formed because a camera's trajectory jumps there (a
// glitch: a pose off by far more than the camera moves, a rotated pose). Batch: times whose
// set of poses is removed from the recording (every camera's, so the pair choice never sees
// them), each counted once under the first cause found; online: sets this slave skipped.
struct GlitchCounts {
  int position_jump = 0;   // a camera's position jumps and returns (robust step speed)
  int rotation_jump = 0;   // a camera's orientation jumps and returns (robust angular speed)
  int angle_mismatch = 0;  // master and slave rotate by different angles (scale-free)
  int in_master = 0;       // of the dropped poses: the master's pose is a glitch
  int in_slave = 0;        // this slave's pose is a glitch (a time may count in both)
  int dropped() const { return position_jump + rotation_jump + angle_mismatch; }
};

// The figures that decide what the motions determine (general, planar or translational).
struct Observability {
  // Eigenvalues of the rotation system sum A^T A (4.10), ascending. The smallest is the
  // fit residual; the gap to the second tells how well the rotation is determined.
  Eigen::Vector4d rotation_eigenvalues = Eigen::Vector4d::Zero();
  // σ of the linear rotation (4.11) about its weakest direction, from the eigen-gap λ2 - λ1
  // (degrees; large when every rotation is about one axis).
  double rotation_weak_std_deg = 0.0;
  // Smallest eigenvalue of the (normalised) position/scale normal equations (4.16).
  double position_min_eigenvalue = 0.0;
  // RMS angle of the rotation vectors about their principal axis, degrees (0 = all motions
  // about one axis): master (in its frame) and slave (in its frame).
  double axis_spread_deg = 0.0;
  double slave_axis_spread_deg = 0.0;
  // How much more the master's rotation axes tilt away from the mean axis than rotation noise
  // alone makes them (about 1 for planar motion with noise, 0 without noise).
  double tilt_snr = 0.0;
  // σ of C along the mean rotation axis divided by its in-plane σ (linear position system);
  // infinite when the axis component is not determined at all.
  double axis_std_ratio = 0.0;
  double max_rotation_deg = 0.0;  // largest master rotation angle among the motions
  // The motion-model decision (thesis 5.2): the rotation noise ε of the motions (robust σ of
  // the master-minus-slave rotation angle differences, which are zero whatever the
  // extrinsics), and the largest rotation below which the purely translational model is used
  // (the equal-error boundary at ε, see ModelSelectionOptions::alpha_maxrot_noise_deg). Degrees.
  double rotation_noise_deg = 0.0;
  double translational_below_deg = 0.0;
  bool planar = false;  // planar model: C along planar_axis is not determined
  // Mean rotation axis in the master frame (unit; set for every rotating rig, not only planar).
  Eigen::Vector3d planar_axis = Eigen::Vector3d::Zero();
};

struct SlaveCalibration {
  std::string name;
  // The pairs of times the motions came from: "relative:N", "start", "walk" (batch), empty
  // for the online estimator's keyframe pairs.
  std::string pairs;
  Similarity estimate;               // q, C and the first segment's scale
  std::vector<SegmentScale> scales;  // one per segment / partition
  bool position_observable = true;   // false for the purely translational model
  // Unobservable directions of C in the master frame (unit vectors). C along them is the
  // nominal mounting's when unobservable_from_prior, else 0 (unknown, not estimated).
  std::vector<Eigen::Vector3d> unobservable;
  bool unobservable_from_prior = false;

  // Standard deviations from the covariance of the refined parameters (online: of the linear
  // solution, inflated). NaN = unknown: the covariance was not computed or failed; an estimate
  // with unknown σ is never converged.
  double rot_std_deg = std::numeric_limits<double>::quiet_NaN();  // largest axis
  // σ of C per master axis. Along an unobservable direction only the prior's σ is included
  // (nothing when the prior has none).
  Eigen::Vector3d pos_std = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  // σ of C along the mean rotation axis (observability.planar_axis), master units: estimated
  // (general model; large for nearly planar drives), the prior's σ (planar model with a
  // weighted prior), NaN when unknown (planar model otherwise) or not applicable
  // (translational model).
  double axis_offset_std = std::numeric_limits<double>::quiet_NaN();

  MotionCounts motions;
  GlitchCounts glitches;
  MotionModel motion_model = MotionModel::kGeneral;  // chosen model (never kAuto)
  ScaleModel scale_model = ScaleModel::kFixed;       // chosen model (never kAuto)
  Observability observability;

  // How the solve ended, and what a caller may do with the estimate (slave_state.h: one
  // meaning per state; batch: usable when the data support the estimate
  // (calib/src/batch/batch_acceptance.h: enough independent motions, residuals consistent with
  // the measured noise, every parameter determined; else initialising and the message says
  // what is missing), converged when usable with σ computed from the covariance).
  Termination termination = Termination::kInsufficientMotion;
  SlaveState state = SlaveState::kInitialising;
  std::string message;
  // Batch: why the data contradict the model of a solved estimate (residuals beyond the
  // measured noise, unrelated trajectories, the planar model on tilting axes; the state is then
  // initialising), empty when they do not.
  std::string contradiction;
  // Clock offset of the slave (its stamp - the master clock at the same instant), seconds, and
  // its σ: set by `rigcal solve` (given or estimated, tools/io time_offset.h); NaN = not set
  // (offset) or unknown (σ).
  double time_offset_s = std::numeric_limits<double>::quiet_NaN();
  double time_offset_std_s = std::numeric_limits<double>::quiet_NaN();
  // The solve produced an estimate: q, C and the scales are defined (termination solved or
  // no_convergence). Whether it may be used is `state`.
  bool solved() const {
    return termination == Termination::kSolved || termination == Termination::kNoConvergence;
  }
  // The estimate may be used: state usable or converged.
  bool usable() const { return IsUsable(state); }
};

struct RigCalibration {
  std::string master;
  std::vector<SlaveCalibration> slaves;
  int pairs_selected = 0;  // time pairs (auto: the most any slave's chosen span has)
  std::string BriefReport() const;
};

std::string ToString(Termination t);

}  // namespace rigcal
