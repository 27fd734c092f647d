// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/online_calibrator.h"

#include <gtest/gtest.h>

#include <thread>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

// One producer thread per camera pushes its poses; the estimator thread consumes matched sets
// and the refinement thread refines in the background. The result must equal what a single
// thread computes up to the refinement, and must converge.
TEST(OnlineCalibrator, ThreadedProducersConverge) {
  DriveOptions d;
  d.num_frames = 1600;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "left", "back"}, DemoRig(), d);
  const RigRecording& rec = drive.recording;
  OnlineOptions options;
  options.sync.capacity = 4096;  // producers run free: let them be far ahead of each other
  options.sync.ready_capacity = 4096;
  options.sync.max_wait_ns = 1'000'000'000'000;
  options.refine_period_s = 0.05;
  OnlineCalibrator calibrator({"front", "left", "back"}, options);
  calibrator.Start();
  std::vector<std::thread> producers;
  for (int cam = 0; cam < 3; ++cam) {
    producers.emplace_back([&, cam] {
      for (size_t k = 0; k < rec.size(); ++k) {
        EXPECT_EQ(calibrator.Push(rec.PoseAt(cam, k)), PushResult::kAccepted);
      }
    });
  }
  for (auto& t : producers) t.join();
  calibrator.Flush();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // a few refinement periods
  calibrator.Stop();

  const RigEstimate e = calibrator.Estimate();
  const SyncStats stats = calibrator.sync_stats();
  EXPECT_EQ(stats.sets_emitted, rec.size()) << stats.BriefReport();
  EXPECT_EQ(e.sets, rec.size());
  for (int i = 0; i < 2; ++i) {
    const auto& s = e.rig.slaves[i];
    ASSERT_TRUE(s.usable()) << s.message;
    const auto err = CompareToTruth(s.estimate, drive.truth[i]);
    EXPECT_LT(err.rot_deg, 0.2) << s.message;
    EXPECT_LT(err.scale_pct, 1.0);
  }
  EXPECT_GT(calibrator.refinements_applied(), 0);
  // The state can be saved from another thread and restored into a fresh calibrator.
  OnlineCalibrator other({"front", "left", "back"}, options);
  const Status status = other.RestoreState(calibrator.SaveState());
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(other.Estimate().rig.slaves[0].motions.used, e.rig.slaves[0].motions.used);
}

// Resumed on poses stamped at or before what the state consumed: the same data again keeps the
// state's estimate usable; another drive on a restarted clock (the slave moved: other poses at
// the same stamps) is skipped too, and then no slave is usable with the old values: the
// message says what happened.
TEST(OnlineCalibrator, AResumedDriveOnARestartedClockIsNotUsableWithTheOldValues) {
  DriveOptions d;
  d.num_frames = 800;
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  OnlineOptions options;
  options.lossless = true;
  auto feed = [](OnlineCalibrator* c, const RigRecording& rec) {
    for (size_t k = 0; k < rec.size(); ++k) {
      for (int cam = 0; cam < 2; ++cam) c->Push(rec.PoseAt(cam, k));
    }
    c->Flush();
  };
  OnlineCalibrator first({"front", "left"}, options);
  first.Start();
  feed(&first, drive.recording);
  first.Stop();
  ASSERT_TRUE(first.Estimate().rig.slaves[0].usable());
  const RigEstimatorState state = first.SaveState();

  OnlineCalibrator again({"front", "left"}, options);
  ASSERT_TRUE(again.RestoreState(state).ok());
  again.Start();
  feed(&again, drive.recording);
  again.Stop();
  EXPECT_TRUE(again.Estimate().rig.slaves[0].usable()) << again.Estimate().rig.slaves[0].message;

  Similarity moved = DemoRig()[0];
  moved.q = (moved.q * Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY())).normalized();
  const SyntheticDrive other = GenerateDrive({"front", "left"}, {moved}, d);
  OnlineCalibrator restarted({"front", "left"}, options);
  ASSERT_TRUE(restarted.RestoreState(state).ok());
  restarted.Start();
  feed(&restarted, other.recording);
  restarted.Stop();
  const SlaveCalibration s = restarted.Estimate().rig.slaves[0];
  EXPECT_FALSE(s.usable()) << s.message;
  EXPECT_NE(s.message.find("another drive on a restarted clock"), std::string::npos) << s.message;

  // Stamps the state never took, all before its own: not confirmed either.
  RigRecording shifted = other.recording;
  for (int64_t& t : shifted.t_ns) t -= 1'000'000;
  OnlineCalibrator unmatched({"front", "left"}, options);
  ASSERT_TRUE(unmatched.RestoreState(state).ok());
  unmatched.Start();
  feed(&unmatched, shifted);
  unmatched.Stop();
  const SlaveCalibration u = unmatched.Estimate().rig.slaves[0];
  EXPECT_FALSE(u.usable()) << u.message;
  EXPECT_NE(u.message.find("none is a pose the state took"), std::string::npos) << u.message;
}

TEST(OnlineCalibrator, RejectsInvalidOptions) {
  OnlineOptions options;
  options.estimator.window_size = 0;
  EXPECT_THROW(OnlineCalibrator({"a", "b"}, options), std::invalid_argument);
  EXPECT_THROW(OnlineCalibrator({"a", "b"}, options), InvalidOptions);
  const Status status = options.Check();
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("estimator.window_size"), std::string::npos);
  options = OnlineOptions{};
  options.refine_period_s = -1.0;
  EXPECT_EQ(options.Check().message(), "refine_period_s: must be >= 0 (0 = no refinement)");
  EXPECT_THROW(OnlineCalibrator({"a", "b"}, options), InvalidOptions);
}

}  // namespace
}  // namespace rigcal
