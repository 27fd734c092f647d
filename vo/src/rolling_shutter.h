// SPDX-License-Identifier: Apache-2.0
#pragma once
// Rolling-shutter model of one camera's observations (private to vo/).
//
// A rolling-shutter camera exposes pixel row v at RowDelayS(v) = v / (H - 1) x readout after the
// frame's stamp (the stamp is the top row's, as the simulated rig renders it). Over the readout the
// camera moves with the twist of the VO's constant-velocity model, expressed in the camera frame at
// the stamp: angular rate ω (rad/s) and the velocity of its centre u (map units/s). The camera at
// row time δ is then
//     R(δ) = R_s Exp(ω δ),   C(δ) = C_s + R_s u δ
// (R = world_from_camera, C = centre), so a point at p_row in the row's camera frame lies at
//     p_stamp = Exp(ω δ) p_row + u δ
// in the camera frame at the stamp. ToStamp moves a measured bearing by this map, given the
// point's distance from the row's camera; FromStamp is its inverse, for predicting where a map
// point is seen. The map is exact for the VO's motion model (a straight line at a constant
// turn rate) and a known distance. Without the distance, the observation is exactly the ray
// from the row's camera centre (u δ in the stamp's camera frame) along Exp(ω δ) b_row: the VO
// triangulates new points from such rays (BearingFromStamp then gives the bearing at the
// stamp of a point on one). Without motion (initialisation, after a loss)
// or with a readout of 0 every method returns its input unchanged, bit for bit.

#include <Eigen/Core>

namespace rigcal::vo {

// A camera's motion per second, in its own frame at the stamp.
struct CameraTwist {
  Eigen::Vector3d angular_rad_s = Eigen::Vector3d::Zero();  // ω
  Eigen::Vector3d linear_per_s = Eigen::Vector3d::Zero();   // u = R_s^T dC/dt, map units/s
};

// The twist of the motion `cam_a_from_cam_b` (rotation R_a^T R_b, translation R_a^T (C_b - C_a))
// taking dt_s (> 0) seconds, expressed in the camera frame whose rotation relative to camera b
// is `cam_b_from_cam_now` (identity: camera b itself).
CameraTwist TwistFromMotion(const Eigen::Matrix3d& R_cam_a_from_cam_b,
                            const Eigen::Vector3d& C_b_in_cam_a, double dt_s,
                            const Eigen::Matrix3d& cam_b_from_cam_now);

class RollingShutter {
 public:
  // readout_s: the camera's top-to-bottom readout time (>= 0); height: image rows.
  RollingShutter(double readout_s, int height);

  bool enabled() const { return readout_s_ > 0.0; }
  // True when enabled and a motion is set: observations are then corrected.
  bool active() const { return active_; }
  void SetMotion(const CameraTwist& twist);
  // No motion estimate: nothing is corrected.
  void ClearMotion() { active_ = false; }
  const CameraTwist& twist() const { return twist_; }

  // Time from the stamp to the exposure of (fractional) pixel row v, seconds.
  double RowDelayS(double v) const { return readout_s_ * v * inv_last_row_; }
  // The unit bearing of a point seen along unit `bearing_row` in row v, at `distance_row` from
  // the camera at the row's time, in the camera at the stamp. distance_row <= 0: the rotation
  // only (the ray's direction).
  Eigen::Vector3d ToStamp(const Eigen::Vector3d& bearing_row, double v, double distance_row) const;
  // A point in the stamp's camera frame, in the camera frame of row v's time (the inverse map).
  Eigen::Vector3d FromStamp(const Eigen::Vector3d& p_in_stamp_cam, double v) const;
  // The distance of a point given in the stamp's camera frame from the camera at row v's time.
  double DistanceAtRow(const Eigen::Vector3d& p_in_stamp_cam, double v) const;
  // The ray of an observation in row v, in the camera frame at the stamp: its origin (the row's
  // camera centre, u δ, map units) and its unit direction (Exp(ω δ) b_row).
  Eigen::Vector3d RayOrigin(double v) const;
  Eigen::Vector3d RayDirection(const Eigen::Vector3d& bearing_row, double v) const {
    return ToStamp(bearing_row, v, 0.0);
  }

 private:
  double readout_s_ = 0.0;
  double inv_last_row_ = 0.0;
  bool active_ = false;
  CameraTwist twist_;
};

// The unit bearing, from the camera centre at the stamp, of the point of the ray (origin, unit
// direction; camera frame at the stamp) closest to p_in_cam; the direction itself, bit for bit,
// when the origin is 0.
Eigen::Vector3d BearingFromStamp(const Eigen::Vector3d& ray_origin,
                                 const Eigen::Vector3d& ray_direction,
                                 const Eigen::Vector3d& p_in_cam);

}  // namespace rigcal::vo
