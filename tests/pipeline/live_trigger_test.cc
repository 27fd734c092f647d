// SPDX-License-Identifier: Apache-2.0
// The live trigger path without hardware: a rig config with `trigger.port` on a pseudo-terminal
// whose other end is a generator speaking the firmware's protocol (fake_trigger_generator.h),
// and an image-folder source that the capture sources replay in real time from the next pulse.
// Frames must come out with consecutive trigger sequences, the same one for both cameras, and
// the mapped pulse time within the matcher's tolerance of the true one (printed as RMS). A dead
// port and a silent generator give an error naming the port.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fake_trigger_generator.h"
#include "live_trigger_rig.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/capture_sources.h"
#include "support/temp_dir.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;
using testing::kFrames;
using testing::WriteRig;

TEST(LiveTrigger, ImageFolderFramesCarryConsecutivePulsesAndTheirMappedTimes) {
  testing::FakeTriggerGenerator generator;
  std::string error;
  ASSERT_TRUE(generator.Open(&error)) << error;
  generator.Start();
  const fs::path dir = support::FreshTempDir("live_trigger_folders");
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

  std::vector<int64_t> seqs[2];
  double sum2 = 0;
  int64_t worst = 0;
  for (int k = 0; k < kFrames; ++k) {
    for (int c = 0; c < 2; ++c) {
      auto frame = sources->devices[c]->Grab();
      ASSERT_TRUE(frame.ok()) << frame.error();
      ASSERT_TRUE(frame->has_value()) << "camera " << c << " ended at frame " << k;
      const capture::Frame& f = **frame;
      ASSERT_GE(f.seq, 0) << "camera " << c << " frame " << k << " got no pulse";
      seqs[c].push_back(f.seq);
      const int64_t error_ns = f.t_ns - generator.TrueHostNs(f.seq);
      sum2 += static_cast<double>(error_ns) * static_cast<double>(error_ns);
      worst = std::max(worst, std::abs(error_ns));
    }
  }
  sources->trigger->Stop();
  EXPECT_EQ(sources->trigger->problem(), "");
  for (int k = 0; k < kFrames; ++k) {
    EXPECT_EQ(seqs[0][k], seqs[1][k]) << "frame " << k;
    if (k > 0) {
      EXPECT_EQ(seqs[0][k], seqs[0][k - 1] + 1) << "frame " << k;
    }
  }
  const double rms_us = std::sqrt(sum2 / (2.0 * kFrames)) * 1e-3;
  std::printf(
      "live trigger over a pty (fake generator, 20 Hz): %d frames x 2 cameras, seqs %lld..%lld; "
      "frame time - true pulse time: RMS %.0f us, worst %.0f us\n",
      kFrames, static_cast<long long>(seqs[0].front()), static_cast<long long>(seqs[0].back()),
      rms_us, worst * 1e-3);
  EXPECT_LE(worst, config->trigger->matcher.tolerance_ns);
  std::ostringstream report;
  ReportTrigger(*sources, "", report);
  EXPECT_NE(report.str().find("camera 'cam1': 40 frames with their trigger pulse, 0 without"),
            std::string::npos)
      << report.str();
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
