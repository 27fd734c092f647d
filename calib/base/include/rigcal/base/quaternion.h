// SPDX-License-Identifier: Apache-2.0
#pragma once
// Quaternion algebra of the thesis (appendix A.3), quaternions as 4-vectors (w, x, y, z).

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rigcal {

using Vector4 = Eigen::Vector4d;

Vector4 ToWxyz(const Eigen::Quaterniond& q);
Eigen::Quaterniond FromWxyz(const Vector4& wxyz);

// Left multiplication matrix: q · p = T_q p  (eq. 4.8, A.9).
Eigen::Matrix4d LeftMultiplicationMatrix(const Vector4& q);
// Right multiplication matrix: p · q = T*_q p  (eq. 4.8, A.10).
Eigen::Matrix4d RightMultiplicationMatrix(const Vector4& q);

// Rotation angle in [0, pi] of a unit quaternion (either sign).
double RotationAngle(const Eigen::Quaterniond& q);
// Unit rotation axis; for angles below 1e-12 returns (0, 0, 1).
Eigen::Vector3d RotationAxis(const Eigen::Quaterniond& q);
// Rotation vector (angle in [0, pi] times the unit axis) of a unit quaternion: the log map.
Eigen::Vector3d RotationVector(const Eigen::Quaterniond& q);
// Angle between two rotations: 2 acos |<a, b>| (thesis 5.1.1, rotation orientation error).
double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);
// The representative of q with non-negative scalar part.
Eigen::Quaterniond Canonical(const Eigen::Quaterniond& q);
// Rotation about `axis` (need not be unit) by `angle_rad`.
Eigen::Quaterniond AxisAngle(const Eigen::Vector3d& axis, double angle_rad);

constexpr double kDegPerRad = 57.295779513082320876798;
constexpr double kRadPerDeg = 1.0 / kDegPerRad;

}  // namespace rigcal
