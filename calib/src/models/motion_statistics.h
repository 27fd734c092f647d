// SPDX-License-Identifier: Apache-2.0
#pragma once
// Fixed-size sufficient statistics of the linear rig equations of one slave, so that a
// recursive estimate equals the batch linear least squares of the same motions (thesis
// 4.10 and 4.16/4.17) without keeping the motions.
//
// Rotation: M = sum w A^T A (4.10).
// Position/scale with a rotation dR chosen only at solve time: the normal equations of
// (I - R_0) dC + dλ_s dR C_i = C_0 need
//   H_cc = sum w (I-R0)^T (I-R0),        g_c = sum w (I-R0)^T C_0,
//   per segment s: P_s = sum w (I-R0)^T (C_i^T ⊗ I3)   so that  sum w (I-R0)^T dR C_i = P_s
//   vec(dR),
//                  n_s = sum w |C_i|^2,   Q_s = sum w C_0 C_i^T   so that  sum w C_0^T dR C_i =
//                  <dR, Q_s>.
// Purely translational model (4.29-4.32): S = sum w c_i c_0^T and per segment sum w |C_i||C_0|;
// for its covariance D = sum w c_i c_i^T (c = C/|C| the translation directions).
// Planar model (planar_solver.h): PlanarSums and per segment N_s = sum w C_i C_i^T.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <vector>

#include "models/planar_solver.h"
#include "motions/motion_data.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/refinement_prior.h"

namespace rigcal::internal {

// C restricted to fixed + basis * p (the plane of planar motion, a fixed offset along the axis).
struct PositionConstraint {
  Eigen::Matrix<double, 3, 2> basis;
  Eigen::Vector3d fixed = Eigen::Vector3d::Zero();
};

struct PositionSolution {
  bool ok = false;  // the system is well conditioned (min_eigenvalue > 1e-12) and solved
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::map<int, double> scales;  // open segments
  // Information of C with the scales marginalised (Schur complement); rank 2 when restricted
  // to a plane. covariance: its inverse on the free directions (0 along the fixed one), per
  // unit residual variance; multiply by residual_ss / dof.
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  // Weighted sum of squared position residuals; valid also when !ok (least-squares minimum by
  // a pseudo-inverse), so rotations can be compared by how well they fit the translations.
  double residual_ss = 0.0;
  double min_eigenvalue = 0.0;  // of the column-normalised system
  int unknowns = 0;
};

class MotionStatistics {
 public:
  // Adds one motion (sign-aligned quaternions) with weight w to segment `segment`.
  void Add(const MotionData& m, int segment, double w);
  // Exponential forgetting: every accumulated sum is multiplied by `factor` in (0, 1].
  void Decay(double factor);

  // Smallest eigenvector of M (4.11); eigenvalues ascending.
  Eigen::Quaterniond SolveRotation(Eigen::Vector4d* eigenvalues) const;
  // Horn on translation directions (4.29-4.30).
  Eigen::Quaterniond SolveTranslationalRotation() const;
  // σ (radians, largest axis) of that rotation, a left perturbation Exp(δ) dR, from the
  // direction residuals c_0 - dR c_i with their variance estimated from them (2 equations
  // per motion, 3 unknowns). Infinite when no translation constrains the rotation about
  // some direction (all translations parallel: driving straight).
  double TranslationalRotationStd(const Eigen::Quaterniond& dq) const;
  // Normal equations of (4.16)/(4.17) for the given rotation, with the closed segments'
  // marginalised information added; C restricted by `constraint` when not null.
  PositionSolution SolvePosition(const Eigen::Quaterniond& dq,
                                 const PositionConstraint* constraint = nullptr) const;
  // (4.32) per open segment.
  std::map<int, double> SolveTranslationalScales() const;

  // Folds segment s into the marginal information on C (Schur complement at rotation dq, and
  // of the planar system in `frame` when it is ok) and forgets its per-segment sums. The
  // segment's last scale stays available in closed_scales().
  void MarginaliseSegment(int segment, const Eigen::Quaterniond& dq, const PlanarFrame& frame);
  // Drops the position/scale statistics (master odometry re-initialised: new master unit).
  void ResetPosition();

  const PlanarSums& planar() const { return planar_; }
  // Stage 1 and 2 of the planar solver on these sums (planar_solver.h).
  PlanarFrame SolvePlanarFrame() const;
  PlanarSystemSolution SolvePlanarSystem(const PlanarFrame& frame) const;
  double weight() const { return weight_; }
  // Sum of the weights of the motions in the position sums: weight() until a ResetPosition,
  // then only the motions since (their count of position equations, 3 per motion).
  double position_weight() const { return position_weight_; }
  double max_rotation() const { return max_rotation_; }
  const std::map<int, SegmentSums>& segments() const { return segments_; }
  const std::map<int, double>& closed_scales() const { return closed_scales_; }
  int motions() const { return motions_; }
  void SetSegmentScale(int segment, double scale);

  // The sums as the quadratic forms of a refinement prior (RefinementPrior in
  // refinement_prior.h); the segments are the open ones, ascending.
  RefinementPrior Quadratic() const;

  // Every sum as plain data (the estimator's saved state), and statistics made of them.
  MotionSums Sums() const;
  static MotionStatistics FromSums(const MotionSums& sums);

 private:
  Eigen::Matrix4d M_ = Eigen::Matrix4d::Zero();
  PlanarSums planar_;
  Eigen::Matrix3d H_cc_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g_c_ = Eigen::Vector3d::Zero();
  double c0_sq_ = 0.0;                                // sum w |C_0|^2
  Eigen::Matrix3d S_dir_ = Eigen::Matrix3d::Zero();   // sum w c_i c_0^T
  Eigen::Matrix3d D_dir_ = Eigen::Matrix3d::Zero();   // sum w c_i c_i^T
  Eigen::Matrix3d H_marg_ = Eigen::Matrix3d::Zero();  // marginalised segments
  Eigen::Vector3d g_marg_ = Eigen::Vector3d::Zero();
  double c0_sq_marg_ = 0.0;
  std::map<int, SegmentSums> segments_;
  std::map<int, double> closed_scales_;
  double weight_ = 0.0;
  double position_weight_ = 0.0;  // of the motions since the last ResetPosition
  double max_rotation_ = 0.0;     // largest master rotation angle seen, radians
  int motions_ = 0;
};

}  // namespace rigcal::internal
