// SPDX-License-Identifier: Apache-2.0
// The vec/Kronecker identities of the scale-rotation-translation equations (4.10)-(4.12).
#pragma once

#include <Eigen/Core>

namespace rigcal::internal {

// vec(M) column-major, so that M C = (C^T ⊗ I3) vec(M).
inline Eigen::Matrix<double, 9, 1> Vec(const Eigen::Matrix3d& m) {
  return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(m.data());
}

// C^T ⊗ I3: the 3x9 matrix with M C = (C^T ⊗ I3) vec(M).
inline Eigen::Matrix<double, 3, 9> KronTransposeIdentity(const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 3, 9> k = Eigen::Matrix<double, 3, 9>::Zero();
  for (int j = 0; j < 3; ++j) k.block<3, 3>(0, 3 * j) = c(j) * Eigen::Matrix3d::Identity();
  return k;
}

}  // namespace rigcal::internal
