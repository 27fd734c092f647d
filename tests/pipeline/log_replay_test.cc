// SPDX-License-Identifier: Apache-2.0
// `rigcal replay` / `calib --log` of pose logs through CalibNode: nothing dropped even with the
// default small queues, the same log gives the same result and the same published history bit
// for bit, the timers run on log time (the output log holds the whole history at its rates),
// STATUS counters are true, the time window and pacing follow log time, and damaged logs are
// replayed up to the damage.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/text_file.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/calib_node.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kNames = {"front", "left", "back"};
constexpr int kFrames = 1200;  // 60 s at 20 Hz

class LogReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigcal_log_replay_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // The default sync queues (capacity 64, ready 32): what dropped sets before back-pressure.
    std::ofstream(Path("rig.yaml")) << "rig: {name: test, master: front}\n"
                                       "cameras:\n"
                                       "  - name: front\n"
                                       "  - name: left\n"
                                       "  - name: back\n"
                                       "publish: {extrinsics_rate_hz: 2, status_rate_hz: 1}\n";
    auto config = io::LoadRigConfig(Path("rig.yaml"));
    ASSERT_TRUE(config) << config.error();
    config_ = *config;
    DriveOptions d;
    d.num_frames = kFrames;
    drive_ = GenerateDrive(kNames, DemoRig(), d);
    ASSERT_TRUE(lcm::WritePoseLog(Path("poses.lcmlog"), drive_.recording).ok());
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(dir_, ec);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  CalibNodeSummary Replay(const std::string& log, const std::string& tag,
                          ReplayOptions replay = {}) {
    CalibNodeOptions options;
    options.log_path = log;
    options.publish_url = "file://" + Path(tag + ".out.lcmlog") + "?mode=w";
    options.result_path = Path(tag + ".yaml");
    options.replay = replay;
    CalibNode node(config_, options);
    const Status opened = node.Open();
    EXPECT_TRUE(opened.ok()) << opened.message();
    std::atomic<bool> stop{false};
    return node.Run(stop);
  }

  // The events of an output log by channel.
  std::map<std::string, std::vector<std::vector<uint8_t>>> Events(const std::string& tag) {
    std::map<std::string, std::vector<std::vector<uint8_t>>> events;
    auto reader = lcm::LogReader::Open(Path(tag + ".out.lcmlog"));
    EXPECT_TRUE(reader) << reader.error();
    lcm::LogEvent event;
    while ((*reader)->Next(&event) == lcm::LogReader::Outcome::kEvent) {
      events[event.channel].push_back(event.data);
    }
    EXPECT_TRUE((*reader)->problem().empty()) << (*reader)->problem();
    return events;
  }

  fs::path dir_;
  io::RigConfig config_;
  SyntheticDrive drive_;
};

TEST_F(LogReplayTest, SameLogSameResultBitForBitAndNothingDropped) {
  const CalibNodeSummary a = Replay(Path("poses.lcmlog"), "a");
  const CalibNodeSummary b = Replay(Path("poses.lcmlog"), "b");
  // Every stamp of the log has all three cameras: one set each, none lost.
  EXPECT_EQ(a.sync.sets_emitted, static_cast<uint64_t>(kFrames)) << a.sync.BriefReport();
  EXPECT_EQ(a.sync.consumer_overflow, 0u) << a.sync.BriefReport();
  EXPECT_EQ(a.estimate.sets, static_cast<uint64_t>(kFrames));
  EXPECT_EQ(a.log_events, 3 * kFrames);
  EXPECT_TRUE(a.log_problem.empty()) << a.log_problem;
  EXPECT_FALSE(a.image_replay);
  for (size_t i = 0; i < a.estimate.rig.slaves.size(); ++i) {
    const SlaveCalibration& x = a.estimate.rig.slaves[i];
    const SlaveCalibration& y = b.estimate.rig.slaves[i];
    ASSERT_TRUE(x.usable()) << x.message;
    EXPECT_EQ(x.estimate.q.coeffs(), y.estimate.q.coeffs()) << x.name;
    EXPECT_EQ(x.estimate.C, y.estimate.C) << x.name;
    EXPECT_EQ(x.estimate.scale, y.estimate.scale) << x.name;
  }
  auto yaml_a = io::ReadWholeFile(Path("a.yaml"));
  auto yaml_b = io::ReadWholeFile(Path("b.yaml"));
  ASSERT_TRUE(yaml_a && yaml_b);
  EXPECT_EQ(*yaml_a, *yaml_b);
  // The published history is the same too, message for message.
  EXPECT_EQ(Events("a")[lcm::kExtrinsicsChannel], Events("b")[lcm::kExtrinsicsChannel]);
}

TEST_F(LogReplayTest, TimersRunOnLogTimeAndStatusIsTrue) {
  const CalibNodeSummary summary = Replay(Path("poses.lcmlog"), "out");
  const double span_s = (kFrames - 1) / 20.0;
  EXPECT_NEAR(summary.log_span_s, span_s, 1e-9);
  auto events = Events("out");
  // 2 Hz and 1 Hz of log time, plus the last message at the end.
  const auto extrinsics = events[lcm::kExtrinsicsChannel].size();
  const auto status = events[lcm::kStatusChannel].size();
  EXPECT_NEAR(static_cast<double>(extrinsics), 2.0 * span_s + 1, 1.5);
  EXPECT_NEAR(static_cast<double>(status), 1.0 * span_s + 1, 1.5);
  EXPECT_EQ(summary.extrinsics_published, static_cast<int64_t>(extrinsics));

  lcm::MessageValidator validator(kNames);
  int64_t previous_utime = -1;
  for (const auto& data : events[lcm::kExtrinsicsChannel]) {
    auto msg = validator.Decode<rig_extrinsics_t>(lcm::kExtrinsicsChannel, data.data(),
                                                  static_cast<int64_t>(data.size()));
    ASSERT_TRUE(msg) << msg.error();
    EXPECT_GE(msg->utime, previous_utime);  // log time, not the wall clock
    previous_utime = msg->utime;
  }
  EXPECT_EQ(previous_utime, drive_.recording.t_ns.back() / 1000);
  // STATUS: rates from the stamps (20 Hz), and no drop that did not happen.
  for (const auto& data : events[lcm::kStatusChannel]) {
    auto msg = validator.Decode<rig_status_t>(lcm::kStatusChannel, data.data(),
                                              static_cast<int64_t>(data.size()));
    ASSERT_TRUE(msg) << msg.error();
    for (const camera_status_t& camera : msg->cameras) {
      EXPECT_EQ(camera.dropped_overflow, 0) << camera.name;
      if (msg->utime < drive_.recording.t_ns.back() / 1000) {
        EXPECT_NEAR(camera.fps, 20.0, 1.5) << camera.name << " at " << msg->utime;
      }
    }
  }
}

TEST_F(LogReplayTest, WindowAndPacingFollowLogTime) {
  ReplayOptions window;
  window.from_s = 10.0;
  window.to_s = 30.0;
  const CalibNodeSummary part = Replay(Path("poses.lcmlog"), "window", window);
  EXPECT_EQ(part.sync.sets_emitted, 401u) << part.sync.BriefReport();  // 10.00 .. 30.00 s
  EXPECT_NEAR(part.log_span_s, 20.0, 1e-9);

  ReplayOptions paced;
  paced.to_s = 4.0;
  paced.speed = 10.0;
  const auto start = std::chrono::steady_clock::now();
  const CalibNodeSummary slow = Replay(Path("poses.lcmlog"), "paced", paced);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(wall_s, 0.38);  // 4 s of log at 10x
  EXPECT_EQ(slow.sync.sets_emitted, 81u);
}

// Appends raw bytes to a file.
void Append(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::app);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

TEST_F(LogReplayTest, DamagedLogsReplayUpToTheDamage) {
  // Another channel, then an event whose header announces 2 GiB.
  const std::string log = Path("poses.lcmlog");
  {
    ::lcm::LogFile file(log, "a");
    ASSERT_TRUE(file.good());
    uint8_t byte = 1;
    ::lcm::LogEvent event;
    event.eventnum = 1'000'000;
    event.timestamp = 1;
    event.channel = "OTHER_TOPIC";
    event.datalen = 1;
    event.data = &byte;
    ASSERT_EQ(file.writeEvent(&event), 0);
  }
  const auto damage = fs::file_size(log);
  Append(log, {0xED, 0xA1, 0xDA, 0x01, 0, 0, 0, 0, 0, 0,    0,    3,    0,    0,   0,
               0,    0,    0,    0,    9, 0, 0, 0, 2, 0x7F, 0xFF, 0xFF, 0xFF, 'C', 'H'});
  const CalibNodeSummary summary = Replay(log, "damaged");
  EXPECT_NE(summary.log_problem.find("byte " + std::to_string(damage) + ": data length"),
            std::string::npos)
      << summary.log_problem;
  EXPECT_EQ(summary.skipped_channels.at("OTHER_TOPIC"), 1);
  EXPECT_EQ(summary.estimate.sets, static_cast<uint64_t>(kFrames));
  EXPECT_TRUE(fs::exists(Path("damaged.yaml")));

  // Cut in the middle: the sets before the cut are replayed, the result is written.
  const std::string cut = Path("cut.lcmlog");
  fs::copy_file(Path("poses.lcmlog"), cut);
  fs::resize_file(cut, damage / 2);
  const CalibNodeSummary half = Replay(cut, "cut");
  EXPECT_NE(half.log_problem.find("truncated"), std::string::npos) << half.log_problem;
  EXPECT_NEAR(static_cast<double>(half.estimate.sets), kFrames / 2.0, 3.0);
  EXPECT_TRUE(fs::exists(Path("cut.yaml")));
}

}  // namespace
}  // namespace rigcal::pipeline
