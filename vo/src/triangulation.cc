// SPDX-License-Identifier: Apache-2.0
#include "triangulation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace rigcal::vo {

std::optional<TriangulatedPoint> TriangulateMidpoint(const Eigen::Vector3d& C_a,
                                                     const Eigen::Vector3d& f_a,
                                                     const Eigen::Vector3d& C_b,
                                                     const Eigen::Vector3d& f_b) {
  // Minimise |C_a + s f_a - C_b - t f_b|^2 over s, t.
  const Eigen::Vector3d baseline = C_b - C_a;
  const double c = f_a.dot(f_b);
  const double den = 1.0 - c * c;
  if (den < 1e-12) return std::nullopt;
  const double fa_b = f_a.dot(baseline);
  const double fb_b = f_b.dot(baseline);
  const double s = (fa_b - c * fb_b) / den;
  const double t = (c * fa_b - fb_b) / den;
  if (!(s > 0.0) || !(t > 0.0)) return std::nullopt;
  TriangulatedPoint out;
  out.point = 0.5 * (C_a + s * f_a + C_b + t * f_b);
  out.depth_a = s;
  out.depth_b = t;
  out.ray_angle_rad = VectorAngle(f_a, f_b);
  return out;
}

double BearingAngle(const Eigen::Matrix3d& R_world_from_cam, const Eigen::Vector3d& C,
                    const Eigen::Vector3d& f_in_cam, const Eigen::Vector3d& point) {
  return VectorAngle(f_in_cam, R_world_from_cam.transpose() * (point - C));
}

}  // namespace rigcal::vo
