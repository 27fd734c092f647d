// SPDX-License-Identifier: Apache-2.0
// The σ floor of auto and gls batch results (batch_sigma_floor.h).
#include "batch/batch_sigma_floor.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

#include "batch/batch_gls.h"
#include "noise/time_blocks.h"
#include "refinement/gls_refinement.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// Raises a known (finite) `*sigma` to `floor` when that is larger; an unknown σ stays unknown.
bool RaiseTo(double floor, double* sigma) {
  if (!std::isfinite(*sigma) || !std::isfinite(floor) || !(floor > *sigma)) return false;
  *sigma = floor;
  return true;
}

// The difference d of one block of parameters in the metric of its GLS covariance: the sum of
// d_i² / λ_i over the covariance's eigenvalues λ_i (those above 1e-12 of the largest: a fixed
// direction has none), and how many terms.
struct Mahalanobis {
  double sum = 0.0;
  int terms = 0;
  void Add(const Eigen::MatrixXd& cov, const Eigen::VectorXd& d) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
    const double largest = eig.eigenvalues().maxCoeff();
    if (!(largest > 0.0) || !std::isfinite(largest)) return;
    for (Eigen::Index i = 0; i < d.size(); ++i) {
      const double lambda = eig.eigenvalues()(i);
      if (!(lambda > 1e-12 * largest)) continue;
      const double along = eig.eigenvectors().col(i).dot(d);
      sum += along * along / lambda;
      ++terms;
    }
  }
  // λ = dᵀ Σ⁻¹ d / terms: Var(d) = λ Σ when d's covariance is proportional to Σ (0 without
  // terms).
  double Lambda() const { return terms > 0 ? sum / terms : 0.0; }
};

}  // namespace

void HoldSigmaToConsecutiveGls(const RigRecording& recording, int slave,
                               const CalibrationOptions& options, SlaveCalibration* r) {
  if (!r->solved() || r->scale_model == ScaleModel::kPartitions || !options.compute_covariance ||
      options.covariance_time_blocks <= 0) {
    return;
  }
  const std::vector<MotionData> motions = ChainMotions(recording, slave, 1, *r);
  GlsInput in = GlsStartOf(*r, options);
  in.time_blocks = BlocksForDurations(motions, options.covariance_time_blocks);
  const GlsResult g = RefineGls(motions, in);
  if (!g.ok) return;
  SlaveCalibration efficient = *r;
  TakeGls(g, in, options, &efficient);
  // Var(d) per parameter of C and per scale: the mean of d² (the one observed d for its
  // expectation, one degree of freedom) and λ σ_gls² (Var(d) proportional to the GLS's
  // covariance, λ from the k differences of C and the scales together), so that a d small by
  // chance does not leave σ at the GLS's alone, nor one large d inflate the whole block. The
  // rotation's d is already the angle of three differences: there Var(d) is the larger of d²
  // and λ σ_gls² (λ from the rotation vector's three).
  // The GLS's rotation parameter: dR = Exp(δ) dR about its estimate (gls_refinement.cc).
  const Eigen::Vector3d d_rotation =
      RotationVector(r->estimate.q * efficient.estimate.q.conjugate());
  Mahalanobis rotation;
  rotation.Add(g.cov_rotation, d_rotation);
  Mahalanobis translation;  // C and the scales
  const Eigen::Vector3d d_c = efficient.estimate.C - r->estimate.C;
  if (!in.translational) translation.Add(g.cov_position, d_c);
  const size_t scales = std::min({r->scales.size(), efficient.scales.size(), g.scale_std.size()});
  for (size_t s = 0; s < scales; ++s) {
    const double sigma = g.scale_std[s];
    if (sigma > 0.0 && std::isfinite(sigma)) {
      translation.Add(Eigen::MatrixXd::Constant(1, 1, sigma * sigma),
                      Eigen::VectorXd::Constant(1, efficient.scales[s].scale - r->scales[s].scale));
    }
  }
  // `sigma_efficient`: the GLS result's σ (with a nominal prior's part); `variance_gls`: the
  // GLS's own variance of the parameter, from the data alone.
  auto raise = [](double sigma_efficient, double var_d, double* sigma) {
    return RaiseTo(std::hypot(sigma_efficient, std::sqrt(std::max(0.0, var_d))), sigma);
  };
  auto mean = [](double d, double lambda, double variance_gls) {
    return 0.5 * (d * d + lambda * std::max(0.0, variance_gls));
  };
  bool raised = false;
  const double d_deg = AngleBetween(efficient.estimate.q, r->estimate.q) * kDegPerRad;
  const double rot_var_gls = efficient.rot_std_deg * efficient.rot_std_deg;
  raised |= raise(efficient.rot_std_deg, std::max(d_deg * d_deg, rotation.Lambda() * rot_var_gls),
                  &r->rot_std_deg);
  const double lambda = translation.Lambda();
  if (!in.translational) {
    for (int a = 0; a < 3; ++a) {
      raised |=
          raise(efficient.pos_std[a], mean(d_c[a], lambda, g.cov_position(a, a)), &r->pos_std[a]);
    }
    const Eigen::Vector3d& axis = r->observability.planar_axis;
    raised |=
        raise(efficient.axis_offset_std,
              mean(axis.dot(d_c), lambda, axis.dot(g.cov_position * axis)), &r->axis_offset_std);
  }
  for (size_t s = 0; s < scales; ++s) {
    const double d = efficient.scales[s].scale - r->scales[s].scale;
    raised |= raise(efficient.scales[s].std, mean(d, lambda, g.scale_std[s] * g.scale_std[s]),
                    &r->scales[s].std);
  }
  if (raised) {
    r->message += "; sigma raised to that of generalised least squares on the " +
                  std::to_string(g.increments) +
                  " consecutive motions with its difference from this estimate";
  }
}

}  // namespace rigcal::internal
