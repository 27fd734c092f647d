// SPDX-License-Identifier: Apache-2.0
#include "refinement/statistics_prior.h"

#include <ceres/rotation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// u = [C; λ_1 vec(dR); ...; 1] of the position form (vec column-major).
template <typename T>
void FillU(const T* q, const T* c, const std::vector<const T*>& scales, T* u) {
  T r[9];  // row-major
  ceres::QuaternionToRotation(q, r);
  for (int i = 0; i < 3; ++i) u[i] = c[i];
  int j = 3;
  for (const T* s : scales) {
    for (int col = 0; col < 3; ++col) {
      for (int row = 0; row < 3; ++row) u[j + 3 * col + row] = s[0] * r[3 * row + col];
    }
    j += 9;
  }
  u[j] = T(1.0);
}

struct PositionPriorFunctor {
  Eigen::MatrixXd l;  // rows x dim, already whitened
  PriorPosition layout;
  Eigen::Matrix3d t;
  int segments = 0;

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    const T* q = parameters[0];
    T c[3] = {T(0.0), T(0.0), T(0.0)};
    int next = 1;
    if (layout == PriorPosition::kPlain) {
      for (int i = 0; i < 3; ++i) c[i] = parameters[1][i];
      next = 2;
    } else if (layout == PriorPosition::kAxis) {
      const T* p = parameters[1];
      const T* h = parameters[2];
      for (int i = 0; i < 3; ++i) c[i] = T(t(i, 0)) * p[0] + T(t(i, 1)) * p[1] + T(t(i, 2)) * h[0];
      next = 3;
    }
    std::vector<const T*> scales(static_cast<size_t>(segments));
    for (int k = 0; k < segments; ++k) scales[static_cast<size_t>(k)] = parameters[next + k];
    std::vector<T> u(static_cast<size_t>(l.cols()));
    FillU(q, c, scales, u.data());
    for (Eigen::Index row = 0; row < l.rows(); ++row) {
      T v(0.0);
      for (Eigen::Index col = 0; col < l.cols(); ++col) v += T(l(row, col)) * u[col];
      residuals[row] = v;
    }
    return true;
  }
};

class RotationPriorCost : public ceres::CostFunction {
 public:
  explicit RotationPriorCost(Eigen::MatrixXd l) : l_(std::move(l)) {
    set_num_residuals(static_cast<int>(l_.rows()));
    mutable_parameter_block_sizes()->push_back(4);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Eigen::Map<const Eigen::Vector4d> q(parameters[0]);
    Eigen::Map<Eigen::VectorXd>(residuals, l_.rows()) = l_ * q;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>(jacobians[0], l_.rows(),
                                                                            4) = l_;
    }
    return true;
  }

 private:
  Eigen::MatrixXd l_;
};

}  // namespace

Eigen::MatrixXd SquareRootOf(const Eigen::MatrixXd& g) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
  const Eigen::VectorXd& d = eig.eigenvalues();
  const double floor = 1e-14 * std::max(d.cwiseAbs().maxCoeff(), 1e-300);
  std::vector<int> keep;
  for (Eigen::Index i = 0; i < d.size(); ++i) {
    if (d(i) > floor) keep.push_back(static_cast<int>(i));
  }
  Eigen::MatrixXd l(static_cast<Eigen::Index>(keep.size()), g.cols());
  for (size_t k = 0; k < keep.size(); ++k) {
    l.row(static_cast<Eigen::Index>(k)) =
        std::sqrt(d(keep[k])) * eig.eigenvectors().col(keep[k]).transpose();
  }
  return l;
}

double PositionPriorValue(const RefinementPrior& prior, const Eigen::Quaterniond& q,
                          const Eigen::Vector3d& c, const std::vector<double>& segment_scales) {
  if (prior.position.size() == 0) return 0.0;
  const Eigen::Vector4d w = ToWxyz(q.normalized());
  std::vector<const double*> scales;
  scales.reserve(segment_scales.size());
  for (const double& s : segment_scales) scales.push_back(&s);
  Eigen::VectorXd u(prior.position.cols());
  FillU(w.data(), c.data(), scales, u.data());
  return std::max(0.0, u.dot(prior.position * u));
}

double RotationPriorValue(const RefinementPrior& prior, const Eigen::Quaterniond& q) {
  const Eigen::Vector4d w = ToWxyz(q.normalized());
  return std::max(0.0, w.dot(prior.rotation * w));
}

ceres::CostFunction* MakeRotationPriorCost(const RefinementPrior& prior, double inv_sigma) {
  return new RotationPriorCost(SquareRootOf(prior.rotation) * inv_sigma);
}

ceres::CostFunction* MakePositionPriorCost(const RefinementPrior& prior, double inv_sigma,
                                           PriorPosition layout, const Eigen::Matrix3d& t) {
  auto* functor = new PositionPriorFunctor;
  functor->l = SquareRootOf(prior.position) * inv_sigma;
  functor->layout = layout;
  functor->t = t;
  functor->segments = static_cast<int>(prior.segments.size());
  auto* cost = new ceres::DynamicAutoDiffCostFunction<PositionPriorFunctor, 8>(functor);
  cost->AddParameterBlock(4);
  if (layout == PriorPosition::kPlain) cost->AddParameterBlock(3);
  if (layout == PriorPosition::kAxis) {
    cost->AddParameterBlock(2);
    cost->AddParameterBlock(1);
  }
  for (size_t k = 0; k < prior.segments.size(); ++k) cost->AddParameterBlock(1);
  cost->SetNumResiduals(static_cast<int>(functor->l.rows()));
  return cost;
}

}  // namespace rigcal::internal
