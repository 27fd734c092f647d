// SPDX-License-Identifier: Apache-2.0
// The live trigger path against the real firmware: `trigger.port` is the pseudo-terminal of
// QEMU's USART1 (qemu-system-arm -M netduinoplus2 running the cross-built trigger firmware),
// the source an image-folder replay paced from its pulses. Frames come out with consecutive
// pulse sequences, the same for both cameras, spaced by the pulse period (printed: the spread of
// frame time - (first + k * period)); a frame may lack its pulse only through a late report
// (triggered_frames_check.h). Labels: pipeline, firmware. Skips without the toolchain or
// QEMU (fails under CI=true).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <vector>

#include "firmware/qemu_process.h"
#include "live_trigger_rig.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/trigger/serial_port.h"
#include "rigcal/trigger/trigger_link.h"
#include "support/skip.h"
#include "support/temp_dir.h"
#include "triggered_frames_check.h"

namespace rigcal::pipeline {
namespace {

TEST(LiveTriggerQemu, FramesCarryTheFirmwaresConsecutivePulses) {
  if (const std::string missing = testing::QemuFirmwareMissing(); !missing.empty()) {
    RIGCAL_SKIP_MISSING() << missing;
  }
  testing::QemuFirmware qemu;
  std::string error;
  ASSERT_TRUE(qemu.Start(testing::QemuFirmware::Serial::kPty, &error)) << error;
  {
    // On a loaded host QEMU may take seconds to run the firmware: wait until it speaks.
    auto port = trigger::SerialPort::Open(qemu.pty_path(), 115200);
    ASSERT_TRUE(port.ok()) << port.error();
    trigger::TriggerLink link(std::move(*port));
    std::vector<trigger::TriggerEvent> events;
    for (int i = 0; i < 60 && events.empty(); ++i) ASSERT_TRUE(link.Poll(500, &events).ok());
    ASSERT_FALSE(events.empty()) << "no message from the firmware within 30 s";
  }
  auto config = io::LoadRigConfig(testing::WriteRig(support::FreshTempDir("live_trigger_qemu"),
                                                    qemu.pty_path(), "uart_wire: false"));
  ASSERT_TRUE(config.ok()) << config.error();
  std::ostringstream progress;
  auto sources = OpenCaptureSources(*config, false, "", progress);
  ASSERT_TRUE(sources.ok()) << sources.error();

  const int64_t period_ns = 50'000'000;
  std::array<std::vector<int64_t>, 2> seqs;
  std::vector<int64_t> times;  // camera 0's mapped pulse times, -1 for a frame without
  for (int k = 0; k < testing::kFrames; ++k) {
    for (int c = 0; c < 2; ++c) {
      auto frame = sources->devices[c]->Grab();
      ASSERT_TRUE(frame.ok()) << frame.error();
      ASSERT_TRUE(frame->has_value());
      seqs[c].push_back((*frame)->seq);  // -1: CheckTriggeredFrames allows only late reports
      if (c == 0) times.push_back((*frame)->seq >= 0 ? (*frame)->t_ns : -1);
    }
  }
  sources->trigger->Stop();
  EXPECT_EQ(sources->trigger->problem(), "");
  const std::optional<int64_t> first =
      testing::CheckTriggeredFrames(seqs, {sources->triggered[0], sources->triggered[1]},
                                    sources->trigger->matcher().stats().map_restarts);
  ASSERT_TRUE(first.has_value());
  // Every mapped pulse time against the line through the first one at the pulse period.
  std::optional<int64_t> time0;  // frame 0's pulse time, from the first timed frame
  double sum2 = 0;
  int64_t worst = 0;
  int timed = 0;
  for (int k = 0; k < testing::kFrames; ++k) {
    if (times[k] < 0) continue;
    if (!time0) time0 = times[k] - k * period_ns;
    const int64_t off = times[k] - (*time0 + k * period_ns);
    sum2 += static_cast<double>(off) * static_cast<double>(off);
    worst = std::max(worst, std::abs(off));
    ++timed;
  }
  std::printf(
      "live trigger over QEMU's pty (firmware, 20 Hz): %d frames x 2 cameras with consecutive "
      "pulses %lld..%lld (%d of camera 0's frames timed); mapped pulse time - (first + k period): "
      "RMS %.0f us, worst %.0f us; drift %.1f ppm\n",
      testing::kFrames, static_cast<long long>(*first),
      static_cast<long long>(*first + testing::kFrames - 1), timed,
      std::sqrt(sum2 / std::max(timed, 1)) * 1e-3, worst * 1e-3,
      sources->trigger->matcher().stats().drift_ppm);
  EXPECT_LE(worst, config->trigger->matcher.tolerance_ns);
}

}  // namespace
}  // namespace rigcal::pipeline
