// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/quaternion.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>

namespace rigcal {
namespace {

// A direction drawn uniformly on the unit sphere.
Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    const double z = normal(rng);
    const double y = normal(rng);
    v = Eigen::Vector3d(normal(rng), y, z);
  } while (v.norm() < 1e-9);
  return v.normalized();
}

TEST(Quaternion, MultiplicationMatricesMatchHamiltonProduct) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Quaterniond a = AxisAngle(RandomUnitVector(rng), 0.1 + trial * 0.05);
    const Eigen::Quaterniond b = AxisAngle(RandomUnitVector(rng), 2.0 - trial * 0.03);
    const Vector4 ab = ToWxyz(a * b);
    EXPECT_LT((LeftMultiplicationMatrix(ToWxyz(a)) * ToWxyz(b) - ab).norm(), 1e-14);   // A.9
    EXPECT_LT((RightMultiplicationMatrix(ToWxyz(b)) * ToWxyz(a) - ab).norm(), 1e-14);  // A.10
    // T_{q*} = T_q^T for unit quaternions (A.3).
    EXPECT_LT((LeftMultiplicationMatrix(ToWxyz(a.conjugate())) -
               LeftMultiplicationMatrix(ToWxyz(a)).transpose())
                  .norm(),
              1e-14);
  }
}

TEST(Quaternion, AnglesAndAxes) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -2).normalized();
  for (double deg : {0.0, 1e-6, 0.5, 45.0, 179.0, 180.0}) {
    const Eigen::Quaterniond q = AxisAngle(axis, deg * kRadPerDeg);
    EXPECT_NEAR(RotationAngle(q) * kDegPerRad, deg, 1e-9);
    EXPECT_NEAR(RotationAngle(Eigen::Quaterniond(-q.coeffs())) * kDegPerRad, deg, 1e-9);
    if (deg > 1e-3 && deg < 180.0) {
      EXPECT_LT((RotationAxis(q) - axis).norm(), 1e-9);
    }
  }
  const Eigen::Quaterniond a = AxisAngle(axis, 0.3), b = AxisAngle(axis, 0.5);
  EXPECT_NEAR(AngleBetween(a, b), 0.2, 1e-12);
  EXPECT_NEAR(AngleBetween(a, Eigen::Quaterniond(-b.coeffs())), 0.2, 1e-12);
  EXPECT_GE(Canonical(Eigen::Quaterniond(-a.coeffs())).w(), 0.0);
}

}  // namespace
}  // namespace rigcal
