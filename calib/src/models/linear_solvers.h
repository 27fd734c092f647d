// SPDX-License-Identifier: Apache-2.0
#pragma once
// The linear least-squares steps of the decoupled estimation (thesis 4.3, 4.5).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "motions/motion_data.h"

namespace rigcal::internal {

// A_i^k = T_{q0} - T*_{qi}, eq. (4.7)/(4.9).
Eigen::Matrix4d RotationConstraintMatrix(const MotionData& m);

struct LinearRotation {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector4d eigenvalues = Eigen::Vector4d::Zero();  // of sum A^T A, ascending
};

// Smallest eigenvector of sum A^T A (4.10, 4.11). Realigns the quaternion signs of the
// motions with the first estimate and solves again (q and -q are the same rotation).
LinearRotation SolveLinearRotation(std::vector<MotionData>* motions);

// Horn's closed-form absolute orientation (A.4): the rotation R maximising
// sum target_k^T R source_k.
Eigen::Quaterniond SolveAbsoluteOrientation(const std::vector<Eigen::Vector3d>& source,
                                            const std::vector<Eigen::Vector3d>& target);
// The same from the correlation S = sum source_k target_k^T.
Eigen::Quaterniond SolveAbsoluteOrientation(const Eigen::Matrix3d& s);

// σ (radians, largest axis) of the translational model's rotation dR (Horn on the translation
// directions c, 4.29-4.30), a left perturbation Exp(δ) dR, from S = sum w c_i c_0^T and
// D = sum w c_i c_i^T: the direction residuals c_0 - dR c_i with their variance estimated from
// them (2 equations per motion, 3 unknowns). Infinite when the translations do not constrain
// the rotation about some direction beyond what their noise does (all translations parallel:
// driving straight).
double TranslationalRotationStd(const Eigen::Matrix3d& s, const Eigen::Matrix3d& d,
                                const Eigen::Quaterniond& dq);
// The same from the motions (unit weights).
double TranslationalRotationStd(const std::vector<MotionData>& motions,
                                const Eigen::Quaterniond& dq);

struct LinearPositionScale {
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::vector<double> scales;
  double min_eigenvalue = 0.0;  // of the column-normalised normal equations
  bool ok = false;
};

// Purely translational model, eq. (4.29)-(4.30): dR from the directions of C_i and C_0.
Eigen::Quaterniond SolveTranslationalRotation(const std::vector<MotionData>& motions);

// Purely translational model, eq. (4.31)-(4.32): scale per scale variable from lengths.
std::vector<double> SolveTranslationalScales(const std::vector<MotionData>& motions,
                                             int num_scales);

// Residual norms of one motion for a given estimate.
double RotationResidual(const MotionData& m, const Eigen::Vector4d& dq);  // |A dq|
double PositionResidual(const MotionData& m, const Eigen::Quaterniond& dq,
                        const Eigen::Vector3d& dC, double scale);  // |(I-R0)dC + s dR Ci - C0|
double TranslationalResidual(const MotionData& m, const Eigen::Quaterniond& dq,
                             double scale);  // |s dR Ci - C0|

}  // namespace rigcal::internal
