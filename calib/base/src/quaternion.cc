// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/quaternion.h"

#include <algorithm>
#include <cmath>

namespace rigcal {

Vector4 ToWxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

Eigen::Quaterniond FromWxyz(const Vector4& wxyz) {
  return Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
}

// T_q, eq. (4.8) / (A.9): q · p = T_q p.
Eigen::Matrix4d LeftMultiplicationMatrix(const Vector4& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  Eigen::Matrix4d t;
  t << w, -x, -y, -z,  //
      x, w, -z, y,     //
      y, z, w, -x,     //
      z, -y, x, w;
  return t;
}

// T*_q, eq. (4.8) / (A.10): p · q = T*_q p.
Eigen::Matrix4d RightMultiplicationMatrix(const Vector4& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  Eigen::Matrix4d t;
  t << w, -x, -y, -z,  //
      x, w, z, -y,     //
      y, -z, w, x,     //
      z, y, -x, w;
  return t;
}

double RotationAngle(const Eigen::Quaterniond& q) {
  // atan2 form: accurate for small and large angles alike.
  const double v = q.vec().norm();
  return 2.0 * std::atan2(v, std::abs(q.w()));
}

Eigen::Vector3d RotationAxis(const Eigen::Quaterniond& q) {
  const Eigen::Quaterniond c = Canonical(q);
  const double v = c.vec().norm();
  if (v < 1e-12) return Eigen::Vector3d::UnitZ();
  return c.vec() / v;
}

Eigen::Vector3d RotationVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(Canonical(q));
  return aa.angle() * aa.axis();
}

double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return RotationAngle(a.conjugate() * b);
}

Eigen::Quaterniond Canonical(const Eigen::Quaterniond& q) {
  if (q.w() < 0.0) return Eigen::Quaterniond(-q.w(), -q.x(), -q.y(), -q.z());
  return q;
}

Eigen::Quaterniond AxisAngle(const Eigen::Vector3d& axis, double angle_rad) {
  const double n = axis.norm();
  if (n == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis / n));
}

}  // namespace rigcal
