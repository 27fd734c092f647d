// SPDX-License-Identifier: Apache-2.0
// The choice between the general and the purely translational motion model (thesis 5.2) by the
// measured rotation noise, on a sewer-like drive (thesis 5.6): the rig advances 6 m along the
// master's optical axis with a few centimetres of sway and rotations below 10 degrees about
// varied axes, and the slave sits 35 cm behind the master on that axis. The translational
// model ignores (I - R_0) dC, which is as large as the sway that fixes the rotation about the
// travel direction: it is biased. The rotations, small as they are, are far above the pose
// noise, so the general model determines the rotation. When the rig really does not rotate
// (rotations below the noise) the translational model is used and says so. Batch and online.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

constexpr double kRotationNoiseDeg = 0.02;  // white, per pose
constexpr double kPositionNoise = 0.001;    // metres, per pose
constexpr int kFrames = 480;                // 24 s at 20 Hz

// The slave looks backwards, 35 cm behind the master on its optical axis.
Similarity BackToBack() {
  Similarity rig;
  rig.q = Eigen::Quaterniond(0.0, 0.0, 1.0, 0.0);  // 180 degrees about y
  rig.C = Eigen::Vector3d(0.0, 0.0, -0.35);
  rig.scale = 1.3;
  return rig;
}

// world_from_master: 6 m along z (the master's optical axis) with up to 5 cm of sway in x and
// y, and rotations about varied axes (sines of up to rotation_deg per axis; with 4 degrees the
// largest rotation between any two poses stays below the thesis's 10 degrees).
SyntheticDrive SewerDrive(double rotation_deg, double drift_deg_per_frame, uint64_t seed) {
  std::vector<int64_t> t_ns;
  std::vector<Pose> world;
  for (int k = 0; k < kFrames; ++k) {
    const double u = 2.0 * M_PI * k;
    t_ns.push_back(static_cast<int64_t>(k) * 50'000'000);
    Pose p;
    p.C = Eigen::Vector3d(0.05 * std::sin(u / 160.0), 0.05 * std::sin(u / 115.0 + 1.0),
                          6.0 * k / kFrames);
    const Eigen::Vector3d rv =
        rotation_deg / 8.0 * kRadPerDeg *
        Eigen::Vector3d(8.0 * std::sin(u / 80.0), 6.0 * std::sin(u / 130.0 + 0.5),
                        7.0 * std::sin(u / 95.0 + 1.3));
    p.q = rv.norm() > 0.0 ? AxisAngle(rv, rv.norm()) : Eigen::Quaterniond::Identity();
    world.push_back(p);
  }
  DriveOptions noise;
  noise.rotation_noise_deg = kRotationNoiseDeg;
  noise.position_noise = kPositionNoise;
  noise.drift_deg_per_frame = drift_deg_per_frame;
  noise.seed = seed;
  return GenerateDriveAlong({"front", "rear"}, {BackToBack()}, t_ns, world, noise);
}

TEST(MotionModel, SmallRotationsAboveTheNoiseChooseTheGeneralModel) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const SyntheticDrive drive = SewerDrive(4.0, 0.0, seed);
    // Pairs by the walk, whose motions here stay below the thesis's fixed 10 degrees (the
    // premise of this test; auto may choose longer spans).
    CalibrationOptions walk;
    walk.pairs.policy = PairOptions::Policy::kWalk;
    const SlaveCalibration r = CalibrateRig(drive.recording, walk).slaves[0];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral) << r.message;
    EXPECT_LT(r.observability.max_rotation_deg, 10.0);
    // The measured rotation noise is that of the poses (the angle difference of a motion has
    // the noise of four poses' angles), and puts the boundary far below the rotations.
    EXPECT_GT(r.observability.rotation_noise_deg, 0.3 * kRotationNoiseDeg);
    EXPECT_LT(r.observability.rotation_noise_deg, 3.0 * kRotationNoiseDeg);
    EXPECT_LT(r.observability.translational_below_deg, r.observability.max_rotation_deg);
    EXPECT_NE(r.message.find("equal-error boundary"), std::string::npos) << r.message;
    // A few times the pose noise (the motions rotate by a few degrees, the noise is 0.02).
    const double rot_err = CompareToTruth(r.estimate, drive.truth[0]).rot_deg;
    EXPECT_LT(rot_err, 5.0 * kRotationNoiseDeg) << "seed " << seed << ": " << r.message;

    // On motions of one second (25 cm of travel, as the online estimator forms them) the purely
    // translational model is biased by (I - R_0) dC; the general model is not.
    CalibrationOptions short_pairs;
    short_pairs.pairs.policy = PairOptions::Policy::kRelative;
    short_pairs.pairs.step = 20;
    CalibrationOptions ptm = short_pairs;
    ptm.motion_model = MotionModel::kTranslational;
    const SlaveCalibration g = CalibrateRig(drive.recording, short_pairs).slaves[0];
    const SlaveCalibration t = CalibrateRig(drive.recording, ptm).slaves[0];
    ASSERT_TRUE(g.usable()) << g.message;
    // The forced translational model is solved, but its rotation residuals exceed what the
    // measured rotation noise explains: the data contradict it, so it is not usable.
    ASSERT_TRUE(t.solved()) << t.message;
    EXPECT_FALSE(t.usable()) << t.message;
    EXPECT_NE(t.message.find("residuals inconsistent with the measured noise"), std::string::npos)
        << t.message;
    EXPECT_EQ(g.motion_model, MotionModel::kGeneral) << g.message;
    const double general_err = CompareToTruth(g.estimate, drive.truth[0]).rot_deg;
    EXPECT_LT(general_err, 5.0 * kRotationNoiseDeg) << g.message;
    EXPECT_GT(CompareToTruth(t.estimate, drive.truth[0]).rot_deg, 10.0 * general_err + 0.2)
        << t.message;

    // The thesis's fixed alpha_maxrot of 10 degrees (for 1 degree of noise) takes the same
    // drive as purely translational.
    CalibrationOptions fixed = walk;
    fixed.model_selection.alpha_maxrot_noise_deg = 0.0;
    EXPECT_EQ(CalibrateRig(drive.recording, fixed).slaves[0].motion_model,
              MotionModel::kTranslational);
  }
}

TEST(MotionModel, RotationsBelowTheNoiseKeepTheTranslationalModel) {
  // Rotations of 0.01 degrees under 0.02 degrees of pose noise: nothing to estimate a rotation
  // from; the translational model is right (and unbiased: dC hardly moves with R_0 = I).
  const SyntheticDrive drive = SewerDrive(0.01, 0.0, 4);
  const SlaveCalibration r = CalibrateRig(drive.recording, CalibrationOptions{}).slaves[0];
  ASSERT_TRUE(r.usable()) << r.message;
  EXPECT_EQ(r.motion_model, MotionModel::kTranslational) << r.message;
  EXPECT_FALSE(r.position_observable);
  EXPECT_LT(r.observability.max_rotation_deg, r.observability.translational_below_deg);
  EXPECT_NE(r.message.find("equal-error boundary"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("position unobservable"), std::string::npos) << r.message;
  // The direction of travel (6 m, 1 mm noise) fixes the tilt; the sway (5 cm) the rest.
  EXPECT_LT(CompareToTruth(r.estimate, drive.truth[0]).rot_deg, 0.5) << r.message;
}

// The online estimator makes the same choice from its running noise figures, and neither the
// switch from the translational start to the general model nor the drift of the odometry
// (correlated errors of overlapping pairs) raises a decalibration alarm.
TEST(MotionModel, OnlineEstimatorChoosesTheGeneralModelWithoutFalseAlarms) {
  for (double drift : {0.0, 0.01}) {
    const SyntheticDrive drive = SewerDrive(4.0, drift, 5);
    RigEstimator est({"front", "rear"}, RigEstimatorOptions{});
    bool alarm = false, translational_at_end = true;
    for (size_t k = 0; k < drive.recording.size(); ++k) {
      est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
      alarm = alarm || (est.Estimate().rig.slaves[0].state == SlaveState::kDecalibrated);
      translational_at_end = (est.Estimate().online[0].flags & kFlagTranslationalOnly) != 0;
    }
    const SlaveCalibration linear = est.Estimate().rig.slaves[0];
    ASSERT_TRUE(linear.usable()) << linear.message;
    EXPECT_FALSE(translational_at_end) << linear.message;
    EXPECT_EQ(linear.motion_model, MotionModel::kGeneral) << linear.message;
    EXPECT_FALSE(alarm) << "drift " << drift << ": " << linear.message;
    EXPECT_EQ(est.Estimate().online[0].decalibration_events, 0);
    // The linear estimate is within its σ (largest axis; the error spreads over three).
    EXPECT_LT(CompareToTruth(linear.estimate, drive.truth[0]).rot_deg,
              6.0 * std::sqrt(3.0) * linear.rot_std_deg)
        << linear.message;
    // The final refinement (as OnlineCalibrator::RefineNow at the end of a stream) is within a
    // few times the pose noise; the drift random walk adds sqrt(frames) * drift.
    const RefinementJob job = est.MakeRefinementJob(0);
    est.ApplyRefinement(job, RefineWindow(job));
    const SlaveCalibration& r = est.Estimate().rig.slaves[0];
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral) << r.message;
    const double noise = kRotationNoiseDeg + drift * std::sqrt(static_cast<double>(kFrames));
    EXPECT_LT(CompareToTruth(r.estimate, drive.truth[0]).rot_deg, 5.0 * noise)
        << "drift " << drift << ": " << r.message;
  }
}

TEST(MotionModel, OnlineEstimatorKeepsTheTranslationalModelWithoutRotation) {
  const SyntheticDrive drive = SewerDrive(0.01, 0.0, 6);
  RigEstimator est({"front", "rear"}, RigEstimatorOptions{});
  for (size_t k = 0; k < drive.recording.size(); ++k) {
    est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
  }
  const SlaveCalibration& r = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(r.usable()) << r.message;
  EXPECT_TRUE(est.Estimate().online[0].flags & kFlagTranslationalOnly) << r.message;
  EXPECT_EQ(r.motion_model, MotionModel::kTranslational);
  EXPECT_NE(r.message.find("equal-error boundary"), std::string::npos) << r.message;
  EXPECT_FALSE(est.Estimate().rig.slaves[0].state == SlaveState::kDecalibrated);
}

}  // namespace
}  // namespace rigcal
