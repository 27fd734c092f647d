// SPDX-License-Identifier: Apache-2.0
// `rigcal status` in one process: messages published on memq:// reach the monitor, which shows
// them (dashboard, plain lines, JSON) and decides the health exit code.
#include "rigcal/monitor/status_monitor.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <thread>

#include "monitor/status_fixtures.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::monitor {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

template <typename Message>
void Publish(::lcm::LCM* lcm, const char* channel, const Message& msg) {
  auto bytes = lcm::EncodeMessage(channel, lcm::CameraNames{}, msg);
  ASSERT_TRUE(bytes.ok()) << bytes.error();
  ASSERT_EQ(lcm->publish(channel, bytes->data(), bytes->size()), 0);
}

struct MonitorRun {
  int code = -1;
  std::string out;
  std::string err;
};

// memq:// delivers a message to the subscriptions that exist when it is published: the
// messages go out from another thread once the monitor listens.
using Publisher = std::function<void(::lcm::LCM*)>;

MonitorRun RunOnce(::lcm::LCM* lcm, bool json, double timeout_s = 2.0,
                   const Publisher& publish = nullptr) {
  StatusRunOptions options;
  options.url = "memq://";
  options.once = true;
  options.json = json;
  options.timeout_s = timeout_s;
  std::ostringstream out, err;
  std::atomic<bool> stop{false};
  MonitorRun run;
  std::thread sender;
  if (publish) {
    sender = std::thread([&]() {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      publish(lcm);
    });
  }
  run.code = RunStatusMonitor(options, out, err, stop, lcm);
  if (sender.joinable()) sender.join();
  run.out = out.str();
  run.err = err.str();
  return run;
}

TEST(StatusMonitor, OnceJsonShowsTheNewestMessagesAndTheHealth) {
  ::lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  const MonitorRun run = RunOnce(&lcm, true, 2.0, [](::lcm::LCM* bus) {
    Publish(bus, lcm::kStatusChannel, MakeStatus(rig_status_t::ESTIMATOR_USABLE));
    Publish(bus, lcm::kExtrinsicsChannel, MakeExtrinsics(slave_extrinsics_t::STATE_USABLE, -1));
  });
  EXPECT_EQ(run.code, 1) << run.out;  // usable, not converged: still converging
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["health"], "converging");
  EXPECT_EQ(j["exit_code"], 1);
  EXPECT_EQ(j["status"]["estimator_state"], "usable");
  EXPECT_EQ(j["status"]["cameras"][0]["dropped"]["never_matched"], 7);
  EXPECT_EQ(j["status"]["cameras"][1]["vo_state"], "lost");
  EXPECT_EQ(j["status"]["cameras"][1]["relocalisations"], 3);
  EXPECT_EQ(j["status"]["sync"]["sets_emitted"], 999);
  EXPECT_EQ(j["status"]["process"]["rss_bytes"], 123 << 20);
  EXPECT_GE(j["status"]["age_s"].get<double>(), 0.0);
  const nlohmann::json& slave = j["extrinsics"]["slaves"][0];
  EXPECT_EQ(slave["name"], "left");
  EXPECT_TRUE(slave["std"]["rot_deg"].is_null());  // -1 on LCM: unknown, never 0
  EXPECT_TRUE(slave["std"]["pos"][1].is_null());
  EXPECT_DOUBLE_EQ(slave["std"]["pos"][2].get<double>(), 0.03);
  EXPECT_NEAR(slave["axis_angle"]["angle_deg"].get<double>(), 90.0, 1e-9);
  EXPECT_NEAR(slave["roll_pitch_yaw_deg"][1].get<double>(), 90.0, 1e-6);
  EXPECT_EQ(slave["segment"], 4);
  EXPECT_EQ(slave["facts"], nlohmann::json::array({"refined"}));
}

TEST(StatusMonitor, HealthCodes) {
  const std::pair<int8_t, int> cases[] = {
      {rig_status_t::ESTIMATOR_CONVERGED, 0},    {rig_status_t::ESTIMATOR_IDLE, 1},
      {rig_status_t::ESTIMATOR_INITIALISING, 1}, {rig_status_t::ESTIMATOR_DEGRADED, 1},
      {rig_status_t::ESTIMATOR_USABLE, 1},       {rig_status_t::ESTIMATOR_DECALIBRATED, 2}};
  for (const auto& [state, code] : cases) {
    ::lcm::LCM lcm("memq://");
    const int8_t s = state;
    const MonitorRun run = RunOnce(&lcm, true, 2.0, [s](::lcm::LCM* bus) {
      Publish(bus, lcm::kStatusChannel, MakeStatus(s));
      Publish(bus, lcm::kExtrinsicsChannel,
              MakeExtrinsics(slave_extrinsics_t::STATE_CONVERGED, 0.1));
    });
    EXPECT_EQ(run.code, code) << EstimatorStateName(state);
  }
  // Without a status the slaves' states decide.
  ::lcm::LCM lcm("memq://");
  const MonitorRun run = RunOnce(&lcm, false, 0.5, [](::lcm::LCM* bus) {
    Publish(bus, lcm::kExtrinsicsChannel,
            MakeExtrinsics(slave_extrinsics_t::STATE_DECALIBRATED, 0.1));
  });
  EXPECT_EQ(run.code, 2);
  EXPECT_THAT(run.out, HasSubstr("RIGCAL_STATUS never"));
}

TEST(StatusMonitor, NoDataWithinTheTimeoutIsExitCode3) {
  ::lcm::LCM lcm("memq://");
  const auto start = std::chrono::steady_clock::now();
  const MonitorRun run = RunOnce(&lcm, true, 0.3);
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(run.code, 3);
  EXPECT_GE(waited, 0.3);
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["health"], "no_data");
  EXPECT_TRUE(j["status"].is_null());
}

TEST(StatusMonitor, RejectedMessagesAreCountedNotShown) {
  ::lcm::LCM lcm("memq://");
  rig_status_t bad = MakeStatus(rig_status_t::ESTIMATOR_CONVERGED);
  bad.cameras[0].fps = -1.0;  // violates fps >= 0: a sender that skips the checks
  const int size = bad.getEncodedSize();
  std::vector<uint8_t> raw(size);
  ASSERT_EQ(bad.encode(raw.data(), 0, size), size);
  const MonitorRun run = RunOnce(&lcm, true, 0.6, [&raw](::lcm::LCM* bus) {
    const uint8_t junk[] = {1, 2, 3, 4, 5};
    bus->publish(lcm::kStatusChannel, junk, sizeof(junk));
    bus->publish(lcm::kStatusChannel, raw.data(), raw.size());
    Publish(bus, lcm::kExtrinsicsChannel, MakeExtrinsics(slave_extrinsics_t::STATE_CONVERGED, 0.1));
  });
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["rejected_messages"], 2);
  EXPECT_TRUE(j["status"].is_null());
  EXPECT_EQ(run.code, 0);  // the extrinsics' converged slave
}

TEST(StatusMonitor, DashboardShowsEveryFigure) {
  MonitorSnapshot s;
  s.source = "memq://";
  s.status = MakeStatus(rig_status_t::ESTIMATOR_DEGRADED);
  s.extrinsics = MakeExtrinsics(slave_extrinsics_t::STATE_USABLE, -1);
  s.status_age_s = 0.4;
  s.extrinsics_age_s = 1.25;
  s.status_received = 3;
  const std::string text = FormatDashboard(s);
  for (const char* expected :
       {"memq://", "RIGCAL_STATUS 0.4 s ago", "RIGCAL_EXTRINSICS 1.2 s ago", "rig: degraded",
        "left holds the rig back", "CPU 87.5 %", "RSS 123.0 MiB",
        "sync: 999 sets emitted, buffer 5 / 64", "tracking", "lost",
        "slave left (master front): usable refined", "motions 321 used, 9 rejected",
        "angle 90.000 deg", "sigma unknown deg", "[0.01, unknown, 0.03]", "segment 4",
        "health: converging (exit code 1)"}) {
    EXPECT_THAT(text, HasSubstr(expected));
  }
  EXPECT_THAT(text, Not(HasSubstr("clock "))) << "synchronised stamps: no clock line";
  slave_extrinsics_t& left = s.extrinsics->slaves[0];
  left.time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATED;
  left.time_offset_s = 0.040012;
  left.time_offset_std_s = 0.00021;
  left.clock_jumps = 1;
  EXPECT_THAT(FormatDashboard(s),
              HasSubstr("  clock     offset 40.012 ms  sigma 0.21 ms (estimated), 1 jump"));
  left.time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATING;
  EXPECT_THAT(FormatDashboard(s), HasSubstr("offset being estimated"));
  left = MakeExtrinsics(slave_extrinsics_t::STATE_USABLE, -1).slaves[0];
  // The clock of a free-running camera from RIGCAL_STATUS (version 4).
  camera_status_t& left_status = s.status->cameras[1];
  left_status.time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATED;
  left_status.time_offset_s = -39.950012;
  left_status.time_offset_std_s = 0.00021;
  left_status.clock_drift_ppm = 50.2;
  left_status.clock_drift_std_ppm = 0.75;
  left_status.clock_jumps = 2;
  EXPECT_THAT(FormatDashboard(s),
              HasSubstr("clock left         offset -39950.012 ms sigma 0.21 ms, drift 50.2 ppm "
                        "sigma 0.75 ppm (estimated), 2 jumps"));
  const nlohmann::json clock = SnapshotToJson(s)["status"]["cameras"][1]["clock"];
  EXPECT_EQ(clock["source"], "estimated");
  EXPECT_EQ(clock["offset_s"], -39.950012);
  EXPECT_EQ(clock["drift_std_ppm"], 0.75);
  EXPECT_EQ(clock["jumps"], 2);
  EXPECT_TRUE(SnapshotToJson(s)["status"]["cameras"][0]["clock"]["std_s"].is_null());
  left_status = MakeStatus(rig_status_t::ESTIMATOR_DEGRADED).cameras[1];
  // Every camera's segment and relocalisations from its camera_status_t (the master's too); no
  // segment yet: "-".
  EXPECT_THAT(text, ::testing::ContainsRegex("left +19.5 +1234 +3 .*lost +1 +3 +42 ms"));
  EXPECT_THAT(text, ::testing::ContainsRegex("front +19.5 .*tracking +1 +0 +42 ms"));
  s.status->cameras[0].vo_segment = -1;
  EXPECT_THAT(FormatDashboard(s), ::testing::ContainsRegex("front +19.5 .*tracking +- +0 +42 ms"));
  // Cut at the terminal's width; framed for in-place refresh.
  for (size_t pos = 0, next; (next = FormatDashboard(s, 40).find('\n', pos)) != std::string::npos;
       pos = next + 1) {
    EXPECT_LE(next - pos, 40u);
  }
  const std::string frame = AnsiFrame("a\nb\n");
  EXPECT_EQ(frame, "\x1b[Ha\x1b[K\nb\x1b[K\n\x1b[J");
  EXPECT_THAT(text, Not(HasSubstr("\x1b")));
}

TEST(StatusMonitor, PlainLinesPerStatusUntilStopped) {
  ::lcm::LCM lcm("memq://");
  std::atomic<bool> stop{false};
  std::ostringstream out, err;
  StatusRunOptions options;
  options.url = "memq://";
  int code = -1;
  std::thread monitor([&]() { code = RunStatusMonitor(options, out, err, stop, &lcm); });
  for (int i = 0; i < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    Publish(&lcm, lcm::kStatusChannel,
            MakeStatus(i < 2 ? rig_status_t::ESTIMATOR_USABLE : rig_status_t::ESTIMATOR_CONVERGED,
                       1000 + i));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  stop = true;
  monitor.join();
  const std::string text = out.str();
  int blocks = 0;
  for (size_t pos = text.find("---\n"); pos != std::string::npos;
       pos = text.find("---\n", pos + 1)) {
    ++blocks;
  }
  EXPECT_EQ(blocks, 3) << text;
  EXPECT_THAT(text, Not(HasSubstr("\x1b")));  // not a terminal: no control codes
  EXPECT_EQ(code, 0);                         // the last status: converged
}

}  // namespace
}  // namespace rigcal::monitor
