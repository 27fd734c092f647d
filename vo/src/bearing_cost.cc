// SPDX-License-Identifier: Apache-2.0
#include "bearing_cost.h"

#include <Eigen/Geometry>

namespace rigcal::vo {
namespace {

Eigen::Matrix3d SkewOf(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

bool BearingCost::Evaluate(double const* const* parameters, double* residuals,
                           double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> u(parameters[0]);  // quaternion x, y, z
  const double w = parameters[0][3];
  const Eigen::Map<const Eigen::Vector3d> centre(parameters[1]);
  const Eigen::Map<const Eigen::Vector3d> point(parameters[2]);
  const Eigen::Vector3d v = point - centre;
  // p = R(q)^T v: Eigen's rotation of v by the conjugate (-u, w).
  const Eigen::Vector3d uv = u.cross(v);
  const Eigen::Vector3d p = v - 2.0 * w * uv + 2.0 * u.cross(uv);
  const double norm = p.norm();
  if (!(norm > 1e-12)) return false;
  const Eigen::Vector3d n = p / norm;
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = n - f_;
  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d dn_dp = (Eigen::Matrix3d::Identity() - n * n.transpose()) / norm;
  // dp/dv = R^T, so dp/dC = -R^T and dp/dX = R^T.
  const Eigen::Matrix3d rt =
      Eigen::Quaterniond(w, u.x(), u.y(), u.z()).conjugate().toRotationMatrix();
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 3, 4> dp_dq;
    dp_dq.leftCols<3>() = 2.0 * w * SkewOf(v) + 2.0 * (u.dot(v) * Eigen::Matrix3d::Identity() +
                                                       u * v.transpose() - 2.0 * v * u.transpose());
    dp_dq.col(3) = -2.0 * uv;
    Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> j(jacobians[0]);
    j = dn_dp * dp_dq;
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[1]);
    j = -dn_dp * rt;
  }
  if (jacobians[2] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[2]);
    j = dn_dp * rt;
  }
  return true;
}

}  // namespace rigcal::vo
