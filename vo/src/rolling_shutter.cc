// SPDX-License-Identifier: Apache-2.0
// Rolling-shutter model: observations moved between a row's time and the frame's stamp.
#include "rolling_shutter.h"

#include <Eigen/Geometry>

#include "absolute_pose.h"

namespace rigcal::vo {

CameraTwist TwistFromMotion(const Eigen::Matrix3d& R_cam_a_from_cam_b,
                            const Eigen::Vector3d& C_b_in_cam_a, double dt_s,
                            const Eigen::Matrix3d& cam_b_from_cam_now) {
  CameraTwist twist;
  if (!(dt_s > 0.0)) return twist;
  const Eigen::AngleAxisd turn(R_cam_a_from_cam_b);
  // ω is the same vector in cameras a and b (it is the rotation's axis); in the camera now:
  const Eigen::Matrix3d cam_now_from_cam_b = cam_b_from_cam_now.transpose();
  twist.angular_rad_s = cam_now_from_cam_b * (turn.axis() * (turn.angle() / dt_s));
  twist.linear_per_s =
      cam_now_from_cam_b * (R_cam_a_from_cam_b.transpose() * (C_b_in_cam_a / dt_s));
  return twist;
}

RollingShutter::RollingShutter(double readout_s, int height)
    : readout_s_(readout_s > 0.0 ? readout_s : 0.0),
      inv_last_row_(height > 1 ? 1.0 / (height - 1) : 0.0) {}

void RollingShutter::SetMotion(const CameraTwist& twist) {
  twist_ = twist;
  active_ = enabled() && twist.angular_rad_s.allFinite() && twist.linear_per_s.allFinite();
}

Eigen::Vector3d RollingShutter::ToStamp(const Eigen::Vector3d& bearing_row, double v,
                                        double distance_row) const {
  const double delay_s = RowDelayS(v);
  if (!active_ || delay_s == 0.0) return bearing_row;
  Eigen::Vector3d rotated = ExpSO3(twist_.angular_rad_s * delay_s) * bearing_row;
  if (!(distance_row > 0.0)) return rotated;
  return (rotated * distance_row + twist_.linear_per_s * delay_s).normalized();
}

Eigen::Vector3d RollingShutter::FromStamp(const Eigen::Vector3d& p_in_stamp_cam, double v) const {
  const double delay_s = RowDelayS(v);
  if (!active_ || delay_s == 0.0) return p_in_stamp_cam;
  return ExpSO3(twist_.angular_rad_s * delay_s).transpose() *
         (p_in_stamp_cam - twist_.linear_per_s * delay_s);
}

double RollingShutter::DistanceAtRow(const Eigen::Vector3d& p_in_stamp_cam, double v) const {
  if (!active_) return p_in_stamp_cam.norm();
  return (p_in_stamp_cam - twist_.linear_per_s * RowDelayS(v)).norm();
}

Eigen::Vector3d RollingShutter::RayOrigin(double v) const {
  if (!active_) return Eigen::Vector3d::Zero();
  return twist_.linear_per_s * RowDelayS(v);
}

Eigen::Vector3d BearingFromStamp(const Eigen::Vector3d& ray_origin,
                                 const Eigen::Vector3d& ray_direction,
                                 const Eigen::Vector3d& p_in_cam) {
  if (ray_origin.isZero(0.0)) return ray_direction;
  const double along = ray_direction.dot(p_in_cam - ray_origin);
  return (ray_origin + along * ray_direction).normalized();
}

}  // namespace rigcal::vo
