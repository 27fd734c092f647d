#include "rigcal/calib/synthetic.h"

#include <gtest/gtest.h>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/quaternion.h"

namespace rigcal {
namespace {

// Noise-free generated poses satisfy the rig constraint T_0 dT = dT T_i (4.2, 4.3).
TEST(Synthetic, ThesisSampleSatisfiesRigConstraint) {
  std::mt19937_64 rng(7);
  ThesisSampleOptions opt;
  opt.num_poses = 6;
  opt.num_slaves = 3;
  std::vector<Similarity> truth;
  const RigRecording rec = ThesisSample(opt, rng, &truth);
  ASSERT_TRUE(rec.Check().ok()) << rec.Check().message();
  ASSERT_EQ(truth.size(), 3u);
  const auto pairs = SelectPairs(rec, {.policy = PairOptions::Policy::kSinceStart});
  for (int i = 0; i < 3; ++i) {
    for (const auto& m : MotionsForSlave(rec, i, pairs)) {
      const ConstraintResidual r = ResidualOf(m, truth[i]);
      EXPECT_LT(r.rotation_deg, 1e-9);
      EXPECT_LT(r.position_abs, 1e-9);
    }
  }
}

TEST(Synthetic, PerturbationHasExactAngle) {
  std::mt19937_64 rng(1);
  Pose p;
  p.q = AxisAngle(Eigen::Vector3d(0, 1, 0), 0.4);
  p.C = Eigen::Vector3d(1, 2, 3);
  const Pose n = PerturbPose(p, 1.5 * kRadPerDeg, rng);
  EXPECT_NEAR(AngleBetween(n.q, p.q) * kDegPerRad, 1.5, 1e-9);
  EXPECT_NEAR(n.C.norm(), p.C.norm(), 1e-12);
  EXPECT_LE(std::acos(n.C.normalized().dot(p.C.normalized())) * kDegPerRad, 1.5 + 1e-6);
}

TEST(Synthetic, DriveIsDeterministicAndConsistent) {
  DriveOptions opt;
  opt.num_frames = 200;
  opt.rotation_noise_deg = 0.0;
  opt.position_noise = 0.0;
  const auto a = GenerateDrive({"front", "left", "back"}, DemoRig(), opt);
  const auto b = GenerateDrive({"front", "left", "back"}, DemoRig(), opt);
  ASSERT_TRUE(a.recording.Check().ok()) << a.recording.Check().message();
  EXPECT_EQ(a.recording.slaves[1].poses[50].C, b.recording.slaves[1].poses[50].C);
  const auto pairs =
      SelectPairs(a.recording, {.policy = PairOptions::Policy::kRelative, .step = 7});
  for (int i = 0; i < 2; ++i) {
    for (const auto& m : MotionsForSlave(a.recording, i, pairs)) {
      EXPECT_LT(ResidualOf(m, a.truth[i]).position_abs, 1e-9);
    }
  }
}

}  // namespace
}  // namespace rigcal
