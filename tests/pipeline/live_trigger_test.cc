// SPDX-License-Identifier: Apache-2.0
// The live trigger path without hardware: a rig config with `trigger.port` on a pseudo-terminal
// whose other end is a generator speaking the firmware's protocol (fake_trigger_generator.h),
// and an image-folder source that the capture sources replay in real time from the next pulse.
// Frames must come out with consecutive trigger sequences, the same one for both cameras, and
// the mapped pulse time within the matcher's tolerance of the true one (printed as RMS); a frame
// may lack its pulse only through a late report (triggered_frames_check.h). A dead
// port and a silent generator give an error naming the port.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "fake_trigger_generator.h"
#include "live_trigger_rig.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/capture_sources.h"
#include "support/temp_dir.h"
#include "triggered_frames_check.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;
using testing::kFrames;
using testing::WriteRig;

// Replays the image-folder rig of `generator` (started) and checks every frame's pulse, and the
// time of those whose pulse came at least `settled_ns` after the generator's late start (the
// host maps a pulse that arrives late as late: it cannot know); `map_restarts` gets the clock
// map's restarts.
void CheckFramesCarryTheirPulses(testing::FakeTriggerGenerator& generator, const std::string& name,
                                 int64_t settled_ns, int64_t* map_restarts) {
  const fs::path dir = support::FreshTempDir(name);
  auto config =
      io::LoadRigConfig(WriteRig(dir, generator.slave_path(), "uart_wire: false, tolerance_ms: 5"));
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_TRUE(config->online.sync.match_by_trigger_seq);
  std::ostringstream progress;
  auto sources = OpenCaptureSources(*config, false, "", progress);
  ASSERT_TRUE(sources.ok()) << sources.error();
  ASSERT_TRUE(sources->trigger);
  ASSERT_EQ(sources->triggered.size(), 2u);
  EXPECT_TRUE(sources->realtime);

  std::array<std::vector<int64_t>, 2> seqs;
  double sum2 = 0;
  int64_t worst = 0;
  int timed = 0;
  for (int k = 0; k < kFrames; ++k) {
    for (int c = 0; c < 2; ++c) {
      auto frame = sources->devices[c]->Grab();
      ASSERT_TRUE(frame.ok()) << frame.error();
      ASSERT_TRUE(frame->has_value()) << "camera " << c << " ended at frame " << k;
      const capture::Frame& f = **frame;
      seqs[c].push_back(f.seq);
      if (f.seq < 0) continue;  // CheckTriggeredFrames: only for a counted cause
      if (generator.TrueHostNs(f.seq) < generator.settled_from_ns(settled_ns)) continue;
      const int64_t error_ns = f.t_ns - generator.TrueHostNs(f.seq);
      sum2 += static_cast<double>(error_ns) * static_cast<double>(error_ns);
      worst = std::max(worst, std::abs(error_ns));
      ++timed;
    }
  }
  sources->trigger->Stop();
  EXPECT_EQ(sources->trigger->problem(), "");
  *map_restarts = sources->trigger->matcher().stats().map_restarts;
  const std::optional<int64_t> first =
      testing::CheckTriggeredFrames(seqs, {sources->triggered[0], sources->triggered[1]},
                                    sources->trigger->matcher().stats().map_restarts);
  if (!first) return;
  const double rms_us = std::sqrt(sum2 / std::max(timed, 1)) * 1e-3;
  std::printf(
      "live trigger over a pty (fake generator, 20 Hz): %d frames x 2 cameras, seqs %lld..%lld, "
      "%lld without their pulse, %lld clock-map restarts; frame time - true pulse time over %d "
      "frames: RMS %.0f us, worst %.0f us\n",
      kFrames, static_cast<long long>(*first), static_cast<long long>(*first + kFrames - 1),
      static_cast<long long>(sources->triggered[0]->unmatched() +
                             sources->triggered[1]->unmatched()),
      static_cast<long long>(*map_restarts), timed, rms_us, worst * 1e-3);
  EXPECT_LE(worst, config->trigger->matcher.tolerance_ns);
  std::ostringstream report;
  ReportTrigger(*sources, "", report);
  std::printf("%s", report.str().c_str());
  const trigger::TriggeredCamera& cam1 = *sources->triggered[1];
  std::string expected = "camera 'cam1': " + std::to_string(cam1.matched()) +
                         " frames with their trigger pulse, " + std::to_string(cam1.unmatched()) +
                         " without";
  if (cam1.late_reports() + cam1.unsynced() > 0) {
    expected += " (" + std::to_string(cam1.late_reports()) +
                " because the pulse report came more than 50 ms after the frame: a busy host or a "
                "slow link; " +
                std::to_string(cam1.unsynced()) + " while the clock map was not synced)";
  }
  EXPECT_EQ(cam1.matched() + cam1.unmatched(), kFrames);
  EXPECT_NE(report.str().find(expected), std::string::npos) << report.str();
}

TEST(LiveTrigger, ImageFolderFramesCarryConsecutivePulsesAndTheirMappedTimes) {
  testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.Start();
  int64_t map_restarts = 0;
  CheckFramesCarryTheirPulses(generator, "live_trigger_folders", 0, &map_restarts);
}

// Every message reaches the host 30 ms late (a loaded host at the start) until 0.15 s after the
// trigger starts: the clock map is first fitted on them and the replay starts on a tick it maps
// (0.3 s ahead); then the messages come on time and the map restarts 30 ms earlier, before the
// first frame. The replayed frames move with the pulses: a replay clock fixed at the start left
// every frame 30 ms from its pulse, none matched.
TEST(LiveTrigger, ImageFolderFramesStayOnTheirPulsesWhenTheClockMapRestarts) {
  testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.set_late_start(30'000'000, 150'000'000);
  generator.Start();
  int64_t map_restarts = 0;
  // The map restarts after 3 early samples and maps again after 4 (messages every 25 ms).
  CheckFramesCarryTheirPulses(generator, "live_trigger_late_start", 200'000'000, &map_restarts);
  EXPECT_GE(map_restarts, 1) << "the clock map did not restart: the test did not test it";
}

// A glitched stamp far ahead (4e18 ns, about 127 years) in a paced replay: not waited for; the
// camera's Grab returns, promptly, an error naming the frame and the gap.
TEST(LiveTrigger, AGlitchedStampFarAheadIsAnErrorNotAWait) {
  testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.Start();
  const fs::path dir = support::FreshTempDir("live_trigger_glitch");
  const int64_t late_ns = 4'000'000'000'000'000'000 - 1'403'636'579'763'555'584;
  auto config = io::LoadRigConfig(
      WriteRig(dir, generator.slave_path(), "uart_wire: false, tolerance_ms: 5", late_ns));
  ASSERT_TRUE(config.ok()) << config.error();
  std::ostringstream progress;
  auto sources = OpenCaptureSources(*config, false, "", progress);
  ASSERT_TRUE(sources.ok()) << sources.error();
  for (int k = 0; k + 1 < kFrames; ++k) {
    auto frame = sources->devices[0]->Grab();
    ASSERT_TRUE(frame.ok()) << "frame " << k << ": " << frame.error();
    ASSERT_TRUE(frame->has_value()) << "ended at frame " << k;
  }
  auto glitched = sources->devices[0]->Grab();  // waiting for it would not end (ctest timeout)
  sources->trigger->Stop();
  ASSERT_FALSE(glitched.ok()) << "the frame stamped 4e18 ns was delivered";
  EXPECT_NE(glitched.error().find("frame " + std::to_string(kFrames - 1) + " is stamped"),
            std::string::npos)
      << glitched.error();
  EXPECT_NE(glitched.error().find("a paced replay waits at most 10 s"), std::string::npos)
      << glitched.error();
}

TEST(LiveTrigger, ADeadPortIsAnErrorNamingIt) {
  const fs::path dir = support::FreshTempDir("live_trigger_dead");
  auto config = io::LoadRigConfig(WriteRig(dir, "/dev/rigcal-no-such-tty", "uart_wire: false"));
  ASSERT_TRUE(config.ok()) << config.error();
  std::ostringstream progress;
  auto sources = OpenCaptureSources(*config, false, "", progress);
  ASSERT_FALSE(sources.ok());
  EXPECT_NE(sources.error().find("trigger"), std::string::npos) << sources.error();
  EXPECT_NE(sources.error().find("/dev/rigcal-no-such-tty"), std::string::npos) << sources.error();

  // A port whose generator never answers: the first command times out, naming the port.
  testing::FakeTriggerGenerator silent;
  std::string error;
  ASSERT_TRUE(silent.Open(&error)) << error;
  silent.Start(/*answer=*/false);
  auto quiet = io::LoadRigConfig(WriteRig(support::FreshTempDir("live_trigger_silent"),
                                          silent.slave_path(), "command_timeout_ms: 100"));
  ASSERT_TRUE(quiet.ok()) << quiet.error();
  auto none = OpenCaptureSources(*quiet, false, "", progress);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("trigger generator on " + silent.slave_path()), std::string::npos)
      << none.error();
  EXPECT_NE(none.error().find("no answer"), std::string::npos) << none.error();
}

}  // namespace
}  // namespace rigcal::pipeline
