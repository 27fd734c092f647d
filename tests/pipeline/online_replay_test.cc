// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/online_replay.h"

#include <gtest/gtest.h>

#include "rigcal/calib/synthetic.h"

namespace rigcal::pipeline {
namespace {

TEST(OnlineReplay, ConvergesAndRecordsHistory) {
  DriveOptions d;
  d.num_frames = 2400;  // 2 minutes at 20 Hz
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "left", "back"}, DemoRig(), d);
  std::map<std::string, Similarity> truth = {{"left", drive.truth[0]}, {"back", drive.truth[1]}};
  OnlineReplayOptions options;
  options.report_every_s = 20.0;
  const OnlineReplayResult r = ReplayOnline(drive.recording, options, &truth);

  // Every frame is complete and exact, so every master pose makes a set.
  EXPECT_EQ(r.sync.sets_emitted, drive.recording.size());
  EXPECT_EQ(r.estimate.sets, drive.recording.size());
  ASSERT_EQ(r.estimate.rig.slaves.size(), 2u);
  // 5 reports at 20, 40, ..., 100 s (the drive ends at 119.95 s) and the final one, per slave.
  EXPECT_EQ(r.history.size(), 12u);
  for (int i = 0; i < 2; ++i) {
    const auto& s = r.estimate.rig.slaves[i];
    ASSERT_TRUE(s.usable()) << s.message;
    EXPECT_TRUE(r.estimate.rig.slaves[i].state == SlaveState::kConverged) << s.message;
    const auto e = CompareToTruth(s.estimate, drive.truth[i]);
    EXPECT_LT(e.rot_deg, 0.2);
    EXPECT_LT(e.scale_pct, 1.0);
  }
  // The estimate improves: the final error of a slave is not larger than its first report's.
  const auto& first = r.history.front();
  const auto& last = r.history[r.history.size() - 2];
  ASSERT_EQ(first.slave, last.slave);
  ASSERT_TRUE(first.error && last.error);
  EXPECT_LE(last.error->rot_deg, first.error->rot_deg + 0.02);
  const std::string table = FormatConvergence(r.history);
  EXPECT_NE(table.find("converged"), std::string::npos);
  EXPECT_NE(table.find("left"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::pipeline
