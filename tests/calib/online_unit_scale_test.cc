// SPDX-License-Identifier: Apache-2.0
// The recursive estimator does not depend on the unit of the odometry: a monocular VO sets its
// unit arbitrarily at each initialisation, so the same drive with every position multiplied by
// 1e-6, 1 or 1e6 must make the same keyframes and motions, the same rotations and scales, and
// positions (and their σ) multiplied by the same factor. With the keyframe distance in master
// units that this replaced, the three units made 362, 553 and 1191 keyframes and rotations 3σ
// apart.
// Nor does whether it calls a position converged: the position σ is measured against a length in
// the master's own unit, |C|, or the median length of the master's motions when the cameras sit
// close together. A length of 1 in whatever unit (the rule this replaced) called the same drive
// converged in metres and not in millimetres.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

// The drive with every master and slave position multiplied by `unit`.
RigEstimate RunInUnit(const SyntheticDrive& drive, double unit) {
  const RigRecording& rec = drive.recording;
  std::vector<std::string> names = {rec.master.name};
  for (const auto& s : rec.slaves) names.push_back(s.name);
  RigEstimator estimator(names, RigEstimatorOptions{});
  for (size_t k = 0; k < rec.size(); ++k) {
    std::vector<std::optional<CameraPose>> set = rec.SetAt(k);
    for (auto& pose : set) {
      if (pose) pose->pose.C *= unit;
    }
    estimator.AddSet(rec.t_ns[k], set);
  }
  return estimator.Estimate();
}

TEST(OnlineUnitScale, TheUnitOfTheOdometryChangesNothingButThePositionsUnit) {
  DriveOptions d;
  d.num_frames = 1500;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "left", "back"}, DemoRig(), d);
  const RigEstimate unit = RunInUnit(drive, 1.0);
  for (double k : {1e-6, 1e6}) {
    const RigEstimate scaled = RunInUnit(drive, k);
    ASSERT_EQ(scaled.rig.slaves.size(), unit.rig.slaves.size());
    for (size_t i = 0; i < unit.rig.slaves.size(); ++i) {
      const SlaveCalibration& a = unit.rig.slaves[i];
      const SlaveCalibration& b = scaled.rig.slaves[i];
      SCOPED_TRACE(a.name + " in units of " + std::to_string(k));
      ASSERT_TRUE(a.usable()) << a.message;
      EXPECT_EQ(scaled.online[i].keyframes, unit.online[i].keyframes);
      std::printf("%s in units of %g: %d keyframes, %d motions used\n", a.name.c_str(), k,
                  scaled.online[i].keyframes, b.motions.used);
      EXPECT_EQ(b.motions.used, a.motions.used);
      EXPECT_EQ(b.state, a.state) << b.message;
      EXPECT_EQ(b.motion_model, a.motion_model);
      // Rounding differs with the unit; far below σ (both are ~1e-2 deg and more).
      EXPECT_LT(AngleBetween(a.estimate.q, b.estimate.q) * kDegPerRad, 1e-6 * a.rot_std_deg);
      EXPECT_NEAR(b.rot_std_deg, a.rot_std_deg, 1e-6 * a.rot_std_deg);
      EXPECT_LT((b.estimate.C / k - a.estimate.C).norm(), 1e-6 * a.pos_std.norm());
      EXPECT_NEAR(b.pos_std.norm() / k, a.pos_std.norm(), 1e-6 * a.pos_std.norm());
      ASSERT_EQ(b.scales.size(), a.scales.size());
      for (size_t j = 0; j < a.scales.size(); ++j) {
        // The online scale's σ may be unknown (NaN): relative rounding instead.
        EXPECT_NEAR(b.scales[j].scale, a.scales[j].scale, 1e-9 * a.scales[j].scale);
      }
    }
  }
}

TEST(OnlineConvergenceUnit, CamerasCloseTogetherConvergeInEveryUnit) {
  // A camera 4 mm from the master, looking left; the demo drive moves the master by metres.
  Similarity close = DemoRig()[0];
  close.C = Eigen::Vector3d(0.003, 0.002, -0.002);
  DriveOptions d;
  d.num_frames = 1500;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "close"}, {close}, d);
  const RigEstimate metres = RunInUnit(drive, 1.0);
  const SlaveCalibration& a = metres.rig.slaves[0];
  ASSERT_TRUE(a.usable()) << a.message;
  std::printf("in metres: %s, C σ %.4f (|C| %.4f)\n", std::string(ToString(a.state)).c_str(),
              a.pos_std.maxCoeff(), a.estimate.C.norm());
  // The σ is over 5 % of |C| (so |C| alone cannot be the length) and within 5 % of a metre (so
  // the old rule called it converged in metres, not in millimetres).
  ASSERT_GT(a.pos_std.maxCoeff(), 0.05 * a.estimate.C.norm());
  ASSERT_LT(a.pos_std.maxCoeff(), 0.05);
  EXPECT_EQ(a.state, SlaveState::kConverged) << a.message;
  for (double unit : {1e-3, 1e3}) {
    const RigEstimate scaled = RunInUnit(drive, unit);
    const SlaveCalibration& b = scaled.rig.slaves[0];
    SCOPED_TRACE("in units of " + std::to_string(unit) + " m");
    EXPECT_EQ(b.state, a.state) << b.message;
    EXPECT_EQ(b.motions.used, a.motions.used);
    // The same estimate up to rounding, far below its σ.
    EXPECT_LT(AngleBetween(a.estimate.q, b.estimate.q) * kDegPerRad, 1e-6 * a.rot_std_deg);
    EXPECT_NEAR(b.pos_std.maxCoeff() / unit, a.pos_std.maxCoeff(), 1e-6 * a.pos_std.maxCoeff());
  }
}

}  // namespace
}  // namespace rigcal
