#include "motion_geometry.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "rigcal/calib/quaternion.h"

namespace rigcal::internal {

AxisSpread MasterAxisSpread(const std::vector<MotionData>& motions) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& m : motions) {
    const Eigen::Vector3d v = m.q0.tail<3>();
    const double n = v.norm();
    if (n < 1e-12) continue;
    scatter += (v / n) * (v / n).transpose();
  }
  AxisSpread out;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d e = eig.eigenvalues().cwiseMax(0.0);
  if (e(2) <= 0.0) return out;
  out.spread_deg = std::atan(std::sqrt((e(0) + e(1)) / e(2))) * kDegPerRad;
  out.principal_axis = eig.eigenvectors().col(2);
  return out;
}

RobustStats Robust(std::vector<double> values) {
  RobustStats s;
  if (values.empty()) return s;
  auto median_of = [](std::vector<double>& v) {
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    double m = v[mid];
    if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
    return m;
  };
  s.median = median_of(values);
  for (double& x : values) x = std::abs(x - s.median);
  s.sigma = 1.4826 * median_of(values);
  return s;
}

}  // namespace rigcal::internal
