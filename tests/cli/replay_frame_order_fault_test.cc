// SPDX-License-Identifier: Apache-2.0
// Image logs whose cameras are out of step in the file, through `rigcal replay`: one camera's
// frames written seconds ahead of the other's (a recording made faster than real time), a camera
// that stops half-way, a camera whose first frames come at the end of the file. The replay
// feeds the frames in stamp order (pipeline/replay_frame_order.h): it never waits for frames
// behind those it holds, so it ends (before the fix it deadlocked: 0 % CPU, SIGTERM ignored);
// a camera ahead in the file gives the result of the ordered log; late frames are dropped and
// counted. And SIGTERM in the busiest phase of an image replay ends it within 2 s.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "cli/command_test.h"
#include "support/lcm_log_events.h"
#include "support/simulated_rig_config.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using cli_test::Slurp;
using cli_test::Spawn;
using cli_test::WaitExit;
using cli_test::YamlWithoutProvenance;
using support::LoggedEvent;

constexpr int64_t kSecondUs = 1'000'000;
const char kSlaveChannel[] = "RIGCAL_IMAGE_cam1";

class ReplayFrameOrderFault : public cli_test::CommandTest {
 protected:
  void SetUp() override {
    CommandTest::SetUp();
    if (HasFatalFailure()) return;
    // 12 s of the thesis rig at 20 Hz, 320 x 240: images only.
    std::ofstream(Path("rig.yaml")) << support::SimulatedRigConfig(320, 240, 240);
    const auto r = Run("record --config " + Quote(Path("rig.yaml")) + " -o " +
                       Quote(Path("ordered.lcmlog")) + " --fast --no-vo");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    events_ = support::ReadLcmLog(Path("ordered.lcmlog"));
    ASSERT_EQ(events_.size(), 480u);
  }

  void WriteLog(const std::string& name, const std::vector<LoggedEvent>& events) const {
    ::lcm::LogFile log(Path(name), "w");
    ASSERT_TRUE(log.good());
    int64_t number = 0;
    for (const LoggedEvent& e : events) {
      ::lcm::LogEvent out{};
      out.eventnum = number++;
      out.timestamp = e.timestamp;
      out.channel = e.channel;
      out.datalen = static_cast<int32_t>(e.data.size());
      out.data = const_cast<uint8_t*>(e.data.data());
      ASSERT_EQ(log.writeEvent(&out), 0);
    }
  }

  struct Replayed {
    int code = -1;  // -1: still running after 60 s (then killed)
    std::string err;
    std::string Hung() const { return "still running after 60 s\n" + err.substr(0, 4000); }
  };
  // `rigcal replay` of `log`: its exit code and stderr.
  Replayed Replay(const std::string& log, const std::string& result) const {
    const pid_t pid = Spawn(
        binary_,
        {"replay", Path(log), "--config", Path("rig.yaml"), "--out", Path(result), "--no-progress"},
        Path("err.txt"));
    EXPECT_GT(pid, 0);
    Replayed r;
    r.code = pid > 0 ? WaitExit(pid, std::chrono::seconds(60)) : -1;
    r.err = Slurp(Path("err.txt"));
    return r;
  }

  std::vector<LoggedEvent> events_;  // the recorded log, each camera in capture order
};

TEST_F(ReplayFrameOrderFault, ACameraAheadInTheFileGivesTheResultOfTheOrderedLog) {
  const Replayed ordered = Replay("ordered.lcmlog", "ordered.yaml");
  ASSERT_EQ(ordered.code, 0) << ordered.err;
  // cam1's frames written 8 s of log time before cam0's of the same stamp.
  std::vector<LoggedEvent> ahead = events_;
  std::stable_sort(ahead.begin(), ahead.end(), [](const LoggedEvent& a, const LoggedEvent& b) {
    const auto key = [](const LoggedEvent& e) {
      return e.timestamp - (e.channel == kSlaveChannel ? 8 * kSecondUs : 0);
    };
    return key(a) < key(b);
  });
  WriteLog("ahead.lcmlog", ahead);
  const Replayed replayed = Replay("ahead.lcmlog", "ahead.yaml");
  const int code = replayed.code;
  const std::string& err = replayed.err;
  ASSERT_NE(code, -1) << replayed.Hung();
  EXPECT_EQ(code, 0) << err;
  EXPECT_EQ(err.find("late"), std::string::npos) << err;
  EXPECT_EQ(YamlWithoutProvenance(Slurp(Path("ahead.yaml"))),
            YamlWithoutProvenance(Slurp(Path("ordered.yaml"))));
}

TEST_F(ReplayFrameOrderFault, ACameraThatStopsHalfWayDoesNotStopTheReplay) {
  // cam1 delivers its first 6 s only; cam0 goes on for 6 s more (120 frames: more than the
  // replay's queues hold).
  std::vector<LoggedEvent> stopped;
  const int64_t first = events_.front().timestamp;
  for (const LoggedEvent& e : events_) {
    if (e.channel == kSlaveChannel && e.timestamp - first > 6 * kSecondUs) continue;
    stopped.push_back(e);
  }
  WriteLog("stopped.lcmlog", stopped);
  const Replayed replayed = Replay("stopped.lcmlog", "stopped.yaml");
  const int code = replayed.code;
  const std::string& err = replayed.err;
  ASSERT_NE(code, -1) << replayed.Hung();
  EXPECT_TRUE(code == 0 || code == 3) << code << "\n" << err;
  EXPECT_NE(Slurp(Path("stopped.yaml")).find("cam1:"), std::string::npos) << err;
}

TEST_F(ReplayFrameOrderFault, LateFramesAreDroppedAndCounted) {
  // cam1's first 40 frames (2 s at 20 Hz) moved to the end of the file: 10 s behind the rest.
  // Counted, not cut at an event time: `record --fast` stamps a camera's events up to a second
  // after its capture times (never decreasing), so how many fall in 2 s of event time varies.
  std::vector<LoggedEvent> head, rest;
  for (const LoggedEvent& e : events_) {
    const bool early = e.channel == kSlaveChannel && head.size() < 40;
    (early ? head : rest).push_back(e);
  }
  ASSERT_EQ(head.size(), 40u);
  rest.insert(rest.end(), head.begin(), head.end());
  WriteLog("late.lcmlog", rest);
  const Replayed replayed = Replay("late.lcmlog", "late.yaml");
  const int code = replayed.code;
  const std::string& err = replayed.err;
  ASSERT_NE(code, -1) << replayed.Hung();
  EXPECT_EQ(code, 0) << err;
  EXPECT_NE(err.find("late frames are dropped and counted"), std::string::npos) << err;
  EXPECT_NE(err.find("cam1"), std::string::npos) << err;
}

TEST_F(ReplayFrameOrderFault, SigtermInAnImageReplayEndsItWithinTwoSeconds) {
  // Paced at a quarter of real time, the 12-s log replays for 48 s; SIGTERM after 3 s.
  const pid_t pid = Spawn(binary_,
                          {"replay", Path("ordered.lcmlog"), "--config", Path("rig.yaml"), "--out",
                           Path("stopped.yaml"), "--no-progress", "--speed", "0.25"},
                          Path("err.txt"));
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const auto signalled = std::chrono::steady_clock::now();
  const int code = WaitExit(pid, std::chrono::seconds(10));
  const double took_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  const std::string err = Slurp(Path("err.txt"));
  ASSERT_NE(code, -1) << "still running 10 s after SIGTERM\n" << err.substr(0, 4000);
  EXPECT_LE(took_s, 2.0) << err;
}

}  // namespace
}  // namespace rigcal
