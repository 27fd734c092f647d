// SPDX-License-Identifier: Apache-2.0
// Parameter standard deviations of a calibrated camera (intrinsics_uncertainty.h).
#include "intrinsics_uncertainty.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "rigcal/camera/camera_model.h"

namespace rigcal::pattern::internal {
namespace {

using camera::CameraSpec;

// Pointers to the free parameters of `spec`, in ParameterNames' order.
std::vector<double*> FreeParameters(CameraSpec* spec) {
  std::vector<double*> params;
  if (spec->model == CameraSpec::Model::kScaramuzza) return params;
  for (double& v : spec->intrinsics) params.push_back(&v);
  for (double& v : spec->distortion) params.push_back(&v);
  return params;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

std::vector<std::string> ParameterNames(const CameraSpec& spec) {
  switch (spec.model) {
    case CameraSpec::Model::kPinhole:
      return {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
    case CameraSpec::Model::kFisheye:
      return {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
    default:
      return {};
  }
}

Expected<std::vector<double>> ParameterStdDev(const CameraSpec& spec, const CameraViews& views,
                                              const std::vector<ViewStatistics>& stats,
                                              const std::vector<size_t>& used) {
  CameraSpec work = spec;
  const std::vector<double*> params = FreeParameters(&work);
  if (params.empty() || params.size() != ParameterNames(spec).size()) {
    return Error{spec.name + ": parameter sigma not computed for the " +
                 std::string(camera::ModelName(spec.model)) + " model"};
  }
  const auto p = static_cast<Eigen::Index>(params.size());
  auto base = camera::MakeCameraModel(spec);
  if (!base) return Error{base.error()};
  // The model with each parameter moved by +-h, for central differences.
  std::vector<std::unique_ptr<camera::CameraModel>> plus;
  std::vector<std::unique_ptr<camera::CameraModel>> minus;
  std::vector<double> step;
  for (double* param : params) {
    const double value = *param;
    const double h = 1e-6 * std::max(1.0, std::abs(value));
    *param = value + h;
    auto up = camera::MakeCameraModel(work);
    *param = value - h;
    auto down = camera::MakeCameraModel(work);
    *param = value;
    if (!up || !down) return Error{spec.name + ": a parameter step makes an invalid camera"};
    plus.push_back(std::move(*up));
    minus.push_back(std::move(*down));
    step.push_back(h);
  }

  Eigen::MatrixXd reduced = Eigen::MatrixXd::Zero(p, p);  // Schur complement of the poses
  double sum_sq = 0.0;
  Eigen::Index residuals = 0;
  for (size_t index : used) {
    const TargetView& view = views.views.at(index);
    const Pose& pose = stats.at(index).target_from_cam;
    const Eigen::Matrix3d R = pose.q.conjugate().toRotationMatrix();  // cam from target
    const Eigen::Vector3d t = -R * pose.C;
    const auto m = static_cast<Eigen::Index>(view.pixels.size());
    Eigen::MatrixXd J_cam(2 * m, p);
    Eigen::MatrixXd J_pose(2 * m, 6);  // x_cam = exp(dtheta) R X + t + dt
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Vector3d rotated = R * view.target_points[static_cast<size_t>(j)];
      const Eigen::Vector3d x = rotated + t;
      Eigen::Matrix<double, 2, 3> d_point;
      const auto pixel = (*base)->Project(x, &d_point);
      if (!pixel) return Error{view.file + ": a corner does not project under the estimate"};
      sum_sq += (*pixel - view.pixels[static_cast<size_t>(j)]).squaredNorm();
      residuals += 2;
      for (Eigen::Index i = 0; i < p; ++i) {
        const auto up = plus[static_cast<size_t>(i)]->Project(x);
        const auto down = minus[static_cast<size_t>(i)]->Project(x);
        if (!up || !down) return Error{view.file + ": a corner leaves the model's domain"};
        J_cam.block<2, 1>(2 * j, i) = (*up - *down) / (2.0 * step[static_cast<size_t>(i)]);
      }
      J_pose.block<2, 3>(2 * j, 0) = -d_point * Skew(rotated);
      J_pose.block<2, 3>(2 * j, 3) = d_point;
    }
    const Eigen::Matrix<double, 6, 6> C = J_pose.transpose() * J_pose;
    const Eigen::MatrixXd B = J_cam.transpose() * J_pose;
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> C_ldlt(C);
    if (C_ldlt.info() != Eigen::Success || C_ldlt.rcond() < 1e-14) {
      return Error{view.file + ": its target pose is not determined"};
    }
    reduced += J_cam.transpose() * J_cam - B * C_ldlt.solve(B.transpose());
  }
  const Eigen::Index dof = residuals - p - 6 * static_cast<Eigen::Index>(used.size());
  if (dof <= 0) {
    return Error{spec.name + ": too few corners for the parameters' sigma (" +
                 std::to_string(residuals) + " residuals)"};
  }
  const double variance = sum_sq / static_cast<double>(dof);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(reduced);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.rcond() < 1e-15) {
    return Error{spec.name + ": the views do not determine every camera parameter"};
  }
  const Eigen::MatrixXd covariance = variance * ldlt.solve(Eigen::MatrixXd::Identity(p, p));
  std::vector<double> sigma;
  for (Eigen::Index i = 0; i < p; ++i) sigma.push_back(std::sqrt(std::max(covariance(i, i), 0.0)));
  return sigma;
}

}  // namespace rigcal::pattern::internal
