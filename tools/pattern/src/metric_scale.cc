// SPDX-License-Identifier: Apache-2.0
// lambda_world: the master odometry's unit in metres from target poses in some master frames.
#include "rigcal/pattern/metric_scale.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

namespace rigcal::pattern {

Expected<WorldScale> EstimateWorldScale(const TimedTrajectory& master_odometry,
                                        const TimedTrajectory& master_target,
                                        int64_t tolerance_ns) {
  std::vector<Eigen::Vector3d> odo;
  std::vector<Eigen::Vector3d> metric;
  size_t j = 0;
  for (size_t k = 0; k < master_target.size(); ++k) {
    const int64_t t = master_target.t_ns[k];
    while (j < master_odometry.size() && master_odometry.t_ns[j] < t - tolerance_ns) ++j;
    if (j == master_odometry.size()) break;
    if (std::llabs(master_odometry.t_ns[j] - t) > tolerance_ns) continue;
    odo.push_back(master_odometry.poses[j].C);
    metric.push_back(master_target.poses[k].C);
  }
  const int n = static_cast<int>(odo.size());
  if (n < 3) {
    return Error{"metric scale: " + std::to_string(n) +
                 " master frames have both an odometry pose and a target pose (stamps within " +
                 std::to_string(tolerance_ns / 1000000.0) + " ms), need 3"};
  }
  Eigen::Matrix3Xd src(3, n);
  Eigen::Matrix3Xd dst(3, n);
  for (int k = 0; k < n; ++k) {
    src.col(k) = odo[static_cast<size_t>(k)];
    dst.col(k) = metric[static_cast<size_t>(k)];
  }
  const Eigen::Vector3d src_mean = src.rowwise().mean();
  const Eigen::Matrix3Xd centred = src.colwise() - src_mean;
  const double spread = centred.squaredNorm();
  // Collinear or coincident centres leave the rotation, and so the fit, undetermined.
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred);
  const Eigen::Vector3d sv = svd.singularValues();
  if (!(sv[0] > 0.0) || sv[1] < 1e-3 * sv[0]) {
    return Error{"metric scale: the master's centres in the " + std::to_string(n) +
                 " frames with a target pose lie on a line or coincide; the scale is not "
                 "determined (the master must move between target views)"};
  }
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, true);
  const double lambda = T.topLeftCorner<3, 3>().determinant() > 0.0
                            ? std::cbrt(T.topLeftCorner<3, 3>().determinant())
                            : 0.0;
  const Eigen::Matrix3Xd fitted =
      (T.topLeftCorner<3, 3>() * src).colwise() + T.topRightCorner<3, 1>();
  const double residual_sq = (fitted - dst).squaredNorm();
  WorldScale out;
  out.frames = n;
  out.metres_per_unit = lambda;
  out.fit_rms_m = std::sqrt(residual_sq / n);
  const double dof = std::max(1, 3 * n - 7);
  out.std = std::sqrt(residual_sq / dof / spread);
  char line[400];
  std::snprintf(line, sizeof(line),
                "metric scale from the target in %d master frames: 1 master unit = %.6g m (± "
                "%.2g, fit RMS %.3g m); positions are in metres",
                n, out.metres_per_unit, out.std, out.fit_rms_m);
  out.message = line;
  return out;
}

void ScaleResult(double metres_per_unit, RigCalibration* result) {
  for (SlaveCalibration& s : result->slaves) {
    s.estimate.C *= metres_per_unit;
    s.estimate.scale *= metres_per_unit;
    for (SegmentScale& seg : s.scales) {
      seg.scale *= metres_per_unit;
      seg.std *= metres_per_unit;
      seg.measured_mean *= metres_per_unit;
      seg.measured_std *= metres_per_unit;
    }
    s.pos_std *= metres_per_unit;
    s.axis_offset_std *= metres_per_unit;
  }
}

}  // namespace rigcal::pattern
