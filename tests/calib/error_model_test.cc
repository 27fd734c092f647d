// SPDX-License-Identifier: Apache-2.0
// Constraint residua and the direct scale measurement of one motion (thesis 5.1.1, 4.18, 4.23).
#include "rigcal/calib/error_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rigcal/base/quaternion.h"

namespace rigcal {
namespace {

// The slave's motion of a master motion through the rig dT: R_i = dR^T R_0 dR,
// C_i = dR^T ((R_0 - I) dC + C_0) / s.
RigMotion MotionThrough(const Pose& master, const Similarity& rig) {
  RigMotion m;
  m.master = master;
  m.slave.q = rig.q.conjugate() * master.q * rig.q;
  m.slave.C = rig.q.conjugate() * ((master.R() - Eigen::Matrix3d::Identity()) * rig.C + master.C) /
              rig.scale;
  return m;
}

Similarity Rig() {
  Similarity rig;
  rig.q = AxisAngle(Eigen::Vector3d(0.3, 1, -0.2).normalized(), 1.1);
  rig.C = Eigen::Vector3d(-1, 1, 3);
  rig.scale = 0.4;
  return rig;
}

TEST(ErrorModel, MeasuredScaleOfAConsistentMotionIsTheScale) {
  Pose master;
  master.q = AxisAngle(Eigen::Vector3d(0.1, 0.9, 0.4).normalized(), 0.5);
  master.C = Eigen::Vector3d(0.7, -0.2, 1.5);
  const ConstraintResidual r = ResidualOf(MotionThrough(master, Rig()), Rig());
  EXPECT_NEAR(r.rotation_deg, 0.0, 1e-9);
  EXPECT_NEAR(r.position_abs, 0.0, 1e-12);
  EXPECT_NEAR(r.measured_scale, 0.4, 1e-12);
  EXPECT_NEAR(r.measured_scale, r.master_axis_dot / r.slave_axis_dot, 1e-15);
  // C_0^T r_0 with r_0 the unit axis of the master rotation.
  EXPECT_NEAR(r.master_axis_dot, master.C.dot(Eigen::Vector3d(0.1, 0.9, 0.4).normalized()), 1e-12);
  EXPECT_NEAR(r.scale_pct, 0.0, 1e-9);

  // A wrong scale shows in the residual, not in the measurement.
  Similarity wrong = Rig();
  wrong.scale = 0.5;
  const ConstraintResidual w = ResidualOf(MotionThrough(master, Rig()), wrong);
  EXPECT_NEAR(w.measured_scale, 0.4, 1e-12);
  EXPECT_NEAR(w.scale_pct, 20.0, 1e-9);
  EXPECT_GT(w.position_abs, 0.01);
}

TEST(ErrorModel, NoAxisNoMeasurement) {
  Pose master;  // no rotation
  master.C = Eigen::Vector3d(1, 0, 0);
  const ConstraintResidual r = ResidualOf(MotionThrough(master, Rig()), Rig());
  EXPECT_TRUE(std::isnan(r.master_axis_dot));
  EXPECT_TRUE(std::isnan(r.slave_axis_dot));
  EXPECT_TRUE(std::isnan(r.measured_scale));
  EXPECT_EQ(r.scale_pct, 0.0);
}

TEST(ErrorModel, ScaleDotEpsilon) {
  EXPECT_EQ(ScaleDotEpsilon(0.004, {Eigen::Vector3d(3, 4, 0)}), 0.004);  // configured
  // 1e-3 of the RMS length: lengths 3 and 5 -> sqrt(17).
  EXPECT_NEAR(ScaleDotEpsilon(0.0, {Eigen::Vector3d(3, 0, 0), Eigen::Vector3d(0, 3, 4)}),
              1e-3 * std::sqrt(17.0), 1e-15);
  EXPECT_EQ(ScaleDotEpsilon(0.0, {}), 0.0);
}

}  // namespace
}  // namespace rigcal
