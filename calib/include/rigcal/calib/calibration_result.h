#pragma once
// Result of the batch rig calibrator, Ceres Summary style: every slave result says whether it
// is usable and why, never a silent garbage answer.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/types.h"

namespace rigcal {

enum class Termination {
  kConverged,           // usable estimate
  kNoConvergence,       // refinement hit the iteration limit; linear estimate kept
  kInsufficientMotion,  // too few usable motions; no estimate
  kDegenerate,          // the motions do not determine the parameters (see message)
  kInvalidInput,
};

// The scale of one segment (or partition) of the slave's odometry.
struct SegmentScale {
  int segment = 0;  // segment id, or partition index for the partition model
  double scale = 1.0;
  double std = 0.0;  // standard deviation from the covariance (0 when not computed)
  // Scale measurements of eq. (4.18) / (4.31) in this segment: mean, std, count.
  double measured_mean = 0.0;
  double measured_std = 0.0;
  int measured_count = 0;
};

struct MotionCounts {
  int total = 0;
  int used = 0;
  int small_rotation = 0;   // below alpha_threshold (general model)
  int angle_mismatch = 0;   // master/slave rotation angles differ (invariant)
  int residual_outlier = 0;
  int rejected() const { return small_rotation + angle_mismatch + residual_outlier; }
};

struct Observability {
  // Eigenvalues of the rotation system sum A^T A (4.10), ascending. The smallest is the
  // fit residual; the gap to the second tells how well the rotation is determined.
  Eigen::Vector4d rotation_eigenvalues = Eigen::Vector4d::Zero();
  // Smallest eigenvalue of the (normalised) position/scale normal equations (4.16).
  double position_min_eigenvalue = 0.0;
  // Spread of the master rotation axes, degrees (0 = all motions about one axis).
  double axis_spread_deg = 0.0;
  double max_rotation_deg = 0.0;  // largest master rotation angle among the motions
  bool planar = false;            // all rotation axes parallel
  Eigen::Vector3d planar_axis = Eigen::Vector3d::Zero();  // in the master frame
};

struct SlaveCalibration {
  std::string name;
  Similarity estimate;                 // q, C and the first segment's scale
  std::vector<SegmentScale> scales;    // one per segment / partition
  bool position_observable = true;     // false for the purely translational model
  // Unobservable directions of C in the master frame (unit vectors).
  std::vector<Eigen::Vector3d> unobservable;

  // Standard deviations from the covariance of the refined parameters.
  double rot_std_deg = 0.0;  // largest axis
  Eigen::Vector3d pos_std = Eigen::Vector3d::Zero();

  MotionCounts motions;
  MotionModel motion_model = MotionModel::kGeneral;  // chosen model (never kAuto)
  ScaleModel scale_model = ScaleModel::kFixed;       // chosen model (never kAuto)
  Observability observability;

  Termination termination = Termination::kInsufficientMotion;
  std::string message;
  bool usable() const {
    return termination == Termination::kConverged || termination == Termination::kNoConvergence;
  }
};

struct RigCalibration {
  std::string master;
  std::vector<SlaveCalibration> slaves;
  int pairs_selected = 0;
  std::string BriefReport() const;
};

std::string ToString(Termination t);

}  // namespace rigcal
