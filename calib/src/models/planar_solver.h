// SPDX-License-Identifier: Apache-2.0
#pragma once
// The planar-motion solver (a car on a road: every rotation about one axis). The thesis's
// linear rotation (4.9-4.11) has a two-dimensional solution space there: the rotation about
// the common axis is not constrained by the rotations. It is solved in two stages:
//
//  1. Axes (2 DoF): R_0 dR = dR R_i maps the slave's rotation axis onto the master's, so the
//     principal axis a_i of the slave's rotation vectors (vector parts of q_i) is rotated onto
//     the master's a_0 by the minimal rotation R_a ("align").
//  2. Angle, scale and in-plane position: with dR = R(a_0, γ) R_a and C' = R_a C_i, the part of
//     (I - R_0) dC + dλ dR C_i = C_0 (4.14) in the plane orthogonal to a_0 is
//         (I - R_0) B p + u P C' + w [a_0]x C' = P C_0,     u = dλ cos γ,  w = dλ sin γ,
//     with P = I - a_0 a_0^T, dC = B p + h a_0 and B a basis of the plane: linear in (p, u, w),
//     one (u, w) per scale segment. The offset h along a_0 drops out ((I - R_0) a_0 = 0): it
//     is unobservable.
//
// Everything here works on fixed-size sums (PlanarSums plus per-segment sums), so the batch
// calibrator and the recursive estimator compute the same solution.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <vector>

#include "motions/motion_data.h"
#include "rigcal/calib/estimator_state.h"

namespace rigcal::internal {

// Sums of the planar solver over motions (weights w) that are not per scale segment; the data
// are PlanarMotionSums (estimator_state.h, saved with the estimator's state).
struct PlanarSums : PlanarMotionSums {
  void Add(const MotionData& m, double w);
  void Decay(double f);
  void ResetPosition();  // the position sums (k, c0c0, marginal); the rotation sums stay
};

// Per scale segment: what the planar system needs besides the general (4.16) sums.
struct PlanarSegmentView {
  int id = 0;
  const Eigen::Matrix<double, 3, 9>* P = nullptr;  // sum w (I - R_0)^T (C_i^T ⊗ I3)
  const Eigen::Matrix3d* Q = nullptr;              // sum w C_0 C_i^T
  const Eigen::Matrix3d* N = nullptr;              // sum w C_i C_i^T
};

// Stage 1.
struct PlanarFrame {
  bool ok = false;
  // a_0, unit, master frame; its largest component is positive.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d slave_axis = Eigen::Vector3d::UnitZ();  // a_i, unit, slave frame, sign-matched
  Eigen::Matrix<double, 3, 2> basis;                      // B: a_0 = b_1 x b_2
  Eigen::Quaterniond align = Eigen::Quaterniond::Identity();  // R_a: a_i -> a_0, minimal
  // RMS angle of the master / slave rotation vectors about their principal axis, degrees.
  double master_spread_deg = 0.0;
  double slave_spread_deg = 0.0;
};

// Orthonormal basis B of the plane orthogonal to the unit `axis`, with b_1 x b_2 = axis.
Eigen::Matrix<double, 3, 2> PlaneBasis(const Eigen::Vector3d& axis);

// Principal axes of the rotation vectors and the minimal rotation between them. ok = false
// when the master's rotation vectors are all zero.
PlanarFrame SolvePlanarFrame(const PlanarSums& sums);

// Stage 2: the in-plane translation equations, solved in the least-squares sense.
struct PlanarSystemSolution {
  bool ok = false;
  Eigen::Vector2d p = Eigen::Vector2d::Zero();  // in-plane position, dC = B p (+ h a_0)
  double gamma = 0.0;              // rotation angle about a_0, radians, combined over the segments
  double gamma_information = 0.0;  // 1 / var(γ) per unit residual variance (σ² = 1)
  std::map<int, double> scales;    // dλ = |(u, w)| per open segment
  double residual_ss = 0.0;        // of the planar system
  double min_eigenvalue = 0.0;     // of the column-normalised normal equations
  int unknowns = 0;
};

// h_cc = sum w (I - R_0)^T (I - R_0) and g_c = sum w (I - R_0)^T C_0 over every motion.
PlanarSystemSolution SolvePlanarSystem(const PlanarSums& sums, const Eigen::Matrix3d& h_cc,
                                       const Eigen::Vector3d& g_c,
                                       const std::vector<PlanarSegmentView>& segments,
                                       const PlanarFrame& frame);

// The terms of one segment's (u, w) in the planar system, for marginalisation.
void MarginalisePlanarSegment(const PlanarSegmentView& segment, const PlanarFrame& frame,
                              PlanarSums* sums);

// dR = R(a_0, γ) R_a.
Eigen::Quaterniond PlanarRotation(const PlanarFrame& frame, double gamma);

// Tilt signal-to-noise ratio: how much more the master rotation axes tilt away from `axis`
// than rotation noise alone makes them, sqrt(mean |P v_0|^2 / (mean |P (v_0 - dR v_i)|^2 / 2)).
// The difference v_0 - dR v_i is zero without noise whatever the tilt (R_0 dR = dR R_i), so
// it measures the noise of one camera's rotation vectors (equal noise in both assumed).
// About 1 for planar motion with noise, infinite without noise when the axes tilt, 0 for
// noise-free planar motion.
double TiltSignalToNoise(const PlanarSums& sums, const Eigen::Vector3d& axis,
                         const Eigen::Quaterniond& dq);

}  // namespace rigcal::internal
