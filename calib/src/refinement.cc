#include "refinement.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <memory>

#include "linear_solvers.h"
#include "rigcal/calib/quaternion.h"

namespace rigcal::internal {
namespace {

// Rotation residual of (4.26): (T_q0 - T*_qi) dq / sigma. Linear in dq.
class RotationCost : public ceres::SizedCostFunction<4, 4> {
 public:
  RotationCost(const MotionData& m, double inv_sigma)
      : a_(RotationConstraintMatrix(m) * inv_sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Eigen::Map<const Eigen::Vector4d> q(parameters[0]);
    Eigen::Map<Eigen::Vector4d> r(residuals);
    r = a_ * q;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> j(jacobians[0]);
      j = a_;
    }
    return true;
  }

 private:
  Eigen::Matrix4d a_;
};

// Position residual of (4.26): ((I - R0) dC + dλ dR C_i - C_0) / sigma, eq. (4.14).
struct PositionCost {
  PositionCost(const MotionData& m, double inv_sigma)
      : i_minus_r0(Eigen::Matrix3d::Identity() - m.R0), ci(m.Ci), c0(m.C0), w(inv_sigma) {}
  template <typename T>
  bool operator()(const T* q, const T* c, const T* scale, T* residual) const {
    const T ci_t[3] = {T(ci[0]), T(ci[1]), T(ci[2])};
    T rotated[3];
    ceres::UnitQuaternionRotatePoint(q, ci_t, rotated);
    for (int r = 0; r < 3; ++r) {
      T v = scale[0] * rotated[r] - T(c0[r]);
      for (int col = 0; col < 3; ++col) v += T(i_minus_r0(r, col)) * c[col];
      residual[r] = v * T(w);
    }
    return true;
  }
  Eigen::Matrix3d i_minus_r0;
  Eigen::Vector3d ci, c0;
  double w;
};

// Purely translational residual, eq. (4.28): (dλ dR C_i - C_0) / sigma.
struct TranslationalCost {
  TranslationalCost(const MotionData& m, double inv_sigma) : ci(m.Ci), c0(m.C0), w(inv_sigma) {}
  template <typename T>
  bool operator()(const T* q, const T* scale, T* residual) const {
    const T ci_t[3] = {T(ci[0]), T(ci[1]), T(ci[2])};
    T rotated[3];
    ceres::UnitQuaternionRotatePoint(q, ci_t, rotated);
    for (int r = 0; r < 3; ++r) residual[r] = (scale[0] * rotated[r] - T(c0[r])) * T(w);
    return true;
  }
  Eigen::Vector3d ci, c0;
  double w;
};

// Scale prior of (4.27): (dλ - λ_measured) / σ.
struct ScalePriorCost {
  ScalePriorCost(double value, double sigma) : v(value), inv_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* scale, T* residual) const {
    residual[0] = (scale[0] - T(v)) * T(inv_sigma);
    return true;
  }
  double v, inv_sigma;
};

ceres::LossFunction* MakeLoss(const CalibrationOptions& options) {
  switch (options.robust_loss) {
    case RobustLoss::kHuber:
      return new ceres::HuberLoss(options.robust_scale);
    case RobustLoss::kCauchy:
      return new ceres::CauchyLoss(options.robust_scale);
    case RobustLoss::kNone:
      break;
  }
  return nullptr;
}

}  // namespace

RefinementResult RefineNonlinear(const std::vector<MotionData>& motions,
                                 const RefinementInput& input, const CalibrationOptions& options,
                                 bool solve) {
  RefinementResult out;
  Eigen::Vector4d q = ToWxyz(input.q.normalized());
  Eigen::Vector3d c = input.C;
  std::vector<double> scales = input.scales;
  const int num_scales = static_cast<int>(scales.size());

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(q.data(), 4, new ceres::QuaternionManifold());
  if (!input.translational) problem.AddParameterBlock(c.data(), 3);
  for (auto& s : scales) problem.AddParameterBlock(&s, 1);

  const double w_rot = 1.0 / input.sigma_rotation;
  const double w_pos = 1.0 / input.sigma_position;
  std::vector<bool> scale_used(num_scales, false);
  int num_residuals = 0;
  for (const auto& m : motions) {
    if (!input.translational) {
      problem.AddResidualBlock(new RotationCost(m, w_rot), MakeLoss(options), q.data());
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<PositionCost, 3, 4, 3, 1>(new PositionCost(m, w_pos)),
          MakeLoss(options), q.data(), c.data(), &scales[m.scale_index]);
      num_residuals += 7;
    } else {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TranslationalCost, 3, 4, 1>(
                                   new TranslationalCost(m, w_pos)),
                               MakeLoss(options), q.data(), &scales[m.scale_index]);
      num_residuals += 3;
    }
    scale_used[m.scale_index] = true;
  }
  for (int s = 0; s < num_scales; ++s) {
    const auto& prior = s < static_cast<int>(input.priors.size()) ? input.priors[s] : ScalePrior{};
    if (prior.sigma > 0.0 && std::isfinite(prior.sigma)) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScalePriorCost, 1, 1>(
                                   new ScalePriorCost(prior.value, prior.sigma)),
                               nullptr, &scales[s]);
      num_residuals += 1;
    }
    if (!scale_used[s]) problem.SetParameterBlockConstant(&scales[s]);
  }

  if (solve) {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.function_tolerance = 1e-12;
    solver_options.parameter_tolerance = 1e-12;
    solver_options.gradient_tolerance = 1e-14;
    solver_options.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    out.message = summary.message;
  } else {
    out.converged = true;
    out.message = "linear estimate (no refinement)";
  }
  out.q = Canonical(FromWxyz(q).normalized());
  out.C = c;
  out.scales = scales;
  out.scale_std.assign(num_scales, 0.0);

  if (!options.compute_covariance) return out;
  double cost = 0.0;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  const int num_params = 3 + (input.translational ? 0 : 3) + num_scales;
  const double dof = num_residuals - num_params;
  const double chi2 = dof > 0 ? 2.0 * cost / dof : 1.0;

  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.null_space_rank = 0;
  ceres::Covariance covariance(cov_options);
  std::vector<std::pair<const double*, const double*>> blocks = {{q.data(), q.data()}};
  if (!input.translational) blocks.emplace_back(c.data(), c.data());
  for (int s = 0; s < num_scales; ++s) {
    if (scale_used[s]) blocks.emplace_back(&scales[s], &scales[s]);
  }
  if (!covariance.Compute(blocks, &problem)) return out;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> cov_delta;
  covariance.GetCovarianceMatrixInTangentSpace({q.data()}, cov_delta.data());
  // QuaternionManifold: q ⊕ δ = Exp(δ) q with Exp(δ) = (cos|δ|, sin|δ| δ/|δ|), a rotation by 2|δ|.
  out.cov_rotation = 4.0 * chi2 * cov_delta;
  if (!input.translational) {
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> cov_c;
    covariance.GetCovarianceBlock(c.data(), c.data(), cov_c.data());
    out.cov_position = chi2 * cov_c;
  }
  for (int s = 0; s < num_scales; ++s) {
    if (!scale_used[s]) continue;
    double var = 0.0;
    covariance.GetCovarianceBlock(&scales[s], &scales[s], &var);
    out.scale_std[s] = std::sqrt(std::max(0.0, chi2 * var));
  }
  out.covariance_ok = out.cov_rotation.allFinite() && out.cov_position.allFinite();
  return out;
}

}  // namespace rigcal::internal
