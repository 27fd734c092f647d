// SPDX-License-Identifier: Apache-2.0
// Glitch detection (calib/src/motions/pose_glitches.h) on real trajectories: the KITTI 00 car drive
// and the EuRoC V1_02 drone flight, as recorded and with simulated rigs along them. No pose
// of these clean recordings may be taken for a glitch, by the batch stage or by the online
// gate (pose_glitch_gate.h); a 100-unit jump in them is found.
// Without the shared data the tests are skipped, under CI=true they fail.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"
#include "rigcal/io/trajectory_io.h"
#include "support/kitti.h"
#include "support/skip.h"

namespace rigcal {
namespace {

// The trajectory alone (the master of a rig without slaves).
RigRecording MasterOnly(const SampledTrajectory& path) {
  RigRecording rec;
  rec.t_ns = path.t_ns;
  rec.master.name = "master";
  rec.master.poses = path.poses;
  rec.master.segment.assign(path.poses.size(), 0);
  return rec;
}

std::vector<int> Dropped(const RigRecording& rec) {
  std::vector<int> dropped;
  WithoutGlitches(rec, &dropped);
  return dropped;
}

// Sets the online estimator skipped as glitches, over all slaves.
int SkippedOnline(const RigRecording& rec) {
  std::vector<std::string> names = {rec.master.name};
  for (const CameraTrack& s : rec.slaves) names.push_back(s.name);
  RigEstimator est(names, RigEstimatorOptions{});
  for (size_t k = 0; k < rec.size(); ++k) est.AddSet(rec.t_ns[k], rec.SetAt(k));
  int skipped = 0;
  for (const SlaveCalibration& s : est.Estimate().rig.slaves) skipped += s.glitches.dropped();
  return skipped;
}

// The trajectory, every `stride`-th pose, and a simulated rig along it with VO-like noise.
void ExpectNoGlitches(const std::string& what, const SampledTrajectory& full, int stride) {
  SampledTrajectory path;
  for (size_t k = 0; k < full.poses.size(); k += stride) {
    path.t_ns.push_back(full.t_ns[k]);
    path.poses.push_back(full.poses[k]);
  }
  std::vector<int> dropped = Dropped(MasterOnly(path));
  EXPECT_TRUE(dropped.empty()) << what << " every " << stride << ": " << dropped.size()
                               << " poses dropped, first " << dropped.front();
  DriveOptions noise;
  noise.seed = 4;
  const RigRecording demo = GenerateDriveAlong({"m", "a", "b"}, DemoRig(), path, noise).recording;
  dropped = Dropped(demo);
  EXPECT_TRUE(dropped.empty()) << what << " every " << stride
                               << " with a noisy rig: " << dropped.size()
                               << " poses dropped, first " << dropped.front();
  EXPECT_EQ(SkippedOnline(demo), 0) << what << " every " << stride << " with a noisy rig";
  const RigRecording car = DriveCarRig(path, noise).recording;
  dropped = Dropped(car);
  EXPECT_TRUE(dropped.empty()) << what << " every " << stride
                               << " with the car rig: " << dropped.size()
                               << " poses dropped, first " << dropped.front();
  EXPECT_EQ(SkippedOnline(car), 0) << what << " every " << stride << " with the car rig";

  // A 100-unit jump of one master pose in the middle is found, and only it.
  RigRecording glitched = MasterOnly(path);
  const size_t k = path.poses.size() / 2;
  glitched.master.poses[k].C += Eigen::Vector3d(0.0, 100.0, 0.0);
  EXPECT_EQ(Dropped(glitched), std::vector<int>{static_cast<int>(k)}) << what;
}

TEST(PoseGlitchesRealTrajectories, Kitti00) {
  auto kitti = support::LoadKitti00();
  if (!kitti) {
    RIGCAL_SKIP_MISSING() << kitti.error();
  }
  for (const int stride : {1, 5}) ExpectNoGlitches("KITTI 00", *kitti, stride);
}

TEST(PoseGlitchesRealTrajectories, EurocV102) {
  const std::filesystem::path path =
      std::filesystem::path(RIGCAL_SHARED_DATA_DIR) / "trajectories" / "V102_groundtruth.csv";
  if (!std::filesystem::exists(path)) {
    RIGCAL_SKIP_MISSING() << path << " not found";
  }
  io::TrajectoryReadOptions read;
  read.max_quaternion_norm_error = 1e-3;  // the ground truth has 6-decimal quaternions
  auto body = io::ReadTrajectory(path.string(), read);
  ASSERT_TRUE(body) << body.error();
  SampledTrajectory flight;
  flight.t_ns = body->t_ns;
  flight.poses = body->poses;
  for (const int stride : {1, 10}) ExpectNoGlitches("EuRoC V1_02", flight, stride);
}

}  // namespace
}  // namespace rigcal
