// SPDX-License-Identifier: Apache-2.0
#include "refinement/refinement.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_set>

#include "models/linear_solvers.h"
#include "models/planar_solver.h"
#include "noise/loewner.h"
#include "refinement/statistics_prior.h"
#include "rigcal/base/quaternion.h"

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

// Position residual of (4.26) with C = B p + h a (the axis parameterisation).
struct AxisPositionCost {
  AxisPositionCost(const MotionData& m, double inv_sigma, const Eigen::Matrix3d& basis_and_axis)
      : cost(m, inv_sigma), t(basis_and_axis) {}
  template <typename T>
  bool operator()(const T* q, const T* p, const T* h, const T* scale, T* residual) const {
    T c[3];
    for (int r = 0; r < 3; ++r) c[r] = T(t(r, 0)) * p[0] + T(t(r, 1)) * p[1] + T(t(r, 2)) * h[0];
    return cost(q, c, scale, residual);
  }
  PositionCost cost;
  Eigen::Matrix3d t;  // columns b_1, b_2, a
};

// Prior on the axis offset: (h - value) / σ.
struct AxisPriorCost {
  AxisPriorCost(double value, double sigma) : v(value), inv_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* h, T* residual) const {
    residual[0] = (h[0] - T(v)) * T(inv_sigma);
    return true;
  }
  double v, inv_sigma;
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

// Cluster-robust (sandwich) covariance of the free parameters at the current point, tangent
// coordinates: H⁻¹ M H⁻¹ with H = JᵀJ over every residual, M = sum over clusters of g gᵀ,
// g = Jᵀr of the cluster's residuals, times B / (B - 1) for B time blocks. The motions'
// residual blocks are clustered by the time block of their motion, every other residual block
// (priors) is a cluster of its own. Empty when H is singular.
Eigen::MatrixXd ClusteredCovariance(ceres::Problem& problem, const std::vector<double*>& free,
                                    const std::vector<ceres::ResidualBlockId>& motion_blocks,
                                    const std::vector<int>& motion_of_block,
                                    const std::vector<int>& time_block) {
  std::vector<ceres::ResidualBlockId> all;
  problem.GetResidualBlocks(&all);
  const std::unordered_set<ceres::ResidualBlockId> of_motions(motion_blocks.begin(),
                                                              motion_blocks.end());
  std::vector<ceres::ResidualBlockId> ordered = motion_blocks;
  std::vector<int> cluster;
  int num_blocks = 0;
  for (size_t k = 0; k < motion_blocks.size(); ++k) {
    cluster.push_back(time_block[motion_of_block[k]]);
    num_blocks = std::max(num_blocks, cluster.back() + 1);
  }
  int next = num_blocks;
  for (ceres::ResidualBlockId id : all) {
    if (of_motions.count(id) > 0) continue;
    ordered.push_back(id);
    cluster.push_back(next++);
  }
  if (num_blocks < 2) return {};
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = free;
  options.residual_blocks = ordered;
  options.apply_loss_function = true;
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(options, nullptr, &residuals, nullptr, &jacobian)) return {};
  const int n = jacobian.num_cols;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  std::vector<Eigen::VectorXd> gradient(next, Eigen::VectorXd::Zero(n));
  Eigen::VectorXd j_row(n);
  int row = 0;
  for (size_t b = 0; b < ordered.size(); ++b) {
    const int size = problem.GetCostFunctionForResidualBlock(ordered[b])->num_residuals();
    for (int i = 0; i < size; ++i, ++row) {
      j_row.setZero();
      for (int e = jacobian.rows[row]; e < jacobian.rows[row + 1]; ++e) {
        j_row(jacobian.cols[e]) = jacobian.values[e];
      }
      h.noalias() += j_row * j_row.transpose();
      gradient[cluster[b]] += j_row * residuals[row];
    }
  }
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(n, n);
  for (int c = 0; c < next; ++c) {
    const double factor = c < num_blocks ? num_blocks / (num_blocks - 1.0) : 1.0;
    meat.noalias() += factor * gradient[c] * gradient[c].transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(h);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  if (!(lambda(0) > 1e-12 * lambda(n - 1))) return {};
  const Eigen::MatrixXd h_inv =
      eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return h_inv * meat * h_inv;
}

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

ceres::Problem::Options ProblemOptions() {
  ceres::Problem::Options options;
  options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  return options;
}

// The problem RefineNonlinear solves: its parameter blocks (Ceres keeps pointers to them, so the
// object stays where it is made), the residual blocks of the motions in their order (rotation
// then position; the clusters of the covariance), and the count of residuals (its degrees of
// freedom).
struct RefinementProblem {
  explicit RefinementProblem(const RefinementInput& in)
      : input(in),
        q(ToWxyz(in.q.normalized())),
        c(in.C),
        scales(in.scales),
        num_scales(static_cast<int>(in.scales.size())),
        problem(ProblemOptions()),
        use_axis(!in.translational && in.axis.norm() > 0.5),
        h_free(use_axis && !in.axis_offset_fixed),
        inv_sigma_rot(1.0 / in.sigma_rotation),
        inv_sigma_pos(1.0 / in.sigma_position),
        scale_used(num_scales, false) {}
  RefinementProblem(const RefinementProblem&) = delete;
  RefinementProblem& operator=(const RefinementProblem&) = delete;

  const RefinementInput& input;
  Eigen::Vector4d q;  // (w, x, y, z)
  Eigen::Vector3d c;
  std::vector<double> scales;
  const int num_scales;
  ceres::Problem problem;
  // Axis parameterisation: C = t (p, h) with t = [b_1 b_2 a].
  const bool use_axis;
  const bool h_free;  // h is a free parameter (not held at its start)
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  double h = 0.0;
  const double inv_sigma_rot;
  const double inv_sigma_pos;
  std::vector<bool> scale_used;
  int num_residuals = 0;
  std::vector<ceres::ResidualBlockId> motion_blocks;
  std::vector<int> motion_of_block;
};

// The parameter blocks: q on the quaternion manifold, C (or p and h about the axis, h constant
// when the axis offset is fixed; nothing for the translational model), one per scale.
void AddParameters(RefinementProblem* rp) {
  const RefinementInput& input = rp->input;
  rp->problem.AddParameterBlock(rp->q.data(), 4, new ceres::QuaternionManifold());
  if (rp->use_axis) {
    const Eigen::Vector3d a = input.axis.normalized();
    rp->t.leftCols<2>() = PlaneBasis(a);
    rp->t.col(2) = a;
    rp->p = rp->t.leftCols<2>().transpose() * rp->c;
    rp->h = a.dot(rp->c);
    rp->problem.AddParameterBlock(rp->p.data(), 2);
    rp->problem.AddParameterBlock(&rp->h, 1);
    if (input.axis_offset_fixed) rp->problem.SetParameterBlockConstant(&rp->h);
  } else if (!input.translational) {
    rp->problem.AddParameterBlock(rp->c.data(), 3);
  }
  for (auto& s : rp->scales) rp->problem.AddParameterBlock(&s, 1);
}

// The residuals of every motion (4.26, or 4.28 for the translational model), weighted and
// whitened, with the robust loss of `options`.
void AddMotionResiduals(const std::vector<MotionData>& motions, const CalibrationOptions& options,
                        RefinementProblem* rp) {
  const RefinementInput& input = rp->input;
  ceres::Problem& problem = rp->problem;
  double* q = rp->q.data();
  auto record = [&](ceres::ResidualBlockId id, size_t j) {
    rp->motion_blocks.push_back(id);
    rp->motion_of_block.push_back(static_cast<int>(j));
  };
  for (size_t j = 0; j < motions.size(); ++j) {
    const MotionData& m = motions[j];
    const double sqrt_w =
        input.weights.size() == motions.size() ? std::sqrt(input.weights[j]) : 1.0;
    const double w_rot = sqrt_w * rp->inv_sigma_rot;
    const double w_pos = sqrt_w * rp->inv_sigma_pos;
    double* scale = &rp->scales[m.scale_index];
    if (!input.translational) {
      record(problem.AddResidualBlock(new RotationCost(m, w_rot), MakeLoss(options), q), j);
      if (rp->use_axis) {
        record(problem.AddResidualBlock(
                   new ceres::AutoDiffCostFunction<AxisPositionCost, 3, 4, 2, 1, 1>(
                       new AxisPositionCost(m, w_pos, rp->t)),
                   MakeLoss(options), q, rp->p.data(), &rp->h, scale),
               j);
      } else {
        record(problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PositionCost, 3, 4, 3, 1>(
                                            new PositionCost(m, w_pos)),
                                        MakeLoss(options), q, rp->c.data(), scale),
               j);
      }
      rp->num_residuals += 7;
    } else {
      record(problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TranslationalCost, 3, 4, 1>(
                                          new TranslationalCost(m, w_pos)),
                                      MakeLoss(options), q, scale),
             j);
      rp->num_residuals += 3;
    }
    rp->scale_used[m.scale_index] = true;
  }
}

// The motions outside the given ones (input.prior): the exact sums of their squared residuals,
// as residual blocks without robust loss.
void AddOutsidePrior(RefinementProblem* rp) {
  const RefinementInput& input = rp->input;
  if (input.prior == nullptr || !(input.prior->weight > 0.0)) return;
  const RefinementPrior& prior = *input.prior;
  if (!input.translational) {
    ceres::CostFunction* rotation = MakeRotationPriorCost(prior, rp->inv_sigma_rot);
    if (rotation->num_residuals() > 0) {
      rp->problem.AddResidualBlock(rotation, nullptr, rp->q.data());
    } else {
      delete rotation;
    }
  }
  std::vector<double*> blocks = {rp->q.data()};
  PriorPosition layout = PriorPosition::kTranslational;
  if (rp->use_axis) {
    layout = PriorPosition::kAxis;
    blocks.push_back(rp->p.data());
    blocks.push_back(&rp->h);
  } else if (!input.translational) {
    layout = PriorPosition::kPlain;
    blocks.push_back(rp->c.data());
  }
  for (int index : input.prior_scale_index) {
    blocks.push_back(&rp->scales[index]);
    rp->scale_used[index] = true;
  }
  ceres::CostFunction* position = MakePositionPriorCost(prior, rp->inv_sigma_pos, layout, rp->t);
  if (position->num_residuals() > 0) {
    rp->problem.AddResidualBlock(position, nullptr, blocks);
  } else {
    delete position;
  }
  // 4 rotation residuals per motion of the prior, 3 position ones per motion of its position sums
  // (fewer after a master re-initialisation: 7 w - 3 (w - w_pos)).
  const double position_gap = prior.weight - prior.position_weight;
  rp->num_residuals +=
      static_cast<int>(std::lround(input.translational ? 3.0 * prior.weight - 3.0 * position_gap
                                                       : 7.0 * prior.weight - 3.0 * position_gap));
}

// The scale priors of (4.27) and the weighted prior on the axis offset h; scales no residual
// uses are held constant.
void AddScaleAndAxisPriors(RefinementProblem* rp) {
  const RefinementInput& input = rp->input;
  for (int s = 0; s < rp->num_scales; ++s) {
    const auto& prior = s < static_cast<int>(input.priors.size()) ? input.priors[s] : ScalePrior{};
    if (prior.sigma > 0.0 && std::isfinite(prior.sigma)) {
      rp->problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScalePriorCost, 1, 1>(
                                       new ScalePriorCost(prior.value, prior.sigma)),
                                   nullptr, &rp->scales[s]);
      rp->num_residuals += 1;
    }
    if (!rp->scale_used[s]) rp->problem.SetParameterBlockConstant(&rp->scales[s]);
  }
  if (rp->h_free && input.axis_prior_sigma > 0.0 && std::isfinite(input.axis_prior_sigma)) {
    rp->problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AxisPriorCost, 1, 1>(
                                     new AxisPriorCost(input.axis_prior, input.axis_prior_sigma)),
                                 nullptr, &rp->h);
    rp->num_residuals += 1;
  }
}

// Ends the solve at the next iteration once options.cancel is set.
class CancelCallback : public ceres::IterationCallback {
 public:
  explicit CancelCallback(const CalibrationOptions& options) : options_(options) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& /*summary*/) override {
    return options_.cancelled() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const CalibrationOptions& options_;
};

// Solves the problem (or not: `solve` false) and returns the estimate, σ of the scales unknown.
RefinementResult SolveProblem(const CalibrationOptions& options, bool solve,
                              RefinementProblem* rp) {
  RefinementResult out;
  if (solve) {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::DENSE_QR;
    solver_options.max_num_iterations = options.max_iterations;
    solver_options.function_tolerance = 1e-12;
    solver_options.parameter_tolerance = 1e-12;
    solver_options.gradient_tolerance = 1e-14;
    solver_options.num_threads = 1;
    CancelCallback cancel(options);
    if (options.cancel != nullptr) solver_options.callbacks.push_back(&cancel);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &rp->problem, &summary);
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    out.message = summary.message;
  } else {
    out.converged = true;
    out.message = "linear estimate (no refinement)";
  }
  if (rp->use_axis) rp->c = rp->t.leftCols<2>() * rp->p + rp->t.col(2) * rp->h;
  out.q = Canonical(FromWxyz(rp->q).normalized());
  out.C = rp->c;
  out.scales = rp->scales;
  // Unknown (NaN) until the covariance gives them.
  out.scale_std.assign(rp->num_scales, std::numeric_limits<double>::quiet_NaN());
  return out;
}

// The covariance of the free parameters scaled by the reduced chi-square of the fit, into
// `out`. False when Ceres cannot compute it (`out` unchanged).
bool ComputeCovariance(RefinementProblem* rp, RefinementResult* out) {
  const RefinementInput& input = rp->input;
  ceres::Problem& problem = rp->problem;
  double cost = 0.0;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  const int num_params =
      3 + (input.translational ? 0 : (rp->use_axis ? (rp->h_free ? 3 : 2) : 3)) + rp->num_scales;
  const double dof = rp->num_residuals - num_params;
  const double chi2 = dof > 0 ? 2.0 * cost / dof : 1.0;

  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.null_space_rank = 0;
  ceres::Covariance covariance(cov_options);
  double* q = rp->q.data();
  double* p = rp->p.data();
  double* h = &rp->h;
  std::vector<std::pair<const double*, const double*>> blocks = {{q, q}};
  if (rp->use_axis) {
    blocks.emplace_back(p, p);
    if (rp->h_free) {
      blocks.emplace_back(h, h);
      blocks.emplace_back(p, h);
    }
  } else if (!input.translational) {
    blocks.emplace_back(rp->c.data(), rp->c.data());
  }
  for (int s = 0; s < rp->num_scales; ++s) {
    if (rp->scale_used[s]) blocks.emplace_back(&rp->scales[s], &rp->scales[s]);
  }
  if (!covariance.Compute(blocks, &problem)) return false;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> cov_delta;
  covariance.GetCovarianceMatrixInTangentSpace({q}, cov_delta.data());
  // QuaternionManifold: q ⊕ δ = Exp(δ) q with Exp(δ) = (cos|δ|, sin|δ| δ/|δ|), a rotation by 2|δ|.
  out->cov_rotation = 4.0 * chi2 * cov_delta;
  if (rp->use_axis) {
    // Covariance of (p, h), mapped to C = t (p, h).
    Eigen::Matrix3d cov_ph = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 2, 2, Eigen::RowMajor> cov_p;
    covariance.GetCovarianceBlock(p, p, cov_p.data());
    cov_ph.topLeftCorner<2, 2>() = cov_p;
    if (rp->h_free) {
      double var_h = 0.0;
      Eigen::Vector2d cov_p_h;
      covariance.GetCovarianceBlock(h, h, &var_h);
      covariance.GetCovarianceBlock(p, h, cov_p_h.data());
      cov_ph(2, 2) = var_h;
      cov_ph.topRightCorner<2, 1>() = cov_p_h;
      cov_ph.bottomLeftCorner<1, 2>() = cov_p_h.transpose();
      out->axis_std = std::sqrt(std::max(0.0, chi2 * var_h));
    }
    out->cov_position = chi2 * rp->t * cov_ph * rp->t.transpose();
  } else if (!input.translational) {
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> cov_c;
    covariance.GetCovarianceBlock(rp->c.data(), rp->c.data(), cov_c.data());
    out->cov_position = chi2 * cov_c;
  }
  for (int s = 0; s < rp->num_scales; ++s) {
    if (!rp->scale_used[s]) continue;
    double var = 0.0;
    covariance.GetCovarianceBlock(&rp->scales[s], &rp->scales[s], &var);
    out->scale_std[s] = std::sqrt(std::max(0.0, chi2 * var));
  }
  out->covariance_ok = out->cov_rotation.allFinite() && out->cov_position.allFinite();
  out->independent_cov_rotation = out->cov_rotation;
  out->independent_cov_position = out->cov_position;
  return true;
}

// Raises the covariance in `out` to the cluster-robust one of the motions' time blocks
// (input.blocks) where that is larger.
void RaiseToClusteredCovariance(RefinementProblem* rp, RefinementResult* out) {
  const RefinementInput& input = rp->input;
  const bool use_axis = rp->use_axis;
  const bool h_free = rp->h_free;
  // The free parameters in tangent coordinates: q (3), C (3) or p (2) and h (1, when free),
  // the used scales (1 each).
  std::vector<double*> free = {rp->q.data()};
  if (use_axis) {
    free.push_back(rp->p.data());
    if (h_free) free.push_back(&rp->h);
  } else if (!input.translational) {
    free.push_back(rp->c.data());
  }
  std::vector<int> scale_column(rp->num_scales, -1);
  int column = 3 + (use_axis ? (h_free ? 3 : 2) : (input.translational ? 0 : 3));
  for (int s = 0; s < rp->num_scales; ++s) {
    if (!rp->scale_used[s]) continue;
    scale_column[s] = column++;
    free.push_back(&rp->scales[s]);
  }
  const Eigen::MatrixXd cov =
      ClusteredCovariance(rp->problem, free, rp->motion_blocks, rp->motion_of_block, input.blocks);
  if (cov.size() == 0 || !cov.allFinite()) return;
  Eigen::Matrix3d rot = 4.0 * cov.topLeftCorner<3, 3>();  // tangent δ rotates by 2|δ|
  Eigen::Matrix3d position = Eigen::Matrix3d::Zero();
  if (use_axis) {
    Eigen::Matrix3d ph = Eigen::Matrix3d::Zero();
    ph.block(0, 0, h_free ? 3 : 2, h_free ? 3 : 2) =
        cov.block(3, 3, h_free ? 3 : 2, h_free ? 3 : 2);
    position = rp->t * ph * rp->t.transpose();
    if (h_free) out->axis_std = std::max(out->axis_std, std::sqrt(std::max(0.0, ph(2, 2))));
  } else if (!input.translational) {
    position = cov.block<3, 3>(3, 3);
  }
  bool larger = false;
  out->cov_rotation = LoewnerMax(out->cov_rotation, rot, &larger);
  out->cov_position = LoewnerMax(out->cov_position, position, &larger);
  for (int s = 0; s < rp->num_scales; ++s) {
    if (scale_column[s] < 0) continue;
    const double sd = std::sqrt(std::max(0.0, cov(scale_column[s], scale_column[s])));
    if (sd > out->scale_std[s]) {
      out->scale_std[s] = sd;
      larger = true;
    }
  }
  out->clustered_larger = larger;
}

}  // namespace

RefinementResult RefineNonlinear(const std::vector<MotionData>& motions,
                                 const RefinementInput& input, const CalibrationOptions& options,
                                 bool solve) {
  RefinementProblem rp(input);
  AddParameters(&rp);
  AddMotionResiduals(motions, options, &rp);
  AddOutsidePrior(&rp);
  AddScaleAndAxisPriors(&rp);
  RefinementResult out = SolveProblem(options, solve, &rp);
  if (options.cancelled()) {
    out.converged = false;
    out.message = "cancelled";
    return out;
  }
  if (!options.compute_covariance || !ComputeCovariance(&rp, &out)) return out;
  if (out.covariance_ok && input.blocks.size() == motions.size()) {
    RaiseToClusteredCovariance(&rp, &out);
  }
  return out;
}

}  // namespace rigcal::internal
