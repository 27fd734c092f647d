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
