// SPDX-License-Identifier: Apache-2.0
#pragma once
// General or planar: the linear solution of a rotating rig from fixed-size statistics, with
// the figures that decide which parameters the motions determine. Shared by the batch
// calibrator (on statistics of its motions) and the recursive estimator, so both decide alike.
//
// Figures (Observability): the eigenvalues of the rotation system (4.10) and the σ of the
// linear rotation (4.11) about its weakest direction; the spread of the master and slave
// rotation axes; the tilt signal-to-noise ratio (planar_solver.h); the conditioning of the
// position system (4.16) and the ratio of the σ of C along the mean rotation axis to its
// in-plane σ. The general model needs the axes to tilt (SNR >= min_tilt_snr, or a spread of
// general_axis_spread_deg: noisy rotations about clearly different axes) and C along the mean
// axis to be determined (ratio <= max_axis_std_ratio); otherwise the motion is planar: the planar
// solver gives rotation, scales and in-plane position, and the offset along the axis is
// unobservable (a prior's value, or 0 reported as unknown).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "models/motion_statistics.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/model_selection_options.h"

namespace rigcal::internal {

// A prior on the offset of C along the mean rotation axis a: h = a^T C_nominal.
struct AxisPrior {
  bool given = false;
  Eigen::Vector3d nominal_C = Eigen::Vector3d::Zero();  // master frame
  double sigma = 0.0;  // > 0: combined with the estimate as a weighted term; 0: value only
};

struct RotatingSolution {
  bool ok = false;
  MotionModel model = MotionModel::kGeneral;  // kGeneral or kPlanar
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::map<int, double> scales;  // open segments
  Observability observability;
  double rot_std_deg = 0.0;
  // Covariance of C: in the planar model only the in-plane part, plus the prior's σ along the
  // axis when it has one.
  Eigen::Matrix3d cov_C = Eigen::Matrix3d::Zero();
  double axis_std = 0.0;              // σ of C along observability.planar_axis; NaN when unknown
  bool axis_from_prior = false;       // planar: C along the axis is the prior's value
  double axis_prior = 0.0;            // a^T C_nominal for the axis found (when prior.given)
  bool rotation_from_planar = false;  // the rotation comes from the planar solver
  std::string why;                    // the figures behind the model, one phrase for the message
};

// Thesis 5.2 (fig. 5.5): while the largest master rotation stays below the equal-error
// boundary the purely translational model (4.5) gives the more accurate rotation. The boundary
// grows with the orientation error ε of the input poses: the general model's error falls as
// ε / α_max, the translational model's bias grows as α_max |dC| / |C_0| ((I - R_0) dC is
// ignored), so the two meet at α_max ∝ √ε (`rigcal experiment motion-model` measures 14°, 20°,
// 24° for ε = 1°, 2°, 3°). The thesis fixes α_maxrot = 10° for the ε ≈ 1° it expects; this
// scales that to the measured ε: α_maxrot √(ε / ε_ref), never below `floor_deg` (the general
// model drops motions below its smallest usable rotation). ε_ref <= 0: the fixed α_maxrot.
double TranslationalBelowDeg(double alpha_maxrot_deg, double noise_ref_deg, double noise_deg,
                             double floor_deg);

// ε of a set of motions: the robust σ (1.4826 MAD) of the master-minus-slave rotation angle
// differences, degrees (0 for fewer than 2 motions).
double RotationNoiseDeg(const std::vector<MotionData>& motions);

// `requested`: kAuto (decide), kGeneral (the thesis's general model, figures reported only)
// or kPlanar. The statistics must hold a rotating rig's motions.
RotatingSolution SolveRotating(const MotionStatistics& stats, MotionModel requested,
                               const ModelSelectionOptions& options, const AxisPrior& prior);

}  // namespace rigcal::internal
