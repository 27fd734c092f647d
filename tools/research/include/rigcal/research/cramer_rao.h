// SPDX-License-Identifier: Apache-2.0
#pragma once
// Cramér–Rao lower bound (CRB) of the thesis 5.1.2 calibration problem in its linear-Gaussian
// approximation: the measurement model is linearised around the true values and the noise is
// replaced by Gaussian noise with the same covariance as the thesis perturbation. The bound is
// therefore linear in the noise level eps (standard deviations scale with eps): compute it at one
// eps and scale it. It bounds the RMS error of any (locally) unbiased estimator; least-squares
// estimators, whose first-order error depends on the noise covariance only, are bounded by it also
// for the non-Gaussian thesis noise.
//
// Parameters of interest theta = (delta, dC, lambda): the rig rotation dR_true * Exp(delta)
// (delta in radians), the rig position dC and the scale lambda. Nuisance parameters: the K true
// master poses T_0^k, k = 1..K (left rotation vector 3 + position 3 each). Observations: the noisy
// master poses and the noisy slave poses, slave = f(master, theta) by eq. (5.1) and (5.2). Pose 0
// is the identity reference of every camera and is exact.

#include <Eigen/Core>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::research {

// ---- Fisher information algebra (generic) ----

// Moore–Penrose pseudo-inverse of a symmetric positive semi-definite matrix; eigenvalues at or
// below rel_tol * (largest eigenvalue) count as zero.
Eigen::MatrixXd PseudoInverseSpd(const Eigen::MatrixXd& m, double rel_tol = 1e-12);

// Fisher information J = H^T W H of observations y = h(p) + n, with H = dh/dp at the true p and W
// the information (inverse covariance, or pseudo-inverse for a singular covariance) of n.
Eigen::MatrixXd FisherInformation(const Eigen::MatrixXd& jacobian, const Eigen::MatrixXd& weight);

// CRB of the first `num_interest` parameters when the others are nuisance parameters: the inverse
// of the Schur complement S = J_tt - J_tn J_nn^+ J_nt. A pseudo-inverse is used for J_nn, so
// nuisance directions the data does not determine do not matter unless they couple to theta.
// When S is singular (theta not determined) every entry of the result is +infinity.
Eigen::MatrixXd SchurComplementBound(const Eigen::MatrixXd& fisher, int num_interest);

// CRB of the first `num_interest` parameters when the parameters also satisfy exact equality
// constraints with Jacobian `constraint_jacobian` (one row per constraint; an exactly observed
// function of p is such a constraint): U (U^T J U)^+ U^T restricted to theta, with U an orthonormal
// basis of the constraint null space (Stoica & Ng 1998). With no constraint rows it equals
// SchurComplementBound. Every entry is +infinity when theta is not determined.
Eigen::MatrixXd ConstrainedBound(const Eigen::MatrixXd& fisher,
                                 const Eigen::MatrixXd& constraint_jacobian, int num_interest);

// ---- The thesis problem ----

// Gaussian stand-in for the thesis perturbation at level eps (radians).
struct ThesisNoiseModel {
  // Rotation: left rotation vector n with covariance rotation_variance_factor * eps^2 * I.
  // The thesis rotates by exactly eps about a uniform axis r: E[n n^T] = eps^2 E[r r^T] = eps^2/3 I
  // (per-axis sigma eps/sqrt(3), RMS eps).
  double rotation_variance_factor = 1.0 / 3.0;
  // Position: covariance position_variance_factor * eps^2 * |C|^2 * (I - u u^T), u = C/|C|.
  // The thesis rotates C by eps about a uniform axis c; to first order the displacement is
  // eps c x C with E[.] = eps^2/3 (|C|^2 I - C C^T): per-axis sigma |C| eps/sqrt(3) in the plane
  // perpendicular to C (RMS |C| eps sqrt(2/3): the direction changes by eps sin(angle(c, C))).
  double position_variance_factor = 1.0 / 3.0;
  // The thesis perturbation keeps |C| exactly. true: every |C_obs| is an exact observation, i.e. a
  // constraint (the true, smaller bound). false: the radial component carries no information
  // (pseudo-inverse weight), a bound for estimators that do not use lengths.
  bool exact_lengths = true;
};

struct ThesisBound {
  bool finite = false;  // false: theta is not determined by the poses (all numbers infinite)
  // Covariance bound on theta = (delta [rad], dC, lambda), 7 x 7.
  Eigen::Matrix<double, 7, 7> covariance = Eigen::Matrix<double, 7, 7>::Zero();
  // RMS bounds in the units of the thesis error model (5.1.1):
  double rot_deg = 0.0;    // sqrt(trace cov_delta): rotation orientation error
  double dir_deg = 0.0;    // sqrt(trace of cov_dC projected perpendicular to dC) / |dC|
  double dist_pct = 0.0;   // sqrt(u^T cov_dC u) / |dC|, u = dC / |dC|
  double scale_pct = 0.0;  // sqrt(var lambda) / lambda
};

// The full linearised thesis system, for inspection and tests: the Fisher information of
// p = (theta, [phi_k, c_k] for k = 1..K) (7 + 6K parameters) and the Jacobian of the exact-length
// constraints (2K rows; no rows when !noise.exact_lengths). ConstrainedBound(fisher, constraints,
// 7) equals ThesisCramerRaoBound(...).covariance, which eliminates the nuisance pose by pose in
// O(K).
struct ThesisFisherSystem {
  Eigen::MatrixXd fisher;
  Eigen::MatrixXd constraints;
};
ThesisFisherSystem ThesisFisher(const std::vector<Pose>& master_poses, const Similarity& rig,
                                double eps_rad, const ThesisNoiseModel& noise = {});

// CRB of one thesis problem. `master_poses`: the true master poses T_0^k for k = 1..K relative to
// pose 0 (the identity, not included); `rig`: the true rig similarity; `eps_rad` > 0: the noise
// level. Needs K >= 2 and rig.scale > 0. Thread-safe.
ThesisBound ThesisCramerRaoBound(const std::vector<Pose>& master_poses, const Similarity& rig,
                                 double eps_rad, const ThesisNoiseModel& noise = {});

}  // namespace rigcal::research
