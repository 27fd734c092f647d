// SPDX-License-Identifier: Apache-2.0
#pragma once
// The bundle adjustment's residual of one observation with analytic Jacobians: the chord
// r = p / |p| - f between the observed unit bearing f and the direction p = R(q)^T (X - C) to
// the landmark, in the camera frame (valid on the whole sphere). Parameter blocks: the
// keyframe's world_from_cam quaternion q (Eigen storage x, y, z, w; EigenQuaternionManifold),
// its centre C and the landmark X (world frame).
//
// The quaternion's Jacobian is the derivative of the rotation formula Eigen applies,
// p = v - 2 w (u x v) + 2 u x (u x v) with v = X - C and q = (u, w), with respect to the four
// ambient coefficients; the manifold maps it to the tangent space. Analytic Jacobians make a
// local bundle adjustment about twice as fast as automatic differentiation (vo/bearing_cost
// checks them against numeric differentiation).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

namespace rigcal::vo {

class BearingCost final : public ceres::SizedCostFunction<3, 4, 3, 3> {
 public:
  explicit BearingCost(const Eigen::Vector3d& f) : f_(f) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d f_;
};

}  // namespace rigcal::vo
