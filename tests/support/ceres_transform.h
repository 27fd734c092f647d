// SPDX-License-Identifier: Apache-2.0
#pragma once
// Rigid transforms as Ceres parameter blocks, and the solver settings of the evaluations'
// adjustments (support/tag_grid_refinement.h, support/offline_bundle_adjustment.h).

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <array>

#include "rigcal/base/types.h"

namespace rigcal::support {

// The transform p_to = Q p_from + T of a Pose `to_from` (Pose's q and C), as a quaternion block
// in Eigen's (x, y, z, w) memory order (ceres::EigenQuaternionManifold) and a translation block.
struct CeresTransform {
  std::array<double, 4> q{0.0, 0.0, 0.0, 1.0};
  std::array<double, 3> t{0.0, 0.0, 0.0};

  static CeresTransform FromPose(const Pose& to_from) {
    CeresTransform out;
    Eigen::Map<Eigen::Quaterniond>(out.q.data()) = to_from.q.normalized();
    Eigen::Map<Eigen::Vector3d>(out.t.data()) = to_from.C;
    return out;
  }
  Eigen::Quaterniond Q() const { return Eigen::Quaterniond(q[3], q[0], q[1], q[2]); }
  Eigen::Vector3d T() const { return Eigen::Vector3d(t[0], t[1], t[2]); }
  Pose ToPose() const {
    Pose pose;
    pose.q = Q().normalized();
    pose.C = T();
    return pose;
  }
};

// Sparse Schur, at most 100 iterations, 2 threads, silent.
inline void SolveAdjustment(ceres::Problem* problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_SCHUR;
  options.max_num_iterations = 100;
  options.num_threads = 2;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
}

}  // namespace rigcal::support
