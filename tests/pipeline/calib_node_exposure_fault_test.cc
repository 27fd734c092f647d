// SPDX-License-Identifier: Apache-2.0
// Exposure of the calibration node: only poses on the configured cameras' channels, naming the
// camera of their channel, reach the estimator; everything else is counted and dropped.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/pipeline/calib_node.h"
#include "support/temp_dir.h"

namespace rigcal::pipeline {
namespace {

void Publish(::lcm::LCM& bus, const std::string& channel, const CameraPose& pose,
             const lcm::CameraNames& names) {
  auto msg = lcm::CameraPoseToLcm(pose, names, pose.t_ns / 1000);
  ASSERT_TRUE(msg) << msg.error();
  auto bytes = lcm::EncodeMessage(channel, names, *msg);
  ASSERT_TRUE(bytes) << bytes.error();
  bus.publish(channel, bytes->data(), static_cast<unsigned int>(bytes->size()));
}

TEST(CalibNodeExposure, OnlyConfiguredCamerasOnTheirOwnChannelsReachTheEstimator) {
  const std::filesystem::path dir = support::FreshTempDir("calib_node_exposure");
  const std::string config_path = (dir / "rig.yaml").string();
  std::ofstream(config_path) << "rig: {name: test, master: front}\n"
                                "cameras:\n"
                                "  - name: front\n"
                                "  - name: left\n";
  auto config = io::LoadRigConfig(config_path);
  ASSERT_TRUE(config) << config.error();
  const lcm::CameraNames names{"front", "left"};
  const lcm::CameraNames intruders{"front", "left", "roof"};

  ::lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  CalibNode node(*config, CalibNodeOptions{}, &bus);
  ASSERT_TRUE(node.Open().ok());
  std::atomic<bool> stop{false};
  CalibNodeSummary summary;
  std::thread runner([&] { summary = node.Run(stop); });

  DriveOptions d;
  d.num_frames = 100;
  const SyntheticDrive drive = GenerateDrive(names, {DemoRig()[1]}, d);
  int64_t good = 0;
  for (size_t k = 0; k < drive.recording.size(); ++k) {
    for (int cam = 0; cam < 2; ++cam) {
      Publish(bus, lcm::PoseChannel(names[cam]), drive.recording.PoseAt(cam, k), names);
      ++good;
    }
    CameraPose p = drive.recording.PoseAt(0, k);
    p.t_ns += 1;
    // The master's pose on the slave's channel (a publisher naming another camera).
    Publish(bus, lcm::PoseChannel("left"), p, names);
    // A camera the config does not name, on its own channel.
    p.camera = 2;
    Publish(bus, lcm::PoseChannel("roof"), p, intruders);
    // The same on a configured camera's channel: its name is not the rig's.
    Publish(bus, lcm::PoseChannel("front"), p, intruders);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (node.ReceivedPoses() < good && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  stop = true;
  runner.join();

  const int64_t n = static_cast<int64_t>(drive.recording.size());
  EXPECT_EQ(node.ReceivedPoses(), good);     // only the rig's own poses
  EXPECT_EQ(summary.unknown_channel, n);     // RIGCAL_POSE_roof
  EXPECT_EQ(summary.cameras[1].invalid, n);  // front's pose on left's channel
  EXPECT_EQ(summary.cameras[0].invalid, n);  // roof's pose on front's channel
  EXPECT_EQ(summary.sync.total.pushed, static_cast<uint64_t>(good));
  // Every set of the rig's own poses is matched (a live node may lose some to a full ready queue
  // when poses arrive this fast: counted consumer_overflow, not this test's subject).
  EXPECT_EQ(static_cast<int64_t>(summary.sync.sets_emitted), n);
}

}  // namespace
}  // namespace rigcal::pipeline
