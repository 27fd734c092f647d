// SPDX-License-Identifier: Apache-2.0
// Replay throughput (figures, no wall-clock asserts): an image log of a 2-camera 752x480 rig
// through VO (the real-time factor: log seconds per wall second, target >= 4 on 2 cores), and a
// pose log (sets per second). `ctest -L eval -R pipeline/replay_throughput -V` prints them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "pipeline/room_rig.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/pipeline/calib_node.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;

struct Timed {
  CalibNodeSummary summary;
  double wall_s = 0.0;
};

Timed Replay(const io::RigConfig& config, const std::string& log) {
  CalibNodeOptions options;
  options.log_path = log;
  CalibNode node(config, options);
  const Status opened = node.Open();
  EXPECT_TRUE(opened.ok()) << opened.message();
  std::atomic<bool> stop{false};
  const auto start = std::chrono::steady_clock::now();
  Timed t;
  t.summary = node.Run(stop);
  t.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return t;
}

class ReplayThroughput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigcal_replay_throughput_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ReplayThroughput, ImageLogThroughVo) {
  sim::SimulatedRigSpec spec = RoomRigSpec(15.0);
  spec.names.resize(2);
  spec.master_from_camera.resize(2);
  spec.cameras.clear();
  io::RigConfig config;
  config.path = "eval";
  for (const std::string& name : spec.names) {
    camera::CameraSpec camera = RoomRigCameraSpec(name);
    camera.width = 752;
    camera.height = 480;
    camera.intrinsics = {458.0, 457.0, 367.0, 248.0};  // EuRoC-like
    auto model = camera::MakeCameraModel(camera);
    ASSERT_TRUE(model) << model.error();
    spec.cameras.emplace_back(std::move(*model));
    io::CameraConfig c;
    c.name = name;
    c.spec = camera;
    config.cameras.push_back(c);
  }
  auto rig = sim::MakeSimulatedRig(spec);
  ASSERT_TRUE(rig) << rig.error();
  const std::string log = (dir_ / "images.lcmlog").string();
  WriteImageLog(*rig, spec.names, log);
  const Timed t = Replay(config, log);
  ASSERT_TRUE(t.summary.image_replay);
  EXPECT_GT(t.summary.estimate.sets, 0u);
  const double span_s = t.summary.log_span_s;
  std::printf(
      "image log, 2 cameras 752x480 raw GREY, %.1f s at 20 Hz (%.0f MB): replayed through VO in "
      "%.1f s wall = %.2fx real time (%.0f frames/s); %llu sets\n",
      span_s, static_cast<double>(fs::file_size(log)) / 1e6, t.wall_s, span_s / t.wall_s,
      2.0 * static_cast<double>(rig->num_frames()) / t.wall_s,
      static_cast<unsigned long long>(t.summary.estimate.sets));
}

TEST_F(ReplayThroughput, PoseLog) {
  const std::vector<std::string> names = {"front", "left", "back"};
  DriveOptions d;
  d.num_frames = 20000;
  const SyntheticDrive drive = GenerateDrive(names, DemoRig(), d);
  const std::string log = (dir_ / "poses.lcmlog").string();
  ASSERT_TRUE(lcm::WritePoseLog(log, drive.recording).ok());
  io::RigConfig config;
  config.path = "eval";
  for (const std::string& name : names) {
    io::CameraConfig camera;
    camera.name = name;
    config.cameras.push_back(camera);
  }
  const Timed t = Replay(config, log);
  EXPECT_EQ(t.summary.estimate.sets, drive.recording.size());
  std::printf(
      "pose log, 3 cameras, %zu sets (%.0f s at 20 Hz): %.2f s wall = %.0f sets/s, "
      "%.0fx real time\n",
      drive.recording.size(), t.summary.log_span_s, t.wall_s,
      static_cast<double>(t.summary.estimate.sets) / t.wall_s, t.summary.log_span_s / t.wall_s);
}

}  // namespace
}  // namespace rigcal::pipeline
