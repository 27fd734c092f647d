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
  const double w = stats.weight();

  // General candidate: smallest eigenvector of (4.10), σ per direction from the eigen-gaps
  // (q = q0 + eps e_j rotates by 2 eps).
  Eigen::Vector4d eig;
  const Eigen::Quaterniond q_general = stats.SolveRotation(&eig);
  obs.rotation_eigenvalues = eig;
  const double sigma2_rot = std::max(eig(0), 0.0) / std::max(1.0, 4.0 * w - 3.0);
  Eigen::Vector3d var_dir;
  for (int j = 1; j < 4; ++j) var_dir(j - 1) = 4.0 * sigma2_rot / std::max(eig(j) - eig(0), 1e-300);
  obs.rotation_weak_std_deg = std::sqrt(var_dir(0)) * kDegPerRad;

  // Planar candidate: stage 1 (axes) and stage 2 (angle, scales, in-plane position).
  const PlanarFrame frame = stats.SolvePlanarFrame();
  obs.axis_spread_deg = frame.master_spread_deg;
  obs.slave_axis_spread_deg = frame.slave_spread_deg;
  obs.planar_axis = frame.ok ? frame.axis : Eigen::Vector3d::Zero();
  const bool has_prior = prior.given && frame.ok;
  const double h_prior = has_prior ? frame.axis.dot(prior.nominal_C) : 0.0;
  out.axis_prior = h_prior;
  // Axes that tilt far more than the noise (kClearlyTilting times the SNR the general model
  // needs): the rotation system determines every direction well and the planar candidate is
  // not computed (it costs as much as the rest of the solve).
  constexpr double kClearlyTilting = 10.0;
  const bool clearly_general =
      frame.ok && TiltSignalToNoise(stats.planar(), frame.axis, q_general) >=
                      kClearlyTilting * std::max(options.min_tilt_snr, 1.0);
  PlanarSystemSolution planar;
  if (frame.ok && requested != MotionModel::kGeneral &&
      (!clearly_general || requested == MotionModel::kPlanar)) {
    planar = stats.SolvePlanarSystem(frame);
  }
  const Eigen::Quaterniond q_planar = planar.ok ? PlanarRotation(frame, planar.gamma) : q_general;
  const double var_gamma =
      planar.ok ? Variance(planar.residual_ss, 2.0 * w, planar.unknowns) / planar.gamma_information
                : kInf;

  // The rotation the general model starts from: the candidate whose translations fit better
  // (the general candidate's angle about the axis is arbitrary for planar motion).
  Eigen::Quaterniond q = q_general;
  PositionSolution general = stats.SolvePosition(q_general);
  if (planar.ok) {
    const PositionSolution from_planar = stats.SolvePosition(q_planar);
    if (from_planar.residual_ss < general.residual_ss) {
      q = q_planar;
      general = from_planar;
      out.rotation_from_planar = true;
    }
  }
  obs.position_min_eigenvalue = general.min_eigenvalue;
  obs.tilt_snr = frame.ok ? TiltSignalToNoise(stats.planar(), frame.axis, q) : kInf;
  const double var_pos = Variance(general.residual_ss, 3.0 * w, general.unknowns);
  Eigen::Matrix3d cov_general = var_pos * general.covariance;
  double axis_std = kInf, plane_std = 0.0;
  if (general.ok && frame.ok) {
    AxisAndPlaneStd(cov_general, frame.axis, &axis_std, &plane_std);
    obs.axis_std_ratio = plane_std > 0.0 ? axis_std / plane_std : (axis_std > 0.0 ? kInf : 1.0);
  } else {
    obs.axis_std_ratio = kInf;
  }

  // The decision.
  bool is_general = requested == MotionModel::kGeneral;
  if (requested == MotionModel::kAuto) {
    const bool one_axis = obs.axis_spread_deg < options.planar_axis_spread_deg;
    const bool tilts = obs.tilt_snr >= options.min_tilt_snr ||
                       obs.axis_spread_deg >= options.general_axis_spread_deg;
    const bool determined = obs.axis_std_ratio <= options.max_axis_std_ratio;
    if (!frame.ok) {
      is_general = general.ok;
    } else if (!one_axis && tilts && determined) {
      is_general = true;
      out.why = fmt::format("the rotation axes tilt: spread {:.3f} deg, tilt SNR {:.1f}",
                            obs.axis_spread_deg, obs.tilt_snr);
    } else if (one_axis) {
      out.why = fmt::format("rotation axes within {:.3f} deg < {:.3f} deg", obs.axis_spread_deg,
                            options.planar_axis_spread_deg);
    } else if (!tilts) {
      out.why = fmt::format(
          "the rotation axes tilt no more than rotation noise explains: spread {:.3f} deg, tilt "
          "SNR {:.1f} < {:.1f}",
          obs.axis_spread_deg, obs.tilt_snr, options.min_tilt_snr);
    } else {
      out.why = fmt::format(
          "C along the rotation axis is {:.0f}x less determined than in the plane (> {:.0f}x)",
          obs.axis_std_ratio, options.max_axis_std_ratio);
    }
  }

  if (is_general) {
    out.model = MotionModel::kGeneral;
    out.q = q;
    if (!general.ok) return out;
    out.C = general.C;
    out.scales = general.scales;
    out.cov_C = cov_general;
    if (has_prior && prior.sigma > 0.0) {
      // Weighted prior along the axis: the linear-Gaussian update of C with h = a^T C.
      const Eigen::Vector3d& a = frame.axis;
      const Eigen::Vector3d k =
          cov_general * a / (a.dot(cov_general * a) + prior.sigma * prior.sigma);
      out.C += k * (h_prior - a.dot(out.C));
      out.cov_C -= k * a.transpose() * cov_general;
    }
    out.axis_std =
        frame.ok ? std::sqrt(std::max(0.0, frame.axis.dot(out.cov_C * frame.axis))) : kNaN;
    double var_rot = var_dir.maxCoeff();
    if (out.rotation_from_planar) {
      var_rot = std::max({var_dir(1), var_dir(2), std::min(var_dir(0), var_gamma)});
    }
    out.rot_std_deg = std::sqrt(var_rot) * kDegPerRad;
    out.ok = out.C.allFinite();
    return out;
  }

  // Planar model: rotation from the planar solver; scales and in-plane position from the
  // translation equations with dR fixed and C along the axis at the prior (or 0).
  out.model = MotionModel::kPlanar;
  obs.planar = true;
  out.rotation_from_planar = true;
  if (!planar.ok) return out;
  out.q = q_planar;
  PositionConstraint constraint;
  constraint.basis = frame.basis;
  constraint.fixed = h_prior * frame.axis;
  const PositionSolution in_plane = stats.SolvePosition(q_planar, &constraint);
  if (!in_plane.ok) return out;
  out.C = in_plane.C;
  out.scales = in_plane.scales;
  out.cov_C = Variance(in_plane.residual_ss, 3.0 * w, in_plane.unknowns) * in_plane.covariance;
  out.axis_from_prior = has_prior;
  out.axis_std = kNaN;
  if (has_prior && prior.sigma > 0.0) {
    out.axis_std = prior.sigma;
    out.cov_C += prior.sigma * prior.sigma * frame.axis * frame.axis.transpose();
  }
  out.rot_std_deg = std::sqrt(std::max({var_dir(1), var_dir(2), var_gamma})) * kDegPerRad;
  out.ok = out.C.allFinite() && out.q.coeffs().allFinite();
  return out;
}

}  // namespace rigcal::internal
