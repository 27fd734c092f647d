// SPDX-License-Identifier: Apache-2.0
// The bundle adjustment's bearing residual: its value is the chord between the observed bearing
// and the direction to the landmark, and its analytic Jacobians match central differences of
// the residual for every parameter block, all around the sphere.
#include "../../vo/src/bearing_cost.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <random>

namespace rigcal::vo {
namespace {

TEST(BearingCost, ResidualAndJacobiansMatchNumericDifferentiation) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
    const Eigen::Vector3d centre(g(rng), g(rng), g(rng));
    const Eigen::Vector3d point = centre + 3.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    const Eigen::Vector3d f = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    std::array<double, 4> q_xyzw = {q.x(), q.y(), q.z(), q.w()};
    std::array<double, 3> c = {centre.x(), centre.y(), centre.z()};
    std::array<double, 3> x = {point.x(), point.y(), point.z()};
    double* blocks[3] = {q_xyzw.data(), c.data(), x.data()};
    const BearingCost cost(f);
    Eigen::Vector3d r;
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> jq;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jc, jx;
    double* jacobians[3] = {jq.data(), jc.data(), jx.data()};
    ASSERT_TRUE(cost.Evaluate(blocks, r.data(), jacobians));
    const Eigen::Vector3d expected = (q.conjugate() * (point - centre)).normalized() - f;
    EXPECT_LT((r - expected).norm(), 1e-12);
    // Central differences with step h: truncation error O(h^2) ~ 1e-10 at h = 1e-5.
    const double h = 1e-5;
    const std::array<int, 3> sizes = {4, 3, 3};
    const std::array<const double*, 3> analytic = {jq.data(), jc.data(), jx.data()};
    for (int b = 0; b < 3; ++b) {
      for (int j = 0; j < sizes[b]; ++j) {
        const double saved = blocks[b][j];
        Eigen::Vector3d plus, minus;
        blocks[b][j] = saved + h;
        ASSERT_TRUE(cost.Evaluate(blocks, plus.data(), nullptr));
        blocks[b][j] = saved - h;
        ASSERT_TRUE(cost.Evaluate(blocks, minus.data(), nullptr));
        blocks[b][j] = saved;
        const Eigen::Vector3d numeric = (plus - minus) / (2.0 * h);
        for (int i = 0; i < 3; ++i) {
          EXPECT_NEAR(analytic[b][i * sizes[b] + j], numeric(i), 1e-7)
              << "block " << b << " parameter " << j << " residual " << i;
        }
      }
    }
  }
}

TEST(BearingCost, PointAtTheCameraCentreHasNoResidual) {
  const BearingCost cost(Eigen::Vector3d::UnitZ());
  std::array<double, 4> q = {0, 0, 0, 1};
  std::array<double, 3> c = {1, 2, 3};
  std::array<double, 3> x = {1, 2, 3};
  double* blocks[3] = {q.data(), c.data(), x.data()};
  double r[3];
  EXPECT_FALSE(cost.Evaluate(blocks, r, nullptr));
}

}  // namespace
}  // namespace rigcal::vo
