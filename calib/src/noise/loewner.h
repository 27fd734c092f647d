// SPDX-License-Identifier: Apache-2.0
// The Loewner-order maximum of two covariances, for the cluster-robust σ of the refinements.
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace rigcal::internal {

// The smallest covariance (Loewner order) above both a and b: a + (b - a)₊, the positive part
// of the difference. Sets *larger when b exceeds a in some direction.
inline Eigen::Matrix3d LoewnerMax(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b,
                                  bool* larger) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(b - a);
  const Eigen::Vector3d positive = eig.eigenvalues().cwiseMax(0.0);
  if (positive.maxCoeff() > 1e-6 * std::max(a.trace(), 1e-300)) *larger = true;
  return a + eig.eigenvectors() * positive.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace rigcal::internal
