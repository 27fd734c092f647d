// SPDX-License-Identifier: Apache-2.0
#pragma once
// Triangulation of a 3D point from two rays (camera centre + unit bearing in the world frame),
// with the checks a VO needs: positive depth along both rays (valid for any bearing, also
// behind the image plane of a wide-angle lens) and a minimum angle between the rays.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <optional>

namespace rigcal::vo {

struct TriangulatedPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // world frame
  double depth_a = 0.0;                             // distance along ray a
  double depth_b = 0.0;                             // distance along ray b
  double ray_angle_rad = 0.0;                       // angle between the two rays
};

// Midpoint of the closest points of the rays C_a + s f_a and C_b + t f_b (f_* unit, world
// frame). nullopt when the rays are (nearly) parallel or a depth is not positive.
std::optional<TriangulatedPoint> TriangulateMidpoint(const Eigen::Vector3d& C_a,
                                                     const Eigen::Vector3d& f_a,
                                                     const Eigen::Vector3d& C_b,
                                                     const Eigen::Vector3d& f_b);

// Angle between two vectors (any length, not zero), radians in [0, pi]: atan2(|a x b|, a . b),
// accurate also for tiny and near-opposite angles.
inline double VectorAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Angle between a unit bearing and the direction from a camera to a point, radians
// (R_world_from_cam, C: the camera's pose; f_in_cam: bearing in camera coordinates).
double BearingAngle(const Eigen::Matrix3d& R_world_from_cam, const Eigen::Vector3d& C,
                    const Eigen::Vector3d& f_in_cam, const Eigen::Vector3d& point);

}  // namespace rigcal::vo
