// SPDX-License-Identifier: Apache-2.0
// A recorded live session replays to the result the live run gave: a lossless live pipeline on
// the simulated room rig (room_rig.h) (rendered images -> VO -> sync -> estimator) records its
// poses on a file:// bus; the rig's images are written as an image log. Replaying the image log
// (through VO again) and replaying the pose recording both give the live result bit for bit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "pipeline/room_rig.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/shared_bus.h"
#include "rigcal/pipeline/calib_node.h"
#include "rigcal/pipeline/image_codec.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;

io::RigConfig Config(const sim::SimulatedRigSpec& spec) {
  io::RigConfig config;
  config.path = "test-config";
  config.name = "test";
  for (const std::string& name : spec.names) {
    io::CameraConfig camera;
    camera.name = name;
    camera.spec = RoomRigCameraSpec(name);
    config.cameras.push_back(camera);
  }
  config.online.refine_period_s = 0.5;  // several refinements on stream time
  return config;
}

CalibNodeSummary ReplayLog(const io::RigConfig& config, const std::string& path, bool poses_only) {
  CalibNodeOptions options;
  options.log_path = path;
  options.replay.poses_only = poses_only;
  CalibNode node(config, options);
  const Status opened = node.Open();
  EXPECT_TRUE(opened.ok()) << opened.message();
  std::atomic<bool> stop{false};
  return node.Run(stop);
}

void ExpectSameEstimate(const RigEstimate& live, const RigEstimate& replayed, const char* what) {
  EXPECT_EQ(live.sets, replayed.sets) << what;
  ASSERT_EQ(live.rig.slaves.size(), replayed.rig.slaves.size());
  for (size_t i = 0; i < live.rig.slaves.size(); ++i) {
    const SlaveCalibration& a = live.rig.slaves[i];
    const SlaveCalibration& b = replayed.rig.slaves[i];
    EXPECT_GT(a.motions.used, 0) << a.name;
    EXPECT_EQ(a.motions.used, b.motions.used) << what << " " << a.name;
    EXPECT_EQ(a.estimate.q.coeffs(), b.estimate.q.coeffs()) << what << " " << a.name;
    EXPECT_EQ(a.estimate.C, b.estimate.C) << what << " " << a.name;
    EXPECT_EQ(a.estimate.scale, b.estimate.scale) << what << " " << a.name;
    EXPECT_EQ(a.state, b.state) << what << " " << a.name;
  }
}

TEST(ImageLogReplay, RecordedLiveRunReplaysToTheLiveResult) {
  const fs::path dir =
      fs::temp_directory_path() / ("rigcal_image_replay_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const sim::SimulatedRigSpec spec = RoomRigSpec(8.0);
  auto rig = sim::MakeSimulatedRig(spec);
  ASSERT_TRUE(rig) << rig.error();
  const io::RigConfig config = Config(spec);
  const std::string images = (dir / "images.lcmlog").string();
  const std::string poses = (dir / "poses.lcmlog").string();
  WriteImageLog(*rig, spec.names, images);

  // The live run: lossless, publishing every pose on a file:// bus (the recording).
  PipelineSnapshot live;
  {
    ::lcm::LCM recorder("file://" + poses + "?mode=w");
    ASSERT_TRUE(recorder.good());
    lcm::SharedBus bus(&recorder);
    PipelineOptions options;
    options.lossless = true;
    Pipeline pipeline(spec.names, rig->MakeDevices(), spec.cameras, config.online, options, &bus);
    ASSERT_TRUE(RunToEnd(&pipeline));
    live = pipeline.Snapshot();
  }
  ASSERT_EQ(live.sync.consumer_overflow, 0u) << live.sync.BriefReport();  // dropped nothing
  for (const CameraHealth& h : live.cameras) EXPECT_EQ(h.dropped_backlog, 0) << h.name;

  const CalibNodeSummary from_images = ReplayLog(config, images, /*poses_only=*/false);
  EXPECT_TRUE(from_images.image_replay);
  EXPECT_TRUE(from_images.log_problem.empty()) << from_images.log_problem;
  EXPECT_EQ(from_images.cameras[0].images, rig->num_frames());
  ExpectSameEstimate(live.estimate, from_images.estimate, "image log");

  const CalibNodeSummary from_poses = ReplayLog(config, poses, /*poses_only=*/false);
  EXPECT_FALSE(from_poses.image_replay);
  ExpectSameEstimate(live.estimate, from_poses.estimate, "pose recording");

  // --poses-only on the image log: it has no poses, nothing is calibrated, and says so.
  const CalibNodeSummary no_poses = ReplayLog(config, images, /*poses_only=*/true);
  EXPECT_EQ(no_poses.estimate.sets, 0u);
  EXPECT_EQ(no_poses.skipped_channels.at(lcm::ImageChannel("front")), rig->num_frames());
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace rigcal::pipeline
