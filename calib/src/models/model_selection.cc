// SPDX-License-Identifier: Apache-2.0
#include "models/model_selection.h"

#include <spdlog/fmt/fmt.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "motions/non_finite.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

// Residual variance per unknown-corrected degree of freedom.
double Variance(double residual_ss, double equations, int unknowns) {
  return residual_ss / std::max(1.0, equations - unknowns);
}

// σ of C along `axis` and the largest in-plane σ of a position covariance.
void AxisAndPlaneStd(const Eigen::Matrix3d& cov, const Eigen::Vector3d& axis, double* axis_std,
                     double* plane_std) {
  const Eigen::Matrix<double, 3, 2> b = PlaneBasis(axis);
  *axis_std = std::sqrt(std::max(0.0, axis.dot(cov * axis)));
  const Eigen::Matrix2d plane = b.transpose() * cov * b;
  *plane_std = std::sqrt(
      std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(plane).eigenvalues()(1)));
}

// Axes that tilt far more than the noise (kClearlyTilting times the SNR the general model
// needs): the rotation system determines every direction well and the planar candidate is not
// computed (it costs as much as the rest of the solve).
constexpr double kClearlyTilting = 10.0;

// The general candidate: the smallest eigenvector of (4.10), and the variance of the rotation
// about each of the other three directions from the eigen-gaps (q = q0 + eps e_j rotates by
// 2 eps).
struct GeneralCandidate {
  Eigen::Quaterniond q;
  Eigen::Vector3d var_dir;  // rad², the weakest direction first
};
GeneralCandidate SolveGeneralRotation(const MotionStatistics& stats, Observability* obs) {
  const double w = stats.weight();
  Eigen::Vector4d eig;
  GeneralCandidate out;
  out.q = stats.SolveRotation(&eig);
  obs->rotation_eigenvalues = eig;
  const double sigma2_rot = std::max(eig(0), 0.0) / std::max(1.0, 4.0 * w - 3.0);
  for (int j = 1; j < 4; ++j) {
    out.var_dir(j - 1) = 4.0 * sigma2_rot / std::max(eig(j) - eig(0), 1e-300);
  }
  obs->rotation_weak_std_deg = std::sqrt(out.var_dir(0)) * kDegPerRad;
  return out;
}

// The planar candidate: stage 1 (axes) and stage 2 (angle, scales, in-plane position) of the
// planar solver; stage 2 only when the model may be planar.
struct PlanarCandidate {
  PlanarFrame frame;
  PlanarSystemSolution system;
  Eigen::Quaterniond q;     // the general candidate's when stage 2 did not solve
  double var_gamma = kInf;  // variance of the angle about the axis, rad²
};
PlanarCandidate SolvePlanarRotation(const MotionStatistics& stats, MotionModel requested,
                                    const ModelSelectionOptions& options,
                                    const Eigen::Quaterniond& q_general, Observability* obs) {
  PlanarCandidate out;
  out.frame = stats.SolvePlanarFrame();
  const PlanarFrame& frame = out.frame;
  obs->axis_spread_deg = frame.master_spread_deg;
  obs->slave_axis_spread_deg = frame.slave_spread_deg;
  obs->planar_axis = frame.ok ? frame.axis : Eigen::Vector3d::Zero();
  const bool clearly_general =
      frame.ok && TiltSignalToNoise(stats.planar(), frame.axis, q_general) >=
                      kClearlyTilting * std::max(options.min_tilt_snr, 1.0);
  if (frame.ok && requested != MotionModel::kGeneral &&
      (!clearly_general || requested == MotionModel::kPlanar)) {
    out.system = stats.SolvePlanarSystem(frame);
  }
  const PlanarSystemSolution& planar = out.system;
  out.q = planar.ok ? PlanarRotation(frame, planar.gamma) : q_general;
  out.var_gamma =
      planar.ok ? Variance(planar.residual_ss, 2.0 * stats.position_weight(), planar.unknowns) /
                      planar.gamma_information
                : kInf;
  return out;
}

// The general model's position (4.16) at the candidate rotation whose translations fit better
// (the general candidate's angle about the axis is arbitrary for planar motion), with its
// covariance, and the figures it gives: the position system's conditioning, the tilt SNR at
// that rotation and the ratio of C's σ along the axis to its in-plane σ.
struct GeneralPosition {
  Eigen::Quaterniond q;
  PositionSolution position;
  bool rotation_from_planar = false;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  // of C
};
GeneralPosition SolveGeneralPosition(const MotionStatistics& stats,
                                     const Eigen::Quaterniond& q_general,
                                     const PlanarCandidate& planar, Observability* obs) {
  const PlanarFrame& frame = planar.frame;
  GeneralPosition out;
  out.q = q_general;
  out.position = stats.SolvePosition(q_general);
  if (planar.system.ok) {
    const PositionSolution from_planar = stats.SolvePosition(planar.q);
    if (from_planar.residual_ss < out.position.residual_ss) {
      out.q = planar.q;
      out.position = from_planar;
      out.rotation_from_planar = true;
    }
  }
  const PositionSolution& general = out.position;
  obs->position_min_eigenvalue = general.min_eigenvalue;
  obs->tilt_snr = frame.ok ? TiltSignalToNoise(stats.planar(), frame.axis, out.q) : kInf;
  // The position residuals are of the motions in the position sums only (position_weight).
  const double var_pos =
      Variance(general.residual_ss, 3.0 * stats.position_weight(), general.unknowns);
  out.cov = var_pos * general.covariance;
  double axis_std = kInf, plane_std = 0.0;
  if (general.ok && frame.ok) {
    AxisAndPlaneStd(out.cov, frame.axis, &axis_std, &plane_std);
    obs->axis_std_ratio = plane_std > 0.0 ? axis_std / plane_std : (axis_std > 0.0 ? kInf : 1.0);
  } else {
    obs->axis_std_ratio = kInf;
  }
  return out;
}

// Whether the motion model `requested` (kAuto: decided by the figures `obs`) is the general one;
// `why` gets the figures behind an automatic decision.
bool IsGeneral(MotionModel requested, const ModelSelectionOptions& options, bool frame_ok,
               bool general_ok, const Observability& obs, std::string* why) {
  if (requested != MotionModel::kAuto) return requested == MotionModel::kGeneral;
  const bool one_axis = obs.axis_spread_deg < options.planar_axis_spread_deg;
  const bool tilts = obs.tilt_snr >= options.min_tilt_snr ||
                     obs.axis_spread_deg >= options.general_axis_spread_deg;
  const bool determined = obs.axis_std_ratio <= options.max_axis_std_ratio;
  if (!frame_ok) return general_ok;
  if (!one_axis && tilts && determined) {
    *why = fmt::format("the rotation axes tilt: spread {:.3f} deg, tilt SNR {:.1f}",
                       obs.axis_spread_deg, obs.tilt_snr);
    return true;
  }
  if (one_axis) {
    *why = fmt::format("rotation axes within {:.3f} deg < {:.3f} deg", obs.axis_spread_deg,
                       options.planar_axis_spread_deg);
  } else if (!tilts) {
    *why = fmt::format(
        "the rotation axes tilt no more than rotation noise explains: spread {:.3f} deg, tilt "
        "SNR {:.1f} < {:.1f}",
        obs.axis_spread_deg, obs.tilt_snr, options.min_tilt_snr);
  } else {
    *why = fmt::format(
        "C along the rotation axis is {:.0f}x less determined than in the plane (> {:.0f}x)",
        obs.axis_std_ratio, options.max_axis_std_ratio);
  }
  return false;
}

// The general model's solution in `out`, C pulled towards the prior's offset along the axis
// when it has a σ.
void TakeGeneral(const GeneralCandidate& general_rotation, const PlanarCandidate& planar,
                 const GeneralPosition& general, const AxisPrior& prior, bool has_prior,
                 double h_prior, RotatingSolution* out) {
  const PlanarFrame& frame = planar.frame;
  const Eigen::Vector3d& var_dir = general_rotation.var_dir;
  out->model = MotionModel::kGeneral;
  out->q = general.q;
  if (!general.position.ok) return;
  out->C = general.position.C;
  out->scales = general.position.scales;
  out->cov_C = general.cov;
  if (has_prior && prior.sigma > 0.0) {
    // Weighted prior along the axis: the linear-Gaussian update of C with h = a^T C.
    const Eigen::Vector3d& a = frame.axis;
    const Eigen::Matrix3d& cov_general = general.cov;
    const Eigen::Vector3d k =
        cov_general * a / (a.dot(cov_general * a) + prior.sigma * prior.sigma);
    out->C += k * (h_prior - a.dot(out->C));
    out->cov_C -= k * a.transpose() * cov_general;
  }
  out->axis_std =
      frame.ok ? std::sqrt(std::max(0.0, frame.axis.dot(out->cov_C * frame.axis))) : kNaN;
  double var_rot = var_dir.maxCoeff();
  if (out->rotation_from_planar) {
    var_rot = std::max({var_dir(1), var_dir(2), std::min(var_dir(0), planar.var_gamma)});
  }
  out->rot_std_deg = std::sqrt(var_rot) * kDegPerRad;
  out->ok = out->C.allFinite();
}

// The planar model's solution in `out`: the rotation from the planar solver; scales and in-plane
// position from the translation equations with dR fixed and C along the axis at the prior (or
// 0).
void TakePlanar(const MotionStatistics& stats, const GeneralCandidate& general_rotation,
                const PlanarCandidate& planar, const AxisPrior& prior, bool has_prior,
                double h_prior, RotatingSolution* out) {
  const PlanarFrame& frame = planar.frame;
  const Eigen::Vector3d& var_dir = general_rotation.var_dir;
  out->model = MotionModel::kPlanar;
  out->observability.planar = true;
  out->rotation_from_planar = true;
  if (!planar.system.ok) return;
  out->q = planar.q;
  PositionConstraint constraint;
  constraint.basis = frame.basis;
  constraint.fixed = h_prior * frame.axis;
  const PositionSolution in_plane = stats.SolvePosition(planar.q, &constraint);
  if (!in_plane.ok) return;
  out->C = in_plane.C;
  out->scales = in_plane.scales;
  out->cov_C = Variance(in_plane.residual_ss, 3.0 * stats.position_weight(), in_plane.unknowns) *
               in_plane.covariance;
  out->axis_from_prior = has_prior;
  out->axis_std = kNaN;
  if (has_prior && prior.sigma > 0.0) {
    out->axis_std = prior.sigma;
    out->cov_C += prior.sigma * prior.sigma * frame.axis * frame.axis.transpose();
  }
  out->rot_std_deg = std::sqrt(std::max({var_dir(1), var_dir(2), planar.var_gamma})) * kDegPerRad;
  out->ok = out->C.allFinite() && out->q.coeffs().allFinite();
}

}  // namespace

double TranslationalBelowDeg(double alpha_maxrot_deg, double noise_ref_deg, double noise_deg,
                             double floor_deg) {
  const double boundary =
      noise_ref_deg > 0.0 ? alpha_maxrot_deg * std::sqrt(std::max(noise_deg, 0.0) / noise_ref_deg)
                          : alpha_maxrot_deg;
  return std::max(boundary, floor_deg);
}

double RotationNoiseDeg(const std::vector<MotionData>& motions) {
  if (motions.size() < 2) return 0.0;
  std::vector<double> diff;
  diff.reserve(motions.size());
  for (const auto& m : motions) diff.push_back((m.angle0 - m.anglei) * kDegPerRad);
  return MedianAndSigma(diff).sigma;
}

RotatingSolution SolveRotating(const MotionStatistics& stats, MotionModel requested,
                               const ModelSelectionOptions& options, const AxisPrior& prior) {
  RotatingSolution out;
  Observability& obs = out.observability;
  obs.max_rotation_deg = stats.max_rotation() * kDegPerRad;
  const GeneralCandidate general_rotation = SolveGeneralRotation(stats, &obs);
  const PlanarCandidate planar =
      SolvePlanarRotation(stats, requested, options, general_rotation.q, &obs);
  const bool has_prior = prior.given && planar.frame.ok;
  const double h_prior = has_prior ? planar.frame.axis.dot(prior.nominal_C) : 0.0;
  out.axis_prior = h_prior;
  const GeneralPosition general = SolveGeneralPosition(stats, general_rotation.q, planar, &obs);
  out.rotation_from_planar = general.rotation_from_planar;
  if (IsGeneral(requested, options, planar.frame.ok, general.position.ok, obs, &out.why)) {
    TakeGeneral(general_rotation, planar, general, prior, has_prior, h_prior, &out);
  } else {
    TakePlanar(stats, general_rotation, planar, prior, has_prior, h_prior, &out);
  }
  return out;
}

}  // namespace rigcal::internal
