// SPDX-License-Identifier: Apache-2.0
// `rigcal run` with a live trigger generator: the built binary on a simulated rig whose
// `trigger.port` is a pseudo-terminal with a generator speaking the firmware's protocol at the
// other end (pipeline/fake_trigger_generator.h). The rig runs in real time from the next pulse,
// every frame gets its pulse (but for a few reported as late reports: a stall of the loaded test
// host), the poses are stamped at the pulses' true times, and the summary
// reports the generator; when the generator dies mid-run the run says so and still ends.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "cli/command_test.h"
#include "pipeline/fake_trigger_generator.h"

namespace {

namespace fs = std::filesystem;

class RunTriggerTest : public rigcal::cli_test::CommandTest {
 protected:
  void RunOnTheGenerator(rigcal::testing::FakeTriggerGenerator& generator, int64_t settled_ns,
                         int64_t* map_restarts);
};
using rigcal::cli_test::RunResult;

constexpr int64_t kPeriodNs = 50'000'000;

std::string RigConfig(const std::string& port) {
  const std::string camera =
      "    model: pinhole\n    resolution: [320, 240]\n    intrinsics: [200, 200, 159.5, 119.5]\n";
  return "rig: {name: triggered, master: cam0}\n"
         "trigger: {port: " +
         port +
         ", rate_hz: 20, heartbeat_ms: 50, uart_wire: false}\n"
         "cameras:\n"
         "  - name: cam0\n" +
         camera +
         "    trigger: {line: 0}\n"
         "  - name: cam1\n" +
         camera +
         "    truth: {q_wxyz: [0.70710678118654752, 0, 0.70710678118654752, 0], C: [0.5, 0, 0]}\n"
         "    trigger: {line: 1}\n"
         "source:\n"
         "  type: simulated\n"
         "  realtime: true\n"
         "  frame_rate_hz: 20\n"
         "  num_frames: 100\n"
         "  scene: {type: room, size: [20, 16, 6], boxes: 10}\n"
         "  trajectory:\n"
         "    waypoint_interval_s: 2\n"
         "    waypoints:\n"
         "      - {p: [-3.0, 0.0, 3.0], ypr_deg: [0, 0, 0]}\n"
         "      - {p: [-2.3, 0.8, 3.2], ypr_deg: [20, -10, 8]}\n"
         "      - {p: [-1.4, 1.5, 3.0], ypr_deg: [38, 5, -6]}\n"
         "      - {p: [-0.4, 1.2, 2.8], ypr_deg: [15, 15, -15]}\n";
}

// The frames' pulses as the summary of `rigcal run` reports them for `camera`: a frame without
// only for a cause the camera counted (a late report, an unsynced map; the loaded test host's
// stalls), or one per clock-map restart (stamped with the map before it, matched after it), and
// few of them.
void CheckPulsesReported(const std::string& err, const std::string& camera) {
  const std::string line = "camera '" + camera + "': ";
  const size_t at = err.find(line, err.find(" clock-map restarts, clock drift "));
  ASSERT_NE(at, std::string::npos) << err;
  long long with = -1;
  long long without = -1;
  ASSERT_EQ(std::sscanf(err.c_str() + at + line.size(),
                        "%lld frames with their trigger pulse, %lld without", &with, &without),
            2)
      << err.substr(at, 200);
  EXPECT_GT(with, 0) << camera;
  if (without == 0) return;
  // "(<a> because the pulse report came more than ...; <b> while the clock map was not synced)",
  // or nothing when no frame had a counted cause (a + b = 0).
  long long late = 0;
  long long unsynced = 0;
  const size_t line_end = err.find('\n', at);
  const size_t open = err.find(" without (", at);
  if (open != std::string::npos && open < line_end) {
    ASSERT_EQ(std::sscanf(err.c_str() + open, " without (%lld because the pulse report", &late), 1)
        << err.substr(at, 300);
    const size_t semicolon = err.find("; ", open);
    ASSERT_NE(semicolon, std::string::npos) << err.substr(at, 300);
    ASSERT_EQ(std::sscanf(err.c_str() + semicolon, "; %lld while the clock map was not synced",
                          &unsynced),
              1)
        << err.substr(at, 300);
  }
  const size_t restarts_at = err.rfind(" MCU resets, ", at);
  long long restarts = -1;
  ASSERT_NE(restarts_at, std::string::npos) << err;
  ASSERT_EQ(
      std::sscanf(err.c_str() + restarts_at, " MCU resets, %lld clock-map restarts", &restarts), 1)
      << err.substr(restarts_at, 100);
  EXPECT_GE(without, late + unsynced) << err.substr(at, 300);
  EXPECT_LE(without, late + unsynced + restarts) << err.substr(at, 300);
  EXPECT_LE(without * 8, with + without) << err.substr(at, 300);
}

// `rigcal run` on the simulated rig paced by `generator` (started): every frame on its pulse,
// the poses whose pulse came `settled_ns` after the generator's late start stamped at the
// pulses' true times (the host maps a pulse that arrives late as late: it cannot know);
// `map_restarts` gets the clock map's restarts.
void RunTriggerTest::RunOnTheGenerator(rigcal::testing::FakeTriggerGenerator& generator,
                                       int64_t settled_ns, int64_t* map_restarts) {
  const std::string config = Path("rig.yaml");
  std::ofstream(config) << RigConfig(generator.slave_path());
  const RunResult r = Run("run --config '" + config + "' --status-every 0 --poses-out '" +
                          Path("poses") + "' --out '" + Path("result.yaml") + "'");
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;
  EXPECT_NE(r.err.find("trigger generator on " + generator.slave_path() + ": 20 Hz, 2 line(s)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("simulated rig paced by the trigger generator"), std::string::npos) << r.err;
  for (const char* camera : {"cam0", "cam1"}) CheckPulsesReported(r.err, camera);
  EXPECT_EQ(r.err.find("trigger link failed"), std::string::npos) << r.err;
  const size_t restarts_at = r.err.find(" MCU resets, ");
  long long restarts = -1;
  ASSERT_NE(restarts_at, std::string::npos) << r.err;
  ASSERT_EQ(
      std::sscanf(r.err.c_str() + restarts_at, " MCU resets, %lld clock-map restarts", &restarts),
      1);
  *map_restarts = restarts;
  // Every pose is stamped at a pulse's true time (within the matcher's 5 ms; in fact < 1 ms).
  const int64_t pulse0 = generator.TrueHostNs(0);
  const int64_t settled_from_ns = generator.settled_from_ns(settled_ns);
  int poses = 0;
  double worst_us = 0;
  for (const char* camera : {"cam0", "cam1"}) {
    std::ifstream in(fs::path(Path("poses")) / (std::string(camera) + ".txt"));
    std::string row;
    while (std::getline(in, row)) {
      if (row.empty() || row[0] == '#') continue;
      const int64_t t_ns = std::stoll(row.substr(0, row.find(' ')));
      if (t_ns < settled_from_ns) continue;
      const int64_t off = ((t_ns - pulse0) % kPeriodNs + kPeriodNs) % kPeriodNs;
      worst_us = std::max(worst_us, std::min(off, kPeriodNs - off) * 1e-3);
      ++poses;
    }
  }
  std::printf("rigcal run with a live trigger: %d poses, worst |stamp - true pulse| %.0f us\n",
              poses, worst_us);
  EXPECT_GT(poses, 20);
  EXPECT_LT(worst_us, 1000.0);
}

TEST_F(RunTriggerTest, FramesOfASimulatedRigCarryTheGeneratorsPulses) {
  rigcal::testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.Start();
  int64_t map_restarts = 0;
  RunOnTheGenerator(generator, 0, &map_restarts);
}

// Every message reaches the host 30 ms late (a loaded host at the start) until 2 s after the
// trigger starts, past frame 0; then on time, and the clock map restarts 30 ms earlier mid-run.
// The rig's frames move with the pulses (a rig clock fixed at the start left every later frame
// 30 ms from its pulse).
TEST_F(RunTriggerTest, FramesOfASimulatedRigStayOnTheirPulsesWhenTheClockMapRestarts) {
  rigcal::testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.set_late_start(30'000'000, 2'000'000'000);
  generator.Start();
  int64_t map_restarts = 0;
  RunOnTheGenerator(generator, 300'000'000, &map_restarts);
  EXPECT_GE(map_restarts, 1) << "the clock map did not restart: the test did not test it";
}

TEST_F(RunTriggerTest, AGeneratorThatDiesMidRunIsReported) {
  rigcal::testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.Start();
  const std::string port = generator.slave_path();
  const std::string config = Path("rig.yaml");
  std::ofstream(config) << RigConfig(port);
  const std::string stderr_path = Path("stderr.txt");  // where Run puts rigcal's stderr
  std::thread killer([&generator, &stderr_path] {
    // Mid-run: a second after rigcal says its first frame waits for a pulse (building the
    // simulated rig takes seconds under a sanitizer, longer than any fixed delay).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (rigcal::cli_test::Slurp(stderr_path).find("simulated rig paced by the trigger") ==
               std::string::npos &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
    generator.Stop();  // closes the pty: the host's reads fail
  });
  const RunResult r =
      Run("run --config '" + config + "' --status-every 0 --out '" + Path("result.yaml") + "'");
  killer.join();
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;
  EXPECT_NE(r.err.find("trigger link failed: " + port), std::string::npos) << r.err;
}

TEST_F(RunTriggerTest, ADeadPortStopsTheRunNamingIt) {
  const std::string config = Path("rig.yaml");
  std::ofstream(config) << RigConfig("/dev/rigcal-no-such-tty");
  const RunResult r = Run("run --config '" + config + "' --status-every 0");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("trigger: trigger generator: /dev/rigcal-no-such-tty: open"),
            std::string::npos)
      << r.err;
}

}  // namespace
