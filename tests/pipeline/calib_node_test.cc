// SPDX-License-Identifier: Apache-2.0
// The `rigcal calib` node end to end: in-process over memq://, replaying a file:// log (with
// garbage and a truncated tail), state persistence and resume.
#include "rigcal/pipeline/calib_node.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <thread>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/lcm/pose_message.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("rigcal_calib_node_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

const std::vector<std::string> kNames = {"front", "left", "back"};

// A config for the demo rig with fast publishing, buffers large enough for a burst of poses
// delivered at once, and nominal values for the slaves.
std::string WriteConfig(const TempDir& dir, const std::string& extra = "") {
  const std::string path = dir / "rig.yaml";
  std::ofstream out(path);
  out << "rig: {name: test, master: front}\n"
         "cameras:\n"
         "  - name: left\n"
         "    nominal: {q_wxyz: [1, 0, 0, 0], C: [0, 0, 0]}\n"
         "  - name: front\n"
         "  - name: back\n"
         "sync: {capacity: 8192, ready_capacity: 8192, max_wait_ms: 1000000}\n"
         "publish: {extrinsics_rate_hz: 100, status_rate_hz: 50}\n"
      << extra;
  return path;
}

SyntheticDrive Drive(int frames = 1600) {
  DriveOptions d;
  d.num_frames = frames;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  return GenerateDrive(kNames, DemoRig(), d);
}

// Received messages, collected by handlers that run on the node's LCM thread.
struct Sink {
  std::mutex mutex;
  lcm::MessageValidator validator{lcm::CameraNames{"front", "left", "back"}};
  std::vector<rig_extrinsics_t> extrinsics;
  std::vector<rig_status_t> status;
  int64_t rejected = 0;
};

void OnExtrinsics(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, Sink* sink) {
  std::lock_guard<std::mutex> lock(sink->mutex);
  auto msg = sink->validator.Decode<rig_extrinsics_t>(channel, rbuf->data, rbuf->data_size);
  if (msg) {
    sink->extrinsics.push_back(*msg);
  } else {
    ++sink->rejected;
  }
}

void OnStatus(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, Sink* sink) {
  std::lock_guard<std::mutex> lock(sink->mutex);
  auto msg = sink->validator.Decode<rig_status_t>(channel, rbuf->data, rbuf->data_size);
  if (msg) {
    sink->status.push_back(*msg);
  } else {
    ++sink->rejected;
  }
}

void Publish(::lcm::LCM& bus, const CameraPose& pose, const lcm::CameraNames& names) {
  auto msg = lcm::CameraPoseToLcm(pose, names, pose.t_ns / 1000);
  ASSERT_TRUE(msg) << msg.error();
  const std::string channel = lcm::PoseChannel(names[pose.camera]);
  auto bytes = lcm::EncodeMessage(channel, names, *msg);
  ASSERT_TRUE(bytes) << bytes.error();
  bus.publish(channel, bytes->data(), static_cast<unsigned int>(bytes->size()));
}

// Slave i of the message, found by name.
const slave_extrinsics_t* FindSlave(const rig_extrinsics_t& msg, const std::string& name) {
  for (const slave_extrinsics_t& slave : msg.slaves) {
    if (slave.name == name) return &slave;
  }
  return nullptr;
}

TEST(CalibNode, MemqEndToEndConvergesAndPublishes) {
  TempDir dir;
  auto config = io::LoadRigConfig(WriteConfig(dir));
  ASSERT_TRUE(config) << config.error();
  ASSERT_EQ(config->CameraNames(), kNames);  // the master first, then file order
  const SyntheticDrive drive = Drive();
  const RigRecording& rec = drive.recording;

  ::lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  Sink sink;
  bus.subscribeFunction(lcm::kExtrinsicsChannel, &OnExtrinsics, &sink);
  bus.subscribeFunction(lcm::kStatusChannel, &OnStatus, &sink);

  CalibNodeOptions options;
  options.result_path = dir / "result.yaml";
  options.state_path = dir / "state.txt";
  CalibNode node(*config, options, &bus);
  ASSERT_TRUE(node.Open().ok());

  std::atomic<bool> stop{false};
  CalibNodeSummary summary;
  std::thread runner([&] { summary = node.Run(stop); });
  // The publisher: every camera's poses in time order, plus bad input that must be counted and
  // must not disturb the estimate.
  int64_t sent = 0;
  for (size_t k = 0; k < rec.size(); ++k) {
    for (int cam = 0; cam < 3; ++cam) {
      CameraPose pose;
      pose.camera = cam;
      pose.t_ns = rec.t_ns[k];
      pose.pose = cam == 0 ? rec.master.poses[k] : rec.slaves[cam - 1].poses[k];
      Publish(bus, pose, kNames);
      ++sent;
    }
    if (k % 200 == 100) {
      // A NaN pose (hand-encoded: the converters refuse it), an unknown camera, garbage bytes.
      camera_pose_t bad{};
      bad.version = camera_pose_t::VERSION;
      bad.camera = "left";
      bad.q[0] = 1.0;
      bad.C[0] = std::nan("");
      bad.t_ns = rec.t_ns[k] + 1;
      bad.quality = 1.0;
      std::vector<uint8_t> buffer(bad.getEncodedSize());
      bad.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
      bus.publish(lcm::PoseChannel("left"), buffer.data(), static_cast<unsigned int>(buffer.size()));
      const uint8_t garbage[7] = {1, 2, 3, 4, 5, 6, 7};
      bus.publish(lcm::PoseChannel("back"), garbage, sizeof(garbage));
      CameraPose stranger;
      stranger.t_ns = rec.t_ns[k];
      auto msg = lcm::CameraPoseToLcm(stranger, lcm::CameraNames{"roof"}, 1);
      ASSERT_TRUE(msg);
      auto bytes = lcm::EncodeMessage(lcm::PoseChannel("roof"), lcm::CameraNames{"roof"}, *msg);
      ASSERT_TRUE(bytes);
      bus.publish(lcm::PoseChannel("roof"), bytes->data(), static_cast<unsigned int>(bytes->size()));
    }
  }
  // Wait until the node has received everything and has published on its periods at least
  // once while running (a fast machine takes the whole burst in less than a status period),
  // then stop it as a signal would.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  const auto published_while_running = [&sink] {
    std::lock_guard<std::mutex> lock(sink.mutex);
    return !sink.extrinsics.empty() && !sink.status.empty();
  };
  while ((node.ReceivedPoses() < sent || !published_while_running()) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop = true;
  runner.join();
  bus.handleTimeout(100);  // deliver what the node published while stopping
  while (bus.handleTimeout(10) > 0) {
  }

  ASSERT_EQ(node.ReceivedPoses(), sent);
  EXPECT_TRUE(summary.errors.empty()) << summary.errors.front();
  EXPECT_EQ(summary.estimate.sets, rec.size());
  const int64_t bad_batches = static_cast<int64_t>((rec.size() + 99) / 200);
  EXPECT_EQ(summary.unknown_channel, bad_batches);
  EXPECT_EQ(summary.cameras[1].invalid, bad_batches);  // NaN on left
  EXPECT_EQ(summary.cameras[2].invalid, bad_batches);  // garbage on back
  EXPECT_EQ(summary.decode.Rejected(lcm::RejectCause::kNonFinite), bad_batches);
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& slave = summary.estimate.rig.slaves[i];
    ASSERT_TRUE(slave.usable()) << slave.message;
    const CalibrationError error = CompareToTruth(slave.estimate, drive.truth[i]);
    // 0.05 deg pose noise over ~1600 frames: well below 0.2 deg and 1 % scale.
    EXPECT_LT(error.rot_deg, 0.2) << slave.name;
    EXPECT_LT(error.scale_pct, 1.0) << slave.name;
  }

  // Published messages: decodable, the last one equals the final estimate, flags converged.
  std::lock_guard<std::mutex> lock(sink.mutex);
  EXPECT_EQ(sink.rejected, 0);
  ASSERT_GE(sink.extrinsics.size(), 2u);
  ASSERT_GE(sink.status.size(), 2u);
  const rig_extrinsics_t& last = sink.extrinsics.back();
  EXPECT_EQ(last.master, "front");
  for (int i = 0; i < 2; ++i) {
    const slave_extrinsics_t* slave = FindSlave(last, kNames[i + 1]);
    ASSERT_NE(slave, nullptr);
    const Similarity& estimate = summary.estimate.rig.slaves[i].estimate;
    EXPECT_NEAR(slave->C[0], estimate.C.x(), 1e-12);
    EXPECT_NEAR(slave->q[0], estimate.q.w(), 1e-12);
    EXPECT_EQ(slave->state, static_cast<int8_t>(summary.estimate.rig.slaves[i].state));
    EXPECT_TRUE(slave->state == slave_extrinsics_t::STATE_USABLE ||
                slave->state == slave_extrinsics_t::STATE_CONVERGED)
        << static_cast<int>(slave->state);
  }
  const rig_status_t& status = sink.status.back();
  ASSERT_EQ(status.num_cameras, 3);
  EXPECT_EQ(status.cameras[0].name, "front");
  EXPECT_EQ(status.cameras[0].frames_received, static_cast<int64_t>(rec.size()));
  EXPECT_EQ(status.cameras[1].dropped_invalid, bad_batches);
  EXPECT_EQ(status.sync_sets_emitted, static_cast<int64_t>(rec.size()));
  EXPECT_GT(status.rss_bytes, 0);
  EXPECT_EQ(status.estimator_state, rig_status_t::ESTIMATOR_CONVERGED) << status.estimator_message;

  // The result YAML and the state file were written on stop.
  auto result = io::ReadRigYaml(options.result_path);
  ASSERT_TRUE(result) << result.error();
  EXPECT_NEAR((*result)["left"].C.x(), summary.estimate.rig.slaves[0].estimate.C.x(), 1e-9);
  EXPECT_TRUE(fs::exists(options.state_path));
  EXPECT_GE(summary.state_saves, 1);
}

// Writes `recording` as a pose log, appends garbage events, then cuts the file inside the last
// event (a logger killed mid-write).
std::string WriteDamagedLog(const TempDir& dir, const RigRecording& recording) {
  const std::string path = dir / "poses.lcmlog";
  EXPECT_TRUE(lcm::WritePoseLog(path, recording).ok());
  {
    ::lcm::LogFile log(path, "a");
    EXPECT_TRUE(log.good());
    const uint8_t garbage[5] = {9, 9, 9, 9, 9};
    ::lcm::LogEvent event;
    event.eventnum = 1'000'000;
    event.timestamp = recording.t_ns.back() / 1000 + 1;
    event.channel = lcm::PoseChannel("left");
    event.datalen = sizeof(garbage);
    event.data = const_cast<uint8_t*>(garbage);
    EXPECT_EQ(log.writeEvent(&event), 0);
    event.channel = "SOMETHING_ELSE";  // not a pose channel: ignored
    EXPECT_EQ(log.writeEvent(&event), 0);
  }
  const auto size = fs::file_size(path);
  fs::resize_file(path, size - 3);
  return path;
}

TEST(CalibNode, ReplaysLogFileWithDamageAndResumes) {
  TempDir dir;
  auto config = io::LoadRigConfig(WriteConfig(dir));
  ASSERT_TRUE(config) << config.error();
  // The resume check compares the window refinement of the statistics with the first run's:
  // without the pose history (which a restored state does not have) both refine alike.
  config->online.estimator.history_sets = 0;
  const SyntheticDrive drive = Drive(1200);
  const std::string log_path = WriteDamagedLog(dir, drive.recording);

  CalibNodeOptions options;
  options.log_path = log_path;
  options.publish_url = "file://" + (dir / "out.lcmlog") + "?mode=w";
  options.result_path = dir / "result.yaml";
  options.state_path = dir / "state.txt";
  CalibNodeSummary first;
  {
    CalibNode node(*config, options);
    ASSERT_TRUE(node.Open().ok());
    std::atomic<bool> stop{false};
    first = node.Run(stop);
  }
  EXPECT_TRUE(first.end_of_log);
  EXPECT_NE(first.log_problem.find("truncated"), std::string::npos) << first.log_problem;
  EXPECT_EQ(first.cameras[1].invalid, 1);  // the garbage event on left
  EXPECT_EQ(first.estimate.sets, drive.recording.size());
  ASSERT_TRUE(first.estimate.rig.slaves[0].usable());
  EXPECT_LT(CompareToTruth(first.estimate.rig.slaves[0].estimate, drive.truth[0]).rot_deg, 0.3);

  // What the node published went into the output log: the last extrinsics equal the result.
  {
    ::lcm::LogFile out(dir / "out.lcmlog", "r");
    ASSERT_TRUE(out.good());
    lcm::MessageValidator validator(lcm::CameraNames{"front", "left", "back"});
    std::optional<rig_extrinsics_t> last;
    while (const ::lcm::LogEvent* event = out.readNextEvent()) {
      if (event->channel != lcm::kExtrinsicsChannel) continue;
      auto msg = validator.Decode<rig_extrinsics_t>(event->channel, event->data, event->datalen);
      ASSERT_TRUE(msg) << msg.error();
      last = *msg;
    }
    ASSERT_TRUE(last.has_value());
    EXPECT_NEAR(FindSlave(*last, "left")->C[1], first.estimate.rig.slaves[0].estimate.C.y(), 1e-12);
  }

  // Resume from the saved state with an empty log: the estimate continues from the state.
  const std::string empty_log = dir / "empty.lcmlog";
  ASSERT_TRUE(
      lcm::WritePoseLog(empty_log,
                   RigRecording{{}, {"front", {}, {}}, {{"left", {}, {}}, {"back", {}, {}}}})
          .ok());
  options.log_path = empty_log;
  options.publish_url.clear();
  options.resume = true;
  options.result_path = dir / "result2.yaml";
  {
    CalibNode node(*config, options);
    ASSERT_TRUE(node.Open().ok());
    std::atomic<bool> stop{false};
    const CalibNodeSummary resumed = node.Run(stop);
    EXPECT_TRUE(resumed.resumed);
    EXPECT_EQ(resumed.estimate.rig.slaves[0].motions.used,
              first.estimate.rig.slaves[0].motions.used);
    // The state holds the statistics, not the refinement window: the resumed node refines
    // from the statistics alone (the window's prior holds every motion), the same minimum but
    // for the robust loss the first run applied to its window's residuals.
    const SlaveCalibration& a = first.estimate.rig.slaves[0];
    const SlaveCalibration& b = resumed.estimate.rig.slaves[0];
    ASSERT_GT(a.pos_std.x(), 0.0);
    EXPECT_TRUE(resumed.estimate.online[0].flags & rigcal::kFlagRefined);
    EXPECT_NEAR(b.estimate.C.x(), a.estimate.C.x(), 0.5 * a.pos_std.x());
    EXPECT_LT(AngleBetween(a.estimate.q, b.estimate.q) * kDegPerRad, 0.5 * a.rot_std_deg);
  }

  // A corrupt state file is reported and ignored: the node starts afresh and does not crash.
  {
    std::string text;
    {
      std::ifstream in(options.state_path);
      text.assign(std::istreambuf_iterator<char>(in), {});
    }
    ASSERT_GT(text.size(), 100u);
    text[text.size() / 2] ^= 0x5a;
    std::ofstream(options.state_path) << text;
    CalibNode node(*config, options);
    ASSERT_TRUE(node.Open().ok());
    std::atomic<bool> stop{false};
    const CalibNodeSummary fresh = node.Run(stop);
    EXPECT_FALSE(fresh.resumed);
    EXPECT_EQ(fresh.estimate.rig.slaves[0].motions.used, 0);
  }
}

TEST(CalibNode, OpenReportsUnusableInputs) {
  TempDir dir;
  auto config = io::LoadRigConfig(WriteConfig(dir));
  ASSERT_TRUE(config) << config.error();
  CalibNodeOptions options;
  options.log_path = dir / "missing.lcmlog";
  CalibNode node(*config, options);
  const Status status = node.Open();
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("missing.lcmlog"), std::string::npos) << status.message();
}

TEST(CalibNode, EstimatorStateNamesTheDecalibratedSlave) {
  RigEstimate estimate;
  std::string message;
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_IDLE);
  estimate.sets = 10;
  estimate.rig.slaves.resize(2);
  estimate.rig.slaves[0].name = "left";
  estimate.rig.slaves[1].name = "back";
  estimate.online.resize(2);
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_INITIALISING);
  estimate.rig.slaves[0].state = SlaveState::kConverged;
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_DEGRADED);
  EXPECT_NE(message.find("back"), std::string::npos) << message;  // the one holding it back
  EXPECT_NE(message.find("1 of 2 slaves usable"), std::string::npos) << message;
  estimate.rig.slaves[1].state = SlaveState::kUsable;
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_USABLE);
  estimate.rig.slaves[1].state = SlaveState::kConverged;
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_CONVERGED);
  estimate.rig.slaves[1].state = SlaveState::kDecalibrated;
  EXPECT_EQ(lcm::EstimatorState(estimate, &message), rig_status_t::ESTIMATOR_DECALIBRATED);
  EXPECT_NE(message.find("back"), std::string::npos) << message;
}

}  // namespace
}  // namespace rigcal::pipeline
